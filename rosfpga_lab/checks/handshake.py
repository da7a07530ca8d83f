"""Checks of notebook 1 (STEP 1a): the XML-RPC handshake between master, publisher, subscriber.

The expected call order is the ROS 1 protocol itself (ROS wiki, Master and Slave APIs), written
out here, not taken from a recorded run.
"""

from __future__ import annotations

from typing import Any
from urllib.parse import urlsplit

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type

#: Exercise 1.1: the listener subscribes first, then the talker advertises.
SUBSCRIBER_FIRST_CALLS: tuple[tuple[str, str, str], ...] = (
    ("/listener", "/master", "registerSubscriber"),
    ("/talker", "/master", "registerPublisher"),
    ("/master", "/listener", "publisherUpdate"),
    ("/listener", "/talker", "requestTopic"),
)
#: Who calls whom for each method (used to explain a wrong entry).
CALL_RULES = {
    "registerSubscriber": ("/listener", "/master", "a node registers its subscription with the master"),
    "registerPublisher": ("/talker", "/master", "a node registers its publication with the master"),
    "publisherUpdate": ("/master", "/listener", "the master tells each subscriber's slave API "
                        "the new list of publishers"),
    "requestTopic": ("/listener", "/talker", "the subscriber asks the publisher's slave API "
                     "(not the master) for a TCPROS port"),
}


def check_call_order(calls: Any) -> CheckResult:
    """Exercise 1.1: the XML-RPC calls that connect /listener (subscribed first) to /talker.

    Args:
        calls: a list of ``(caller, callee, method)`` tuples, in order.

    Raises:
        ExerciseError: a call is missing, extra, misdirected or out of order.
    """
    ex = "1.1 (who calls whom)"
    require_type(ex, "calls", calls, (list, tuple))
    got = []
    for i, c in enumerate(calls):
        if not (isinstance(c, (list, tuple)) and len(c) == 3 and all(isinstance(x, str) for x in c)):
            raise fail(ex, f"entry {i} is {c!r}: each entry is a (caller, callee, method) tuple of "
                           "strings, e.g. ('/talker', '/master', 'registerPublisher')")
        got.append(tuple(c))
    problems = []
    methods = [c[2] for c in got]
    for method in CALL_RULES:
        if method not in methods:
            src, dst, why = CALL_RULES[method]
            problems.append(f"{method} is missing ({src} -> {dst}: {why})")
    for i, (src, dst, method) in enumerate(got):
        if method not in CALL_RULES:
            problems.append(f"entry {i}: {method!r} is not one of the calls that connect the two "
                            f"nodes here ({', '.join(CALL_RULES)})")
            continue
        want_src, want_dst, why = CALL_RULES[method]
        if (src, dst) != (want_src, want_dst):
            problems.append(f"entry {i}: {method} goes {want_src} -> {want_dst}, you wrote "
                            f"{src} -> {dst} ({why})")
    if not problems:
        for i, (want, have) in enumerate(zip(SUBSCRIBER_FIRST_CALLS, got)):
            if want != have:
                problems.append(f"entry {i} is {have[2]}, expected {want[2]} at this point: "
                                + _order_hint(want[2]))
                break
        if len(got) != len(SUBSCRIBER_FIRST_CALLS) and not problems:
            problems.append(f"{len(got)} calls listed, {len(SUBSCRIBER_FIRST_CALLS)} expected "
                            "(list each call once)")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, ["registerSubscriber, registerPublisher, publisherUpdate, requestTopic: "
                            "the master only introduces the nodes; the data path is set up "
                            "between the two nodes"])


def _order_hint(method: str) -> str:
    return {
        "registerSubscriber": "the listener subscribed before the talker existed",
        "registerPublisher": "the talker advertises after the listener subscribed",
        "publisherUpdate": "the master can only tell the listener about the talker after the "
                           "talker registered",
        "requestTopic": "the listener asks the talker for a port once it knows the talker's URI",
    }[method]


def check_talker_contact(talker_uri: Any, tcpros_port: Any, *, talker: Any,
                         master_uri: str | None = None) -> CheckResult:
    """Exercise 1.2: the talker's XML-RPC URI (lookupNode) and TCPROS port (requestTopic).

    Args:
        talker_uri: the reader's answer for the talker's slave API URI.
        tcpros_port: the reader's answer for its TCPROS port.
        talker: the talker :class:`rosfpga_lab.graph.Node` (holds the right answers).
        master_uri: the master's URI (to recognise it as a wrong answer).

    Raises:
        ExerciseError: a wrong URI or port, or a wrong type.
    """
    ex = "1.2 (lookupNode and requestTopic)"
    require_answer(ex, "talker_uri", talker_uri)
    require_answer(ex, "tcpros_port", tcpros_port)
    problems = []
    if isinstance(talker_uri, (list, tuple)) and len(talker_uri) == 3:
        problems.append("talker_uri is a whole [code, statusMessage, value] reply: take its value "
                        "(index 2)")
    elif not isinstance(talker_uri, str):
        problems.append(f"talker_uri should be a str like 'http://127.0.0.1:PORT/', you gave "
                        f"{type(talker_uri).__name__}")
    elif talker_uri.rstrip("/") != talker.uri.rstrip("/"):
        if master_uri and talker_uri.rstrip("/") == master_uri.rstrip("/"):
            problems.append("talker_uri is the master's URI: ask the master lookupNode('/talker')")
        else:
            problems.append(f"talker_uri {talker_uri!r} is not /talker's slave API URI")
    if isinstance(tcpros_port, (list, tuple)):
        problems.append("tcpros_port is a list: requestTopic's value is ['TCPROS', host, port]; "
                        "take the port (index 2)")
    elif isinstance(tcpros_port, str):
        problems.append(f"tcpros_port is the str {tcpros_port!r}: give an int")
    elif isinstance(tcpros_port, bool) or not isinstance(tcpros_port, int):
        problems.append(f"tcpros_port should be an int, you gave {type(tcpros_port).__name__}")
    elif tcpros_port != talker.tcpros_port:
        xmlrpc_port = urlsplit(talker.uri).port
        if tcpros_port == xmlrpc_port:
            problems.append(f"tcpros_port {tcpros_port} is the port of the talker's XML-RPC server "
                            "(from its URI); the TCPROS port is what requestTopic answers")
        elif master_uri and tcpros_port == urlsplit(master_uri).port:
            problems.append(f"tcpros_port {tcpros_port} is the master's port")
        else:
            problems.append(f"tcpros_port {tcpros_port} is not the port /talker serves TCPROS on")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"/talker: slave API at {talker.uri}, TCPROS on port {talker.tcpros_port}",
                            "two different servers: XML-RPC for negotiation, TCPROS for data"])


def check_http_body(raw: bytes, body_start: Any, content_length: Any) -> CheckResult:
    """Exercise 1.3: where the XML body of a raw HTTP request starts, and how long it is.

    Args:
        raw: the whole HTTP request (head and body) as recorded.
        body_start: the reader's offset of the body's first byte.
        content_length: the reader's value of the Content-Length header.

    Raises:
        ExerciseError: a wrong offset or length (with the likely slip).
    """
    ex = "1.3 (HTTP head and body)"
    require_type(ex, "body_start", body_start, int)
    require_type(ex, "content_length", content_length, int)
    raw = bytes(raw)
    blank = raw.find(b"\r\n\r\n")
    if blank < 0:
        raise fail(ex, "raw is not an HTTP message (no blank line after the head); use the "
                       "recorded request, e.g. reg_pub.raw")
    start = blank + 4
    length = len(raw) - start
    problems = []
    if body_start != start:
        if body_start == blank:
            problems.append(f"body_start {body_start} points at the blank line (\\r\\n\\r\\n); the "
                            "body starts 4 bytes later")
        elif body_start == blank + 2:
            problems.append(f"body_start {body_start} is off by 2: the head ends with \\r\\n\\r\\n "
                            "(4 bytes)")
        elif 0 <= body_start < len(raw):
            problems.append(f"body_start {body_start} is byte {raw[body_start:body_start + 12]!r}...,"
                            f" expected {start} where {raw[start:start + 12]!r}... begins")
        else:
            problems.append(f"body_start {body_start} is outside the {len(raw)} bytes")
    if content_length != length:
        if content_length == len(raw):
            problems.append(f"content_length {content_length} is the whole request; Content-Length "
                            "counts only the body")
        elif content_length == len(raw) - body_start:
            problems.append(f"content_length {content_length} follows from your body_start; fix "
                            "that first")
        else:
            problems.append(f"content_length {content_length}, expected {length} (read the "
                            "Content-Length header, or count len(raw) - body_start)")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"head: bytes 0..{start - 1}, body: {length} bytes of XML from byte {start}"])

