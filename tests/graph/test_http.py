"""graph.http's sans-IO HTTP decoder, as tcpros/header.py's is tested: fed whole, one byte at a
time and with trailing bytes; keep-alive messages in one stream; every limit and every cut."""

from __future__ import annotations

import pytest

from rosfpga_lab.graph.errors import XmlRpcError, XmlRpcTooLargeError
from rosfpga_lab.graph.http import Body, EndOfStream, Head, HttpDecoder, parse_head

BODY = b"<?xml version='1.0'?><methodCall><methodName>getPid</methodName></methodCall>"
REQUEST = (b"POST / HTTP/1.1\r\nHost: 127.0.0.1:11311\r\nContent-Type: text/xml\r\n"
           b"Content-Length: " + str(len(BODY)).encode() + b"\r\n\r\n" + BODY)
HEAD_BYTES = REQUEST[:REQUEST.index(b"\r\n\r\n") + 4]


def events(dec: HttpDecoder, chunks: list[bytes], *, eof: bool = True) -> list[object]:
    out: list[object] = []
    for chunk in [*chunks, *([b""] if eof else [])]:
        dec.receive(chunk)
        while (event := dec.next_event()) is not None:
            out.append(event)
            if isinstance(event, EndOfStream):
                return out
    return out


def test_a_request_fed_whole() -> None:
    dec = HttpDecoder()
    head, body, end = events(dec, [REQUEST])
    assert isinstance(head, Head) and isinstance(body, Body) and isinstance(end, EndOfStream)
    assert head.start_line == "POST / HTTP/1.1"
    assert head.headers["content-type"] == "text/xml"
    assert head.content_length == len(BODY) and head.raw == HEAD_BYTES
    assert body.data == BODY and dec.consumed == len(REQUEST) and dec.buffered == 0


def test_one_byte_at_a_time_gives_the_same_events() -> None:
    whole = events(HttpDecoder(), [REQUEST])
    dec = HttpDecoder()
    seen = []
    for i in range(len(REQUEST)):
        dec.receive(REQUEST[i:i + 1])
        event = dec.next_event()
        if event is not None:
            seen.append((i, event))
            assert dec.next_event() is None   # one event per completed part
    assert [e for _i, e in seen] == whole[:2]
    assert [i for i, _e in seen] == [len(HEAD_BYTES) - 1, len(REQUEST) - 1]


def test_trailing_bytes_stay_for_the_next_message() -> None:
    dec = HttpDecoder()
    evs = events(dec, [REQUEST + b"POST / HT"], eof=False)
    assert [type(e) for e in evs] == [Head, Body]
    assert dec.buffered == len(b"POST / HT") and dec.in_message


def test_keep_alive_messages_in_one_stream_split_anywhere() -> None:
    stream = REQUEST * 3
    for cut in (1, 7, len(HEAD_BYTES), len(REQUEST) + 3, len(stream) - 1):
        evs = events(HttpDecoder(), [stream[:cut], stream[cut:]])
        assert [type(e) for e in evs] == [Head, Body] * 3 + [EndOfStream]
        assert all(e.data == BODY for e in evs if isinstance(e, Body))


def test_the_head_comes_before_its_body_is_checked() -> None:
    """A server answers the head first (405 for GET, 503 over its budget): a head without
    Content-Length is an event; its body is refused only when asked for."""
    dec = HttpDecoder()
    dec.receive(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
    head = dec.next_event()
    assert isinstance(head, Head) and head.content_length is None
    with pytest.raises(XmlRpcError, match="without Content-Length"):
        dec.next_event()


def test_missing_tells_how_much_of_a_declared_body_is_to_come() -> None:
    dec = HttpDecoder()
    dec.receive(REQUEST[:len(HEAD_BYTES) + 10])
    assert isinstance(dec.next_event(), Head)
    assert dec.missing == len(BODY) - 10 and dec.next_event() is None


def test_a_head_over_the_limit_is_refused_however_chunked() -> None:
    for chunks in ([b"POST / HTTP/1.1\r\n" + b"X: y\r\n" * 20], [b"P"] * 100):
        dec = HttpDecoder(max_head=64)
        with pytest.raises(XmlRpcError, match="HTTP head longer than 64 bytes"):
            events(dec, chunks, eof=False)


def test_a_declared_body_over_the_limit_is_refused_before_it_is_read() -> None:
    dec = HttpDecoder(max_body=10)
    dec.receive(b"POST / HTTP/1.1\r\nContent-Length: 11\r\n\r\n")
    assert isinstance(dec.next_event(), Head)
    with pytest.raises(XmlRpcTooLargeError, match="11 bytes, over the limit of 10"):
        dec.next_event()


def test_a_reply_to_the_end_of_the_stream_is_bounded() -> None:
    dec = HttpDecoder(max_body=10, eof_ends_body=True)
    head, body, _end = events(dec, [b"HTTP/1.0 200 OK\r\n\r\n", b"0123456789"])
    assert isinstance(head, Head) and body == Body(b"0123456789")
    dec = HttpDecoder(max_body=10, eof_ends_body=True)
    with pytest.raises(XmlRpcTooLargeError, match="over the limit of 10"):
        events(dec, [b"HTTP/1.0 200 OK\r\n\r\n", b"01234", b"567890"], eof=False)


@pytest.mark.parametrize("value", ["-1", "ten", "1e3"])
def test_a_bad_content_length_is_refused(value: str) -> None:
    dec = HttpDecoder()
    dec.receive(f"POST / HTTP/1.1\r\nContent-Length: {value}\r\n\r\n".encode())
    assert isinstance(dec.next_event(), Head)
    with pytest.raises(XmlRpcError, match="bad Content-Length"):
        dec.next_event()


def test_a_malformed_header_line_is_refused() -> None:
    with pytest.raises(XmlRpcError, match="malformed HTTP header line"):
        events(HttpDecoder(), [b"POST / HTTP/1.1\r\nno colon here\r\n\r\n"])
    assert parse_head(b"HTTP/1.1 200 OK\r\nA: 1\r\na:  2 ") == ("HTTP/1.1 200 OK", {"a": "2"})


def test_streams_cut_inside_a_message() -> None:
    with pytest.raises(XmlRpcError, match=r"closed inside an HTTP head \(5 bytes\)"):
        events(HttpDecoder(), [REQUEST[:5]])
    cut = len(HEAD_BYTES) + 3
    with pytest.raises(XmlRpcError, match=f"closed after 3 of {len(BODY)} body bytes"):
        events(HttpDecoder(), [REQUEST[:cut]])


def test_a_clean_end_between_messages() -> None:
    assert events(HttpDecoder(), []) == [EndOfStream()]
    dec = HttpDecoder()
    assert [type(e) for e in events(dec, [REQUEST])] == [Head, Body, EndOfStream]
    assert not dec.in_message
