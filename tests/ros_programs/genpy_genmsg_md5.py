"""Compute md5 sums and full texts with Debian's genmsg (run by /usr/bin/python3).

stdin: JSON object {"pkg/Name": ".msg text", ...}. stdout: JSON object
{"pkg/Name": {"md5": ..., "full_text": ...} or {"error": "..."}} for every type given.
"""

import json
import sys

from genmsg import gentools, msg_loader


def main():
    texts = json.load(sys.stdin)
    ctx = msg_loader.MsgContext.create_default()
    specs, out = {}, {}
    for name, text in texts.items():
        try:
            specs[name] = msg_loader.load_msg_from_string(ctx, text, name)
        except Exception as exc:  # genmsg raises several kinds
            out[name] = {"error": "%s: %s" % (type(exc).__name__, exc)}
    for name, spec in specs.items():
        try:
            msg_loader.load_depends(ctx, spec, {})
            out[name] = {"md5": gentools.compute_md5(ctx, spec),
                         "full_text": gentools.compute_full_text(ctx, spec)}
        except Exception as exc:
            out[name] = {"error": "%s: %s" % (type(exc).__name__, exc)}
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
