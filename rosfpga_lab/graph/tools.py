"""What ``rosfpga-lab topic`` does, as functions: query the graph, format and parse messages.

The CLI modules stay thin and call these; notebooks can call them too.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rosfpga_lab.config.master import master_uri
from rosfpga_lab.graph.errors import GraphError, MasterError, XmlRpcTooLargeError
from rosfpga_lab.graph.limits import MAX_ARRAY_SHOWN, TOPIC_POLL
from rosfpga_lab.graph.rate import RateMeter  # noqa: F401  (rostopic hz's meter, re-exported)
from rosfpga_lab.graph.xmlrpc import call
from rosfpga_lab.msg.builtins import BUILTIN_TYPES, TIME_CLASS

TOOL_ID = "/rosfpga_lab_topic"


def pick_master_uri(explicit: str | None = None) -> str:
    """``explicit``, else ROS_MASTER_URI, else roscore's default (:func:`rosfpga_lab.config.master_uri`)."""
    return master_uri(explicit)


def master_call(uri: str, method: str, *args: Any) -> Any:
    """Call a Master API method as the topic tool; return the value.

    Raises:
        GraphError: the master cannot be reached (with a hint) or refused.
    """
    try:
        reply = call(uri, method, TOOL_ID, *args, timeout=5.0)
    except XmlRpcTooLargeError as exc:  # the master answered: it is not "unreachable"
        raise GraphError(f"the ROS master at {uri} answered {method}, but the reply is too large "
                         f"for this tool ({exc})") from None
    except GraphError as exc:
        raise GraphError(f"cannot reach the ROS master at {uri} ({exc}). Start one with "
                         "`rosfpga-lab master` (or roscore), or set ROS_MASTER_URI.") from None
    code, status, value = reply
    if code != 1:
        raise MasterError(f"master refused {method}: {status}", code, status)
    return value


def check_master(uri: str) -> None:
    """Make sure a master answers at ``uri`` before a tool starts a node against it.

    Raises:
        GraphError: nobody answers (the text says how to start a master).
    """
    master_call(uri, "getUri")


def topic_types(uri: str) -> dict[str, str]:
    """topic -> type as the master knows them."""
    return {t: ty for t, ty in master_call(uri, "getTopicTypes")}


def topic_type(uri: str, topic: str) -> str:
    """The type of ``topic``.

    Raises:
        GraphError: the master does not know the topic.
    """
    types = topic_types(uri)
    if topic not in types:
        raise GraphError(f"topic {topic} is unknown to the master at {uri} "
                         f"(known: {', '.join(sorted(types)) or 'none'})")
    return types[topic]


def wait_for_topic_type(uri: str, topic: str, timeout: float | None = None,
                        notice: Callable[[str], Any] | None = None) -> str | None:
    """The type of ``topic``, waiting until the master knows it (as ``rostopic echo`` does).

    Args:
        timeout: seconds to wait; None: for ever.
        notice: called once with a warning text when the topic is not known yet.

    Returns:
        The type, or None when ``timeout`` ran out first.

    Raises:
        GraphError: the master cannot be reached.
    """
    deadline = None if timeout is None else time.monotonic() + timeout
    warned = False
    while True:
        found = topic_types(uri).get(topic)
        if found is not None:
            return found
        if not warned and notice is not None:
            notice(f"WARNING: topic [{topic}] does not appear to be published yet")
            warned = True
        if deadline is not None and time.monotonic() >= deadline:
            return None
        time.sleep(TOPIC_POLL if deadline is None else
                   max(0.0, min(TOPIC_POLL, deadline - time.monotonic())))


def format_topic_list(uri: str, verbose: bool = False) -> str:
    """``rostopic list`` (``-v``) output."""
    pubs, subs, _ = master_call(uri, "getSystemState")
    if not verbose:
        return "\n".join(sorted({t for t, _ in pubs} | {t for t, _ in subs}))
    types = topic_types(uri)

    def section(title: str, entries: list, noun: str) -> list[str]:
        lines = [title]
        for t, nodes in sorted(entries):
            n = len(nodes)
            lines.append(f" * {t} [{types.get(t, '*')}] {n} {noun}{'s' if n != 1 else ''}")
        return lines

    return "\n".join(section("Published topics:", pubs, "publisher") + [""] +
                     section("Subscribed topics:", subs, "subscriber"))


def format_topic_info(uri: str, topic: str) -> str:
    """``rostopic info`` output: type, publishers and subscribers with their URIs."""
    ty = topic_type(uri, topic)
    pubs, subs, _ = master_call(uri, "getSystemState")

    def nodes_of(entries: list) -> list[str]:
        out = []
        for t, nodes in entries:
            if t == topic:
                for n in nodes:
                    try:
                        api = master_call(uri, "lookupNode", n)
                    except GraphError:
                        api = "unknown address"
                    out.append(f" * {n} ({api})")
        return out or [" None"]

    return "\n".join([f"Type: {ty}", "", "Publishers: ", *nodes_of(pubs), "",
                      "Subscribers: ", *nodes_of(subs), ""])


def format_message(value: Any, indent: int = 0, max_array: int = MAX_ARRAY_SHOWN) -> str:
    """Format a message dict as ``rostopic echo`` does (genpy's ``strify_message``: valid YAML,
    arrays of messages as block lists); arrays longer than ``max_array`` are summarised."""
    return _strify_fields(value, "  " * indent, max_array)


def _strify_fields(value: Any, indent: str, max_array: int) -> str:
    inner = "  " + indent
    return "\n".join(f"{indent}{key}: {_strify(v, inner, max_array)}" for key, v in value.items())


def _strify(v: Any, indent: str, max_array: int) -> str:
    """One value as genpy's strify_message writes it at ``indent``."""
    import yaml

    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, dict):
        return "\n" + _strify_fields(v, indent, max_array)
    if hasattr(v, "secs") and hasattr(v, "nsecs"):
        return f"\n{indent}secs: {v.secs}\n{indent}nsecs: {v.nsecs:9d}"
    if isinstance(v, str):
        return yaml.dump(v, default_style='"').rstrip("\n") if v else "''"
    if isinstance(v, (bool, int, float)):
        return str(v)
    if isinstance(v, (np.ndarray, list, tuple, bytes, bytearray, memoryview)):
        n = len(v)
        if n == 0:
            return "[]"
        if n > max_array:
            dtype = getattr(v, "dtype", type(v[0]).__name__)
            return f'"<array type: {dtype}, length: {n}>"'
        items = v.tolist() if isinstance(v, np.ndarray) else list(v)
        if isinstance(items[0], (bool, int, float)):
            return str(items)
        if isinstance(items[0], str):
            return "\n" + "\n".join(indent + line for line in
                                     yaml.dump(items).rstrip("\n").splitlines())
        deeper = indent + "  "
        return "\n" + "\n".join(f"{indent}- {_strify(x, deeper, max_array)}" for x in items)
    return str(v)


def parse_message_value(registry: Any, type_name: str, args: list[str]) -> dict[str, Any]:
    """Build a message from ``rostopic pub`` style arguments (genpy's ``fill_message_args``).

    One argument that is a YAML mapping (``"data: hi"`` or ``"{data: hi}"``) sets those
    fields; otherwise the arguments (each parsed as YAML) fill the top-level fields in order.
    Below the top, a mapping sets fields by name and a list fills a message's fields in order
    (``geometry_msgs/Twist '[0.1, 0, 0]' '[0, 0, 1]'``), also inside arrays of messages. A
    time field takes ``now`` or integer nanoseconds, a Header field ``auto`` (stamp now),
    as for rostopic. Fields not given keep their defaults.

    Raises:
        GraphError: YAML that does not parse, unknown fields, too many values, a wrong shape.
    """
    import yaml

    from rosfpga_lab.msg import Time, new_message

    value = new_message(registry, type_name)
    try:
        parsed = [yaml.safe_load(a) for a in args]
    except yaml.YAMLError as exc:
        raise GraphError(f"cannot parse the message arguments as YAML: {exc}") from None
    now = Time.from_sec(time.time())
    keys = {"now": now, "auto": {**new_message(registry, "std_msgs/Header"), "stamp": now}}
    _fill(registry, type_name, value, parsed[0] if len(parsed) == 1 and isinstance(parsed[0], dict)
          else parsed, type_name, keys)
    return value


def _fill(registry: Any, type_name: str, into: dict, given: Any, where: str,
          keys: dict[str, Any]) -> None:
    """Set the fields of ``into`` (a message of ``type_name``) from a mapping or a list."""
    spec = registry.get(type_name)
    fields = {f.name: f for f in spec.fields}
    if isinstance(given, dict):
        pairs = list(given.items())
    elif isinstance(given, (list, tuple)):
        if len(given) > len(spec.fields):
            raise GraphError(f"{where} has {len(spec.fields)} fields "
                             f"({', '.join(fields)}); got {len(given)} values")
        pairs = [(f.name, v) for f, v in zip(spec.fields, given)]
    else:
        raise GraphError(f"{where} is a {type_name} message: give a mapping or a list of its "
                         f"fields ({', '.join(fields)}), not {given!r}")
    for name, v in pairs:
        f = fields.get(name) if isinstance(name, str) else None
        if f is None:
            raise GraphError(f"{where} has no field {name!r} (fields: {', '.join(fields)})")
        at = f"{where}.{name}"
        v = "" if v is None else v
        if f.is_array and not f.is_builtin or f.is_array and f.base_type in TIME_CLASS:
            if not isinstance(v, (list, tuple)):
                raise GraphError(f"{at} is an array: give a list, not {v!r}")
            if f.array_length is not None and len(v) != f.array_length:
                raise GraphError(f"{at} has {f.array_length} elements; got {len(v)}")
            into[name] = [_element(registry, f.base_type, x, f"{at}[{i}]", keys)
                          for i, x in enumerate(v)]
        elif f.is_array:
            into[name] = v
        else:
            into[name] = _element(registry, f.base_type, v, at, keys, into[name])


def _element(registry: Any, base: str, v: Any, where: str, keys: dict[str, Any],
             current: Any = None) -> Any:
    """One value of type ``base``: a message filled from ``v`` (over ``current`` or defaults),
    a time from ``now``/nanoseconds, or ``v`` itself for a builtin."""
    from rosfpga_lab.msg import new_message

    if base in TIME_CLASS:
        if isinstance(v, str):
            if v not in keys or not hasattr(keys[v], "secs"):
                raise GraphError(f"{where} is a {base}: give now, integer nanoseconds or "
                                 f"{{secs: S, nsecs: N}}, not {v!r}")
            return TIME_CLASS[base](keys[v].secs, keys[v].nsecs)
        if isinstance(v, int) and not isinstance(v, bool):
            return TIME_CLASS[base](*divmod(v, 10**9))
        return v
    if base in BUILTIN_TYPES:
        return v
    if isinstance(v, str):
        if v not in keys or not isinstance(keys[v], dict) or registry.resolve(base) != "std_msgs/Header":
            raise GraphError(f"{where} is a {base} message: {v!r} is no key (rostopic's keys: "
                             "now for a time, auto for a Header)")
        return dict(keys[v])
    out = current if isinstance(current, dict) else new_message(registry, base)
    _fill(registry, base, out, v, where, keys)
    return out


def registry_from_header(type_name: str, header: dict[str, str]) -> Any:
    """A registry holding ``type_name`` as a publisher's connection header defines it (its
    ``message_definition``), checked against the header's ``md5sum``, as rostopic and rosbag
    decode types they have no package for.

    Raises:
        GraphError: the header has no definition, it does not parse, or its md5 differs.
    """
    from rosfpga_lab.msg import MsgError, MsgRegistry

    who = header.get("callerid", "the publisher")
    definition = header.get("message_definition", "")
    if not definition.strip():
        raise GraphError(f"{type_name} is not in the lab's registry and {who} sent no "
                         "message_definition; add its package with --msg-path DIR or use --hex")
    reg = MsgRegistry()
    try:
        reg.add_full_text(type_name, definition, f"message_definition from {who}")
        md5 = reg.md5(type_name)
    except MsgError as exc:
        raise GraphError(f"cannot use the message_definition of {type_name} sent by {who}: "
                         f"{exc}") from None
    if header.get("md5sum", md5) not in (md5, "*"):
        raise GraphError(f"the message_definition of {type_name} sent by {who} has md5 {md5}, "
                         f"but its header says {header['md5sum']}: not decoding")
    return reg
