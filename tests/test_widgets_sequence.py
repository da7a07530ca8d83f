"""Sequence diagram: event order, participants, SVG arrows, byte fields per arrow, a real trace."""

from __future__ import annotations

import re
import struct
import threading
import time
import xmlrpc.client

import pytest

from rosfpga_lab.widgets import (
    SeqEvent,
    SequenceDiagram,
    WidgetError,
    events_from_trace,
    participants_of,
    sequence_html,
    sequence_svg,
)


def _request(method: str, *params: object) -> bytes:
    body = xmlrpc.client.dumps(params, method).encode()
    return b"POST /RPC2 HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % len(body) + body


HEADER = struct.pack("<I", 15) + struct.pack("<I", 11) + b"topic=/chat"
EVENTS = [
    SeqEvent("/pub", "/master", "registerPublisher", _request("registerPublisher", "/pub", "/chat"), 10.0, "xmlrpc"),
    SeqEvent("/sub", "/master", "registerSubscriber", _request("registerSubscriber", "/sub", "/chat"), 10.001, "xmlrpc"),
    SeqEvent("/sub", "/pub", "TCPROS header", HEADER, 10.002, "tcpros_header"),
    SeqEvent("/pub", "/pub", "note <&>", b"", 10.003),
]


def test_participants_master_first_then_appearance() -> None:
    assert participants_of(EVENTS) == ["/pub", "/master", "/sub"]
    assert participants_of(EVENTS, ["/master", "/nobody"]) == ["/master", "/pub", "/sub"]


def test_svg_has_one_numbered_clickable_arrow_per_event() -> None:
    svg = sequence_svg(EVENTS)
    assert svg.count("<g class=\"rfl-arrow") == 4
    assert re.findall(r'data-index="(\d+)"', svg) == ["0", "1", "2", "3"]
    assert "1. registerPublisher" in svg and "4. note &lt;&amp;&gt;" in svg and "note <&>" not in svg
    assert "+2.0 ms" in svg  # times relative to the first event
    # lifelines: master first, then the order of appearance
    xs = {m[1]: float(m[0]) for m in re.findall(r'<text x="([\d.]+)" y="26" text-anchor="middle" font-weight="bold">([^<]+)<', svg)}
    assert xs["/master"] < xs["/pub"] < xs["/sub"]
    with pytest.raises(WidgetError, match=r"\['/sub'\] appear in events"):
        sequence_svg(EVENTS, ["/pub", "/master"])


def test_event_bytes_get_fields_by_kind() -> None:
    spans = EVENTS[2].byte_spans()
    assert [(s.path, s.offset, s.size) for s in spans] == [("header length", 0, 4), ("topic.length", 4, 4), ("topic", 8, 11)]
    http = EVENTS[0].byte_spans()
    assert http[0].path == "request line" and any(s.path == "methodName" and s.value == "registerPublisher" for s in http)
    explicit = SeqEvent("a", "b", "x", b"\x01\x02", spans=[(0, 2, "both")])
    assert [s.path for s in explicit.byte_spans()] == ["both"]


def test_static_html_lists_every_arrow_with_its_bytes() -> None:
    html = sequence_html(EVENTS)
    assert "<script" not in html and html.count("<details>") == 3  # the note has no bytes
    assert "topic=/chat" not in html.split("<table")[0]  # the SVG itself does not dump bytes
    assert "19: 0f 00 00 00 0b 00 00 00 74 6f 70 69 \u2026" in html.replace("&hellip;", "\u2026")


def test_widget_selection_shows_the_arrow_bytes() -> None:
    d = SequenceDiagram([e.__dict__ for e in EVENTS])  # dicts work too
    assert d.selected is None and d.bytes.total == 0
    d.pane.selected = 2  # as a click in the browser would
    assert d.selected is EVENTS[2] or d.selected.label == "TCPROS header"
    assert d.list.value == 2 and d.bytes.total == len(HEADER)
    assert [f["path"] for f in d.bytes.fields] == ["header length", "topic.length", "topic"]
    d.list.value = 0  # choosing from the list does the same
    assert d.pane.selected == 0 and d.bytes.title.startswith("1. /pub \u2192 /master: registerPublisher")
    with pytest.raises(WidgetError, match="arrow 9 does not exist"):
        d.select(9)
    data, _ = d._repr_mimebundle_()
    assert "text/html" in data and "application/vnd.jupyter.widget-view+json" in data


def test_a_real_conversation_from_the_graph_layer() -> None:
    """Figure 2 from a real run on loopback: master, publisher, subscriber, TCPROS, messages."""
    from rosfpga_lab.graph import EmbeddedMaster, Node, Trace

    trace = Trace()
    got = threading.Event()
    with EmbeddedMaster(port=0, trace=trace) as master:
        talker = Node("/talker", master=master, trace=trace)
        listener = Node("/listener", master=master, trace=trace)
        try:
            listener.subscribe("/chatter", "std_msgs/String", lambda *_: got.set())
            pub = talker.advertise("/chatter", "std_msgs/String")
            pub.wait_for_subscribers()
            for i in range(4):
                pub.publish({"data": f"hello {i}"})
            assert got.wait(10)
            time.sleep(0.1)
        finally:
            talker.shutdown()
            listener.shutdown()
    events = events_from_trace(trace, frames_per_connection=2)
    labels = [e.label for e in events]
    for step in ("registerSubscriber", "registerPublisher", "publisherUpdate", "requestTopic"):
        assert step in labels, labels
    headers = [e for e in events if e.kind == "tcpros_header"]
    assert [(e.src, e.dst) for e in headers[:2]] == [("/listener", "/talker"), ("/talker", "/listener")]
    frames = [e for e in events if e.kind == "tcpros_frame"]
    assert [e.label for e in frames[:2]] == ["message #0 (15 B)", "message #1 (15 B)"]
    assert any("more messages" in e.label for e in frames)
    body = struct.pack("<I", 7) + b"hello 0"  # std_msgs/String by hand
    assert frames[0].raw == struct.pack("<I", len(body)) + body
    assert [(s.path, s.role) for s in frames[0].byte_spans()] == [
        ("frame length", "length"), ("data", "length"), ("data", "value")]
    diagram = SequenceDiagram(trace)
    assert diagram.participants[0] == "/master"
    reg = next(i for i, e in enumerate(diagram.events) if e.label == "registerPublisher")
    diagram.select(reg)
    assert any(f["path"] == "methodName" for f in diagram.bytes.fields)
