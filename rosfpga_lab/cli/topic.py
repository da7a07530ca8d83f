"""``rosfpga-lab topic``: list, info, echo, pub and hz, like ``rostopic``."""

from __future__ import annotations

import argparse
import sys
import threading
import time

from rosfpga_lab.config.limits import DEFAULT_MASTER_URI


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``topic`` sub-command and its actions."""
    p = subparsers.add_parser(
        "topic", help="inspect and use ROS topics (like rostopic)",
        description="Inspect and use topics of a running ROS graph (the lab's or real ROS). "
        f"The master is --master-uri, else ROS_MASTER_URI, else {DEFAULT_MASTER_URI}; when "
        "none answers there the command stops with an error (it never starts a master of its "
        "own: start one with `rosfpga-lab master` or roscore).")
    p.add_argument("--master-uri", help="master to talk to (default: ROS_MASTER_URI or "
                   f"{DEFAULT_MASTER_URI})")
    p.add_argument("--msg-path", action="append", metavar="DIR", default=[],
                   help="folder of PKG/msg/NAME.msg packages (repeatable): your own types")
    sub = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    ls = sub.add_parser("list", help="list topics", description="List the topics the master knows.")
    ls.add_argument("-v", "--verbose", action="store_true", help="show types and counts")
    info = sub.add_parser("info", help="type, publishers, subscribers",
                          description="Show a topic's type, publishers and subscribers.")
    info.add_argument("topic", help="topic name, e.g. /chatter")
    echo = sub.add_parser("echo", help="print messages",
                          description="Print the messages published on a topic. A topic not "
                          "published yet: warn and wait for it, as rostopic does.")
    echo.add_argument("topic", help="topic name")
    echo.add_argument("-n", type=int, default=0, help="exit after N messages (default: forever)")
    echo.add_argument("--hex", action="store_true", help="print the raw body bytes in hex instead")
    echo.add_argument("--timeout", type=float, default=0.0,
                      help="give up after this many seconds, waiting included (default: never)")
    pub = sub.add_parser("pub", help="publish a message",
                         description="Publish a message, e.g.: topic pub /chatter std_msgs/String "
                         "'data: hello'. Arguments are YAML: one mapping, or field values in order.")
    pub.add_argument("topic", help="topic name")
    pub.add_argument("type", help="message type, e.g. std_msgs/String")
    pub.add_argument("values", nargs="*", help="YAML mapping or field values")
    pub.add_argument("-r", "--rate", type=float, default=0.0, help="publish at this rate (Hz)")
    pub.add_argument("-1", "--once", action="store_true", help="publish once, wait 3 s, exit")
    pub.add_argument("-l", "--latch", action="store_true", help="latch the message")
    pub.add_argument("-n", "--count", type=int, default=0, help="with --rate: stop after N messages")
    hz = sub.add_parser("hz", help="measure the publishing rate",
                        description="Print the rate at which messages arrive on a topic.")
    hz.add_argument("topic", help="topic name")
    hz.add_argument("-w", "--window", type=int, default=1000, help="window size in messages")
    hz.add_argument("--duration", type=float, default=0.0,
                    help="stop after this many seconds (default: Ctrl-C)")
    p.set_defaults(func=run)


def _node(uri: str, kind: str, msg_path: list[str] | None = None):
    from rosfpga_lab.graph import Node
    from rosfpga_lab.msg import registry_with

    return Node(f"/rosfpga_lab_topic_{kind}_{int(time.time() * 1000) % 10**8}", master_uri=uri,
                registry=registry_with(msg_path or []))


def run(args: argparse.Namespace) -> int:
    """Dispatch the action."""
    from rosfpga_lab.graph import resolve, tools

    uri = tools.pick_master_uri(args.master_uri)
    tools.check_master(uri)  # never end up alone: a clear error when no master answers
    if getattr(args, "topic", None):
        args.topic = resolve(args.topic)  # "chatter" means /chatter, as for rostopic
    if args.action == "list":
        print(tools.format_topic_list(uri, args.verbose))
        return 0
    if args.action == "info":
        print(tools.format_topic_info(uri, args.topic))
        return 0
    if args.action == "echo":
        return _echo(args, uri)
    if args.action == "pub":
        return _pub(args, uri)
    return _hz(args, uri)


def _stopped_remotely(node) -> bool:
    """True (after printing its reason) when something other than this tool shut the node down
    (a slave-API ``shutdown``, as rostopic prints it)."""
    if node.is_shutdown:
        print(f"shutdown request: {node.shutdown_reason}", file=sys.stderr, flush=True)
        return True
    return False


def _echo(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import GraphError, tools

    start = time.monotonic()
    try:
        type_name = tools.wait_for_topic_type(
            uri, args.topic, args.timeout or None,
            notice=lambda text: print(text, file=sys.stderr, flush=True))
    except KeyboardInterrupt:
        return 1
    if type_name is None:
        print(f"topic echo: {args.topic} was not published within {args.timeout} s",
              file=sys.stderr)
        return 1
    node = _node(uri, "echo", args.msg_path)
    done = threading.Event()
    count = [0]

    def show(body, info) -> None:
        if done.is_set():
            return
        if args.hex:
            print(bytes(body).hex(), flush=True)
        else:
            from rosfpga_lab.msg import deserialize

            print(tools.format_message(deserialize(node.registry, type_name, body)), flush=True)
        print("---", flush=True)
        count[0] += 1
        if args.n and count[0] >= args.n:
            done.set()

    try:
        known = type_name in node.registry.types() if hasattr(node.registry, "types") else True
        if not known and not args.hex:
            raise GraphError(f"type {type_name} is not in the lab's registry; use --hex to see "
                             "the raw bytes")
        node.subscribe(args.topic, type_name if known else "*", show, raw=True, queue_size=100,
                       md5sum=None if known else "*")
        end = start + args.timeout if args.timeout else None
        while not done.is_set() and not _stopped_remotely(node):
            if end is not None and time.monotonic() >= end:
                break
            done.wait(0.1)
    except KeyboardInterrupt:
        pass
    finally:
        node.shutdown()
    return 0 if (not args.n or count[0] >= args.n) else 1


def _pub(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import tools

    node = _node(uri, "pub", args.msg_path)
    try:
        value = tools.parse_message_value(node.registry, args.type, args.values)
        pub = node.advertise(args.topic, args.type, latch=args.latch or args.once or not args.rate)
        if args.rate > 0:
            print(f"publishing to {args.topic} at {args.rate} Hz (Ctrl-C to stop)", file=sys.stderr)
            n = 0
            while not args.count or n < args.count:
                pub.publish(value)
                n += 1
                if node.wait_for_shutdown(1.0 / args.rate):
                    _stopped_remotely(node)
                    break
        else:
            pub.publish(value)
            print(f"publishing and latching message{' for 3.0 seconds' if args.once else '. Press ctrl-C to terminate'}",
                  file=sys.stderr)
            if node.wait_for_shutdown(3.0 if args.once else None):
                _stopped_remotely(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.shutdown()
    return 0


def _hz(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import tools

    meter = tools.RateMeter(samples=args.window + 1)  # the last N intervals, as rostopic hz -w N
    node = _node(uri, "hz")
    try:
        node.subscribe(args.topic, "*", lambda body, info: meter.tick(), raw=True, queue_size=0,
                       md5sum="*")
        print(f"subscribed to [{args.topic}]", flush=True)
        start = time.monotonic()
        while not args.duration or time.monotonic() - start < args.duration:
            if node.wait_for_shutdown(1.0):
                _stopped_remotely(node)
                break
            report = meter.report()
            print(report if report else "no new messages", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        node.shutdown()
    return 0
