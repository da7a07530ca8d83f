"""``rosfpga-lab demo``: master, camera, FPGA component and a bit-exact checker, in one command."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rosfpga_lab.cli._args import positive_float, positive_int
from rosfpga_lab.config.vocabulary import MODELS


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``demo`` sub-command."""
    p = subparsers.add_parser(
        "demo", help="the whole paper in one command: camera -> FPGA component -> checker",
        description="Start an embedded ROS master on a free loopback port, the FPGA component "
        "from a node configuration, a camera publishing on its input, and a subscriber that "
        "checks EVERY output frame bit for bit against OpenCV (cv2.dilate / cv2.erode) run on "
        "the input. Prints frames, fps, latency and 'bit-exact: N/N'; writes input, output and "
        "their difference (output - input: what the circuit changed) to a PNG. Exit code 0 only "
        "when every output came back bit-exact and every frame sent is accounted for (back, or "
        "dropped by a full queue in front of a slower circuit, counted). Needs nothing beyond the "
        "lab; takes a few seconds. "
        "For a room: --view serves a live page (input, output, counters) on 127.0.0.1 while it "
        "runs, e.g. rosfpga-lab demo --view --frames 900 --rate 15 (a minute).")
    p.add_argument("--config", type=Path, metavar="CONFIG",
                   help="node configuration (default: data/fpga_dilate_rgba8.yaml, 640x480 rgba8 "
                   "3x3 dilation)")
    p.add_argument("--frames", type=positive_int, default=60, help="frames to send (default: 60)")
    p.add_argument("--rate", type=float, default=30.0, help="camera frames per second (default: 30)")
    p.add_argument("--source", default="grace_hopper",
                   help="camera source: grace_hopper (default), synthetic, an image file or a directory")
    p.add_argument("--output", type=Path, default=Path("demo.png"), metavar="PNG",
                   help="figure to write (default: demo.png)")
    p.add_argument("--scale", type=positive_float, default=1.0,
                   help="scale of the figure's panels (default: 1; 0.5 for a small file)")
    p.add_argument("--no-figure", action="store_true", help="do not write the figure")
    p.add_argument("--model", choices=MODELS, default=MODELS[0],
                   help="circuit model (reference: byte at a time, about 0.3 s per 160x120 "
                   "frame; try --config data/fpga_passthrough_rgb8.yaml --frames 5; rtl: the "
                   "Verilog itself on Verilator, about 0.1-0.3 s per 640x480 frame)")
    p.add_argument("--input-queue", type=positive_int, metavar="N",
                   help="frames waiting in front of the circuit (default: 2, as a camera "
                   "driver's queue; every frame with --model reference). A circuit slower than "
                   "the camera drops the oldest waiting frame and the summary counts it; "
                   "--input-queue at least --frames never drops")
    p.add_argument("--timeout", type=positive_float, default=30.0,
                   help="seconds to wait for the last output (default: 30)")
    p.add_argument("--view", action="store_true",
                   help="serve a live page (input, output, counters) on 127.0.0.1 at a free port "
                   "while the demo runs; its URL is printed first. The page needs no internet "
                   "and stops with the demo")
    p.add_argument("--pcap", type=Path, metavar="FILE",
                   help="write the whole conversation (XML-RPC, TCPROS) as a capture file for "
                   "Wireshark (pcapng; .pcap for classic pcap); frames keep the trace's excerpt "
                   "of their bytes. TCPROS: tshark -2 --enable-heuristic tcpros_tcp, or Decode As")
    p.add_argument("--pcap-frame-bytes", type=positive_int, metavar="N",
                   help="keep N bytes of each frame for the capture (default 64; 1300000 keeps "
                   "whole 640x480 rgba8 frames: use few --frames, each costs 1.2 MB twice, and "
                   "the traces are bounded in bytes: past that the oldest events go, and the "
                   "capture says so)")
    p.add_argument("-v", "--verbose", action="store_true", help="print each step")
    p.add_argument("--ros2", action="store_true",
                   help="the same on ROS 2: camera, component and viewer as DDS participants on "
                   "127.0.0.1, no master (no figure, live view or capture yet)")
    p.add_argument("--domain", type=int, default=None, metavar="N",
                   help="with --ros2: the DDS domain (default: ROS_DOMAIN_ID, else 0)")
    p.set_defaults(func=run)


def _announce(url: str) -> None:
    print(f"live view: {url}  (open it in a browser; it stops with the demo)", flush=True)


def run(args: argparse.Namespace) -> int:
    """Run the demo; 0 when every output came back bit-exact and no frame was lost."""
    from rosfpga_lab.component import run_demo

    if args.ros2:
        return run_ros2(args)

    try:
        result = run_demo(args.config, frames=args.frames, rate=args.rate, source=args.source,
                          png=None if args.no_figure else args.output, model=args.model,
                          timeout=args.timeout, png_scale=args.scale,
                          progress=print if args.verbose else None,
                          view=_announce if args.view else None, pcap=args.pcap,
                          pcap_frame_bytes=args.pcap_frame_bytes, input_queue=args.input_queue)
    except KeyboardInterrupt:
        print("rosfpga-lab demo: interrupted (everything it started is stopped); no verdict",
              file=sys.stderr)
        return 130
    print("\n".join(result.lines()), flush=True)
    return 0 if result.ok else 1


def run_ros2(args: argparse.Namespace) -> int:
    """``demo --ros2``: 0 when every frame came back bit-exact."""
    import os

    from rosfpga_lab.component.demo import run_demo_ros2
    from rosfpga_lab.errors import LabError

    raw = args.domain if args.domain is not None else os.environ.get("ROS_DOMAIN_ID") or "0"
    try:
        result = run_demo_ros2(args.config, frames=args.frames, rate=args.rate,
                               source=args.source, domain=int(raw), model=args.model or "fast",
                               timeout=args.timeout)
    except (ValueError, LabError) as exc:
        print(f"rosfpga-lab demo: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("rosfpga-lab demo: interrupted (everything it started is stopped); no verdict",
              file=sys.stderr)
        return 130
    print("\n".join(result.lines()), flush=True)
    return 0 if result.ok else 1
