"""``rosfpga-lab node CONFIG``: run the emulated FPGA component until Ctrl-C."""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
import time
from pathlib import Path

from rosfpga_lab.cli._args import non_negative_float, positive_float, positive_int
from rosfpga_lab.config.vocabulary import MODELS


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``node`` sub-command."""
    p = subparsers.add_parser(
        "node", help="run the ROS-compliant FPGA component (emulated) from a node config",
        description="Run the FPGA component described by a node configuration (the same YAML "
        "file 'rosfpga-lab generate' reads): it registers with the ROS master, subscribes to "
        "the input topic, pushes every TCPROS frame through the modelled circuit and publishes "
        "the result. A status line shows frames, fps, drops and latency; Ctrl-C stops it "
        "cleanly and prints a summary. Example: rosfpga-lab node data/fpga_dilate_rgba8.yaml")
    p.add_argument("config", type=Path, metavar="CONFIG", help="the node configuration file (YAML)")
    p.add_argument("--master-uri", metavar="URI",
                   help="ROS master (default: ROS_MASTER_URI, else the configuration's "
                   "node.master_uri)")
    p.add_argument("--embedded-master", action="store_true",
                   help="start the lab's embedded master at that URI when none answers there")
    p.add_argument("--model", choices=MODELS, default=MODELS[0],
                   help="circuit model: fast (numpy, default) or reference (byte at a time; "
                   "small images only)")
    p.add_argument("--input-queue", type=positive_int, default=None, metavar="N",
                   help="frames waiting in front of the circuit before the oldest is dropped "
                   "(default: 2)")
    p.add_argument("--output-queue", type=positive_int, default=None, metavar="N",
                   help="frames waiting per downstream subscriber before the oldest is dropped "
                   "(default: 2)")
    p.add_argument("--duration", type=positive_float, default=None, metavar="S",
                   help="stop by itself after S seconds (default: run until Ctrl-C)")
    p.add_argument("--status-interval", type=non_negative_float, default=0.5, metavar="S",
                   help="seconds between status updates (default: 0.5; 0: no status line)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no status line and no log lines, only the final summary")
    p.add_argument("--ros2", action="store_true",
                   help="run as a ROS 2 node (DDS/RTPS on 127.0.0.1, no master) instead of ROS 1")
    p.add_argument("--domain", type=int, default=None, metavar="N",
                   help="with --ros2: the DDS domain (default: ROS_DOMAIN_ID, else 0)")
    p.add_argument("--best-effort-input", action="store_true",
                   help="with --ros2: subscribe BEST_EFFORT (matches best-effort cameras, e.g. "
                   "ROS 2's sensor-data QoS, as well as reliable ones); default RELIABLE, ROS 2's "
                   "default, which a best-effort writer never matches")
    p.set_defaults(func=run)


def run_ros2(args: argparse.Namespace) -> int:
    """``node --ros2``: the component as a ROS 2 participant until Ctrl-C or --duration."""
    import os

    from rosfpga_lab.component.ros2 import Ros2Component
    from rosfpga_lab.errors import LabError
    from rosfpga_lab.rtps.participant import Qos

    if not args.quiet:
        logging.basicConfig(level=logging.INFO, format="[%(levelname)s] %(message)s",
                            stream=sys.stderr)
    raw = args.domain if args.domain is not None else os.environ.get("ROS_DOMAIN_ID", "0") or "0"
    try:
        domain = int(raw)
        qos_in = Qos(reliable=not args.best_effort_input)
        comp = Ros2Component(args.config, domain=domain, model=args.model, qos_in=qos_in).start()
    except (ValueError, LabError) as exc:
        print(f"rosfpga-lab node: error: {exc}", file=sys.stderr)
        return 1
    print(f"{comp.name}: ROS 2 (DDS domain {domain}, participant index "
          f"{comp.node.index if comp.node else '?'}, input {comp.qos_in.describe()}) "
          f"{comp.input_topic} -> {comp.pipeline.op} ({args.model} model) -> {comp.output_topic}; "
          "Ctrl-C to stop", flush=True)
    t_end = None if args.duration is None else time.monotonic() + args.duration
    try:
        while t_end is None or time.monotonic() < t_end:
            time.sleep(0.1)
    except KeyboardInterrupt:
        pass
    finally:
        comp.stop()
    c = comp.counts
    print(f"{c['seen']} samples seen, {c['published']} published, {c['refused']} refused", flush=True)
    return 0


def run(args: argparse.Namespace) -> int:
    """Start the component, show the status until interrupted, stop cleanly."""
    if args.ros2:
        return run_ros2(args)
    from rosfpga_lab.component import FpgaComponent, limits, master_answers
    from rosfpga_lab.config import load_config, master_uri
    from rosfpga_lab.graph import EmbeddedMaster
    from rosfpga_lab.graph.xmlrpc import split_uri

    if not args.quiet:
        logging.basicConfig(level=logging.INFO, format="[%(levelname)s] %(message)s",
                            stream=sys.stderr)
    kw = {}
    if args.input_queue is not None:
        kw["input_queue"] = args.input_queue
    if args.output_queue is not None:
        kw["output_queue"] = args.output_queue
    config = load_config(args.config)
    component = FpgaComponent.from_config(config, master_uri=master_uri(args.master_uri, config),
                                          model=args.model, **kw)
    master = None
    if not master_answers(component.master_uri):
        if not args.embedded_master:
            print(f"rosfpga-lab node: error: no ROS master answers at {component.master_uri}; "
                  "start one (roscore, or 'rosfpga-lab master') or add --embedded-master",
                  file=sys.stderr)
            return 1
        host, port, _path = split_uri(component.master_uri)
        master = EmbeddedMaster(host=host, port=port).start()
        print(f"started the embedded master at {master.uri}", file=sys.stderr)
    terminated = False

    def on_sigterm(*_args: object) -> None:
        # Only a flag: a handler runs between two steps of the main thread, which may hold any
        # lock then (an Event's included), so taking one here could wait forever.
        nonlocal terminated
        terminated = True

    previous = signal.getsignal(signal.SIGTERM)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, on_sigterm)
    component.start()
    tty = sys.stdout.isatty()
    print(f"{component.name}: {component.input_topic} -> {component.pipeline.op} "
          f"({args.model} model) -> {component.output_topic}; master {component.master_uri}; "
          "Ctrl-C to stop", flush=True)
    t_end = None if args.duration is None else time.monotonic() + args.duration
    interval = args.status_interval if args.status_interval > 0 and not args.quiet else 1.0
    last_print = 0.0
    exit_code = 0
    period = min(interval, limits.WATCHDOG_PERIOD)
    next_tick = time.monotonic() + period
    try:
        while not terminated:
            time.sleep(limits.SIGNAL_POLL)
            now = time.monotonic()
            if now < next_tick:
                continue
            next_tick = now + period
            if t_end is not None and now >= t_end:
                break
            if not component.running:
                print("\nthe node was shut down from outside (a 'shutdown' call: another node "
                      "took its name, or rosnode kill)", file=sys.stderr, flush=True)
                exit_code = 1
                break
            if args.quiet or args.status_interval <= 0:
                continue
            line = component.stats.status_line()
            if tty:
                print("\r" + line.ljust(100), end="", flush=True)
            elif now - last_print >= max(5.0, interval):
                print(line, flush=True)
                last_print = now
    except KeyboardInterrupt:
        pass
    finally:
        if tty and not args.quiet:
            print()
        stats = component.stats
        component.stop()
        if master is not None:
            master.stop()
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, previous)
    print(stats.report(), flush=True)
    return exit_code
