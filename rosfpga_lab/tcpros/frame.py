"""TCPROS message framing: ``uint32 length`` (little-endian) then ``length`` body bytes.

:class:`FrameDecoder` accepts any chunking: one byte at a time, many frames in one chunk, a
frame split over chunks. When a whole frame sits inside one chunk it is returned as a
zero-copy ``memoryview`` of that chunk; a frame assembled from several chunks is returned as
a ``bytearray`` (the bytes copied into it as they arrive, then handed over). Either way the
caller gets a bytes-like object; call ``bytes(body)`` for an immutable copy.

Memory follows the bytes received, never the length a peer declares: a frame's buffer starts
at most :data:`FRAME_BUFFER_FIRST` bytes long and at most doubles (by 4 MiB at most) each
time it fills, so a
peer that declares 60 MiB and sends 1 MiB costs about 2 MiB. For big frames a reader can skip
the copy: once a frame's length prefix has been fed, :meth:`FrameDecoder.pending_body` lends
the still-empty room of that frame's buffer (growing it first when it is full); the reader
receives straight into it (``sock.recv_into``) and reports the byte count with
:meth:`FrameDecoder.filled`. The decoder keeps every framing rule (the length limit is checked
when the prefix arrives, before any buffer exists); the reader only chooses where bytes land.
"""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING

from rosfpga_lab.msg.span import ROLE_ERROR, ROLE_LENGTH, ROLE_TRAILING, ROLE_VALUE, Span
from rosfpga_lab.tcpros.errors import FrameError, IncompleteError, StateError
from rosfpga_lab.tcpros.limits import FRAME_BUFFER_FIRST, MAX_FRAME_BYTES

_U32 = struct.Struct("<I")
#: Zeros a growing body buffer is extended with (its largest step). Never written, so its pages
#: stay unmapped/shared: it costs address space, not memory.
_ZEROS = bytes(4 << 20)

if TYPE_CHECKING:
    from rosfpga_lab.msg import MsgRegistry


def encode_frame(body: bytes | bytearray | memoryview) -> bytes:
    """Prefix ``body`` with its 4-byte little-endian length."""
    return _U32.pack(len(body)) + bytes(body)


def frame_prefix(length: int) -> bytes:
    """Just the 4-byte length prefix (send it, then the body, to avoid copying a big body)."""
    return _U32.pack(length)


class FrameDecoder:
    """Incremental frame decoder.

    Args:
        max_frame: largest body length accepted (checked when the prefix arrives).
        stream_offset: stream offset of the first byte fed (for error messages).
        first_buffer: first size of a lent body buffer (see the module docstring).

    Attributes:
        frames: number of complete frames returned so far.
        offset: bytes consumed from the stream so far (for error messages).
    """

    def __init__(self, *, max_frame: int = MAX_FRAME_BYTES, stream_offset: int = 0,
                 first_buffer: int = FRAME_BUFFER_FIRST) -> None:
        self.max_frame = max_frame
        self.first_buffer = max(1, first_buffer)
        self.frames = 0
        self.offset = stream_offset
        self._prefix = bytearray()
        self._body: bytearray | None = None  # the frame being assembled (its room may exceed _have)
        self._length = 0                      # its declared length
        self._have = 0                        # body bytes received
        self._start = stream_offset
        #: stream offsets of the length prefixes of the frames returned by the last feed()
        self.starts: list[int] = []

    @property
    def in_frame(self) -> bool:
        """True when part of a frame (prefix or body) has been fed but not completed."""
        return bool(self._prefix) or self._body is not None

    def _check(self, length: int) -> None:
        if length > self.max_frame:
            raise FrameError(
                f"frame at stream byte {self._start} declares {length} bytes, over the limit of "
                f"{self.max_frame}: the stream is out of sync, or raise max_frame",
                offset=self._start)

    def feed(self, data: bytes | bytearray | memoryview) -> list[bytes | bytearray | memoryview]:
        """Add bytes; return every frame body completed by them (possibly none).

        Raises:
            FrameError: a length prefix over ``max_frame`` (the decoder is then unusable); the
                frames completed before it are in the exception's ``partial`` list.
        """
        out: list[bytes | bytearray | memoryview] = []
        self.starts = []
        try:
            self._feed(data, out)
        except FrameError as exc:
            exc.partial = out
            raise
        return out

    def _feed(self, data: bytes | bytearray | memoryview, out: list) -> None:
        view = memoryview(data).cast("B") if not isinstance(data, memoryview) else data.cast("B")
        pos, end = 0, len(view)
        while pos < end:
            if self._body is None:
                if not self._prefix:
                    self._start = self.offset
                if not self._prefix and end - pos >= 4:
                    (length,) = _U32.unpack_from(view, pos)
                    self._check(length)
                    if end - pos - 4 >= length:  # whole frame in this chunk: zero copy
                        out.append(view[pos + 4:pos + 4 + length])
                        self.starts.append(self._start)
                        pos += 4 + length
                        self.offset += 4 + length
                        self.frames += 1
                        continue
                    self._start_body(length)
                    pos += 4
                    self.offset += 4
                    continue
                take = min(4 - len(self._prefix), end - pos)
                self._prefix += view[pos:pos + take]
                pos += take
                self.offset += take
                if len(self._prefix) < 4:
                    break
                (length,) = _U32.unpack_from(self._prefix, 0)
                self._check(length)
                self._prefix = bytearray()
                if length == 0:
                    out.append(b"")
                    self.starts.append(self._start)
                    self.frames += 1
                    continue
                self._start_body(length)
            take = min(self._length - self._have, end - pos)
            h = self._have
            assert self._body is not None  # a body buffer exists once a length prefix was read
            if len(self._body) - h >= take:
                self._body[h:h + take] = view[pos:pos + take]
            else:  # replaces the room left and grows by the rest: memory = bytes received
                self._body[h:] = view[pos:pos + take]
            pos += take
            self._advance(take, out)

    def _start_body(self, length: int) -> None:
        self._body = bytearray()
        self._length = length
        self._have = 0

    def _advance(self, n: int, out: list) -> None:
        """``n`` more body bytes are in ``self._body``; hand the frame over when it is complete."""
        assert self._body is not None
        self._have += n
        self.offset += n
        if self._have == self._length:
            if len(self._body) > self._have:
                del self._body[self._have:]
            out.append(self._body)  # a fresh buffer per frame: hand it over, no copy
            self.starts.append(self._start)
            self._body = None
            self.frames += 1

    def pending_body(self) -> memoryview | None:
        """Room in the frame body being assembled, to receive into; else None.

        The room is never larger than what the frame still misses; when the buffer is full it
        first grows to at most twice the bytes received so far (at least ``first_buffer``,
        by 4 MiB at most), so memory follows received bytes. None between frames and
        inside a length prefix: then :meth:`feed` the next bytes. Write into the view (e.g.
        ``n = sock.recv_into(view)``), release it, then call :meth:`filled`.
        """
        if self._body is None:
            return None
        if len(self._body) == self._have:
            room = min(self._length - self._have, max(self._have, self.first_buffer), len(_ZEROS))
            try:  # in place (realloc), from one shared zero block: no temporary per growth
                self._body += memoryview(_ZEROS)[:room]
            except BufferError:  # the reader still holds a view: grow into a new buffer
                grown = bytearray(self._have + room)
                grown[:self._have] = self._body
                self._body = grown
        return memoryview(self._body)[self._have:]

    def filled(self, n: int) -> list[bytearray]:
        """Account ``n`` bytes written into the view of :meth:`pending_body`.

        Returns:
            ``[body]`` when those bytes complete the frame (the buffer itself, no copy), else [].

        Raises:
            StateError: no frame body is pending, or ``n`` is not in 1..bytes still missing.
        """
        missing = 0 if self._body is None else self._length - self._have
        room = 0 if self._body is None else len(self._body) - self._have
        if not 0 < n <= room:
            raise StateError(f"filled({n}): the pending frame body misses {missing} bytes, its "
                             f"buffer has room for {room} (write into pending_body() first; "
                             "feed() between frames)")
        out: list[bytearray] = []
        self.starts = []
        self._advance(n, out)
        return out

    def eof(self) -> None:
        """Tell the decoder the stream ended.

        Raises:
            IncompleteError: the stream ended inside a frame.
        """
        if self._prefix:
            raise IncompleteError(
                f"connection closed inside a frame's length prefix ({len(self._prefix)} of 4 "
                f"bytes, stream byte {self.offset})", offset=self.offset)
        if self._body is not None:
            raise IncompleteError(
                f"connection closed mid-frame: {self._have} of {self._length} body bytes "
                f"received (stream byte {self.offset})", offset=self.offset)


def frame_spans(raw: bytes | memoryview, type_name: str | None = None, *,
                registry: MsgRegistry | None = None) -> list[Span]:
    """Spans of one message frame, leniently: its 4-byte length (``frame length``), then the body
    by fields when ``type_name`` is given and the body is complete, else one ``message body``
    span; bytes past the frame are ``(next frame)``. Never raises on bad bytes (an undecodable
    body ends in an ``error`` span, as :func:`rosfpga_lab.msg.field_layout` makes in partial mode).

    Args:
        raw: the frame, from its length prefix on.
        type_name: the message type, e.g. ``sensor_msgs/Image``; None: the body is not split.
        registry: a :class:`~rosfpga_lab.msg.MsgRegistry`; default: the shipped types.
    """
    data = bytes(raw)
    if len(data) < 4:
        return [Span(0, len(data), "frame length (truncated)", "uint32", f"{len(data)} of 4 bytes",
                     ROLE_ERROR)]
    (length,) = _U32.unpack_from(data, 0)
    spans = [Span(0, 4, "frame length", "uint32", length, ROLE_LENGTH)]
    body = data[4:]
    if not body:
        return spans
    if type_name is not None and len(body) >= length:
        from rosfpga_lab.msg import default_registry, field_layout

        reg = registry if registry is not None else default_registry()
        for s in field_layout(reg, type_name, body[:length], partial=True):
            spans.append(s.moved(4) if s.path else Span(s.offset + 4, s.size, f"({s.role})", s.type,
                                                         s.value, s.role))
        if len(body) > length:
            spans.append(Span(4 + length, len(body) - length, "(next frame)", "bytes", None,
                              ROLE_TRAILING))
        return spans
    note = f"{len(body)} of {length} body bytes recorded" if len(body) < length else f"{length} bytes"
    spans.append(Span(4, len(body), "message body", "bytes", note, ROLE_VALUE))
    return spans
