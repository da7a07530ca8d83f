"""The ``rosfpga-lab`` command: a thin shell over the library.

Every sub-command lives in its own module of this package and exposes
``register(subparsers) -> None``, which adds its parser and sets ``func`` (a callable taking
the parsed ``argparse.Namespace`` and returning an exit code). Modules are found by name, so
adding a sub-command means adding one file here, nothing else.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence

from rosfpga_lab import __version__
from rosfpga_lab.errors import LabError


def build_parser() -> argparse.ArgumentParser:
    """Return the top-level parser with every sub-command module registered."""
    parser = argparse.ArgumentParser(
        prog="rosfpga-lab",
        description="Rebuild a ROS-compliant FPGA component byte for byte: "
        "ROS messages, TCPROS, the HLS pipeline and its generator.",
    )
    parser.add_argument("--version", action="version", version=f"rosfpga-lab {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the process exit code."""
    from rosfpga_lab.config.rosargs import split_ros_args

    parser = build_parser()
    try:  # the ROS words (from:=to, __name:=x, _param:=v), as rosgraph's myargv drops them
        own, ros = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    except LabError as exc:
        parser.error(str(exc))
    args = parser.parse_args(own)
    if ros and not getattr(args, "ros_node", False):
        parser.error(f"{' '.join(ros.words)}: ROS arguments (NAME:=VALUE) are for the commands "
                     "that run a ROS node (node, camera, view, topic)")
    args.ros = ros
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except LabError as exc:
        print(f"rosfpga-lab {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"rosfpga-lab {args.command}: interrupted", file=sys.stderr)
        return 130
