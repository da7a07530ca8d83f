"""Test vectors of a generated project: the frames its testbench reads and what the lab's Python
models publish for them (``tb_input.bin``, ``tb_expected.bin``).

How this works: :func:`sample_frames` picks by configuration. ``sensor_msgs/Image`` on TCPROS
gets a picture (:func:`sample_image`: gradients, a grid, bright dots) in one frame and the
live node's model's output for it (the circuit record's
:class:`~rosfpga_lab.hw.msgpipeline.MessagePipeline`: the 2-D application on the picture, its
publisher numbering ``header.seq``). Any
other type on TCPROS gets random messages within the layout's checks and maxima
(:func:`sample_tokens`): a good frame, a refused one, another good one
(:func:`sample_frames_generic`), published by the walker's fast model and the 1-D application
(:func:`model_output`). On CDR (``wire: cdr``) the same with CDR samples
(:func:`sample_records_cdr`, :func:`model_output_cdr`: the 2-D application on a video stream).
Everything is seeded: the same configuration gives the same bytes.
"""

from __future__ import annotations

import math
import struct

import numpy as np

from rosfpga_lab.config import CUSTOM, NodeConfig
from rosfpga_lab.config.vocabulary import CDR_WIRE
from rosfpga_lab.hw.cdrlayout import CdrLayout
from rosfpga_lab.hw.layout import Action, CheckOp, Layout, Step, StepKind, Token, marshal
from rosfpga_lab.hw.layoutsteps import walk_order


def sample_image(config: NodeConfig) -> np.ndarray:
    """A deterministic test picture of ``config.image``: gradients, a grid and bright dots.

    Returns:
        ``(height, width, channels)`` uint8.
    """
    h, w, c = config.image.height, config.image.width, config.image.bytes_per_pixel
    y, x = np.mgrid[0:h, 0:w]
    image = np.empty((h, w, c), np.uint8)
    for k in range(c):
        image[:, :, k] = ((x * (k + 1) * 3 + y * (5 - k) + (x ^ y) * k) % 251).astype(np.uint8)
    image[(y % 16 == 0) | (x % 16 == 0)] //= 2
    rng = np.random.default_rng(20240606)
    n = max(1, h * w // 64)
    image[rng.integers(0, h, n), rng.integers(0, w, n)] = 255
    return image


def sample_frames(config: NodeConfig) -> tuple[bytes, bytes]:
    """A configuration's test frames and the Python models' output for them: what ``generate``
    writes as ``tb_input.bin`` and ``tb_expected.bin`` (``rtl sim`` runs them too). TCPROS
    frames, or for ``wire: cdr`` records (a 4-byte sample length, the payload); for ``op:
    custom`` no expected output (see the module docstring for which frames)."""
    from rosfpga_lab.hls.circuit import circuit_of
    from rosfpga_lab.hw.sample import image_frame

    app = config.application
    circuit = circuit_of(config)
    if config.wire == CDR_WIRE:
        return sample_records_cdr(circuit.cdr, app.op, app.ksize)
    if config.is_image:
        frame = image_frame(sample_image(config), config.image.encoding, seq=7,
                            stamp=(1_700_000_000, 123_456_789), frame_id="camera")
        if app.op == CUSTOM:
            return frame, b""
        return frame, circuit.model().process(frame).output_frame
    return sample_frames_generic(circuit.layout, app.op, app.ksize)


_INT64_MAX = int(np.iinfo(np.int64).max)


def _random_value(step: Step, rng: np.random.Generator) -> object:
    """A value of a SCALAR step that its check (if any) accepts."""
    chk = step.check
    if chk is not None and chk.op is CheckOp.EQUAL:
        return chk.value
    if step.type == "bool":
        return bool(rng.integers(0, 2))
    dt = np.dtype(step.dtype)
    if dt.kind == "f":
        if chk is not None and chk.op is CheckOp.RANGE:
            lo = -1e3 if chk.low is None else float(chk.low)
            hi = 1e3 if chk.high is None else float(chk.high)
            if not math.isfinite(hi - lo):  # an infinite bound, or a span beyond a float's
                a, b = max(lo, -1e3), min(hi, 1e3)
                # (-1e3..1e3 inside the range, else its finite end: the draw is never NaN)
                lo, hi = (a, b) if a <= b else ((lo, lo) if math.isfinite(lo) else (hi, hi))
            return float(dt.type(lo + (hi - lo) * rng.random()))
        return float(dt.type(rng.standard_normal() * 100))
    info = np.iinfo(dt)
    lo, hi = int(info.min), int(info.max)
    if chk is not None and chk.op is CheckOp.RANGE:
        lo = lo if chk.low is None else int(chk.low)
        hi = hi if chk.high is None else int(chk.high)
    # drawn in the field's own integer type: numpy's default (int64) cannot hold a uint64's
    # upper half; every other type keeps the default's draws (and the shipped test frames)
    if hi > _INT64_MAX:
        return int(rng.integers(lo, hi, endpoint=True, dtype=np.uint64))
    return int(rng.integers(lo, hi, endpoint=True))


def sample_tokens(layout: Layout, rng: np.random.Generator, *, stream_count: int | None = None,
                  items: int = 2) -> list[Token]:
    """Random values of a message in the layout's walk order, within its checks and maxima:
    at most ``items`` elements per variable array or string of characters other than the stream
    (``stream_count`` elements for it: default, the length the circuit was built for)."""
    steps = layout.steps
    toks: list[Token] = []
    counts: dict[int, int] = {}

    for i, at in walk_order(steps, counts.__getitem__):
        s = steps[i]
        if s.kind is StepKind.LENGTH:
            part = steps[s.partner] if s.partner is not None else s
            if part.action is Action.STREAM:
                n = layout.stream_length if stream_count is None else stream_count
            elif part.check is not None and part.check.op is CheckOp.EQUAL:
                n = len(str(part.check.value).encode("utf-8"))
            else:
                n = int(rng.integers(0, min(items, part.max_count), endpoint=True))
            counts[i] = n
            toks.append(Token(i, n, at))
        elif s.kind is StepKind.SCALAR:
            toks.append(Token(i, _random_value(s, rng), at))
        elif s.kind is StepKind.STRING:
            n = counts[s.length_step or 0]
            value = (str(s.check.value) if s.check is not None and s.check.op is CheckOp.EQUAL
                     else "".join(chr(c) for c in rng.integers(97, 123, n)))
            toks.append(Token(i, value, at))
        elif s.kind is StepKind.ARRAY:
            n = s.count if s.count is not None else counts[s.length_step or 0]
            dt = np.dtype(s.dtype)
            if dt.kind == "f":
                arr = (rng.standard_normal(n) * 10).astype(dt)
                arr[rng.random(n) < 0.1] = 0.0
            elif dt.kind == "b":
                arr = rng.integers(0, 2, n).astype(dt)
            else:
                info = np.iinfo(dt)
                arr = rng.integers(info.min, info.max, n, dtype=dt, endpoint=True)
            toks.append(Token(i, arr, at))
    return toks


def model_output(layout: Layout, op: str, ksize: int, frames: list[bytes]) -> tuple[bytes, list[str]]:
    """What the lab's Python models (``hw.walker`` fast model, ``hw.morph1d``) publish for
    ``frames``, one whole frame each, and the refusal (``""`` for accepted) per frame."""
    from rosfpga_lab.hw.errors import FrameFieldError
    from rosfpga_lab.hw.morph1d import morph1d_fast
    from rosfpga_lab.hw.walker import extract_fast, publish_fast

    out = bytearray()
    why = []
    for frame in frames:
        try:
            ex = extract_fast(layout, frame)
        except FrameFieldError as exc:
            why.append(str(exc))
            continue
        why.append("")
        out += publish_fast(layout, ex.tokens, morph1d_fast(np.asarray(ex.stream), op, ksize))
    return bytes(out), why


def sample_frames_generic(layout: Layout, op: str, ksize: int, *, seed: int = 20240606
                          ) -> tuple[bytes, bytes]:
    """The testbench's input (a good frame, a refused one, another good one) and what the
    models publish for it (``op: custom``: no expected output).

    The refused frame's stream has one element too few when the stream has a variable length,
    else the frame has one byte too many; both are refused before anything is published.
    """
    rng = np.random.default_rng(seed)
    good = [marshal(layout, sample_tokens(layout, rng)) for _ in range(2)]
    if layout.stream.is_variable and layout.stream_length > 0:
        bad = marshal(layout, sample_tokens(layout, rng, stream_count=layout.stream_length - 1))
    else:
        body = marshal(layout, sample_tokens(layout, rng))[4:] + b"\0"
        bad = struct.pack("<I", len(body)) + body
    frames = [good[0], bad, good[1]]
    if op == "custom":
        return b"".join(frames), b""
    expected, _why = model_output(layout, op, ksize, frames)
    return b"".join(frames), expected


# -- CDR: test samples and the models' output ----------------------------------------------------

def model_output_cdr(cdr: CdrLayout, op: str, ksize: int, records: list[bytes]
                     ) -> tuple[bytes, list[str]]:
    """What the lab's CDR models (``hw.cdrwalker`` fast model, the application of
    ``hw.cdrpipeline``: ``hw.morph1d``, or ``hw.morph`` on a video stream) publish for
    ``records`` (each a 4-byte sample length + CDR payload), and the refusal per record."""
    from rosfpga_lab.hw.msgpipeline import apply_application
    from rosfpga_lab.hw.cdrwalker import extract_cdr_fast, publish_cdr_fast
    from rosfpga_lab.hw.errors import FrameFieldError

    out = bytearray()
    why = []
    for record in records:
        try:
            ex = extract_cdr_fast(cdr, record)
        except FrameFieldError as exc:
            why.append(str(exc))
            continue
        why.append("")
        out += publish_cdr_fast(cdr, ex.tokens, apply_application(
            cdr.layout.video, op, ksize, np.asarray(ex.stream)))
    return bytes(out), why


def sample_records_cdr(cdr: CdrLayout, op: str, ksize: int, *, seed: int = 20240606
                       ) -> tuple[bytes, bytes]:
    """The CDR testbench's input (a good sample, one with a bad encapsulation header, another
    good one padded at its end as Cyclone DDS pads, options 3 and three zeros) and what the
    models publish for it (``op: custom``: no expected output)."""
    from rosfpga_lab.hw.cdrlayout import cdr_marshal, to_cdr_tokens

    rng = np.random.default_rng(seed)
    good = [cdr_marshal(cdr, to_cdr_tokens(cdr, sample_tokens(cdr.base, rng))) for _ in range(2)]
    bad = good[0][:4] + b"\x01\x00" + good[0][6:]           # CDR big-endian: refused
    body = good[1][4:6] + b"\x00\x03" + good[1][8:] + bytes(3)
    records = [good[0], bad, struct.pack("<I", len(body)) + body]
    if op == "custom":
        return b"".join(records), b""
    expected, _why = model_output_cdr(cdr, op, ksize, records)
    return b"".join(records), expected
