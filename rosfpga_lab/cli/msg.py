"""``rosfpga-lab msg``: message types like ``rosmsg`` (show, md5, list) plus byte layouts."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rosfpga_lab.errors import LabError


def _registry(args: argparse.Namespace):  # -> MsgRegistry
    from rosfpga_lab.msg import registry_with

    return registry_with(args.msg_path or [])


def _show(args: argparse.Namespace) -> int:
    from rosfpga_lab.msg.describe import show

    reg = _registry(args)
    sys.stdout.write(show(reg, args.type, full_text=not args.no_full_text))
    return 0


def _md5(args: argparse.Namespace) -> int:
    reg = _registry(args)
    status = 0
    for name in args.types:
        try:
            print(f"{name} {reg.md5(name)}")
        except LabError as exc:
            print(f"rosfpga-lab msg md5: error: {exc}", file=sys.stderr)
            status = 1
    return status


def _list(args: argparse.Namespace) -> int:
    reg = _registry(args)
    if args.package and args.package not in reg.packages():
        print(f"rosfpga-lab msg list: error: no package {args.package!r}; packages: "
              f"{', '.join(reg.packages())}", file=sys.stderr)
        return 1
    for name in reg.types(args.package):
        print(name)
    return 0


def _layout(args: argparse.Namespace) -> int:
    from rosfpga_lab.msg import field_layout
    from rosfpga_lab.msg.describe import layout_table

    reg = _registry(args)
    if args.hex is not None:
        try:
            data = bytes.fromhex(args.hex)
        except ValueError as exc:
            print(f"rosfpga-lab msg layout: error: --hex: {exc}", file=sys.stderr)
            return 1
    else:
        try:
            data = Path(args.file).read_bytes() if args.file != "-" else sys.stdin.buffer.read()
        except OSError as exc:
            print(f"rosfpga-lab msg layout: error: cannot read {args.file}: "
                  f"{exc.strerror or exc}", file=sys.stderr)
            return 1
    if args.skip < 0:
        print("rosfpga-lab msg layout: error: --skip must be 0 or more", file=sys.stderr)
        return 1
    data = data[args.skip:]
    spans = field_layout(reg, args.type, data, partial=True)
    sys.stdout.write(layout_table(spans))
    if spans and spans[-1].role == "error":
        print(f"rosfpga-lab msg layout: error: {spans[-1].value}", file=sys.stderr)
        return 1
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``msg`` sub-command."""
    parser = subparsers.add_parser(
        "msg", help="show ROS message types, md5 sums and byte layouts",
        description="ROS 1 message types as the lab models them: the shipped std_msgs, "
        "sensor_msgs and geometry_msgs, plus any folder of PKG/msg/NAME.msg files.")
    sub = parser.add_subparsers(dest="msg_command", metavar="ACTION", required=True)

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("--msg-path", action="append", metavar="DIR", default=[],
                       help="also load PKG/msg/NAME.msg files under DIR (a package folder or a "
                       "folder of packages); repeatable")

    p = sub.add_parser("show", help="fields, constants, md5 and full text of a type",
                       description="Print a message type like `rosmsg show` (nested types "
                       "indented), its md5 sum and the full text a TCPROS header carries.")
    common(p)
    p.add_argument("type", metavar="TYPE", help="message type, e.g. sensor_msgs/Image (or Image)")
    p.add_argument("--no-full-text", action="store_true", help="omit the full definition text")
    p.set_defaults(func=_show)

    p = sub.add_parser("md5", help="md5 sums of types, one 'TYPE MD5' line each",
                       description="Print one 'TYPE MD5' line per type, md5 as genmsg computes it.")
    common(p)
    p.add_argument("types", nargs="+", metavar="TYPE", help="message types")
    p.set_defaults(func=_md5)

    p = sub.add_parser("list", help="list known types",
                       description="List the known message types, optionally of one package.")
    common(p)
    p.add_argument("package", nargs="?", metavar="PKG", help="only this package")
    p.set_defaults(func=_list)

    p = sub.add_parser("layout", help="byte layout of a serialized message body",
                       description="Decode a message body (no 4-byte frame length unless "
                       "--skip 4) and print every field's offset, size, type and value. "
                       "Exit status 1 if the bytes do not decode (the rest is shown as 'error').")
    common(p)
    p.add_argument("type", metavar="TYPE", help="message type")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--hex", help="the body as hex digits (spaces allowed)")
    src.add_argument("--file", help="file holding the body ('-' for stdin)")
    p.add_argument("--skip", type=int, default=0, metavar="N",
                   help="ignore the first N bytes (4 skips a TCPROS frame length)")
    p.set_defaults(func=_layout)
