"""The TCPROS connection header: encode, decode whole, decode incrementally.

On the wire a connection header is::

    uint32 total_length            (little-endian, bytes that follow)
    repeated: uint32 field_length  (little-endian)
              field_length bytes   "key=value" in UTF-8

Both rospy and roscpp write the fields sorted by key (rospy sorts a dict, roscpp iterates a
``std::map``), so :func:`encode_header` sorts too and the lab's bytes equal theirs. A value may
contain ``=``; the key ends at the first one. Decoding checks what rospy checks (zero-length
field, field running past the end, field without ``=``) plus UTF-8 and the size limits, and says
at which byte offset the problem is.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping

from rosfpga_lab.msg.span import ROLE_ERROR, ROLE_LENGTH, ROLE_TRAILING, ROLE_VALUE, Span
from rosfpga_lab.tcpros.errors import HeaderFormatError, IncompleteError
from rosfpga_lab.tcpros.limits import MAX_FIELD_BYTES, MAX_HEADER_BYTES

_U32 = struct.Struct("<I")


def _field_bytes(key: str, value: str | bytes) -> bytes:
    if not isinstance(key, str) or not key or "=" in key:
        raise HeaderFormatError(f"header key {key!r} must be a non-empty string without '='")
    raw_value = value if isinstance(value, bytes) else str(value).encode("utf-8")
    return key.encode("utf-8") + b"=" + raw_value


def encode_header(fields: Mapping[str, str | bytes] | Iterable[tuple[str, str | bytes]],
                  *, sort: bool = True) -> bytes:
    """Encode a connection header, length prefix included.

    Args:
        fields: ``key -> value`` mapping (or pairs). Values are str (UTF-8 encoded) or bytes.
        sort: write fields sorted by key, as rospy and roscpp do (default). False keeps the
            given order (useful to build odd test inputs).

    Returns:
        The header bytes, starting with the 4-byte total length.

    Raises:
        HeaderFormatError: a key is empty, not a string, or contains '='.
    """
    pairs = list(fields.items() if isinstance(fields, Mapping) else fields)
    if sort:
        pairs.sort(key=lambda kv: kv[0].encode("utf-8") if isinstance(kv[0], str) else b"")
    body = b"".join(_U32.pack(len(f)) + f for f in (_field_bytes(k, v) for k, v in pairs))
    return _U32.pack(len(body)) + body


def encode_error_header(message: str) -> bytes:
    """The header a node sends to refuse a connection: a single ``error=<message>`` field."""
    return encode_header({"error": message})


def parse_fields(payload: bytes | memoryview, *, base_offset: int = 4,
                 max_field: int = MAX_FIELD_BYTES, lenient: bool = False) -> list[Span]:
    """Split a header payload (the bytes after the total length) into fields.

    Args:
        payload: the ``total_length`` bytes of fields.
        base_offset: offset of ``payload`` in the stream (span offsets and error messages).
        max_field: largest field length accepted.
        lenient: never raise: the first malformed field and everything after it become one
            ``error`` span whose value is the error message (for viewers of broken bytes).

    Returns:
        Two spans per field, in wire order: its 4-byte length (path ``<key>.length``, role
        ``length``, value the length) and its text (path ``<key>``, type ``key=value``, role
        ``value``, value the value).

    Raises:
        HeaderFormatError: (not lenient) truncated or zero-length field, field over
            ``max_field``, field without '=', bytes that are not UTF-8.
    """
    data = bytes(payload)
    out: list[Span] = []
    pos = 0
    while pos < len(data):
        try:
            key, value, size = _parse_field(data, pos, base_offset, max_field)
        except HeaderFormatError as exc:
            if not lenient:
                raise
            out.append(Span(base_offset + pos, len(data) - pos, "(malformed field)", "bytes",
                            str(exc), ROLE_ERROR))
            break
        where = base_offset + pos
        out.append(Span(where, 4, f"{key}.length", "uint32", size, ROLE_LENGTH))
        out.append(Span(where + 4, size, key, "key=value", value, ROLE_VALUE))
        pos += 4 + size
    return out


def _parse_field(data: bytes, pos: int, base_offset: int, max_field: int) -> tuple[str, str, int]:
    """``(key, value, size)`` of the field whose length starts at ``data[pos]``."""
    where = base_offset + pos
    if len(data) - pos < 4:
        raise HeaderFormatError(
            f"header field length truncated at byte {where}: {len(data) - pos} of 4 bytes left",
            offset=where)
    (size,) = _U32.unpack_from(data, pos)
    if size == 0:
        raise HeaderFormatError(f"zero-length header field at byte {where}", offset=where)
    if size > max_field:
        raise HeaderFormatError(
            f"header field at byte {where} declares {size} bytes, over the limit of "
            f"{max_field} (raise max_field if this is legitimate)", offset=where)
    if pos + 4 + size > len(data):
        raise HeaderFormatError(
            f"header field at byte {where} declares {size} bytes but only "
            f"{len(data) - pos - 4} remain in the header", offset=where)
    raw = data[pos + 4:pos + 4 + size]
    try:
        line = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad = where + 4 + exc.start
        raise HeaderFormatError(
            f"header field at byte {where} is not UTF-8 (byte {bad}: {raw[exc.start]:#04x})",
            offset=bad) from None
    key, sep, value = line.partition("=")
    if not sep:
        raise HeaderFormatError(
            f"header field at byte {where} has no '=': {line[:60]!r}", offset=where)
    if not key:
        raise HeaderFormatError(f"header field at byte {where} has an empty key", offset=where)
    return key, value, size


def header_spans(raw: bytes | memoryview, *, lenient: bool = True,
                 max_field: int = MAX_FIELD_BYTES) -> list[Span]:
    """Spans of a whole connection header: its total length, its fields (:func:`parse_fields`),
    then any bytes after it (``trailing``). Every byte of ``raw`` is in one span.

    Args:
        raw: the header bytes, from its 4-byte total length on.
        lenient: (default) never raise; a header cut short or a bad field gets an ``error``
            span. False: raise as :func:`parse_fields` does.
        max_field: largest field length accepted.

    Raises:
        HeaderFormatError, IncompleteError: only when not ``lenient``.
    """
    data = bytes(raw)
    if len(data) < 4:
        if not lenient:
            raise IncompleteError(f"connection header length truncated: {len(data)} of 4 bytes",
                                  offset=len(data))
        return [Span(0, len(data), "header length (truncated)", "uint32",
                     f"{len(data)} of 4 bytes", ROLE_ERROR)] if data else []
    (total,) = _U32.unpack_from(data, 0)
    end = min(len(data), 4 + total)
    if not lenient and end < 4 + total:
        raise IncompleteError(f"connection header declares {total} bytes, only {end - 4} given",
                              offset=end)
    spans = [Span(0, 4, "header length", "uint32", total, ROLE_LENGTH)]
    spans += parse_fields(data[4:end], base_offset=4, max_field=max_field, lenient=lenient)
    if len(data) > end:
        spans.append(Span(end, len(data) - end, "(after the header)", "bytes", None, ROLE_TRAILING))
    return spans


def decode_header(data: bytes | memoryview, *, max_header: int = MAX_HEADER_BYTES,
                  max_field: int = MAX_FIELD_BYTES) -> tuple[dict[str, str], int]:
    """Decode one complete header from the start of ``data``.

    Returns:
        ``(fields, consumed)``: the key/value dict (a repeated key keeps its last value, as in
        rospy and roscpp) and how many bytes of ``data`` the header used.

    Raises:
        IncompleteError: ``data`` ends before the header does.
        HeaderFormatError: see :func:`parse_fields`; also a total length over ``max_header``.
    """
    dec = HeaderDecoder(max_header=max_header, max_field=max_field)
    fields = dec.feed(data)
    if fields is None:
        dec.eof()
    return fields, dec.consumed  # type: ignore[return-value]


class HeaderDecoder:
    """Incremental header decoder: feed any chunks, get the fields once complete.

    After completion, :attr:`remainder` holds the bytes that followed the header in the
    chunks fed (the start of the first message frame, if the peer sent it at once).
    """

    def __init__(self, *, max_header: int = MAX_HEADER_BYTES,
                 max_field: int = MAX_FIELD_BYTES) -> None:
        self.max_header = max_header
        self.max_field = max_field
        self._buf = bytearray()
        self._need: int | None = None
        self.fields: dict[str, str] | None = None
        self.layout: list[Span] = []
        self.raw: bytes = b""
        self.remainder: bytes = b""

    @property
    def done(self) -> bool:
        """True once a whole header has been decoded."""
        return self.fields is not None

    @property
    def consumed(self) -> int:
        """Bytes of the stream the header occupied (0 until complete)."""
        return len(self.raw)

    def feed(self, data: bytes | memoryview) -> dict[str, str] | None:
        """Add bytes; return the header fields once complete, else None.

        Raises:
            HeaderFormatError: bad total length or a bad field (the decoder is then unusable).
        """
        if self.fields is not None:
            self.remainder += bytes(data)
            return self.fields
        self._buf += data
        if self._need is None and len(self._buf) >= 4:
            (total,) = _U32.unpack_from(self._buf, 0)
            if total > self.max_header:
                raise HeaderFormatError(
                    f"connection header declares {total} bytes, over the limit of "
                    f"{self.max_header}: not a TCPROS peer, or raise max_header", offset=0)
            self._need = 4 + total
        if self._need is None or len(self._buf) < self._need:
            return None
        raw = bytes(self._buf[:self._need])
        self.layout = parse_fields(raw[4:], base_offset=4, max_field=self.max_field)
        self.fields = {s.path: s.value for s in self.layout if s.role == ROLE_VALUE}
        self.raw = raw
        self.remainder = bytes(self._buf[self._need:])
        self._buf = bytearray()
        return self.fields

    def eof(self) -> None:
        """Tell the decoder the stream ended.

        Raises:
            IncompleteError: the header was not complete.
        """
        if self.fields is None:
            have = len(self._buf)
            want = f"{self._need} bytes" if self._need is not None else "at least 4 bytes"
            raise IncompleteError(
                f"connection closed before the connection header was complete: got {have} "
                f"bytes, needed {want}", offset=have)
