"""``rosfpga-lab camera`` (publish images) and ``rosfpga-lab view TOPIC`` (receive and save them).

Both live here because they are the two ends of the same test set-up: a camera when there is
no camera, and a screen when there is no screen.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from rosfpga_lab.cli._args import positive_float, positive_int
from rosfpga_lab.cli._signals import deliver_held, holding
from rosfpga_lab.config.limits import DEFAULT_MASTER_URI
from rosfpga_lab.config.vocabulary import DEFAULT_ENCODING, ENCODINGS

if TYPE_CHECKING:
    from rosfpga_lab.config import NodeConfig
    from rosfpga_lab.config.rosargs import RosArgs


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must be WIDTHxHEIGHT, e.g. 640x480, got {text!r}") from None
    return w, h


def _common(p: argparse.ArgumentParser, *, with_config: bool) -> None:
    from_config = "the --config file's node.master_uri, else " if with_config else ""
    p.add_argument("--master-uri", metavar="URI",
                   help=f"ROS master (default: ROS_MASTER_URI, else {from_config}{DEFAULT_MASTER_URI})")
    p.add_argument("--name", metavar="NODE", help="node name")
    p.add_argument("--ros2", action="store_true",
                   help="ROS 2 instead of ROS 1: a DDS participant on 127.0.0.1, no master")
    p.add_argument("--domain", type=int, default=None, metavar="N",
                   help="with --ros2: the DDS domain (default: ROS_DOMAIN_ID, else 0)")


def _domain(args: argparse.Namespace) -> int | None:
    """The DDS domain with --ros2 (None: ROS 1)."""
    import os

    from rosfpga_lab.component import ComponentError

    if not args.ros2:
        return None
    raw = args.domain if args.domain is not None else os.environ.get("ROS_DOMAIN_ID") or "0"
    try:
        return int(raw)
    except ValueError:
        raise ComponentError(f"ROS_DOMAIN_ID={raw!r} is not a number; give --domain N") from None


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``camera`` and ``view`` sub-commands."""
    p = subparsers.add_parser(
        "camera", help="publish sensor_msgs/Image frames: a photo, files or a moving scene",
        description="Publish sensor_msgs/Image frames at a fixed rate, size and encoding, for "
        "when there is no camera: a moving synthetic scene, the photo matplotlib ships "
        "(grace_hopper), an image file or a directory of images, panned so frames differ. "
        "header.stamp is the publish time (for latency), header.seq the frame number. With "
        "--config the topic, size and encoding come from a node configuration, so the frames "
        "fit its circuit. Example: rosfpga-lab camera --config data/fpga_dilate_rgba8.yaml")
    p.add_argument("--config", type=Path, metavar="CONFIG",
                   help="take topic (the circuit's input), size, encoding and master from this "
                   "node configuration")
    p.add_argument("--topic", help="topic to publish (default: /image_raw)")
    p.add_argument("--size", type=_size, metavar="WxH", help="frame size (default: 640x480)")
    p.add_argument("--encoding", choices=tuple(ENCODINGS),
                   help=f"image encoding (default: {DEFAULT_ENCODING})")
    p.add_argument("--rate", type=float, default=30.0, help="frames per second (default: 30)")
    p.add_argument("--source", default="synthetic",
                   help="synthetic (default), grace_hopper, an image file, a directory, or a ROS 1 "
                   "bag (FILE.bag: its images replayed with their recorded timing, on --topic, "
                   "which also names the bag topic read; the bag's only image topic otherwise)")
    p.add_argument("--count", type=positive_int, default=None,
                   help="stop after N frames (default: run on; a bag: its frames once)")
    p.add_argument("--frame-id", default="camera", help="header.frame_id (default: camera)")
    _common(p, with_config=True)
    p.set_defaults(func=run_camera, ros_node=True)

    v = subparsers.add_parser(
        "view", help="receive sensor_msgs/Image frames: count, time and save them as PNG",
        description="Subscribe to an image topic and show what arrives: a status line with "
        "frames, fps and latency (receive time minus header.stamp), and, with --save, PNG files "
        f"of the frames ({', '.join(ENCODINGS)}). Example: "
        "rosfpga-lab view /image_dilated --save out --every 30")
    v.add_argument("topic", metavar="TOPIC", help="the image topic")
    v.add_argument("--save", type=Path, metavar="DIR", help="write frames as PNG into DIR")
    v.add_argument("--every", type=positive_int, default=1, metavar="N", help="save one frame in N (default: 1)")
    v.add_argument("--latest", action="store_true",
                   help="overwrite DIR/latest.png instead of numbering the files")
    v.add_argument("--count", type=positive_int, default=None, help="stop after N frames")
    v.add_argument("--timeout", type=positive_float, default=None, metavar="S",
                   help="give up after S seconds (exit code 1 if fewer than --count arrived)")
    _common(v, with_config=False)
    v.set_defaults(func=run_view, ros_node=True)


def _ros(args: argparse.Namespace) -> RosArgs:
    from rosfpga_lab.config.rosargs import RosArgs

    return getattr(args, "ros", None) or RosArgs()


def _identity(args: argparse.Namespace, default_name: str, topic: str) -> tuple[str, str, str]:
    """Node name, topic and address after the ROS command line (``__name:=``, ``from:=to``,
    ``__ip:=``) and the environment (``ROS_NAMESPACE``, ``ROS_HOSTNAME``, ``ROS_IP``). A
    configuration's ``node.ip_address`` is the component's address, not the camera's: unused."""
    from rosfpga_lab.config.rosargs import advertise_host, node_name, remap

    ros = _ros(args)
    name = node_name(args.name or default_name, ros)
    return name, remap(topic, name, ros), advertise_host(ros, None).host


def _master_uri(args: argparse.Namespace, config: NodeConfig | None = None) -> str:
    """The master to use; raises ComponentError (printed by the CLI) when none answers there."""
    from rosfpga_lab.component import ComponentError, master_answers
    from rosfpga_lab.config import master_uri

    uri = master_uri(args.master_uri or _ros(args).special.get("__master"), config)
    if not master_answers(uri):
        raise ComponentError(f"no ROS master answers at {uri}; start one (roscore, or "
                             "'rosfpga-lab master') or give --master-uri")
    return uri


def run_camera(args: argparse.Namespace) -> int:
    """Publish until Ctrl-C, SIGTERM or --count."""
    from rosfpga_lab.cli._signals import StopSignals

    with StopSignals():
        return _run_camera(args)


def _run_camera(args: argparse.Namespace) -> int:
    from rosfpga_lab.component import Camera
    from rosfpga_lab.component.sources import ImageSource, open_source
    from rosfpga_lab.config import load_config

    topic, size, encoding, cfg = "/image_raw", (640, 480), DEFAULT_ENCODING, None
    if args.config is not None:
        cfg = load_config(args.config)
        topic, size, encoding = cfg.subscriber.topic, (cfg.image.width, cfg.image.height), cfg.image.encoding
    size = args.size or size
    encoding = args.encoding or encoding
    source: str | ImageSource = args.source
    if args.source.endswith(".bag"):  # a bag: its topic (named by --topic), once by default
        source = open_source(args.source, size[0], size[1], encoding, topic=args.topic)
        topic = args.topic or (topic if cfg is not None else source.bag_topic or topic)
        args.count = args.count or source.period
    topic = args.topic or topic
    name, topic, host = _identity(args, "/camera", topic)
    uri = None if args.ros2 else _master_uri(args, cfg)   # ROS 2: a DDS participant, no master
    with holding(deliver=False):   # registering: a signal waits (delivered in the try below)
        cam = Camera(topic, width=size[0], height=size[1], encoding=encoding, rate=args.rate,
                     source=source, name=name, master_uri=uri, frame_id=args.frame_id,
                     host=None if args.ros2 else host,
                     domain=_domain(args))
    stop = threading.Event()
    tty = sys.stdout.isatty()
    worker = threading.Thread(target=cam.run, kwargs={"count": args.count, "stop": stop}, daemon=True)
    try:
        deliver_held()
        print(f"{cam.node.name}: publishing {args.source} {size[0]}x{size[1]} {encoding} on "
              f"{topic} at {args.rate:g} fps; master {cam.node.master_uri}; Ctrl-C to stop",
              flush=True)
        worker.start()
        while worker.is_alive():
            worker.join(0.5)
            if tty:
                print(f"\rsent {cam.sent}  subscribers {cam.publisher.get_num_connections()}   ",
                      end="", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        stop.set()
        if worker.is_alive():
            worker.join(5.0)
        if tty:
            print()
        with holding(deliver=False):   # a signal now must not cut the unregistering short
            cam.stop()
    print(f"sent {cam.sent} frames", flush=True)
    return 0


def run_view(args: argparse.Namespace) -> int:
    """Receive until Ctrl-C, SIGTERM, --count or --timeout."""
    from rosfpga_lab.cli._signals import StopSignals

    with StopSignals():
        return _run_view(args)


def _run_view(args: argparse.Namespace) -> int:
    from rosfpga_lab.component import Viewer

    name, topic, host = _identity(args, "/viewer", args.topic)
    uri = None if args.ros2 else _master_uri(args)   # ROS 2: a DDS participant, no master
    with holding(deliver=False):   # registering: a signal waits (delivered in the try below)
        viewer = Viewer(topic, save_dir=args.save, every=args.every, latest_only=args.latest,
                        name=name, master_uri=uri, host=None if args.ros2 else host,
                        domain=_domain(args))
    tty = sys.stdout.isatty()
    deadline = None if args.timeout is None else time.monotonic() + args.timeout
    try:
        deliver_held()
        print(f"{viewer.node.name}: listening on {topic}; master {viewer.node.master_uri}"
              + (f"; saving into {args.save}" if args.save else "") + "; Ctrl-C to stop",
              flush=True)
        while args.count is None or viewer.received < args.count:
            if deadline is not None and time.monotonic() >= deadline:
                break
            time.sleep(0.2)
            if tty:
                lat = viewer.latency.summary()
                last = viewer.last
                what = f"{last.width}x{last.height} {last.encoding}" if last else "-"
                print(f"\rframes {viewer.received}  {viewer.fps:5.1f} fps  {what}  latency "
                      f"{lat.ms()}   ", end="", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        if tty:
            print()
        with holding(deliver=False):   # a signal now must not cut the unregistering short
            viewer.stop()
    lat = viewer.latency.summary()
    print(f"received {viewer.received} frames; latency (stamp -> arrival) {lat.ms()}"
          + (f"; saved {len(viewer.saved)} PNG files in {args.save}" if args.save else ""))
    for problem in viewer.problems[:5]:
        print(f"problem: {problem}", file=sys.stderr)
    if args.count is not None and viewer.received < args.count:
        print(f"rosfpga-lab view: only {viewer.received} of {args.count} frames arrived",
              file=sys.stderr)
        return 1
    return 0
