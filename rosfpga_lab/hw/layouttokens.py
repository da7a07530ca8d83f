"""A message's values in the circuit's walk order, and back to a frame: the layout's definition
of the wire.

:func:`tokens` lists what the subscriber reads, field by field (a :class:`Token` per step
that has a value, with the element indices of its enclosing loops); :func:`marshal` writes
tokens into a TCPROS frame, as the publisher does, from :func:`encode_token`'s bytes of each;
:func:`frame_geometry` says where a message's stream lies in its frame. Tested against the
``msg`` layer's serializer.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping
from typing import Any, NamedTuple

import numpy as np

from rosfpga_lab.hw.layoutsteps import Layout, Step, StepKind
from rosfpga_lab.msg.builtins import SCALARS


class Token(NamedTuple):
    """One value of a frame in walk order: the step, what it read (LENGTH: the count;
    SCALAR: int/float/bool; STRING: str; ARRAY: numpy array; LOOP and END have none) and the
    element indices of the enclosing LOOPs (``step.label_at(token.at)`` names it)."""

    step: int
    value: Any
    at: tuple[int, ...] = ()


def _get(obj: Any, rel: tuple[str, ...]) -> Any:
    for name in rel:
        obj = obj[name] if isinstance(obj, Mapping) else getattr(obj, name)
    return obj


def tokens(layout: Layout, message: Any) -> list[Token]:
    """The values of ``message`` (as ``msg.deserialize`` returns it, or any object with the
    attributes) in the circuit's walk order, without the frame length (step 0).

    This is what the subscriber reads, field by field; :func:`marshal` writes them back.
    """
    out: list[Token] = []
    steps = layout.steps

    def walk(lo: int, hi: int, obj: Any, at: tuple[int, ...]) -> None:
        i = lo
        while i < hi:
            s = steps[i]
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                for k, element in enumerate(_get(obj, s.rel)):
                    walk(i + 1, s.partner, element, at + (k,))
                i = s.partner + 1
                continue
            value = _get(obj, s.rel)
            if s.kind is StepKind.LENGTH:
                value = len(value.encode("utf-8", "surrogateescape")) if isinstance(value, str) \
                    else len(value)
            elif s.kind is StepKind.ARRAY:
                value = (np.frombuffer(bytes(value), np.uint8)
                         if isinstance(value, (bytes, bytearray, memoryview))
                         else np.asarray(value, dtype=np.dtype(s.dtype)))
            elif s.kind is StepKind.SCALAR:
                value = bool(value) if s.type == "bool" else value
            out.append(Token(i, value, at))
            i += 1

    walk(1, len(steps), message, ())
    return out


def scalar_format(type_name: str) -> str:
    """The struct format of a scalar as the circuit carries it: a ``bool`` is its byte, kept as
    received (the walkers copy bytes, as roscpp's ``uint8_t`` bool does), not folded to 0/1."""
    return "<" + ("B" if type_name == "bool" else SCALARS[type_name].struct_char)


def encode_token(step: Step, value: Any) -> bytes:
    """The wire bytes of one token."""
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        return struct.pack(scalar_format(step.type), value)
    if step.kind is StepKind.STRING:
        return value.encode("utf-8", "surrogateescape") if isinstance(value, str) else bytes(value)
    if step.kind is StepKind.ARRAY:
        return np.ascontiguousarray(value, dtype=np.dtype(step.dtype)).tobytes()
    raise ValueError(f"step {step.index} ({step.kind}) has no bytes")


def _token_buffer(step: Step, value: Any) -> bytes | memoryview:
    """The wire bytes of one token; an array's as a view of its memory (no copy when it is
    contiguous and of the step's type already)."""
    if step.kind is StepKind.ARRAY:
        return np.ascontiguousarray(value, dtype=np.dtype(step.dtype)).data.cast("B")
    return encode_token(step, value)


def marshal(layout: Layout, toks: Iterable[Token]) -> bytes:
    """A TCPROS frame (4-byte length + body) from tokens in walk order (the publisher): the
    frame is joined once, so a large stream's bytes are copied once."""
    parts: list[bytes | memoryview] = [b""]
    parts += (_token_buffer(layout.steps[t.step], t.value) for t in toks)
    parts[0] = struct.pack("<I", sum(len(p) for p in parts))
    return b"".join(parts)


class FrameGeometry(NamedTuple):
    """Where a frame's parts are, for given values.

    Attributes:
        frame_length: the 4-byte frame length's value (bytes of the body).
        stream_offset: byte offset in the frame (0 = first byte of the frame length) of the
            streamed array's first element.
        stream_bytes: bytes of the streamed array (both -1 without a stream).
    """

    frame_length: int
    stream_offset: int
    stream_bytes: int


def frame_geometry(layout: Layout, message: Any) -> FrameGeometry:
    """Frame length and stream offset of ``message`` (the values of the layout's type)."""
    offset = 4
    stream_offset = stream_bytes = -1
    for t in tokens(layout, message):
        n = len(encode_token(layout.steps[t.step], t.value))
        if t.step == layout.stream_index:
            stream_offset, stream_bytes = offset, n
        offset += n
    return FrameGeometry(offset - 4, stream_offset, stream_bytes)


__all__ = ["FrameGeometry", "Token", "encode_token", "frame_geometry", "marshal", "tokens"]
