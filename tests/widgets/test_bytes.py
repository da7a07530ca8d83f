"""Byte viewer: span lookup, colours, paging, selection state, static HTML, adapters."""

from __future__ import annotations

import html
import re
import struct
import xmlrpc.client

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.errors import LabError
from rosfpga_lab.widgets import (
    ByteMap,
    ByteViewer,
    Span,
    WidgetError,
    as_span,
    message_spans,
    message_viewer,
    spans_for,
    spans_from_connection_header,
    spans_from_frame,
    spans_from_http,
    spans_from_tcpros_stream,
)
from rosfpga_lab.widgets._common import PALETTE, ROLE_COLOURS

# std_msgs/Header-like prefix written by hand: seq=7, secs=1, nsecs=2, frame_id="ab"
HEADER = struct.pack("<IIII", 7, 1, 2, 2) + b"ab"
HEADER_SPANS = [
    (0, 4, "header.seq", "uint32", 7),
    (4, 4, "header.stamp.secs", "uint32", 1),
    (8, 4, "header.stamp.nsecs", "uint32", 2),
    (12, 4, "header.frame_id", "uint32", 2, "length"),
    (16, 2, "header.frame_id", "string", "ab"),
]


def test_as_span_accepts_tuples_dicts_and_objects() -> None:
    class Obj:
        offset, size, label, type, value, role = 3, 2, "x", "int16", -1, ""

    assert as_span((1, 2, "a")) == Span(1, 2, "a")
    assert as_span({"offset": 1, "size": 2, "name": "b", "type": "t"}) == Span(1, 2, "b", "t")
    assert as_span(Obj()) == Span(3, 2, "x", "int16", -1, "")
    assert as_span({"offset": 0, "size": 1, "path": ("a", "b")}).path == "a.b"
    with pytest.raises(WidgetError, match="needs offset, size and path"):
        as_span({"offset": 1})


def test_span_at_and_uncovered_bytes() -> None:
    bm = ByteMap(HEADER + b"\xff", HEADER_SPANS)
    assert [bm.span_at(i) for i in range(19)] == [0] * 4 + [1] * 4 + [2] * 4 + [3] * 4 + [4] * 2 + [None]
    assert bm.span_at(-1) is None and bm.span_at(19) is None


def test_spans_outside_or_overlapping_are_refused_with_names() -> None:
    with pytest.raises(WidgetError, match=r"'b'.*outside the 4 data bytes"):
        ByteMap(b"\0" * 4, [(0, 2, "a"), (2, 3, "b")])
    with pytest.raises(WidgetError, match=r"'a' \(bytes 0\.\.2\) and 'b' \(from byte 2\) overlap"):
        ByteMap(b"\0" * 4, [(0, 3, "a"), (2, 2, "b")])
    assert issubclass(WidgetError, LabError)


def test_find_prefers_value_over_length_prefix_and_suggests_names() -> None:
    bm = ByteMap(HEADER, HEADER_SPANS)
    assert bm.find("header.frame_id") == 4
    assert bm.find("header.seq") == 0
    with pytest.raises(WidgetError, match="did you mean header.seq"):
        bm.find("header.sq")


def test_colours_role_fixed_and_adjacent_fields_differ() -> None:
    bm = ByteMap(HEADER, HEADER_SPANS)
    assert bm.colour(3) == ROLE_COLOURS["length"]
    assert [bm.colour(i) for i in (0, 1, 2, 4)] == [PALETTE[0], PALETTE[1], PALETTE[2], PALETTE[4]]
    many = ByteMap(bytes(40), [(i, 1, f"f{i}") for i in range(40)])
    assert all(many.colour(i) != many.colour(i + 1) for i in range(39))


def test_describe_names_path_type_offset_size_value() -> None:
    bm = ByteMap(HEADER, HEADER_SPANS)
    assert bm.describe(1) == "header.stamp.secs \u00b7 uint32 \u00b7 offset 4 \u00b7 size 4 \u00b7 value 1"
    assert bm.describe(3).startswith("header.frame_id [length] \u00b7 uint32 \u00b7 offset 12")
    assert bm.describe(4).endswith("value 'ab'")
    raw = ByteMap(b"\x01\x02", [(0, 2, "w")])
    assert raw.describe(0) == "w \u00b7 offset 0 \u00b7 size 2 \u00b7 bytes 01 02"


def test_paging_boundaries() -> None:
    data = bytes(range(256)) * 5  # 1280 bytes
    bm = ByteMap(data, [(0, 10, "a"), (500, 30, "straddles"), (1024, 0, "empty"), (1270, 10, "end"),
                        (1280, 0, "tail-empty")], page_size=512)
    assert bm.n_pages == 3
    assert [bm.page_range(p) for p in range(3)] == [(0, 512), (512, 1024), (1024, 1280)]
    assert [bm.page_of(o) for o in (0, 511, 512, 1023, 1024, 1279, 1280, 10**9)] == [0, 0, 1, 1, 2, 2, 2, 2]
    names = lambda p: [bm.spans[i].path for i in bm.spans_on_page(p)]  # noqa: E731
    assert names(0) == ["a", "straddles"]
    assert names(1) == ["straddles"]
    assert names(2) == ["empty", "end", "tail-empty"]
    with pytest.raises(WidgetError, match=r"page 3 does not exist; pages are 0\.\.2"):
        bm.page_range(3)
    assert ByteMap(b"").n_pages == 1 and ByteMap(b"").page_range(0) == (0, 0)
    with pytest.raises(WidgetError, match="multiple of row_size"):
        ByteMap(b"", page_size=100)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.integers(0, 6), min_size=0, max_size=40), st.sampled_from([16, 32, 64]))
def test_lookup_and_pages_match_a_naive_model(sizes: list[int], page_size: int) -> None:
    spans, off = [], 0
    for i, size in enumerate(sizes):
        if i % 3 == 2:
            off += 1  # leave a gap byte uncovered
        spans.append((off, size, f"f{i}"))
        off += size
    data = bytes(off)
    bm = ByteMap(data, spans, page_size=page_size)
    owner = [None] * len(data)  # naive model: paint every byte with its span's index
    order = sorted(range(len(spans)), key=lambda i: (spans[i][0], spans[i][1]))
    for rank, i in enumerate(order):
        for b in range(spans[i][0], spans[i][0] + spans[i][1]):
            owner[b] = rank
    assert [bm.span_at(b) for b in range(len(data))] == owner
    for p in range(bm.n_pages):
        start, stop = bm.page_range(p)
        on_page = set(bm.spans_on_page(p))
        assert {owner[b] for b in range(start, stop)} - {None} <= on_page
    shown = [b for p in range(bm.n_pages) for b in range(*bm.page_range(p))]
    assert shown == list(range(len(data)))  # every byte on exactly one page


def test_static_html_escapes_bytes_and_values() -> None:
    data = b'<&>"\x00\x7f' + b"A"
    bm = ByteMap(data, [(0, 4, "tag<b>", "string", '<script>alert("x")</script>'), (4, 3, "rest")])
    out = bm.to_html()
    assert "<script>" not in out and "tag<b>" not in out
    assert "tag&lt;b&gt;" in out and "&lt;script&gt;" in out
    assert "|<span" in out
    ascii_col = re.findall(r"\|(.*)\|", out)[0]
    assert html.unescape(re.sub(r"<[^>]+>", "", ascii_col)) == '<&>"..A'
    hex_col = re.sub(r"<[^>]+>", "", out.split("<pre")[1].split("</pre>")[0])
    assert "3c 26 3e 22" in hex_col and "00 7f 41" in hex_col


def test_static_html_carries_meaning_without_css_or_js() -> None:
    bm = ByteMap(HEADER, HEADER_SPANS, title="Header")
    out = bm.to_html()
    assert "<script" not in out and "<style" not in out
    assert "Header \u2014 18 bytes, 5 fields" in out and "page 1 of 1" in out
    # every field: a tooltip on its bytes and a table row with its colour swatch
    for i, s in enumerate(bm.spans):
        assert f'title="{html.escape(bm.describe(i), quote=True)}"' in out
        assert f'<td style="background:{bm.colour(i)};width:14px;border:1px solid #888"></td><td>{bm.label(i)}</td>' in out
    assert bm.label(3) == "header.frame_id [length]" and bm.label(4) == "header.frame_id"


def test_static_html_of_a_megabyte_is_one_page() -> None:
    data = np.arange(1_228_800, dtype=np.uint32).astype(np.uint8)
    bm = ByteMap(data, [(0, 4, "len", "uint32", None, "length"), (4, len(data) - 4, "data", "uint8[]")])
    assert bm.n_pages == 2400
    out = bm.to_html(1234)
    assert len(out) < 60_000
    assert "page 1235 of 2400 (bytes 631808..632319)" in out
    assert "1 more fields on other pages" in out


def test_viewer_selection_paging_and_sync_state() -> None:
    data = bytes(2000)
    spans = [(0, 4, "a"), (4, 1000, "big"), (1500, 8, "late")]
    v = ByteViewer(data, spans, page_size=512)
    assert (v.total, v.n_pages, v.page, v.page_start) == (2000, 4, 0, 0)
    assert v.page_hex == "00" * 512
    assert [f["path"] for f in v.page_fields] == ["a", "big"]
    assert v.selection is None and v.highlighted() == range(0)
    seen = []
    v.on_select(seen.append)
    assert v.select("late").path == "late"
    assert v.page == 2 and v.page_start == 1024  # turned to the field's page
    assert v.highlighted() == range(1500, 1508)
    assert v.select_byte(600).path == "big" and v.page == 1
    assert v.highlighted() == range(600 - 88, 1004)  # the field's bytes on page 1 (512..1003)
    assert v.selected_offset == 600
    v.page = 0  # big spans pages 0 and 1: selecting it again from page 0 keeps page 0
    v.selected = -1
    v.select("big")
    assert v.page == 0
    assert [s.path if s else None for s in seen] == ["late", "big", None, "big"]
    v.page = 99
    assert v.page == 3  # clamped
    with pytest.raises(WidgetError):
        v.select(7)
    with pytest.raises(WidgetError):
        v.select_byte(2000)


def test_viewer_uncovered_byte_selects_nothing() -> None:
    v = ByteViewer(b"\x00\x01\x02", [(0, 1, "a")])
    assert v.select_byte(2) is None and v.selected == -1 and v.selected_offset == 2


def test_viewer_output_has_widget_view_and_static_html() -> None:
    v = ByteViewer(HEADER, HEADER_SPANS)
    data, _meta = v._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in data
    assert data["text/html"] == v.to_html()
    assert "text/html" not in ByteViewer(HEADER, HEADER_SPANS, static_fallback=False)._repr_mimebundle_()[0]


def test_field_list_truncation_is_reported() -> None:
    v = ByteViewer(bytes(2100), [(i, 1, f"f{i}") for i in range(2100)])
    assert len(v.fields) == 2000 and v.fields_truncated == 100


# --- adapters -----------------------------------------------------------------------------------

def test_connection_header_spans_cover_fields_and_length_prefixes() -> None:
    from rosfpga_lab.tcpros import encode_header

    raw = encode_header({"callerid": "/a", "topic": "/t"})
    # hand-written: total 4+11+4+8 = 27; "callerid=/a" (11), "topic=/t" (8)
    assert raw == struct.pack("<I", 27) + struct.pack("<I", 11) + b"callerid=/a" + struct.pack("<I", 8) + b"topic=/t"
    spans = spans_from_connection_header(raw)
    assert [(s.offset, s.size, s.path, s.value, s.role) for s in spans] == [
        (0, 4, "header length", 27, "length"),
        (4, 4, "callerid.length", 11, "length"),
        (8, 11, "callerid", "/a", "value"),
        (19, 4, "topic.length", 8, "length"),
        (23, 8, "topic", "/t", "value"),
    ]
    ByteMap(raw, spans)  # no overlap, inside the data


def test_connection_header_malformed_gets_an_error_span() -> None:
    raw = struct.pack("<I", 12) + struct.pack("<I", 50) + b"topic=/t"
    spans = spans_from_connection_header(raw)
    assert spans[-1].role == "error" and "declares 50 bytes" in spans[-1].value
    assert sum(s.size for s in spans) == len(raw)
    assert spans_from_connection_header(b"\x01")[0].role == "error"


def test_http_spans_split_start_line_headers_and_xmlrpc_params() -> None:
    body = xmlrpc.client.dumps(("/pub", "/chatter", "std_msgs/String", "http://127.0.0.1:1/"),
                               "registerPublisher").encode()
    raw = b"POST /RPC2 HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: %d\r\n\r\n" % len(body) + body
    spans = spans_from_http(raw)
    ByteMap(raw, spans)
    assert sum(s.size for s in spans) == len(raw)  # every byte labelled
    by = {s.path: s for s in spans}
    assert by["request line"].value == "POST /RPC2 HTTP/1.1" and by["request line"].size == 21
    assert by["header Content-Length"].value == str(len(body))
    assert raw[by["end of headers"].offset:by["end of headers"].offset + 2] == b"\r\n"
    assert by["methodName"].value == "registerPublisher"
    # named as in the ROS Master API: registerPublisher(caller_id, topic, topic_type, caller_api)
    assert [by[n].value for n in ("caller_id", "topic", "topic_type", "caller_api")] == \
        ["/pub", "/chatter", "std_msgs/String", "http://127.0.0.1:1/"]
    assert not any(s.path.startswith("param[") for s in spans)
    p1 = by["topic"]
    assert raw[p1.offset:p1.offset + p1.size].startswith(b"<param>") and b"/chatter" in raw[p1.offset:p1.offset + p1.size]
    reply = b"HTTP/1.0 200 OK\r\nServer: x\r\n\r\n"
    assert [s.path for s in spans_from_http(reply)] == ["status line", "header Server", "end of headers"]
    assert spans_for(raw)[0].path == "request line"


def test_frame_spans_with_and_without_type() -> None:
    from rosfpga_lab import msg

    reg = msg.default_registry()
    body = msg.serialize(reg, "std_msgs/String", {"data": "hi"})
    assert body == b"\x02\x00\x00\x00hi"
    raw = struct.pack("<I", len(body)) + body
    typed = spans_from_frame(raw, "std_msgs/String")
    assert [(s.offset, s.size, s.path, s.role) for s in typed] == [
        (0, 4, "frame length", "length"), (4, 4, "data", "length"), (8, 2, "data", "value")]
    untyped = spans_from_frame(raw[:7])  # recorded prefix of a longer frame
    assert untyped[1].value == "3 of 6 body bytes recorded"
    assert spans_for(raw, "tcpros_frame")[0].path == "frame length"


def test_message_viewer_on_a_sensor_msgs_image() -> None:
    from rosfpga_lab import msg

    reg = msg.default_registry()
    img = {"header": {"seq": 3, "stamp": {"secs": 10, "nsecs": 20}, "frame_id": "cam"},
           "height": 2, "width": 3, "encoding": "rgb8", "is_bigendian": 0, "step": 9, "data": bytes(range(18))}
    body = msg.serialize(reg, "sensor_msgs/Image", img)
    spans = message_spans("sensor_msgs/Image", body)
    assert sum(s.size for s in spans) == len(body)
    v = message_viewer("sensor_msgs/Image", body)
    height_at = 12 + 4 + 3  # seq, stamp, frame_id length, "cam"
    span = v.select_byte(height_at + 2)
    assert (span.path, span.offset, span.size, span.value) == ("height", height_at, 4, 2)
    assert "height \u00b7 uint32 \u00b7 offset 19 \u00b7 size 4 \u00b7 value 2" in v.bytemap.describe(v.selected)


def test_tcpros_stream_spans_header_then_frames() -> None:
    from rosfpga_lab import msg
    from rosfpga_lab.tcpros import encode_header

    reg = msg.default_registry()
    header = encode_header({"type": "std_msgs/String"})
    frames = b"".join(struct.pack("<I", 4 + len(t)) + struct.pack("<I", len(t)) + t for t in (b"a", b"bc"))
    raw = header + frames + b"\x09\x00"  # plus the first 2 bytes of a third frame's length
    spans = spans_from_tcpros_stream(raw, "std_msgs/String", registry=reg)
    assert sum(s.size for s in spans) == len(raw)
    ByteMap(raw, spans)
    by = {s.path: s for s in spans}
    h = len(header)
    assert by["type"].value == "std_msgs/String"
    assert (by["msg[0].frame length"].offset, by["msg[0].frame length"].value) == (h, 5)
    assert [s.value for s in spans if s.path == "msg[1].data"] == [2, "bc"]
    # frame 0 took 9 bytes; frame 1: its 4-byte length, the string's length prefix, the text
    assert [s.offset for s in spans if s.path == "msg[1].data"] == [h + 9 + 4, h + 9 + 8]
    assert by["msg[2].frame length (truncated)"].role == "error"


_NAMES = st.text(alphabet=st.sampled_from('ab<>&"\' .'), min_size=1, max_size=8)


@settings(max_examples=60, deadline=None)
@given(st.binary(min_size=0, max_size=80), st.lists(st.tuples(st.integers(0, 5), _NAMES), max_size=12))
def test_static_html_text_is_exactly_the_hex_and_ascii_of_the_bytes(data: bytes, cuts: list) -> None:
    spans, off = [], 0
    for size, name in cuts:  # consecutive spans with hostile names; the rest uncovered
        if off + size > len(data):
            break
        spans.append((off, size, name, "t<", name))
        off += size
    out = ByteMap(data, spans, page_size=32).to_html(0)
    pre = out.split("<pre", 1)[1].split(">", 1)[1].split("</pre>")[0]
    lines = html.unescape(re.sub(r"<[^>]+>", "", pre)).splitlines()
    expected = []  # written independently: offset, 16 hex columns padded, |ascii|
    for row in range(0, min(32, len(data)), 16):
        chunk = data[row:min(row + 16, 32)]
        hexes = " ".join(f"{b:02x}" for b in chunk).ljust(16 * 3 - 1)
        text = "".join(chr(b) if 32 <= b < 127 else "." for b in chunk)
        expected.append(f"{row:08x}  {hexes}  |{text}|")
    assert lines == expected
    assert "<script" not in out
    if any(size for _off, size, *_ in spans):
        assert 'title="' in out


def test_live_viewer_state_stays_small_for_a_megabyte() -> None:
    import json

    data = bytes(range(256)) * 4800  # 1,228,800 bytes
    v = ByteViewer(data, [(0, len(data), "data", "uint8[]")])
    state = v.get_state()
    sizes = {k: len(json.dumps(val, default=str)) for k, val in state.items() if not k.startswith("_")}
    assert len(v.page_hex) == 2 * 512
    assert sum(sizes.values()) < 10_000, sizes
    v.page = v.n_pages - 1
    assert v.page_start == len(data) - 512 and len(v.page_hex) == 1024


def test_image_pixel_bytes_are_named_by_pixel_and_channel() -> None:
    """Notebook 3: data[45] of a 4-pixel-wide rgba8 image is pixel (3, 2)'s green byte
    (45 = 2 rows of 16 bytes + 13 = pixel 3, byte 1)."""
    from rosfpga_lab.msg import default_registry, serialize
    from rosfpga_lab.widgets import message_spans
    from rosfpga_lab.widgets.byte_sources import pixel_label

    image = {"header": {"seq": 1, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": "c"},
             "height": 3, "width": 4, "encoding": "rgba8", "is_bigendian": 0, "step": 16,
             "data": bytes(48)}
    spans = message_spans("sensor_msgs/Image", serialize(default_registry(), "sensor_msgs/Image", image))
    names = [s.path for s in spans if s.path.startswith("data[")]
    assert len(names) == 48 and names[45] == "data[45] = pixel (x 3, y 2) G"
    assert names[0] == "data[0] = pixel (x 0, y 0) R"
    # rgb8, 2 pixels (6 bytes) in a row of step 8: bytes 6 and 7 pad the row
    assert pixel_label(6, 2, 8, "rgb8") == "data[6] = row 0 padding"
    assert pixel_label(11, 2, 8, "bgr8") == "data[11] = pixel (x 1, y 1) B"


def test_no_field_colour_looks_like_cdr_padding() -> None:
    """09's CDR viewer gave frame_id, height, encoding and step pinks and a salmon beside the
    red padding bytes; every field colour's hue now stays 60 degrees away from that red."""
    import colorsys

    def hue(colour: str) -> float:
        r, g, b = (int(colour[i:i + 2], 16) / 255 for i in (1, 3, 5))
        return colorsys.rgb_to_hls(r, g, b)[0] * 360

    red = hue(ROLE_COLOURS["alignment"])
    for colour in PALETTE:
        gap = abs(hue(colour) - red) % 360
        assert min(gap, 360 - gap) >= 60, colour
    assert len(set(PALETTE)) == len(PALETTE)


def test_field_list_breaks_between_words_only() -> None:
    """The live viewer's field list wrapped names mid-word ('overflow-wrap: anywhere')."""
    from pathlib import Path

    import rosfpga_lab.widgets as widgets

    css = (Path(widgets.__file__).parent / "static" / "byteviewer.css").read_text()
    rule = next(line for line in css.splitlines() if line.startswith(".rfl-bv-list td"))
    assert "overflow-wrap: break-word" in rule and "anywhere" not in rule
