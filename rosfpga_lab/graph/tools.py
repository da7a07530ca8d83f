"""What ``rosfpga-lab topic`` does, as functions: query the graph, format and parse messages.

The CLI modules stay thin and call these; notebooks can call them too.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rosfpga_lab.config.master import master_uri
from rosfpga_lab.graph.errors import GraphError, MasterError, XmlRpcTooLargeError
from rosfpga_lab.graph.limits import MAX_ARRAY_SHOWN, TOPIC_POLL
from rosfpga_lab.graph.rate import RateMeter  # noqa: F401  (rostopic hz's meter, re-exported)
from rosfpga_lab.graph.xmlrpc import call

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
    """Format a message dict like ``rostopic echo`` (YAML-ish); long arrays are summarised."""
    pad = "  " * indent
    lines: list[str] = []
    for key, v in value.items():
        if isinstance(v, dict):
            lines.append(f"{pad}{key}: ")
            lines.append(format_message(v, indent + 1, max_array))
        elif hasattr(v, "secs") and hasattr(v, "nsecs"):
            lines.append(f"{pad}{key}: ")
            lines.append(f"{pad}  secs: {v.secs}")
            lines.append(f"{pad}  nsecs: {v.nsecs:>9}")
        elif isinstance(v, (np.ndarray, list, tuple, bytes, bytearray, memoryview)):
            n = len(v)
            if n > max_array:
                dtype = getattr(v, "dtype", type(v[0]).__name__ if n else "?")
                lines.append(f"{pad}{key}: \"<array type: {dtype}, length: {n}>\"")
            elif n and isinstance(v[0], dict):
                lines.append(f"{pad}{key}: ")
                for item in v:
                    body = format_message(item, indent + 1, max_array).split("\n")
                    body[0] = f"{pad}  - " + body[0].lstrip()
                    lines.extend(body)
            else:
                items = [_scalar(x) for x in (list(v) if not isinstance(v, np.ndarray) else v.tolist())]
                lines.append(f"{pad}{key}: [{', '.join(items)}]")
        else:
            lines.append(f"{pad}{key}: {_scalar(v)}")
    return "\n".join(lines)


def _scalar(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"' if v else "''"
    if isinstance(v, bool):
        return "True" if v else "False"
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    return str(v)


def parse_message_value(registry: Any, type_name: str, args: list[str]) -> dict[str, Any]:
    """Build a message from ``rostopic pub`` style arguments.

    One argument that is a YAML mapping (``"data: hi"`` or ``"{data: hi}"``) sets those
    fields; otherwise the arguments (each parsed as YAML) fill the top-level fields in order.
    Unset fields keep their defaults.

    Raises:
        GraphError: YAML that does not parse, unknown fields, too many arguments.
    """
    import yaml

    from rosfpga_lab.msg import new_message

    value = new_message(registry, type_name)
    try:
        parsed = [yaml.safe_load(a) for a in args]
    except yaml.YAMLError as exc:
        raise GraphError(f"cannot parse the message arguments as YAML: {exc}") from None
    if len(parsed) == 1 and isinstance(parsed[0], dict):
        _merge(value, parsed[0], type_name)
        return value
    names = registry.get(type_name).field_names
    if len(parsed) > len(names):
        raise GraphError(f"{type_name} has {len(names)} fields ({', '.join(names)}); got {len(parsed)} values")
    for name, v in zip(names, parsed):
        if isinstance(value[name], dict) and isinstance(v, dict):
            _merge(value[name], v, f"{type_name}.{name}")
        else:
            value[name] = v
    return value


def _merge(into: dict, new: dict, where: str) -> None:
    for k, v in new.items():
        if k not in into:
            raise GraphError(f"{where} has no field {k!r} (fields: {', '.join(into)})")
        if isinstance(into[k], dict) and isinstance(v, dict):
            _merge(into[k], v, f"{where}.{k}")
        else:
            into[k] = v
