"""CDR, the ROS 2 wire format: XCDR1 little-endian with its encapsulation header, as rmw sends.

How this works: a ROS 2 message on the wire (the serialized payload of an RTPS DATA) starts
with a 4-byte *encapsulation header*, ``00 01 00 00`` for CDR little-endian (the two option
bytes are zero). Then come the fields in declaration order, like TCPROS, with three
differences: every primitive of size 2, 4 or 8 starts at a multiple of its size, counted from
the byte *after* the encapsulation header (the gap is filled with padding bytes); a string's
uint32 length counts its terminating NUL, which is sent; and the types are the ROS 2 forms
(:mod:`rosfpga_lab.msg.ros2`: ``builtin_interfaces/Time``, no ``Header.seq``). Sequences
(``T[]``) carry a uint32 element count (aligned to 4), fixed arrays none; a nested message adds
no alignment of its own; a message with no fields is one zero byte (rosidl's
``structure_needs_at_least_one_member``).

:func:`serialize_cdr` writes a payload, :func:`deserialize_cdr` reads one and
:func:`cdr_layout` tells where every byte came from, as ``field_layout`` does for TCPROS, with
``padding`` spans for the alignment bytes and an ``encapsulation`` span for the header. Use a
registry of ROS 2 forms (``ros2_registry()``, the default).
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from rosfpga_lab.msg.builtins import BYTE_ARRAY_TYPES, SCALARS, TIME_CLASS
from rosfpga_lab.msg.encode import _byte_array, _check_scalar, _numeric_array
from rosfpga_lab.msg.errors import DeserializeError, SerializeError
from rosfpga_lab.msg.layout import FieldSpan
from rosfpga_lab.msg.span import ROLE_LENGTH, ROLE_PADDING, ROLE_VALUE, Span
from rosfpga_lab.msg.spanreader import SpanReader
from rosfpga_lab.msg.limits import DEFAULT_LIMITS, LAYOUT_ELEMENT_SPANS, MsgLimits
from rosfpga_lab.msg.parser import Field
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.ros2 import ros2_registry

#: Encapsulation header of CDR little-endian (representation id 0x0001, options 0x0000).
CDR_LE = b"\x00\x01\x00\x00"
#: Encapsulation header of CDR big-endian (recognised, refused).
CDR_BE = b"\x00\x00\x00\x00"
#: Bytes of the encapsulation header; alignment counts from after it.
ENCAPSULATION_SIZE = 4
#: The byte a message with no fields is sent as.
EMPTY_STRUCT = b"\x00"
#: The role of CDR's 4-byte encapsulation header (the other roles are the span vocabulary's).
ROLE_ENCAPSULATION = "encapsulation"


def _align(pos: int, size: int) -> int:
    """Padding bytes needed before a ``size``-byte primitive at body offset ``pos``."""
    return -pos % size if size > 1 else 0


def _no_time(kind: str, path: str, error: type) -> Exception:
    return error(f"field {path}: ROS 1 {kind} has no CDR form; use the ROS 2 types "
                 f"(ros2_registry(), builtin_interfaces/Time)", path, kind)


class _Writer:
    def __init__(self, reg: MsgRegistry) -> None:
        self.reg = reg
        self.out = bytearray(CDR_LE)

    def pad(self, size: int) -> None:
        self.out += bytes(_align(len(self.out) - ENCAPSULATION_SIZE, size))

    def scalar(self, kind: str, value: Any, path: str) -> None:
        sc = SCALARS[kind]
        self.pad(sc.size)
        try:
            if kind == "bool":
                _check_scalar(kind, value, path)
            self.out += struct.pack("<" + sc.struct_char, value)
        except (struct.error, OverflowError, TypeError):
            _check_scalar(kind, value, path)
            raise

    def string(self, value: Any, path: str) -> None:
        if isinstance(value, str):
            data = value.encode("utf-8", "surrogateescape")
        elif isinstance(value, (bytes, bytearray)):
            data = bytes(value)
        else:
            raise SerializeError(f"field {path}: expected string (str or bytes), got "
                                 f"{type(value).__name__}", path, "string")
        self.scalar("uint32", len(data) + 1, path)
        self.out += data + b"\x00"

    def element(self, base: str, value: Any, path: str) -> None:
        if base in SCALARS:
            self.scalar(base, value, path)
        elif base == "string":
            self.string(value, path)
        elif base in TIME_CLASS:
            raise _no_time(base, path, SerializeError)
        else:
            self.message(base, value, path)

    def field(self, f: Field, value: Any, path: str) -> None:
        if not f.is_array:
            self.element(f.base_type, value, path)
            return
        base = f.base_type
        if base in SCALARS:
            arr = (np.frombuffer(_byte_array(value, path, f.type), np.uint8)
                   if base in BYTE_ARRAY_TYPES else _numeric_array(value, path, base, f.type))
            self._count(f, len(arr), path)
            if base == "bool":
                arr = arr.astype(bool)
            if len(arr):
                self.pad(SCALARS[base].size)
            self.out += np.ascontiguousarray(arr, SCALARS[base].dtype).tobytes()
            return
        items = list(value)
        self._count(f, len(items), path)
        for i, item in enumerate(items):
            self.element(base, item, f"{path}[{i}]")

    def _count(self, f: Field, n: int, path: str) -> None:
        if f.array_length is None:
            self.scalar("uint32", n, path)
        elif n != f.array_length:
            raise SerializeError(f"field {path}: expected {f.array_length} elements, got {n}",
                                 path, f.type)

    def message(self, type_name: str, value: Any, prefix: str = "") -> None:
        spec = self.reg.check(type_name)
        if not spec.fields:
            self.out += EMPTY_STRUCT
            return
        for f in spec.fields:
            path = f"{prefix}.{f.name}" if prefix else f.name
            try:
                v = value[f.name] if isinstance(value, dict) else getattr(value, f.name)
            except (KeyError, AttributeError):
                raise SerializeError(f"field {path}: missing from the {spec.full_name} value",
                                     path, f.type) from None
            self.field(f, v, path)


def serialize_cdr(reg: MsgRegistry | None, type_name: str, value: Any) -> bytes:
    """A ROS 2 message value as a CDR payload (encapsulation header included).

    Args:
        reg: a registry of ROS 2 forms (None: ``ros2_registry()`` of the shipped types).
        type_name: e.g. ``sensor_msgs/Image``.
        value: a dict (or object with the fields as attributes) in the ROS 2 form
            (``to_ros2_value`` converts a ROS 1 value).

    Raises:
        SerializeError: a value does not fit its field.
    """
    w = _Writer(reg or ros2_registry())
    w.message(type_name, value)
    return bytes(w.out)


def _may_be_empty(reg: MsgRegistry, type_name: str) -> bool:
    """Whether a message can serialize to no bytes in CDR: only when every field is a
    zero-length fixed array (or such a message); a message with no fields gets ROS 2's one-byte
    placeholder."""
    spec = reg.check(type_name)
    if not spec.fields:
        return False
    for f in spec.fields:
        if f.is_array and f.array_length == 0:
            continue
        if f.is_array and f.array_length is None:
            return False
        base = f.base_type
        if base in SCALARS or base == "string" or base in TIME_CLASS:
            return False
        if not _may_be_empty(reg, base):
            return False
    return True


class _Reader(SpanReader):
    """Plain field-by-field CDR reader that records spans (the decoder and the layout)."""

    body = "payload"

    @staticmethod
    def hold(data: Any) -> memoryview:
        return memoryview(data).cast("B")   # uint8[] values are views into the payload

    def align(self, size: int, path: str) -> None:
        n = _align(self.pos - ENCAPSULATION_SIZE, size)
        if n:
            start = self.pos
            raw = bytes(self._take(n, path, "alignment padding"))
            self.spans.append(Span(start, n, path, "padding", raw, ROLE_PADDING))

    def encapsulation(self) -> None:
        head = bytes(self._take(ENCAPSULATION_SIZE, "", "the encapsulation header"))
        if head[:2] != CDR_LE[:2]:
            kind = "CDR big-endian" if head[:2] == CDR_BE[:2] else f"representation 0x{head[:2].hex()}"
            raise DeserializeError(f"encapsulation header {head.hex(' ')} says {kind}; only CDR "
                                   f"little-endian ({CDR_LE.hex(' ')}) is read", "", 0)
        self.spans.append(Span(0, ENCAPSULATION_SIZE, "", "encapsulation", "CDR_LE", ROLE_ENCAPSULATION))

    def scalar(self, kind: str, path: str, role: str = ROLE_VALUE) -> Any:
        sc = SCALARS[kind]
        self.align(sc.size, path)
        start = self.pos
        (value,) = struct.unpack("<" + sc.struct_char, self._take(sc.size, path, kind))
        self.spans.append(Span(start, sc.size, path, kind, value, role))
        return bool(value) if kind == "bool" else value

    def count(self, path: str, elem_min: int, limit: int, limit_name: str) -> int:
        start = self.pos
        n = self.scalar("uint32", path, ROLE_LENGTH)
        return self.check_length(path, start, n, elem_min, limit, limit_name)

    def string(self, path: str) -> str:
        at = self.pos
        n = self.count(path, 1, self.limits.max_string_bytes + 1, "max_string_bytes")
        if n == 0:
            raise DeserializeError(f"field {path}: string length 0 at byte offset {at} (CDR "
                                   f"counts the terminating NUL, so the least is 1)", path, at)
        start = self.pos
        raw = bytes(self._take(n, path, "string"))
        if raw[-1] != 0:
            raise DeserializeError(f"field {path}: string at byte offset {start} does not end "
                                   f"with NUL", path, start + n - 1)
        text = raw[:-1].decode("utf-8", "surrogateescape")
        self.spans.append(Span(start, n, path, "string", text, ROLE_VALUE))
        return text

    def element(self, base: str, path: str) -> Any:
        if base in SCALARS:
            return self.scalar(base, path)
        if base == "string":
            return self.string(path)
        if base in TIME_CLASS:
            raise _no_time(base, path, DeserializeError)
        return self.message(base, path)

    def field(self, f: Field, path: str) -> Any:
        base = f.base_type
        if not f.is_array:
            return self.element(base, path)
        elem_min = (SCALARS[base].size if base in SCALARS
                    else 0 if base not in ("string", *TIME_CLASS) and _may_be_empty(self.reg, base)
                    else 1)
        if f.array_length is None:
            n = self.count(path, elem_min, self.limits.max_array_length, "max_array_length")
        else:
            n = f.array_length
        if base in SCALARS:
            return self.scalar_array(base, f.type, n, path)
        return [self.element(base, f"{path}[{i}]") for i in range(n)]

    def message(self, type_name: str, prefix: str = "") -> dict:
        spec = self.reg.check(type_name)
        if not spec.fields:
            start = self.pos
            self._take(len(EMPTY_STRUCT), prefix, "the byte of an empty message")
            self.spans.append(Span(start, 1, prefix, "uint8", 0, ROLE_PADDING))
            return {}
        return {f.name: self.field(f, f"{prefix}.{f.name}" if prefix else f.name)
                for f in spec.fields}


def _read(reg: MsgRegistry | None, type_name: str, data: Any, allow_trailing: bool,
          partial: bool, limits: MsgLimits, element_spans: int) -> tuple[dict | None, list[FieldSpan]]:
    reader = _Reader(reg or ros2_registry(), data, limits, element_spans)
    return reader.read(type_name, allow_trailing, partial, start=reader.encapsulation)


def deserialize_cdr(reg: MsgRegistry | None, type_name: str, data: Any, *,
                    allow_trailing: bool = False, limits: MsgLimits = DEFAULT_LIMITS) -> dict:
    """Read a CDR payload (encapsulation header first) as a ROS 2 message value.

    Values are as ``deserialize`` gives them (numeric arrays as numpy arrays; ``uint8[]`` as a
    read-only view into ``data``), times as ``{"sec", "nanosec"}`` dicts.

    Raises:
        DeserializeError: truncated payload, bad length or encapsulation, trailing bytes.
    """
    value, _ = _read(reg, type_name, data, allow_trailing, False, limits, LAYOUT_ELEMENT_SPANS)
    assert value is not None
    return value


def cdr_layout(reg: MsgRegistry | None, type_name: str, data: Any, *,
               allow_trailing: bool = False, partial: bool = False,
               limits: MsgLimits = DEFAULT_LIMITS,
               element_spans: int = LAYOUT_ELEMENT_SPANS) -> list[FieldSpan]:
    """Where every byte of a CDR payload comes from (offsets from the payload's first byte).

    Like ``field_layout``, plus role ``encapsulation`` (bytes 0-3) and role ``padding`` (the
    alignment bytes before the field named in ``path``). The spans cover the payload once.
    """
    return _read(reg, type_name, data, allow_trailing, partial, limits, element_spans)[1]
