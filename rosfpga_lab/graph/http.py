"""HTTP/1.1 messages for XML-RPC, sans-IO: bytes in, a head and a body out, limits enforced.

How it works: :class:`HttpDecoder` is fed whatever the socket (or a capture) gave,
:meth:`~HttpDecoder.receive`, and asked for the next event, :meth:`~HttpDecoder.next_event`: a
:class:`Head` (start line and header fields) once the blank line that ends it is in, then a
:class:`Body` once ``Content-Length`` bytes are in (or, for a reply without one, at the end of
the stream), then the next message's head: keep-alive and pipelined messages follow one another
on one decoder. ``None`` means more bytes are needed; :class:`EndOfStream` that the stream ended
cleanly between messages. Asking for events one at a time lets the caller decide between a head
and its body (the server refuses a method it does not serve, or reserves the body's length in
its budget). A head over ``max_head`` bytes, however chunked, or with a malformed line raises
when the head is asked for; a missing or bad ``Content-Length`` or one over ``max_body`` when
the body is asked for, before more of it is read; a body that grows over ``max_body`` and a
stream that ends inside a message raise :class:`~rosfpga_lab.graph.errors.XmlRpcError`
(:class:`~rosfpga_lab.graph.errors.XmlRpcTooLargeError` for a body's size). Memory follows the
bytes received, never a declared length. The other way, :func:`request_message` and
:func:`response_message` write the two messages XML-RPC sends, and :func:`keeps_alive` reads
whether a request's client keeps its connection.
The socket side (deadlines, refusals) is :mod:`rosfpga_lab.graph.xmlrpc`'s, the XML in the
bodies :mod:`rosfpga_lab.graph.xmlrpccodec`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

from rosfpga_lab.graph.errors import XmlRpcError, XmlRpcTooLargeError
from rosfpga_lab.graph.limits import MAX_HTTP_HEAD, MAX_XMLRPC_BODY

#: What a head ends with.
HEAD_END = b"\r\n\r\n"


@dataclass(frozen=True)
class Head:
    """An HTTP head: the start line, the header fields (names lower-cased) and its bytes.

    Attributes:
        start_line: ``POST / HTTP/1.1`` or ``HTTP/1.1 200 OK``.
        headers: field name (lower case) -> value, stripped; a repeated name keeps the last.
        raw: the head's bytes, the final blank line included.
    """

    start_line: str
    headers: dict[str, str]
    raw: bytes

    @property
    def content_length(self) -> int | None:
        """The body's declared length; None when the head declares none, or not as a number
        (the decoder refuses such a body when it is asked for it)."""
        text = self.headers.get("content-length", "")
        return int(text) if text.isascii() and text.isdigit() else None


@dataclass(frozen=True)
class Body:
    """The body of the message whose :class:`Head` came before it."""

    data: bytes


@dataclass(frozen=True)
class EndOfStream:
    """The stream ended between two messages (no byte of another one had arrived)."""


Event = Head | Body | EndOfStream


def parse_head(head: bytes) -> tuple[str, dict[str, str]]:
    """The start line and the header fields (names lower-cased) of a head without its blank line.

    Raises:
        XmlRpcError: a header line without a colon.
    """
    lines = head.decode("latin-1").split("\r\n")
    headers: dict[str, str] = {}
    for line in lines[1:]:
        if not line:
            continue
        name, sep, value = line.partition(":")
        if not sep:
            raise XmlRpcError(f"malformed HTTP header line: {line[:80]!r}")
        headers[name.strip().lower()] = value.strip()
    return lines[0], headers


def content_length(headers: dict[str, str], max_body: int) -> int | None:
    """The ``Content-Length`` the headers declare, checked against ``max_body``; None if absent.

    Raises:
        XmlRpcError: not a non-negative integer.
        XmlRpcTooLargeError: over ``max_body``.
    """
    text = headers.get("content-length")
    if text is None:
        return None
    try:
        length = int(text)
    except ValueError:
        raise XmlRpcError(f"bad Content-Length {text!r}") from None
    if length < 0:
        raise XmlRpcError(f"bad Content-Length {text!r}")
    if length > max_body:
        raise XmlRpcTooLargeError(f"HTTP body of {length} bytes, over the limit of {max_body}")
    return length


def request_message(host: str, port: int, path: str, body: bytes) -> bytes:
    """The client's ``POST`` of an XML-RPC ``body`` to ``http://host:port/path``, on a
    connection it closes after the reply (``host`` as a URI writes it: IPv6 in brackets)."""
    head = (f"POST {path} HTTP/1.1\r\nHost: {host}:{port}\r\n"
            "User-Agent: rosfpga-lab\r\n"
            f"Content-Type: text/xml\r\nContent-Length: {len(body)}\r\nConnection: close\r\n\r\n")
    return head.encode("latin-1") + body


def response_message(status: str, body: bytes, keep_alive: bool) -> bytes:
    """The server's reply: ``status`` (``200 OK``) and ``body``; ``keep_alive`` says whether the
    connection stays open for another request."""
    head = (f"HTTP/1.1 {status}\r\nServer: rosfpga-lab/XMLRPC\r\n"
            f"Content-Type: text/xml\r\nContent-Length: {len(body)}\r\n"
            f"Connection: {'keep-alive' if keep_alive else 'close'}\r\n\r\n")
    return head.encode("latin-1") + body


def keeps_alive(request: Head) -> bool:
    """Whether the client of ``request`` keeps the connection for another request, as rospy's
    and roscpp's clients expect: HTTP/1.1 unless it says ``Connection: close``, an older
    version only when it says ``Connection: keep-alive``."""
    parts = request.start_line.split()
    version = parts[2] if len(parts) == 3 else "HTTP/1.0"
    connection = request.headers.get("connection", "").lower()
    return (version == "HTTP/1.1" and connection != "close") or connection == "keep-alive"


class HttpDecoder:
    """Incremental decoder of a stream of HTTP messages (see the module docstring).

    Args:
        max_head: the longest head accepted, in bytes.
        max_body: the longest body accepted, declared or (to the end of the stream) received.
        eof_ends_body: a message without ``Content-Length`` has a body that ends with the
            stream (an HTTP/1.0-style reply); otherwise such a message is an error (a request).
    """

    def __init__(self, *, max_head: int = MAX_HTTP_HEAD, max_body: int = MAX_XMLRPC_BODY,
                 eof_ends_body: bool = False) -> None:
        self.max_head = max_head
        self.max_body = max_body
        self.eof_ends_body = eof_ends_body
        self._buf = bytearray()
        self._head: Head | None = None   # a head whose body is still to come
        self._eof = False
        #: bytes of the stream that earlier events took (the offset of the next message's start)
        self.consumed = 0

    @property
    def buffered(self) -> int:
        """Bytes received that no event has taken yet."""
        return len(self._buf)

    @property
    def in_message(self) -> bool:
        """True once a byte of a message is in and that message is not complete."""
        return self._head is not None or bool(self._buf)

    def receive(self, data: bytes | bytearray | memoryview) -> None:
        """Add bytes from the stream; empty ``data`` means the stream ended."""
        if not data:
            self._eof = True
        else:
            self._buf += data

    @property
    def missing(self) -> int:
        """Bytes still to come of a body whose length was declared (0 when none is pending)."""
        length = None if self._head is None else self._head.content_length
        return 0 if length is None else max(0, length - len(self._buf))

    def next_event(self) -> Event | None:
        """The next :class:`Head`, :class:`Body` or :class:`EndOfStream`; None: feed more bytes.

        Raises:
            XmlRpcError: the head is longer than ``max_head`` or malformed, a request has no
                ``Content-Length`` or a bad one, or the stream ended inside a message.
            XmlRpcTooLargeError: the body is (or declares to be) longer than ``max_body``.
        """
        if self._head is None:
            return self._next_head()
        return self._next_body(self._head)

    def _next_head(self) -> Head | EndOfStream | None:
        end = self._buf.find(HEAD_END, 0, self.max_head)
        if end < 0:
            if len(self._buf) >= self.max_head:
                raise XmlRpcError(f"HTTP head longer than {self.max_head} bytes")
            if not self._eof:
                return None
            if self._buf:
                raise XmlRpcError(f"connection closed inside an HTTP head ({len(self._buf)} bytes)")
            return EndOfStream()
        raw = bytes(self._buf[:end + len(HEAD_END)])
        start_line, headers = parse_head(raw[:end])
        del self._buf[:len(raw)]
        self.consumed += len(raw)
        self._head = Head(start_line, headers, raw)
        return self._head

    def _next_body(self, head: Head) -> Body | None:
        # checked when the body is asked for, before any of its bytes are held: the caller may
        # answer the head first (a method it does not serve, a body over its budget)
        length = content_length(head.headers, self.max_body)
        if length is None and not self.eof_ends_body:
            raise XmlRpcError("HTTP message without Content-Length")
        if length is None:   # to the end of the stream
            if len(self._buf) > self.max_body:
                raise XmlRpcTooLargeError(f"HTTP body over the limit of {self.max_body} bytes")
            if not self._eof:
                return None
            length = len(self._buf)
        elif len(self._buf) < length:
            if self._eof:
                raise XmlRpcError(f"connection closed after {len(self._buf)} of {length} "
                                  "body bytes")
            return None
        if len(self._buf) == length:   # the usual case: one copy, not a slice and then a copy
            data = bytes(self._buf)
            self._buf.clear()
        else:
            data = bytes(memoryview(self._buf)[:length])
            del self._buf[:length]
        self.consumed += length
        self._head = None
        return Body(data)


__all__ = ["Body", "EndOfStream", "Event", "HEAD_END", "Head", "HttpDecoder", "content_length",
           "keeps_alive", "parse_head", "request_message", "response_message"]
