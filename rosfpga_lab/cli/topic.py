"""``rosfpga-lab topic``: list, info, echo, pub and hz, like ``rostopic``.

It never starts a master (see the parser's description). As rostopic's: ``echo`` of a topic not
published yet warns and waits (``--timeout`` bounds it) and prints genpy's YAML, decoding a type
the lab ships no definition for from the publisher's ``message_definition`` (md5 checked; or
``--msg-path DIR``), says how many messages it dropped when printing fell behind
(``--queue-size``), and ``--bag FILE`` records a ROS 1 bag (``rosfpga_lab.msg.bag``); ``hz``
prints "no new messages" when none arrived since its last line; ``pub`` takes rostopic's forms
(partial messages inside arrays, positional values, ``stamp: now``, ``header: auto``); a slave-API
``shutdown`` from another node ends ``echo``, ``hz`` and ``pub`` with its reason. A master reply
over ``graph.limits.MAX_XMLRPC_REPLY`` is reported with its size, never as "cannot reach the ROS
master".
"""

from __future__ import annotations

import argparse
import sys
import threading
import time

from rosfpga_lab.cli._signals import holding
from rosfpga_lab.config.limits import DEFAULT_MASTER_URI, ECHO_QUEUE


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
                   help="also load message types from PKG/msg/NAME.msg files under DIR (repeatable)")
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
    echo.add_argument("--queue-size", type=int, default=ECHO_QUEUE, metavar="N",
                      help="messages kept while printing falls behind; older ones are dropped and "
                      f"counted (default: {ECHO_QUEUE}; 0: no limit)")
    echo.add_argument("--bag", metavar="FILE", help="also record the messages to a new ROS 1 bag "
                      "(rosbag info/play read it)")
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
    p.set_defaults(func=run, ros_node=True)


def _node(uri: str, kind: str, args: argparse.Namespace | None = None):
    from rosfpga_lab.graph import Node
    from rosfpga_lab.msg import registry_with

    from rosfpga_lab.graph.names import anonymous_name

    name, host = getattr(args, "identity", None) or (
        anonymous_name(f"/rosfpga_lab_topic_{kind}"), None)
    return Node(name, master_uri=uri, host=host,
                registry=registry_with(getattr(args, "msg_path", None) or []))


def run(args: argparse.Namespace) -> int:
    """Dispatch the action; SIGINT and SIGTERM stop it cleanly (unregistered) whatever
    disposition it inherited."""
    from rosfpga_lab.cli._signals import StopSignals

    with StopSignals():
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    from rosfpga_lab.config.rosargs import RosArgs, advertise_host, node_name, remap
    from rosfpga_lab.graph import tools
    from rosfpga_lab.graph.names import anonymous_name

    ros = getattr(args, "ros", None) or RosArgs()
    uri = tools.pick_master_uri(args.master_uri or ros.special.get("__master"))
    tools.check_master(uri)  # never end up alone: a clear error when no master answers
    # rostopic's own node: anonymous, in ROS_NAMESPACE (or __ns), unless __name gives one
    name = node_name(anonymous_name(f"rosfpga_lab_topic_{args.action}"), ros)
    args.identity = (name, advertise_host(ros, None).host)
    if getattr(args, "topic", None):
        # "chatter" means /chatter (or /NS/chatter under ROS_NAMESPACE), then remapped, as for rostopic
        args.topic = remap(args.topic, name, ros)
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


# long: the callback ``show`` and the waiting loop share the echo's
# state (the bag, decoders per publisher header, counts, the failure); a class would only move it.
def _echo(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import GraphError, tools
    from rosfpga_lab.msg import MsgError, deserialize
    from rosfpga_lab.msg.bag import BagWriter

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
    bag = BagWriter(args.bag) if args.bag else None  # before the node: a refusal leaves nothing
    node = _node(uri, "echo", args)
    done = threading.Event()
    count = [0]
    timed_out = False
    failed: list[str] = []
    known = type_name in node.registry
    decoders: dict[tuple[str, str], object] = {}  # (md5, definition) -> registry from a header

    def show(body, info) -> None:
        if done.is_set():
            return
        try:
            if bag is not None:
                ty = info.header.get("type", type_name)
                md5 = info.header.get("md5sum") or node.registry.md5(ty)
                definition = info.header.get("message_definition") or node.registry.full_text(ty)
                bag.write(args.topic, ty, md5, definition, time.time_ns(), body, info.publisher)
            if args.hex:
                print(bytes(body).hex(), flush=True)
            else:
                reg = node.registry
                if not known:
                    key = (info.header.get("md5sum", ""), info.header.get("message_definition", ""))
                    if key not in decoders:
                        decoders[key] = tools.registry_from_header(type_name, info.header)
                    reg = decoders[key]
                print(tools.format_message(deserialize(reg, type_name, body)), flush=True)
        except (GraphError, MsgError) as exc:
            failed.append(str(exc))
            done.set()
            return
        print("---", flush=True)
        count[0] += 1
        if args.n and count[0] >= args.n:
            done.set()

    reported, last_report = 0, time.monotonic()
    sub = None
    try:
        with holding():   # registering: a signal waits for its end (then interrupts)
            sub = node.subscribe(args.topic, type_name if known else "*", show, raw=True,
                                 queue_size=args.queue_size, md5sum=None if known else "*")
        end = start + args.timeout if args.timeout else None
        while not done.is_set() and not _stopped_remotely(node):
            if end is not None and time.monotonic() >= end:
                timed_out = True
                break
            done.wait(0.1)
            if time.monotonic() - last_report >= 1.0:  # at most a line a second
                reported, last_report = _report_drops(sub, args.queue_size, reported), time.monotonic()
    except KeyboardInterrupt:
        pass
    finally:
        with holding(deliver=False):   # a signal now must not cut the unregistering short
            node.shutdown()
        if bag is not None:
            bag.close()
            print(f"topic echo: recorded {bag.count} messages to {args.bag}", file=sys.stderr)
    if sub is not None:
        _report_drops(sub, args.queue_size, reported, final=True)
    if timed_out and args.n:
        print(f"topic echo: timed out after {args.timeout:g} s: {count[0]} of {args.n} "
              f"message(s) arrived on {args.topic}", file=sys.stderr)
    if failed:
        print(f"topic echo: {failed[0]}", file=sys.stderr)
        return 1
    return 0 if (not args.n or count[0] >= args.n) else 1


def _report_drops(sub, queue_size: int, reported: int, final: bool = False) -> int:
    """Say on stderr how many messages were dropped since the last report; return the total."""
    stats = sub.stats
    if stats.drops > reported or final and stats.drops:
        print(f"topic echo: {stats.drops} of {stats.frames} messages dropped "
              f"{'in all' if final else 'so far'}: printing fell behind and the queue of {queue_size} "
              "was full (a larger --queue-size keeps more; 0: no limit)", file=sys.stderr, flush=True)
    return stats.drops


def _pub(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import GraphError, tools

    node = _node(uri, "pub", args)
    try:
        value = tools.parse_message_value(node.registry, args.type, args.values)
        with holding():   # registering: a signal waits for its end (then interrupts)
            pub = node.advertise(args.topic, args.type,
                                 latch=args.latch or args.once or not args.rate)
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
    except GraphError:
        # a slave-API shutdown between advertise and publish closed the publisher: the node was
        # stopped remotely, as when it comes while waiting (was "publisher ... is closed", exit 1)
        if not _stopped_remotely(node):
            raise
    finally:
        with holding(deliver=False):   # a signal now must not cut the unregistering short
            node.shutdown()
    return 0


def _hz(args: argparse.Namespace, uri: str) -> int:
    from rosfpga_lab.graph import tools

    meter = tools.RateMeter(samples=args.window + 1)  # the last N intervals, as rostopic hz -w N
    node = _node(uri, "hz", args)
    try:
        with holding():   # registering: a signal waits for its end (then interrupts)
            node.subscribe(args.topic, "*", lambda body, info: meter.tick(), raw=True,
                           queue_size=0, md5sum="*")
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
        with holding(deliver=False):   # a signal now must not cut the unregistering short
            node.shutdown()
    return 0
