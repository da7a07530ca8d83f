"""A readable message of any layout's type, and a frame of it the circuit refuses.

How this works: :func:`example_tokens` walks the layout as the subscriber does and picks a value
for every step that its checks accept: a checked field its value (or its bound), a string its
own field name (cut to its maximum), a variable array two elements, the stream the element
count the circuit was built for (a ramp). :func:`example_message` turns the tokens into the
``msg`` layer's dict (through the frame :func:`~rosfpga_lab.hw.layout.marshal` writes), so a
notebook can show, publish and edit a message of a type it has never seen
(notebook 10 with a student's own ``.msg``). :func:`refused_frame` makes the first checked
field of a message wrong (else the stream one element too long). :func:`image_frame` frames a
picture as a ``sensor_msgs/Image`` (the camera's, the benchmarks' and the tests' frames),
written by the same :func:`~rosfpga_lab.hw.layout.marshal` as the publisher's.
"""

from __future__ import annotations

import functools
import struct
from typing import Any, NamedTuple

import numpy as np

from rosfpga_lab.config.limits import IMAGE_TYPE
from rosfpga_lab.hw.encodings import pixel_format
from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.layoutderive import derive_layout
from rosfpga_lab.hw.layoutsteps import Action, CheckOp, Layout, Step, StepKind, walk_order
from rosfpga_lab.hw.layouttokens import Token, marshal, tokens
from rosfpga_lab.msg import MsgRegistry, default_registry, deserialize

#: Elements of a variable array (or loop) other than the stream, in an example message.
EXAMPLE_ITEMS = 2


def _int_value(step: Step, want: int) -> int:
    info = np.iinfo(np.dtype(step.dtype))
    return int(min(max(want, int(info.min)), int(info.max)))


def _scalar(step: Step) -> Any:
    chk = step.check
    if chk is not None and chk.op is CheckOp.EQUAL:
        return chk.value
    if chk is not None and chk.op is CheckOp.RANGE:
        return chk.low if chk.low is not None else chk.high
    if step.type == "bool":
        return True
    if np.dtype(step.dtype).kind == "f":
        return 0.5 * step.index
    return _int_value(step, step.index)


def _text(step: Step) -> str:
    chk = step.check
    if chk is not None and chk.op is CheckOp.EQUAL:
        return str(chk.value)
    name = step.label.replace("[]", "").rsplit(".", 1)[-1]
    return name[:step.max_count]


def _array(step: Step, n: int, stream: bool) -> np.ndarray:
    dt = np.dtype(step.dtype)
    ramp = np.arange(n)
    if dt.kind == "f":
        return (ramp * 0.25).astype(dt)
    if dt.kind == "b":
        return (ramp % 2).astype(dt)
    return ((ramp * 37) % 100 if stream else ramp % 100).astype(dt)


def example_tokens(layout: Layout, *, stream: np.ndarray | None = None) -> list[Token]:
    """A message's values in walk order that the circuit accepts (``stream``: the streamed
    array's elements; default, a ramp of the length the circuit was built for)."""
    steps = layout.steps
    toks: list[Token] = []
    counts: dict[int, int] = {}

    for i, at in walk_order(steps, counts.__getitem__):
        s = steps[i]
        if s.kind is StepKind.LENGTH:
            part = steps[s.partner] if s.partner is not None else s
            if part.action is Action.STREAM:
                n = layout.stream_length if stream is None else len(stream)
            elif part.kind is StepKind.STRING:
                n = len(_text(part).encode("utf-8"))
            else:
                n = min(EXAMPLE_ITEMS, part.max_count)
            counts[i] = n
            toks.append(Token(i, n, at))
        elif s.kind is StepKind.SCALAR:
            toks.append(Token(i, _scalar(s), at))
        elif s.kind is StepKind.STRING:
            toks.append(Token(i, _text(s), at))
        elif s.kind is StepKind.ARRAY:
            n = s.count if s.count is not None else counts[s.length_step or 0]
            if s.index == layout.stream_index and stream is not None:
                toks.append(Token(i, np.asarray(stream, np.dtype(s.dtype)), at))
            else:
                toks.append(Token(i, _array(s, n, s.index == layout.stream_index), at))
    return toks


def example_message(layout: Layout, reg: MsgRegistry, *, stream: np.ndarray | None = None
                    ) -> dict[str, Any]:
    """:func:`example_tokens` as the ``msg`` layer's dict of the layout's type."""
    frame = marshal(layout, example_tokens(layout, stream=stream))
    return deserialize(reg, layout.type_name, frame[4:])


def random_stream(layout: Layout, rng: np.random.Generator) -> np.ndarray:
    """Random elements for the stream (the length the circuit was built for), small enough to
    read: integers 0..4095 within the type, floats -100..100."""
    dt = np.dtype(layout.stream.dtype)
    n = layout.stream_length
    if dt.kind == "f":
        return ((rng.random(n) - 0.5) * 200).astype(dt)
    high = min(4096, int(np.iinfo(dt).max) + 1)
    return rng.integers(0, high, n).astype(dt)


class Refusal(NamedTuple):
    """A frame the circuit refuses: the frame, the step refused and the wrong value."""

    frame: bytes
    step: Step
    value: Any


def _wrong(step: Step) -> Any | None:
    """A value the step's check refuses, or None when none fits its type."""
    chk = step.check
    assert chk is not None
    if step.type == "bool":
        return not chk.value if chk.op is CheckOp.EQUAL else None
    dt = np.dtype(step.dtype)
    if dt.kind == "f":
        if chk.op is CheckOp.EQUAL:
            return float(dt.type(chk.value + 1.0))
        return float(chk.high) + 1.0 if chk.high is not None else float(chk.low) - 1.0
    info = np.iinfo(dt)
    if chk.op is CheckOp.EQUAL:
        candidates = [int(chk.value) + 1, int(chk.value) - 1]
    else:
        candidates = ([int(chk.high) + 1] if chk.high is not None else []) + \
            ([int(chk.low) - 1] if chk.low is not None else [])
    return next((v for v in candidates if info.min <= v <= info.max), None)


def refused_frame(layout: Layout, message: Any) -> Refusal:
    """The frame of ``message`` with its first checked scalar made wrong (a value its check
    refuses), or, when no scalar is checked, with one stream element too many (refused at the
    stream's length)."""
    toks = tokens(layout, message)
    for k, t in enumerate(toks):
        s = layout.steps[t.step]
        if s.kind is StepKind.SCALAR and s.check is not None and s.action is Action.CHECK:
            value = _wrong(s)
            if value is not None:
                toks[k] = t._replace(value=value)
                return Refusal(marshal(layout, toks), s, value)
    assert layout.stream_index is not None
    length = layout.steps[layout.stream_index].length_step
    out = []
    for t in toks:
        if t.step == length:
            t = t._replace(value=t.value + 1)
        elif t.step == layout.stream_index:
            t = t._replace(value=np.append(t.value, t.value[-1:] if len(t.value) else [0]
                                           ).astype(t.value.dtype))
        out.append(t)
    assert length is not None
    return Refusal(marshal(layout, out), layout.steps[length], layout.stream_length + 1)


def framed(body: bytes) -> bytes:
    """A body with its 4-byte TCPROS frame length."""
    return struct.pack("<I", len(body)) + body


@functools.cache
def _image_walk() -> Layout:
    """``sensor_msgs/Image``'s walk with no stream and no checks (what a camera writes)."""
    return derive_layout(default_registry(), IMAGE_TYPE, stream=None)


def image_frame(image: np.ndarray, encoding: str, *, seq: int = 0, stamp: tuple[int, int] = (0, 0),
                frame_id: str = "", is_bigendian: int = 0) -> bytes:
    """A TCPROS ``sensor_msgs/Image`` frame (4-byte length + body) holding ``image``, ``(rows,
    cols[, channels])`` uint8 in ``encoding``, its ``step`` a row's bytes (the pixel bytes
    copied once).

    Raises:
        PipelineConfigError: ``image`` does not hold the encoding's bytes per pixel, or the
            encoding is not one the lab frames (:data:`~rosfpga_lab.hw.encodings.PIXEL_FORMATS`).
    """
    fmt = pixel_format(encoding)
    img = np.ascontiguousarray(image, dtype=np.uint8)
    rows, cols = img.shape[:2]
    if img.size != rows * cols * fmt.bytes_per_pixel:
        raise PipelineConfigError(
            f"image of shape {img.shape} does not hold {fmt.bytes_per_pixel} bytes per pixel ({encoding})")
    message = {"header": {"seq": seq, "stamp": {"secs": stamp[0], "nsecs": stamp[1]},
                          "frame_id": frame_id},
               "height": rows, "width": cols, "encoding": encoding,
               "is_bigendian": is_bigendian & 0xFF, "step": cols * fmt.bytes_per_pixel,
               "data": img.reshape(-1)}
    walk = _image_walk()
    return marshal(walk, tokens(walk, message))


__all__ = ["EXAMPLE_ITEMS", "Refusal", "example_message", "example_tokens", "framed",
           "image_frame", "random_stream", "refused_frame"]
