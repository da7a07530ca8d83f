"""Where every byte of a serialized message comes from: :func:`field_layout`.

How this works: a deliberately plain reader walks the message one field at a time with
``struct`` (no compiled plans, no grouping), recording a :class:`FieldSpan` for each value and
each length prefix. It is also the *reference model* of :mod:`decode`:
:func:`deserialize_reference` returns the same values the fast decoder does, and a property
test holds them equal. The spans of a whole message cover every byte exactly once; spans of size
zero (an empty string's text, an empty array's elements) are left out.

Roles: ``"length"`` (a uint32 length prefix of a string or variable array), ``"value"`` (one
scalar, one time/duration half, or one string's bytes), ``"array"`` (a block of numeric array
elements in one span, used when the array has more than ``element_spans`` elements), and in
``partial`` mode ``"error"`` (the undecodable rest) and ``"trailing"`` (bytes after the message).
"""

from __future__ import annotations

import struct
from typing import Any

from rosfpga_lab.msg.builtins import SCALARS, TIME_CLASS
from rosfpga_lab.msg.decode import min_size
from rosfpga_lab.msg.errors import DeserializeError
from rosfpga_lab.msg.limits import DEFAULT_LIMITS, LAYOUT_ELEMENT_SPANS, MsgLimits
from rosfpga_lab.msg.parser import Field
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.span import ROLE_LENGTH, ROLE_VALUE, Span
from rosfpga_lab.msg.spanreader import SpanReader

#: The span type of a message layout (the lab's one :class:`~rosfpga_lab.msg.span.Span`).
FieldSpan = Span


class _Reader(SpanReader):
    """Plain field-by-field TCPROS reader that records spans."""

    def _span(self, path: str, start: int, type_: str, value: Any, role: str) -> None:
        if self.pos > start:
            self.spans.append(Span(start, self.pos - start, path, type_, value, role))

    def scalar(self, kind: str, path: str) -> Any:
        start = self.pos
        sc = SCALARS[kind]
        (value,) = struct.unpack("<" + sc.struct_char, self._take(sc.size, path, kind))
        self._span(path, start, kind, value, ROLE_VALUE)
        return value

    def length(self, path: str, elem_min: int, limit: int, limit_name: str) -> int:
        start = self.pos
        (n,) = struct.unpack("<I", self._take(4, path, "the uint32 length prefix"))
        self._span(path, start, "uint32", n, ROLE_LENGTH)
        return self.check_length(path, start, n, elem_min, limit, limit_name)

    def string(self, path: str) -> str:
        n = self.length(path, 1, self.limits.max_string_bytes, "max_string_bytes")
        start = self.pos
        text = bytes(self._take(n, path, "string")).decode("utf-8", "surrogateescape")
        self._span(path, start, "string", text, ROLE_VALUE)
        return text

    def element(self, base: str, path: str) -> Any:
        if base in SCALARS:
            value = self.scalar(base, path)
            return bool(value) if base == "bool" else value
        if base in TIME_CLASS:
            half = "uint32" if base == "time" else "int32"
            return TIME_CLASS[base](self.scalar(half, f"{path}.secs"),
                                    self.scalar(half, f"{path}.nsecs"))
        if base == "string":
            return self.string(path)
        return self.message(base, path)

    def field(self, f: Field, path: str) -> Any:
        if not f.is_array:
            return self.element(f.base_type, path)
        base = f.base_type
        if base in SCALARS:
            elem_min = SCALARS[base].size
        elif base in TIME_CLASS:
            elem_min = 8
        elif base == "string":
            elem_min = 4
        else:
            elem_min = min_size(self.reg, base)
        if f.array_length is None:
            n = self.length(path, elem_min, self.limits.max_array_length, "max_array_length")
            if elem_min == 0 and n > self.limits.max_empty_elements:
                raise DeserializeError(
                    f"field {path}: length prefix at byte offset {self.pos - 4} declares {n} "
                    f"elements of {base} (0 bytes each), more than max_empty_elements="
                    f"{self.limits.max_empty_elements}", path, self.pos - 4)
        else:
            n = f.array_length
        if base in SCALARS:
            return self.scalar_array(base, f.type, n, path)
        return [self.element(base, f"{path}[{i}]") for i in range(n)]

    def message(self, type_name: str, prefix: str = "") -> dict:
        spec = self.reg.check(type_name)
        out = {}
        for f in spec.fields:
            out[f.name] = self.field(f, f"{prefix}.{f.name}" if prefix else f.name)
        return out


def _read(reg: MsgRegistry, type_name: str, data: Any, allow_trailing: bool, partial: bool,
          limits: MsgLimits, element_spans: int) -> tuple[dict | None, list[FieldSpan]]:
    return _Reader(reg, data, limits, element_spans).read(type_name, allow_trailing, partial)


def field_layout(reg: MsgRegistry, type_name: str, data: Any, *, allow_trailing: bool = False,
                 partial: bool = False, limits: MsgLimits = DEFAULT_LIMITS,
                 element_spans: int = LAYOUT_ELEMENT_SPANS) -> list[FieldSpan]:
    """The byte layout of a serialized message, one :class:`FieldSpan` per value or prefix.

    Args:
        reg: the registry holding the type.
        type_name: e.g. ``sensor_msgs/Image``.
        data: the message body.
        allow_trailing: accept bytes after the message (they get a ``trailing`` span).
        partial: never raise on bad bytes; the undecodable rest gets one ``error`` span whose
            value is the error message (for byte viewers of broken frames).
        limits: limits on declared lengths.
        element_spans: numeric arrays longer than this get one ``array`` span.

    Returns:
        Spans in byte order; together they cover the body exactly once.

    Raises:
        DeserializeError: (unless ``partial``) as :func:`deserialize` would.
    """
    return _read(reg, type_name, data, allow_trailing, partial, limits, element_spans)[1]


def deserialize_reference(reg: MsgRegistry, type_name: str, data: Any, *,
                          allow_trailing: bool = False,
                          limits: MsgLimits = DEFAULT_LIMITS) -> dict:
    """The plain reference decoder: same result as :func:`deserialize`, one field at a time."""
    value, _spans = _read(reg, type_name, data, allow_trailing, False, limits,
                          LAYOUT_ELEMENT_SPANS)
    assert value is not None
    return value
