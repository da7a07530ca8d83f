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
    xs = {m[1]: float(m[0]) for m in re.findall(r'<text x="([\d.]+)" y="26" text-anchor="middle" font-weight="bold" font-size="11">([^<]+)<', svg)}
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
    # it opens on the first arrow's bytes (not on an empty viewer)
    assert d.selected is not None and d.pane.selected == 0 and d.bytes.total == len(EVENTS[0].raw) > 0
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


def test_trace_parties_are_named_retries_folded_and_the_diagram_fits() -> None:
    """One node is one lifeline whether the trace saw its name, its slave URI or its TCP address;
    retries fold into one arrow; many lifelines still fit a 1,000 px notebook."""
    from rosfpga_lab.graph.trace import TraceEvent
    from rosfpga_lab.widgets.sequence import FIT_WIDTH, events_from_trace

    uri = "http://127.0.0.1:40000/"
    items = [
        TraceEvent(1, 0.001, "xmlrpc", "/fpga", src="/cam", dst="/master", method="registerPublisher",
                   args=["/cam", "/image_raw", "sensor_msgs/Image", uri], t0=0.0),
        TraceEvent(2, 0.011, "xmlrpc", "/fpga", src="/fpga", dst=uri, method="requestTopic",
                   args=["/fpga", "/image_raw", [["TCPROS"]]], t0=0.01),
        TraceEvent(3, 0.021, "tcp_connect", "/fpga", src="/fpga", dst="127.0.0.1:5000", conn=7, t0=0.02),
        TraceEvent(4, 0.031, "tcpros_header", "/fpga", src="/fpga", dst="127.0.0.1:5000", conn=7,
                   args={"callerid": "/fpga", "topic": "/image_raw"}, t0=0.03),
        TraceEvent(5, 0.041, "tcpros_header", "/fpga", src="/cam", dst="/fpga", conn=7,
                   args={"callerid": "/cam", "topic": "/image_raw"}, t0=0.04),
    ] + [TraceEvent(6 + i, 0.05 + i / 100, "error", "/fpga", src="/fpga", dst="", t0=0.05 + i / 100,
                    result=f"{uri}: XML-RPC call requestTopic to {uri} failed: [Errno 111] Connection refused")
         for i in range(3)]   # a retried call to a vanished node: no peer but the URI in the text
    events = events_from_trace(items)
    parties = {e.src for e in events} | {e.dst for e in events}
    assert parties == {"/cam", "/master", "/fpga"}, parties
    errors = [e for e in events if e.kind == "error"]
    assert len(errors) == 1 and errors[0].label == "error: [Errno 111] Connection refused \u00d73"
    assert errors[0].dst == "/cam" and errors[0].detail.count("repeated") == 1
    assert len(events_from_trace(items, fold=False)) == len(events) + 2
    many = [SeqEvent(f"/node_{i}", f"/node_{i + 1}", "a rather long label for one arrow " * 2)
            for i in range(7)]  # 8 lifelines: columns narrow to fit (more: the SVG scales down)
    svg = sequence_svg(many)
    width = int(re.search(r'<svg [^>]*width="(\d+)"', svg)[1])
    assert width <= FIT_WIDTH + 100 and 'style="max-width:100%;height:auto"' in svg
    labels = re.findall(r'stroke-linejoin="round">([^<]*)</text>', svg)
    # two lines each (above and under the arrow); longer than two lines: the second is cut
    assert len(labels) == 14 and all(len(t) < 40 for t in labels), labels
    assert all(t.endswith("\u2026") for t in labels[1::2]), labels
    assert "a rather long label for one arrow a rather long label for one arrow" in svg  # whole in the tooltip


def test_cut_labels_keep_their_number_and_byte_count() -> None:
    """01 and 09 showed "10. TCPROS header /chatter [12…": the byte count was cut away."""
    events = [SeqEvent(f"/node_{i}", f"/node_{i + 1}", "TCPROS header /chatter callerid=/listener",
                       bytes(123), kind="tcpros_header") for i in range(7)]
    svg = sequence_svg(events)
    labels = re.findall(r'stroke-linejoin="round">([^<]*)</text>', svg)
    # issue 32: the text was still cut; it now goes on in a second line under the arrow
    assert len(labels) == 14
    for k in range(7):
        first, second = labels[2 * k], labels[2 * k + 1]
        assert first.startswith(f"{k + 1}. TCPROS") and second.endswith(" [123 B]"), (first, second)
        assert f"{first} {second}" == f"{k + 1}. TCPROS header /chatter callerid=/listener [123 B]"
    lines = re.findall(r'<text x="[\d.]+" y="([\d.]+)"[^>]*stroke-linejoin="round">', svg)
    assert float(lines[1]) - float(lines[0]) == 17            # the second under the arrow
    # the byte count is never split between the lines
    short = [SeqEvent("/a", "/b", "TCPROS header /chatter", bytes(128), kind="tcpros_header"),
             SeqEvent("/b", "/c", "x", bytes(1)), SeqEvent("/c", "/d", "x", bytes(1)),
             SeqEvent("/d", "/e", "x", bytes(1)), SeqEvent("/e", "/f", "x", bytes(1))]
    two = re.findall(r'stroke-linejoin="round">([^<]*)</text>', sequence_svg(short, col=110))
    assert "[128 B]" in " ".join(two) and not any(t.endswith("[128") for t in two), two
    # text longer than two lines keeps its number and byte count, the middle cut
    long = [SeqEvent(f"/node_{i}", f"/node_{i + 1}", "TCPROS header /chatter " * 6, bytes(99),
                     kind="tcpros_header") for i in range(7)]
    cut = re.findall(r'stroke-linejoin="round">([^<]*)</text>', sequence_svg(long))
    assert cut[0].startswith("1. TCPROS") and cut[1].endswith("\u2026 [99 B]"), cut[:2]


def test_a_packed_datagrams_arrows_each_carry_their_own_bytes() -> None:
    """11: a 692-byte datagram packing two senders' submessages was drawn as two arrows of
    692 B each; each now says its own submessages' bytes, the tooltip the datagram's."""
    events = [SeqEvent("camera", "component", "HEARTBEAT", bytes(692), kind="rtps", size=52),
              SeqEvent("viewer", "component", "ACKNACK", bytes(692), kind="rtps", size=620),
              SeqEvent("component", "viewer", "DATA", bytes(100), kind="rtps")]
    svg = sequence_svg(events)
    labels = re.findall(r'stroke-linejoin="round">([^<]*)</text>', svg)
    assert labels == ["1. HEARTBEAT [52 B]", "2. ACKNACK [620 B]", "3. DATA [100 B]"], labels
    assert "(52 of the datagram&#x27;s 692 bytes)" in svg or "(52 of the datagram's 692 bytes)" in svg
    assert "3. component \u2192 viewer: DATA (100 bytes)" in svg
