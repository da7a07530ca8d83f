"""Dump genpy's view of every message class of some packages as JSON (run by /usr/bin/python3).

Usage: genpy_dump.py PKG...   -> JSON list on stdout, one object per message type with
_type, _md5sum, _full_text, __slots__, _slot_types and the constants (name -> value).
"""

import importlib
import json
import sys

import genpy


def dump(package):
    module = importlib.import_module(package + ".msg")
    out = []
    for name in sorted(dir(module)):
        cls = getattr(module, name)
        if not (isinstance(cls, type) and issubclass(cls, genpy.Message) and cls is not genpy.Message):
            continue
        constants = {}
        for attr, value in vars(cls).items():
            if attr.startswith("_") or attr in cls.__slots__ or callable(value) \
                    or isinstance(value, (staticmethod, classmethod, property)):
                continue
            if isinstance(value, bytes):
                value = value.decode("latin-1")
            constants[attr] = value
        out.append({
            "type": cls._type, "md5": cls._md5sum, "full_text": cls._full_text,
            "slots": list(cls.__slots__), "slot_types": list(cls._slot_types),
            "constants": constants,
        })
    return out


if __name__ == "__main__":
    result = []
    for pkg in sys.argv[1:]:
        result.extend(dump(pkg))
    json.dump(result, sys.stdout, allow_nan=True)
