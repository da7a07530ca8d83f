"""``rosfpga-lab master``: run the lab's embedded ROS master (like ``roscore``'s master)."""

from __future__ import annotations

import argparse
import sys
import threading
import warnings

from rosfpga_lab.config.limits import DEFAULT_MASTER_PORT


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``master`` sub-command."""
    p = subparsers.add_parser(
        "master", help="run a ROS master + parameter server (like roscore)",
        description="Run the lab's embedded ROS 1 master and parameter server. Real rospy, "
        "roscpp and rostopic work with it: export the ROS_MASTER_URI it prints. It binds "
        "127.0.0.1 unless --host says otherwise; ROS 1 has no authentication, so binding to "
        "a network interface lets anyone on that network control your nodes.")
    p.add_argument("--port", type=_port, default=DEFAULT_MASTER_PORT,
                   help=f"TCP port, 0 for any free one (default: {DEFAULT_MASTER_PORT}, roscore's)")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to bind and advertise (default: 127.0.0.1; 0.0.0.0 = every "
                   "interface, with a warning)")
    p.add_argument("--trace", action="store_true",
                   help="print every XML-RPC call the master serves")
    p.set_defaults(func=run)


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not a TCP port (0..65535)")
    return port


def run(args: argparse.Namespace) -> int:
    """Serve until Ctrl-C."""
    from rosfpga_lab.graph import EmbeddedMaster, OpenBindWarning, XmlRpcError

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OpenBindWarning)
        master = EmbeddedMaster(host=args.host, port=args.port)
        try:
            master.start()
        except XmlRpcError as exc:
            raise XmlRpcError(f"{exc} (is a roscore or another `rosfpga-lab master` already "
                              "running there? pick another --port)") from None
    for w in caught:
        print(f"rosfpga-lab master: warning: {w.message}", file=sys.stderr)
    print(f"ROS master running; export ROS_MASTER_URI={master.uri}", flush=True)
    stop = threading.Event()
    last_seq = -1
    try:
        while not stop.wait(0.2):
            if args.trace:
                for ev in master.trace.events:
                    if ev.seq <= last_seq:
                        continue
                    last_seq = ev.seq
                    if ev.role == "server":
                        code = ev.result[0] if isinstance(ev.result, list) and ev.result else ev.result
                        print(f"{ev.src} -> {ev.method}{tuple(ev.args[1:]) if ev.args else ()} = {code}",
                              flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        master.stop()
    return 0
