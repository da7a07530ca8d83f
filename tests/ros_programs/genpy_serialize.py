"""Serialize values with Debian's genpy classes (run by /usr/bin/python3).

stdin: JSON list of {"type": "pkg/Name", "value": <value>, "ours": <base64 body>}. Values are
JSON: messages as objects, time/duration as [secs, nsecs], uint8[]/char[] as {"b64": "..."}.
stdout: JSON list of {"genpy": <base64 of genpy's serialize(value)>,
"reserialized": <base64 of genpy deserializing "ours" and serializing it again>}.
Time/duration are built without genpy's canonicalization so every 32-bit pattern survives.
"""

import base64
import importlib
import io
import json
import sys

import genpy


def message_class(type_name):
    pkg, name = type_name.split("/")
    return getattr(importlib.import_module(pkg + ".msg"), name)


def element(base, value):
    if base in ("time", "duration"):
        t = genpy.Time() if base == "time" else genpy.Duration()
        t.secs, t.nsecs = value
        return t
    if "/" in base:
        return build(base, value)
    return value


def build(type_name, value):
    cls = message_class(type_name)
    msg = cls()
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        v = value[name]
        if "[" in slot_type:
            base = slot_type[:slot_type.index("[")]
            if base in ("uint8", "char"):
                v = base64.b64decode(v["b64"])
            else:
                v = [element(base, x) for x in v]
        else:
            v = element(slot_type, v)
        setattr(msg, name, v)
    return msg


def main():
    items = json.load(sys.stdin)
    out = []
    for item in items:
        buf = io.BytesIO()
        build(item["type"], item["value"]).serialize(buf)
        ours = base64.b64decode(item["ours"])
        again = io.BytesIO()
        message_class(item["type"])().deserialize(ours).serialize(again)
        out.append({"genpy": base64.b64encode(buf.getvalue()).decode(),
                    "reserialized": base64.b64encode(again.getvalue()).decode()})
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
