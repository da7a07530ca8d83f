"""Connection-header and frame codecs: golden bytes from real rospy, any chunking, bad input."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.errors import LabError
from rosfpga_lab.tcpros import (
    FrameDecoder,
    FrameError,
    HeaderDecoder,
    HeaderFormatError,
    IncompleteError,
    decode_header,
    encode_error_header,
    encode_frame,
    encode_header,
    parse_fields,
)

# rosgraph.network.encode_ros_handshake_header(...) of a rospy subscriber's header, produced by
# Debian's ROS Noetic (/usr/bin/python3) and pinned here.
ROSPY_SUB_HEADER = bytes.fromhex(
    "9f0000001200000063616c6c657269643d2f6c697374656e6572270000006d643573756d3d39393263653861"
    "313638376365633863386264383833656337336361343164311f0000006d6573736167655f646566696e6974"
    "696f6e3d737472696e6720646174610a0d0000007463705f6e6f64656c61793d300e000000746f7069633d2f"
    "6368617474657214000000747970653d7374645f6d7367732f537472696e67")
ROSPY_SUB_FIELDS = {
    "topic": "/chatter", "message_definition": "string data\n", "tcp_nodelay": "0",
    "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1", "type": "std_msgs/String", "callerid": "/listener",
}
# genpy: std_msgs.msg.String(data="hello wörld").serialize()
STRING_BODY = bytes.fromhex("0c00000068656c6c6f2077c3b6726c64")


def u32(n: int) -> bytes:
    return struct.pack("<I", n)


def raw_header(*fields: bytes) -> bytes:
    body = b"".join(u32(len(f)) + f for f in fields)
    return u32(len(body)) + body


# ------------------------------------------------------------------------------ header
def test_encode_matches_rospy_bytes() -> None:
    assert encode_header(ROSPY_SUB_FIELDS) == ROSPY_SUB_HEADER


def test_decode_whole() -> None:
    fields, used = decode_header(ROSPY_SUB_HEADER)
    assert fields == ROSPY_SUB_FIELDS
    assert used == len(ROSPY_SUB_HEADER) == 4 + 0x9F


def test_decode_byte_by_byte_then_trailing() -> None:
    trailing = encode_frame(STRING_BODY)
    dec = HeaderDecoder()
    results = [dec.feed(bytes([b])) for b in ROSPY_SUB_HEADER + trailing]
    # None until the header's last byte, then the same dict
    n = len(ROSPY_SUB_HEADER)
    assert all(r is None for r in results[:n - 1])
    assert results[n - 1] == ROSPY_SUB_FIELDS
    assert dec.raw == ROSPY_SUB_HEADER
    assert dec.remainder == trailing


def test_decode_with_trailing_in_one_chunk() -> None:
    dec = HeaderDecoder()
    assert dec.feed(ROSPY_SUB_HEADER + b"\x05\x00\x00\x00hel") == ROSPY_SUB_FIELDS
    assert dec.remainder == b"\x05\x00\x00\x00hel"


def test_layout_offsets() -> None:
    layout = parse_fields(ROSPY_SUB_HEADER[4:])
    assert [s.path for s in layout[1::2]] == sorted(ROSPY_SUB_FIELDS)
    assert [s.path for s in layout[::2]] == [f"{k}.length" for k in sorted(ROSPY_SUB_FIELDS)]
    assert (layout[0].offset, layout[0].size, layout[0].value) == (4, 4, len(b"callerid=/listener"))
    assert (layout[1].offset, layout[1].size) == (8, len(b"callerid=/listener"))
    assert layout[2].offset == 4 + 4 + len(b"callerid=/listener")


def test_value_may_contain_equals_and_repeated_key_keeps_last() -> None:
    data = raw_header(b"a=b=c", b"k=1", b"k=2", b"empty=")
    assert decode_header(data)[0] == {"a": "b=c", "k": "2", "empty": ""}


def test_error_header() -> None:
    assert encode_error_header("no") == raw_header(b"error=no")


def test_encode_unsorted_keeps_order() -> None:
    assert encode_header([("b", "1"), ("a", "2")], sort=False) == raw_header(b"b=1", b"a=2")


@pytest.mark.parametrize("key", ["", "a=b"])
def test_encode_rejects_bad_keys(key: str) -> None:
    with pytest.raises(HeaderFormatError):
        encode_header({key: "v"})


BAD_HEADERS = [
    # (name, bytes, error type, offset, text in message)
    ("zero-length field", u32(8) + u32(0) + u32(0), HeaderFormatError, 4, "zero-length"),
    ("field without '='", raw_header(b"callerid"), HeaderFormatError, 4, "no '='"),
    ("empty key", raw_header(b"=x"), HeaderFormatError, 4, "empty key"),
    ("non-UTF-8", raw_header(b"topic=/a\xff"), HeaderFormatError, 4 + 4 + 8, "not UTF-8"),
    ("field runs past header", u32(6) + u32(10) + b"ab", HeaderFormatError, 4, "only 2 remain"),
    ("truncated field length", u32(2) + b"\x01\x00", HeaderFormatError, 4, "truncated"),
    ("header over cap", u32(2_000_000) + b"xx", HeaderFormatError, 0, "over the limit"),
    ("field over cap", u32(8) + u32(1_500_000) + b"abcd", HeaderFormatError, 4, "over the limit"),
]


@pytest.mark.parametrize("name,data,exc,offset,text",
                         BAD_HEADERS, ids=[b[0] for b in BAD_HEADERS])
def test_bad_headers(name: str, data: bytes, exc: type, offset: int, text: str) -> None:
    with pytest.raises(exc) as info:
        decode_header(data)
    assert info.value.offset == offset
    assert text in str(info.value)
    assert isinstance(info.value, LabError)
    # byte by byte gives the same error
    dec = HeaderDecoder()
    with pytest.raises(exc):
        for b in data:
            dec.feed(bytes([b]))
        dec.eof()


@pytest.mark.parametrize("cut", [0, 1, 3, 4, 10, len(ROSPY_SUB_HEADER) - 1])
def test_eof_mid_header(cut: int) -> None:
    dec = HeaderDecoder()
    dec.feed(ROSPY_SUB_HEADER[:cut])
    with pytest.raises(IncompleteError, match="before the connection header was complete"):
        dec.eof()


def test_limits_are_configurable() -> None:
    data = raw_header(b"a=" + b"x" * 100)
    with pytest.raises(HeaderFormatError):
        decode_header(data, max_header=50)
    with pytest.raises(HeaderFormatError):
        decode_header(data, max_field=50)
    assert decode_header(data, max_header=200, max_field=200)[0]["a"] == "x" * 100


# ------------------------------------------------------------------------------ frames
FRAMES = [STRING_BODY, b"", b"\x00" * 7, bytes(range(256)) * 5]
STREAM = b"".join(encode_frame(f) for f in FRAMES)


def test_frame_encoding_is_length_prefixed() -> None:
    assert encode_frame(STRING_BODY) == bytes.fromhex("10000000") + STRING_BODY


def test_frames_whole() -> None:
    dec = FrameDecoder()
    out = dec.feed(STREAM)
    assert [bytes(b) for b in out] == FRAMES
    assert dec.starts == [0, 20, 24, 35]
    assert dec.frames == 4 and not dec.in_frame
    assert all(isinstance(b, memoryview) for b in out)  # one chunk -> zero copy
    dec.eof()


def test_frames_byte_by_byte() -> None:
    dec = FrameDecoder()
    out: list[bytes] = []
    starts: list[int] = []
    for b in STREAM:
        out += [bytes(x) for x in dec.feed(bytes([b]))]
        starts += dec.starts
    assert out == FRAMES
    assert starts == [0, 20, 24, 35]
    dec.eof()


def test_frames_with_trailing_partial() -> None:
    dec = FrameDecoder()
    out = dec.feed(STREAM + u32(10) + b"abc")
    assert [bytes(b) for b in out] == FRAMES
    assert dec.in_frame
    assert [bytes(b) for b in dec.feed(b"defghij")] == [b"abcdefghij"]


@settings(max_examples=100, deadline=None)
@given(bodies=st.lists(st.binary(max_size=300), max_size=8), cuts=st.lists(st.integers(0, 3000), max_size=12))
def test_frames_any_chunking(bodies: list[bytes], cuts: list[int]) -> None:
    stream = b"".join(encode_frame(b) for b in bodies)
    points = sorted({min(c, len(stream)) for c in cuts} | {0, len(stream)})
    dec = FrameDecoder()
    out: list[bytes] = []
    for a, b in zip(points, points[1:]):
        out += [bytes(x) for x in dec.feed(stream[a:b])]
    assert out == bodies
    dec.eof()


@pytest.mark.parametrize("cut,text", [(2, "length prefix"), (6, "mid-frame: 2 of 16")])
def test_eof_mid_frame(cut: int, text: str) -> None:
    dec = FrameDecoder()
    dec.feed(encode_frame(STRING_BODY)[:cut])
    with pytest.raises(IncompleteError, match=text):
        dec.eof()


def test_frame_over_cap() -> None:
    dec = FrameDecoder(max_frame=1000)
    assert [bytes(b) for b in dec.feed(encode_frame(b"x" * 1000))] == [b"x" * 1000]
    with pytest.raises(FrameError, match="declares 1001 bytes, over the limit of 1000") as info:
        dec.feed(u32(1001))
    assert info.value.offset == 1004


def test_frame_over_cap_split_prefix() -> None:
    dec = FrameDecoder(max_frame=10)
    dec.feed(b"\xff\xff")
    with pytest.raises(FrameError):
        dec.feed(b"\xff\xff")


# ------------------------------------------------------------------------------ fuzzing
@settings(max_examples=200, deadline=None)
@given(data=st.binary(max_size=400), chunk=st.integers(1, 50))
def test_fuzz_header_decoder_only_lab_errors(data: bytes, chunk: int) -> None:
    dec = HeaderDecoder(max_header=300, max_field=200)
    try:
        for i in range(0, len(data), chunk):
            dec.feed(data[i:i + chunk])
        dec.eof()
    except LabError:
        pass


@settings(max_examples=200, deadline=None)
@given(fields=st.lists(st.binary(min_size=0, max_size=40), max_size=6), noise=st.binary(max_size=8))
def test_fuzz_structured_headers_only_lab_errors(fields: list[bytes], noise: bytes) -> None:
    try:
        result, used = decode_header(raw_header(*fields) + noise)
    except LabError:
        return
    assert used == 4 + sum(4 + len(f) for f in fields)


@settings(max_examples=200, deadline=None)
@given(data=st.binary(max_size=400), chunk=st.integers(1, 50))
def test_fuzz_frame_decoder_only_lab_errors(data: bytes, chunk: int) -> None:
    dec = FrameDecoder(max_frame=300)
    try:
        for i in range(0, len(data), chunk):
            dec.feed(data[i:i + chunk])
        dec.eof()
    except LabError:
        pass


@settings(max_examples=100, deadline=None)
@given(fields=st.dictionaries(st.text(min_size=1).filter(lambda k: "=" not in k), st.text(), max_size=6))
def test_header_roundtrip(fields: dict[str, str]) -> None:
    assert decode_header(encode_header(fields))[0] == fields


def test_frames_before_a_bad_length_are_not_lost() -> None:
    dec = FrameDecoder(max_frame=100)
    with pytest.raises(FrameError) as info:
        dec.feed(encode_frame(b"good") + encode_frame(b"too") + u32(101))
    assert [bytes(b) for b in info.value.partial] == [b"good", b"too"]
    assert info.value.offset == 15


# ------------------------------------------------------------------------------ receive in place
def read_in_place(stream: bytes, chunks: list[int], lends: list[int],
                  first_buffer: int | None = None) -> tuple[list, list[int], int]:
    """Drive a decoder as the subscriber's socket loop does: feed() a chunk between frame bodies,
    write straight into pending_body() inside one. Returns (bodies, starts, bytes written in place)."""
    dec = FrameDecoder() if first_buffer is None else FrameDecoder(first_buffer=first_buffer)
    out: list = []
    starts: list[int] = []
    pos, i, in_place = 0, 0, 0
    while pos < len(stream):
        view = dec.pending_body()
        if view is None:
            size = chunks[i % len(chunks)] if chunks else 1
            got = dec.feed(stream[pos:pos + size])
            pos += min(size, len(stream) - pos)
        else:
            n = min(lends[i % len(lends)] if lends else len(view), len(view), len(stream) - pos)
            view[:n] = stream[pos:pos + n]  # what sock.recv_into(view) does
            lent = view.obj
            view.release()
            got = dec.filled(n)
            assert not got or got[0] is lent  # the buffer lent is the body handed over
            pos += n
            in_place += n
        out += got
        starts += dec.starts
        i += 1
    dec.eof()
    return out, starts, in_place


def expected_starts(bodies: list[bytes]) -> list[int]:
    starts, at = [], 0
    for b in bodies:
        starts.append(at)
        at += 4 + len(b)
    return starts


def test_big_frame_received_in_place() -> None:
    bodies = [bytes(range(256)) * 40, STRING_BODY, b"", b"\x07" * 5000]
    stream = b"".join(encode_frame(b) for b in bodies)
    out, starts, in_place = read_in_place(stream, chunks=[100], lends=[])
    assert [bytes(b) for b in out] == bodies
    assert starts == expected_starts(bodies)
    # a 100-byte chunk at each frame start (the first: prefix + 96 body bytes; the second: the
    # String and empty frames whole, then prefix + 72 body bytes); the rest went in place
    assert in_place == (10240 - 96) + (5000 - 72)
    assert isinstance(out[0], bytearray) and isinstance(out[3], bytearray)


@settings(max_examples=100, deadline=None)
@given(bodies=st.lists(st.binary(max_size=600), max_size=8),
       chunks=st.lists(st.integers(1, 700), max_size=6), lends=st.lists(st.integers(1, 700), max_size=6))
def test_in_place_reads_equal_plain_feeding(bodies: list[bytes], chunks: list[int], lends: list[int]) -> None:
    stream = b"".join(encode_frame(b) for b in bodies)
    out, starts, _ = read_in_place(stream, chunks, lends)
    assert [bytes(b) for b in out] == bodies
    assert starts == expected_starts(bodies)


@settings(max_examples=100, deadline=None)
@given(bodies=st.lists(st.binary(max_size=600), max_size=8),
       chunks=st.lists(st.integers(1, 700), max_size=6), lends=st.lists(st.integers(1, 700), max_size=6),
       first=st.integers(1, 64))
def test_growing_buffers_read_the_same_frames(bodies: list[bytes], chunks: list[int],
                                              lends: list[int], first: int) -> None:
    """Tiny first buffers make every lent body grow many times: same frames, same offsets."""
    stream = b"".join(encode_frame(b) for b in bodies)
    out, starts, _ = read_in_place(stream, chunks, lends, first_buffer=first)
    assert [bytes(b) for b in out] == bodies
    assert starts == expected_starts(bodies)


def _peak_while(fn) -> int:
    import tracemalloc

    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_follows_bytes_received_not_the_declared_length() -> None:
    """A peer declares 60 MiB and sends 1 MiB: the decoder holds about 1-2 MiB, either path."""
    declared, sent = 60 << 20, 1 << 20
    payload = bytes(range(256)) * (sent // 256)

    def fed() -> None:
        dec = FrameDecoder()
        for i in range(0, sent, 65536):
            first = u32(declared) if i == 0 else b""
            assert dec.feed(first + payload[i:i + 65536]) == []
        assert dec.in_frame

    def lent() -> None:
        dec = FrameDecoder()
        dec.feed(u32(declared))
        got = 0
        while got < sent:
            view = dec.pending_body()
            n = min(len(view), 65536, sent - got)
            view[:n] = payload[got:got + n]
            view.release()
            dec.filled(n)
            got += n

    assert _peak_while(fed) < 4 << 20
    assert _peak_while(lent) < 4 << 20


def test_an_honest_big_frame_grows_in_place() -> None:
    body = bytes(range(256)) * (3 << 12)  # 3 MiB
    out, _, in_place = read_in_place(encode_frame(body) + encode_frame(b"x"), chunks=[4], lends=[])
    assert bytes(out[0]) == body and bytes(out[1]) == b"x" and in_place == len(body) + 1  # both bodies lent


def test_limit_is_checked_before_a_buffer_is_lent() -> None:
    dec = FrameDecoder(max_frame=10)
    dec.feed(u32(10) + b"ab")
    assert len(dec.pending_body()) == 8
    dec.pending_body()[:8] = b"cdefghij"
    assert [bytes(b) for b in dec.filled(8)] == [b"abcdefghij"]
    assert dec.pending_body() is None
    with pytest.raises(FrameError, match="declares 11 bytes"):
        dec.feed(u32(11))
    assert dec.pending_body() is None  # nothing allocated for the refused frame


@pytest.mark.parametrize("before,n,text", [
    (b"", 1, "misses 0 bytes"),             # between frames: nothing lent
    (b"\x05\x00", 1, "misses 0 bytes"),     # inside the length prefix
    (u32(5) + b"ab", 4, "misses 3 bytes"),  # more than the body still misses
    (u32(5) + b"ab", 0, "filled\\(0\\)"),
])
def test_filled_refuses_a_wrong_count(before: bytes, n: int, text: str) -> None:
    from rosfpga_lab.tcpros import StateError

    dec = FrameDecoder()
    dec.feed(before)
    with pytest.raises(StateError, match=text):
        dec.filled(n)
    assert dec.offset == len(before)  # nothing was counted


def test_header_spans_strict_and_lenient_one_parser() -> None:
    """header_spans is parse_fields with the total length and trailing bytes; lenient mode turns
    the strict error into one error span carrying the same message, and covers every byte."""
    from rosfpga_lab.msg import Span
    from rosfpga_lab.tcpros import header_spans

    raw = encode_header({"callerid": "/a", "topic": "/t"})
    spans = header_spans(raw + b"xyz")
    assert all(isinstance(s, Span) for s in spans)
    assert [(s.path, s.offset, s.size, s.value) for s in spans] == [
        ("header length", 0, 4, 27), ("callerid.length", 4, 4, 11), ("callerid", 8, 11, "/a"),
        ("topic.length", 19, 4, 8), ("topic", 23, 8, "/t"), ("(after the header)", 31, 3, None)]
    assert header_spans(raw, lenient=False) == spans[:-1]
    dec = HeaderDecoder()
    dec.feed(raw)
    assert dec.layout == spans[1:-1]
    for bad, words in [(raw_header(b"callerid"), "no '='"), (raw_header(b"a=\xff"), "not UTF-8"),
                       (u32(6) + u32(0) + b"ab", "zero-length")]:
        with pytest.raises(HeaderFormatError) as info:
            header_spans(bad, lenient=False)
        lenient = header_spans(bad)
        assert lenient[-1].role == "error" and lenient[-1].value == str(info.value)
        assert words in lenient[-1].value
        assert sum(s.size for s in lenient) == len(bad)
    with pytest.raises(IncompleteError):
        header_spans(raw[:10], lenient=False)
    cut = header_spans(raw[:10])
    assert sum(s.size for s in cut) == 10 and cut[-1].role == "error"
    assert header_spans(b"\x01")[0].role == "error" and header_spans(b"") == []


def test_frame_spans_are_the_checks_and_the_viewers() -> None:
    from rosfpga_lab.checks.message import frame_fields
    from rosfpga_lab.msg import default_registry, serialize
    from rosfpga_lab.tcpros import frame_spans
    from rosfpga_lab.widgets import spans_from_frame

    reg = default_registry()
    frame = encode_frame(serialize(reg, "std_msgs/String", {"data": "hi"}))
    spans = frame_spans(frame + b"\x01", "std_msgs/String")
    assert [(s.label, s.offset, s.size) for s in spans] == [
        ("frame length", 0, 4), ("data length", 4, 4), ("data", 8, 2), ("(next frame)", 10, 1)]
    assert spans_from_frame(frame, "std_msgs/String") == frame_fields("std_msgs/String", frame) \
        == spans[:-1]
    assert [s.path for s in frame_spans(frame[:7], "std_msgs/String")] == ["frame length", "message body"]
    assert frame_spans(b"\x01\x00")[0].role == "error"
