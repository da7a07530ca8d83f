"""``rosfpga-lab node CONFIG``: run the emulated FPGA component until Ctrl-C."""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from rosfpga_lab.cli._signals import StopSignals
from rosfpga_lab.config.params import ParamSource
from rosfpga_lab.cli._args import non_negative_float, positive_float, positive_int
from rosfpga_lab.config.vocabulary import MODELS, TIMINGS

if TYPE_CHECKING:
    from rosfpga_lab.component import FpgaComponent
    from rosfpga_lab.config import NodeConfig
    from rosfpga_lab.config.rosargs import NodeNames, RosArgs
    from rosfpga_lab.graph import EmbeddedMaster


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``node`` sub-command."""
    p = subparsers.add_parser(
        "node", help="run the ROS-compliant FPGA component (emulated) from a node config",
        description="Run the FPGA component described by a node configuration (the same YAML "
        "file 'rosfpga-lab generate' reads): it registers with the ROS master, subscribes to "
        "the input topic, pushes every TCPROS frame through the modelled circuit and publishes "
        "the result. A status line shows frames, fps, drops and latency; Ctrl-C stops it "
        "cleanly and prints a summary. It takes the ROS command line as rospy does (remappings "
        "FROM:=TO, __name:=, __ns:=, __ip:=, __hostname:=, __master:=, private parameters "
        "_NAME:=VALUE) and ROS_NAMESPACE, so rosrun and roslaunch can start it. Private "
        "parameters (~model, ~input_queue, ~output_queue; ~op, ~ksize, ~width, ~height, "
        "~encoding, ~clock_mhz must equal the configuration's: the YAML is the circuit) come "
        "from the parameter server and the command line. "
        "Example: rosfpga-lab node data/fpga_dilate_rgba8.yaml")
    p.add_argument("config", type=Path, metavar="CONFIG", help="the node configuration file (YAML)")
    p.add_argument("--master-uri", metavar="URI",
                   help="ROS master (default: ROS_MASTER_URI, else the configuration's "
                   "node.master_uri)")
    p.add_argument("--embedded-master", action="store_true",
                   help="start the lab's embedded master at that URI when none answers there")
    p.add_argument("--model", choices=MODELS, default=None,
                   help="the data path: fast (numpy model, default), reference (byte at a time; "
                   "small images only) or rtl (the Verilog itself, simulated by Verilator; with "
                   "--ros2 the generated CDR top); also the private parameter ~model")
    p.add_argument("--timing", choices=TIMINGS, default=TIMINGS[0],
                   help="host (default): publish as soon as the data path is done; fpga: hold "
                   "each output for the circuit's clocks at clock_mhz and drop frames that come "
                   "while it is busy, as the board would")
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
    p.add_argument("--msg-path", action="append", metavar="DIR", default=[],
                   help="folder of PKG/msg/NAME.msg packages (repeatable), after the "
                   "configuration's msg_path")
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
    p.set_defaults(func=run, ros_node=True)


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
        model = args.model or MODELS[0]
        comp = Ros2Component(args.config, domain=domain, model=model, qos_in=qos_in,
                             timing=args.timing).start()
    except (ValueError, LabError) as exc:
        print(f"rosfpga-lab node: error: {exc}", file=sys.stderr)
        return 1
    print(f"{comp.name}: ROS 2 (DDS domain {domain}, participant index "
          f"{comp.node.index if comp.node else '?'}, input {comp.qos_in.describe()}) "
          f"{comp.input_topic} -> {comp.pipeline.op} ({model} CDR circuit model, {args.timing} "
          "timing) -> "
          f"{comp.output_topic}; "
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
    # SIGINT and SIGTERM only set a flag the loops poll (a handler that takes a lock could wait
    # forever on one the interrupted main thread holds), whatever disposition was inherited.
    with StopSignals(raise_interrupt=False) as stop:
        return _run(args, stop)


def _say_shut_down(reason: str) -> None:
    print(f"\nthe node was shut down from outside ({reason or 'a shutdown call'}: rosnode kill, "
          "or another node took its name)", file=sys.stderr, flush=True)


def _start_component(args: argparse.Namespace, config: NodeConfig, ros: RosArgs,
                     names: NodeNames, host: str, uri: str,
                     cmdline: ParamSource) -> tuple[FpgaComponent, str]:
    """The component started with its parameters (the server's ~params, the command line's,
    which also land on the server as rospy puts them) and the model it runs."""
    from rosfpga_lab.component import FpgaComponent
    from rosfpga_lab.config.params import runtime_settings
    from rosfpga_lab.graph.xmlrpc import call

    settings = runtime_settings(config, _server_params(uri, names.node), cmdline)
    for key, value in ros.params.items():   # as rospy: _x:=v lands on the server as ~x
        call(uri, "setParam", names.node, f"{names.node}/{key}", value)
    model = args.model or settings.get("model", MODELS[0])
    kw = {k: v for k, v in settings.items() if k in ("input_queue", "output_queue")}
    if args.input_queue is not None:
        kw["input_queue"] = args.input_queue
    if args.output_queue is not None:
        kw["output_queue"] = args.output_queue
    component = FpgaComponent.from_config(
        config, master_uri=uri, model=model, timing=args.timing, name=names.node,
        host=host, input_topic=names.input, output_topic=names.output, **kw)
    component.start()
    return component, model


def _start_embedded_master(uri: str) -> EmbeddedMaster:
    """``--embedded-master``: a master of this process's own, at the URI no master answered."""
    from rosfpga_lab.graph import EmbeddedMaster
    from rosfpga_lab.graph.xmlrpc import split_uri

    host, port, _path = split_uri(uri)
    master = EmbeddedMaster(host=host, port=port).start()
    print(f"started the embedded master at {master.uri}", file=sys.stderr)
    return master


def _run(args: argparse.Namespace, stop: StopSignals) -> int:
    from rosfpga_lab.component import ComponentShutDown, limits, master_answers
    from rosfpga_lab.config import load_config, master_uri
    from rosfpga_lab.config.params import runtime_settings
    from rosfpga_lab.config.rosargs import RosArgs, advertise_host, component_names

    if not args.quiet:
        logging.basicConfig(level=logging.INFO, format="[%(levelname)s] %(message)s",
                            stream=sys.stderr)
    ros = getattr(args, "ros", None) or RosArgs()
    config = load_config(args.config, msg_path=args.msg_path)
    names = component_names(config, ros)
    host = advertise_host(ros, config.node.ip_address)
    uri = master_uri(args.master_uri or ros.special.get("__master"), config)
    cmdline = ParamSource(ros.params, "the command line", "_")
    runtime_settings(config, cmdline)   # a wrong parameter is refused before any waiting
    t_end = None if args.duration is None else time.monotonic() + args.duration
    master = None
    if not master_answers(uri):
        if args.embedded_master:
            master = _start_embedded_master(uri)
        elif not _wait_for_master(uri, stop, t_end):
            return 0 if stop.fired is not None else 1
    try:
        component, model = _start_component(args, config, ros, names, host.host, uri, cmdline)
    except ComponentShutDown as exc:
        # rosnode kill between its registrations: an ending as normal as one after them
        if master is not None:
            master.stop()
        _say_shut_down(exc.reason + ", while it was starting")
        return 0
    except BaseException:
        if master is not None:
            master.stop()
        raise
    tty = sys.stdout.isatty()
    print(f"{component.name}: {component.input_topic} -> {component.pipeline.op} "
          f"({model} model, {args.timing} timing) -> {component.output_topic}; "
          f"master {component.master_uri}; "
          f"address {component.host} (from {host.source}); Ctrl-C to stop", flush=True)
    interval = args.status_interval if args.status_interval > 0 and not args.quiet else 1.0
    last_print = 0.0
    exit_code = 0
    period = min(interval, limits.WATCHDOG_PERIOD)
    next_tick = time.monotonic() + period
    try:
        while stop.fired is None:
            time.sleep(limits.SIGNAL_POLL)
            now = time.monotonic()
            if now < next_tick:
                continue
            next_tick = now + period
            if t_end is not None and now >= t_end:
                break
            if not component.running:
                # rospy and roscpp end a node shut down this way normally (exit status 0)
                reason = component.node.shutdown_reason if component.node is not None else ""
                _say_shut_down(reason)
                break
            if args.quiet or args.status_interval <= 0:
                continue
            line = component.stats.status_line()
            if tty:
                print("\r" + line.ljust(100), end="", flush=True)
            elif now - last_print >= max(5.0, interval):
                print(line, flush=True)
                last_print = now
    except KeyboardInterrupt:   # a Ctrl-C that came before the handlers were in place
        pass
    finally:
        if tty and not args.quiet:
            print()
        stats = component.stats
        component.stop()
        if master is not None:
            master.stop()
    print(stats.report(), flush=True)
    return exit_code


def _server_params(uri: str, node: str) -> ParamSource:
    """The node's private parameters on the parameter server (``getParam`` of its own name)."""
    from rosfpga_lab.config.params import ParamSource
    from rosfpga_lab.graph.xmlrpc import call

    reply = call(uri, "getParam", node, node, timeout=5.0)
    values = reply[2] if isinstance(reply, list) and len(reply) == 3 and reply[0] == 1 else {}
    return ParamSource(values if isinstance(values, dict) else {},
                       "the parameter server", f"{node}/")


def _wait_for_master(uri: str, stop: StopSignals, t_end: float | None) -> bool:
    """Wait until a master answers at ``uri``, as rospy and roscpp nodes do (a launch order race
    is normal), saying so once; False when stopped by a signal or ``--duration`` first."""
    from rosfpga_lab.component import limits, master_answers

    print(f"rosfpga-lab node: no ROS master answers at {uri} yet; waiting for it and trying "
          "again (start one: roscore, or 'rosfpga-lab master'; or add --embedded-master)",
          file=sys.stderr, flush=True)
    next_try = time.monotonic() + limits.MASTER_RETRY
    while stop.fired is None:
        now = time.monotonic()
        if t_end is not None and now >= t_end:
            print(f"rosfpga-lab node: error: no ROS master answered at {uri} within --duration",
                  file=sys.stderr)
            return False
        if now >= next_try:
            if master_answers(uri, timeout=limits.MASTER_RETRY):
                print(f"rosfpga-lab node: the ROS master at {uri} answers now", file=sys.stderr,
                      flush=True)
                return True
            next_try = time.monotonic() + limits.MASTER_RETRY
        time.sleep(limits.SIGNAL_POLL)
    return False
