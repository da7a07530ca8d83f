"""``rosfpga-lab bench``: the circuit model against OpenCV, and the component against relays."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rosfpga_lab.cli._args import positive_int


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``bench`` sub-command."""
    p = subparsers.add_parser(
        "bench", help="benchmark the circuit model and the component against ROS relays",
        description="Print, from one run: (1) the fast circuit model's frames/s beside "
        "cv2.dilate alone; (2) a publisher -> middle -> subscriber path on loopback, with no "
        "middle (baseline), the FPGA component, roscpp's topic_tools relay and a rospy relay "
        "(the last two where real ROS 1 is installed): sustained frames/s, drops and latency at "
        "a fixed rate, and the latency each middle adds. Each middle runs as its own process; the "
        "sustained runs repeat in interleaved rounds and the median is shown. Takes about a "
        "minute; close other heavy programs for steady figures.")
    p.add_argument("--config", type=Path, metavar="CONFIG",
                   help="node configuration (default: data/fpga_dilate_rgba8.yaml, 640x480 rgba8)")
    p.add_argument("--middles", default=",".join(("direct", "component", "roscpp", "rospy")),
                   help="comma-separated subset of direct,component,roscpp,rospy (default: all)")
    p.add_argument("--frames", type=positive_int, default=200,
                   help="frames per sustained run, per middle (default: 200)")
    p.add_argument("--windows", default="1,2", metavar="A,B",
                   help="frames in flight in the two sustained columns (default: 1,2)")
    p.add_argument("--rounds", type=positive_int, default=3,
                   help="interleaved rounds of the sustained runs; the table shows the median "
                   "(default: 3)")
    p.add_argument("--rate", type=float, default=30.0, help="rate of the second phase (default: 30)")
    p.add_argument("--rate-frames", type=positive_int, default=90,
                   help="frames sent in the second phase (default: 90)")
    p.add_argument("--no-pipeline", action="store_true", help="skip the model-vs-OpenCV part")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print the tables."""
    from rosfpga_lab.bench import MIDDLES, run_bench

    middles = tuple(m.strip() for m in args.middles.split(",") if m.strip())
    unknown = [m for m in middles if m not in MIDDLES]
    if unknown:
        print(f"rosfpga-lab bench: error: unknown middle(s) {', '.join(unknown)}; choose from "
              f"{', '.join(MIDDLES)}", file=sys.stderr)
        return 2
    try:
        windows = tuple(int(v) for v in args.windows.split(","))
        if len(windows) != 2 or min(windows) < 1:
            raise ValueError
    except ValueError:
        print(f"rosfpga-lab bench: error: --windows wants two positive integers like 1,2, got "
              f"{args.windows!r}", file=sys.stderr)
        return 2
    try:
        report = run_bench(args.config, middles=middles, frames=args.frames, windows=windows,
                           rounds=args.rounds, rate=args.rate, rate_frames=args.rate_frames,
                           skip_pipeline=args.no_pipeline,
                           progress=None if args.quiet else (lambda t: print(t, file=sys.stderr, flush=True)))
    except KeyboardInterrupt:
        print("rosfpga-lab bench: interrupted (the middles it started are stopped); no table",
              file=sys.stderr)
        return 130
    print(report.table(), flush=True)
    return 0
