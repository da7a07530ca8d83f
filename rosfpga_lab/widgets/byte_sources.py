"""Adapters: field spans for the byte viewer from messages, TCPROS and HTTP/XML-RPC bytes.

Each function takes raw bytes (plus what it needs to interpret them) and returns a list of
:class:`~rosfpga_lab.msg.Span` (the lab's one span type), covering the bytes in order. TCPROS
headers and frames are split by the tcpros parsers in their lenient mode. They never raise on
malformed input: what cannot be parsed gets one ``error`` span whose value says why, so a broken
frame can still be looked at byte by byte.
"""

from __future__ import annotations

import re
import struct
import xmlrpc.client
from typing import Any

from rosfpga_lab.tcpros import frame_spans, header_spans
from rosfpga_lab.widgets.byteview import ByteViewer, Span

_U32 = struct.Struct("<I")


def spans_from_field_layout(layout: list[Any], base: int = 0) -> list[Span]:
    """Spans from ``rosfpga_lab.msg.field_layout`` output, shifted by ``base`` bytes (an unnamed
    span is named by its role, e.g. ``(trailing)``)."""
    return [Span(f.offset + base, f.size, f.path or f"({f.role})", f.type, f.value, f.role) for f in layout]


def pixel_label(index: int, width: int, step: int, encoding: str) -> str:
    """What byte ``index`` of an Image's ``data`` is: ``data[5] = pixel (x 1, y 0) G``.

    The channel letter comes from the encoding's lanes (``rosfpga_lab.hw.PIXEL_FORMATS``);
    for an encoding the lab does not model, the byte's number within the pixel is given.
    """
    from rosfpga_lab.hw import PIXEL_FORMATS

    fmt = PIXEL_FORMATS.get(encoding)
    bpp = fmt.bytes_per_pixel if fmt else (step // width if width and step >= width else 1)
    y, in_row = divmod(index, step) if step else (0, index)
    x, k = divmod(in_row, bpp)
    if x >= width:   # row padding past the last pixel
        return f"data[{index}] = row {y} padding"
    channel = fmt.channels[k] if fmt else f"byte {k}"
    return f"data[{index}] = pixel (x {x}, y {y}) {channel}"


def _label_pixels(spans: list[Span]) -> list[Span]:
    by = {s.path: s for s in spans}
    width, step, enc = (by.get(k) for k in ("width", "step", "encoding"))
    if width is None or step is None or enc is None or not isinstance(width.value, int):
        return spans
    out = []
    for s in spans:
        if s.path.startswith("data[") and s.path.endswith("]") and s.path[5:-1].isdigit():
            s = Span(s.offset, s.size, pixel_label(int(s.path[5:-1]), width.value, step.value or 0,
                                                   str(enc.value)), s.type, s.value, s.role)
        out.append(s)
    return out


def message_spans(type_name: str, body: bytes, *, registry: Any = None, base: int = 0) -> list[Span]:
    """Spans of a serialized ROS message body (every byte in one span; bad bytes in an ``error`` span).

    An Image's pixel bytes are named by pixel and channel (:func:`pixel_label`).

    Args:
        type_name: e.g. ``sensor_msgs/Image``.
        body: the serialized message (without the TCPROS 4-byte frame length).
        registry: a ``rosfpga_lab.msg.MsgRegistry``; default: the shipped types.
        base: offset added to every span (e.g. 4 when ``body`` follows a frame prefix).
    """
    from rosfpga_lab import msg

    reg = registry if registry is not None else msg.default_registry()
    spans = spans_from_field_layout(msg.field_layout(reg, type_name, body, partial=True), base)
    # an image's pixel bytes are named by pixel and channel, not only by index
    return _label_pixels(spans) if type_name == "sensor_msgs/Image" else spans


def message_viewer(type_name: str, body: bytes, *, registry: Any = None, title: str = "", **kwargs: Any) -> ByteViewer:
    """A :class:`ByteViewer` of one serialized message, fields from the message layout."""
    return ByteViewer(body, message_spans(type_name, body, registry=registry), title=title or type_name, **kwargs)


def spans_from_frame(raw: bytes, type_name: str | None = None, *, registry: Any = None) -> list[Span]:
    """Spans of a TCPROS message frame: the 4-byte length, then the body (by fields if
    ``type_name``); :func:`rosfpga_lab.tcpros.frame_spans`."""
    return frame_spans(raw, type_name, registry=registry)


def spans_from_connection_header(raw: bytes) -> list[Span]:
    """Spans of a TCPROS connection header: total length, then each field's length and ``key=value``.

    A field's span is named by its key and its value is the field's value; its length prefix is
    ``<key>.length``. This is :func:`rosfpga_lab.tcpros.header_spans` (the tcpros parser in its
    lenient mode): the first malformed field and everything after it become one ``error`` span.
    """
    return header_spans(raw, lenient=True)


def spans_from_tcpros_stream(raw: bytes, type_name: str | None = None, *, registry: Any = None) -> list[Span]:
    """Spans of one direction of a TCPROS connection: the connection header, then message frames.

    Header spans are named as in :func:`spans_from_connection_header`; frame ``k``'s spans are
    prefixed ``msg[k].`` (``msg[0].frame length``, ``msg[0].header.seq`` ...). A frame cut off by
    the end of ``raw`` is labelled as such.
    """
    if len(raw) < 4:
        return spans_from_connection_header(raw)
    (total,) = _U32.unpack_from(raw, 0)
    end = min(len(raw), 4 + total)
    spans = [s for s in spans_from_connection_header(raw[:end])]
    pos, k = end, 0
    while pos < len(raw):
        rest = raw[pos:]
        length = _U32.unpack_from(rest, 0)[0] if len(rest) >= 4 else None
        chunk = rest if length is None else rest[:4 + length]
        full = length is not None and len(chunk) == 4 + length
        inner = spans_from_frame(chunk, type_name if full else None, registry=registry)
        spans += [sp.moved(pos, f"msg[{k}].") for sp in inner]
        pos += len(chunk)
        k += 1
    return spans


_XML_PIECES = re.compile(rb"<methodName>.*?</methodName>|<param>.*?</param>|<fault>.*?</fault>", re.S)


def _xmlrpc_values(body: bytes) -> tuple[str | None, list[Any]]:
    try:
        params, method = xmlrpc.client.loads(body.decode("utf-8", errors="replace"))
        return method, list(params)
    except Exception:  # noqa: BLE001 - any parse failure: just no decoded values
        return None, []


def spans_from_http(raw: bytes) -> list[Span]:
    """Spans of an HTTP request or response (as XML-RPC sends them).

    The start line, each header line (named by its header), the blank line that ends the
    headers, and the body; an XML-RPC body is split further into ``methodName`` and one span
    per ``param`` (valued with the decoded parameter), the XML between them as ``xml``.
    """
    spans: list[Span] = []
    head_end = raw.find(b"\r\n\r\n")
    head_stop = len(raw) if head_end < 0 else head_end + 2
    pos = 0
    first = True
    while pos < head_stop:
        nl = raw.find(b"\r\n", pos, head_stop)
        stop = head_stop if nl < 0 else nl + 2
        line = raw[pos:stop].rstrip(b"\r\n").decode("latin-1")
        if first:
            kind = "status line" if line.startswith("HTTP/") else "request line"
            spans.append(Span(pos, stop - pos, kind, "http", line, "value"))
            first = False
        else:
            name, _, value = line.partition(":")
            spans.append(Span(pos, stop - pos, f"header {name.strip()}", "http", value.strip(), "value"))
        pos = stop
    if head_end < 0:
        return spans
    spans.append(Span(head_end + 2, 2, "end of headers", "CRLF", None, "length"))
    body_at = head_end + 4
    body = raw[body_at:]
    if not body:
        return spans
    method, params = _xmlrpc_values(body)
    pieces = list(_XML_PIECES.finditer(body))
    if not pieces:
        spans.append(Span(body_at, len(body), "body", "bytes", None, "value"))
        return spans
    pos, k = 0, 0
    for m in pieces:
        if m.start() > pos:
            spans.append(Span(body_at + pos, m.start() - pos, "xml", "xml", None, "padding"))
        tag = m.group(0)
        if tag.startswith(b"<methodName>"):
            spans.append(Span(body_at + m.start(), m.end() - m.start(), "methodName", "xml", method, "value"))
        elif tag.startswith(b"<fault>"):
            spans.append(Span(body_at + m.start(), m.end() - m.start(), "fault", "xml", None, "error"))
        else:
            param = params[k] if k < len(params) else None
            names = api_param_names(method) if method else ()
            name = names[k] if k < len(names) else f"param[{k}]"
            spans.append(Span(body_at + m.start(), m.end() - m.start(), name, "xml", param, "value"))
            k += 1
        pos = m.end()
    if pos < len(body):
        spans.append(Span(body_at + pos, len(body) - pos, "xml", "xml", None, "padding"))
    return spans


def api_param_names(method: str) -> tuple[str, ...]:
    """The parameter names of a ROS Master or Slave API call (``caller_id``, ``topic``, ...),
    as the lab's master and node declare them; ``()`` for a method they do not serve."""
    from rosfpga_lab.graph import EmbeddedMaster, Node

    for cls in (EmbeddedMaster, Node):
        for attr in vars(cls).values():
            if getattr(attr, "ros_api", False) and getattr(attr, "ros_name", attr.__name__) == method:
                return tuple(getattr(attr, "ros_params", ()))
    return ()


def spans_for(raw: bytes, kind: str = "", type_name: str | None = None) -> list[Span]:
    """Spans for bytes of a known ``kind`` (``xmlrpc``/``http``, ``tcpros_header``,
    ``tcpros_frame``); with no kind, HTTP is recognised by its first bytes, else one span."""
    kind = kind.lower()
    if "header" in kind:
        return spans_from_connection_header(raw)
    if "frame" in kind or "message" in kind:
        return spans_from_frame(raw, type_name)
    if "http" in kind or "xmlrpc" in kind or raw.startswith((b"POST ", b"GET ", b"HTTP/")):
        return spans_from_http(raw)
    return [Span(0, len(raw), "bytes", "bytes", None, "value")] if raw else []


def view_bytes(raw: bytes, kind: str = "", type_name: str | None = None, *, title: str = "", **kwargs: Any) -> ByteViewer:
    """A :class:`ByteViewer` of ``raw`` with fields worked out by :func:`spans_for`.

    Example: ``view_bytes(header_bytes, "tcpros_header")``, ``view_bytes(frame, "tcpros_frame",
    "sensor_msgs/Image")``, ``view_bytes(http_request)`` (HTTP is recognised by itself).
    """
    return ByteViewer(raw, spans_for(raw, kind, type_name), title=title, **kwargs)


def spans_from_layout(layout: Any, message: Any) -> list[Span]:
    """Spans of a TCPROS frame as the circuit of ``layout`` (``rosfpga_lab.hw.layout.Layout``)
    walks it: one per field read, named by its label with indices filled in, its role what the
    circuit does with it (``stream``, ``check``, ``carry``, ``skip``; ``length`` for a length
    prefix). ``message`` holds the frame's values (``rosfpga_lab.msg.deserialize`` of its body).
    """
    from rosfpga_lab.hw.layout import StepKind, encode_token, tokens

    first = layout.steps[0]
    out = [Span(0, 4, first.label, first.type, None, "length")]
    offset = 4
    for t in tokens(layout, message):
        step = layout.steps[t.step]
        n = len(encode_token(step, t.value))
        kind = str(step.kind)
        role = "length" if step.kind is StepKind.LENGTH else str(step.action)
        type_ = f"{step.type}[{len(t.value)}]" if kind == "array" else step.type
        out.append(Span(offset, n, step.label_at(t.at), type_, t.value, role))
        offset += n
    out[0] = Span(0, 4, first.label, first.type, offset - 4, "length")
    return out
