"""The subscriber model of any message type, rendered from its circuit layout.

How this works: the subscriber is a program counter over ``layout.steps`` plus a stack of
loop counters, as the generated circuit is. :class:`LayoutInterpreter` (the reference model)
takes one byte per :meth:`~LayoutInterpreter.push`, collects the current step's bytes, and when
the step is complete decodes it little-endian, runs the step's check, records a
:class:`~rosfpga_lab.hw.layout.Token` and moves on: past a LOOP whose count is 0, back to the
loop body at an END while elements remain, through zero-length strings and arrays at once.
:func:`extract_fast` runs the same machine a whole step at a time (the stream as one numpy
slice). Both raise the same :class:`~rosfpga_lab.hw.errors.FrameFieldError` naming the field
(``history[1].sensor_name length``) and its byte offset, then resynchronise: a sane frame
length lets the reference skip the rest of the refused frame, so the next good frame comes out
right.

The frame length is checked against the shortest body accepted (``Layout.min_body``) and the
lab's limit; each length prefix against its maximum and against the bytes left (when only
fixed-size fields follow, the frame length must match exactly, as the Image interpreter checks
``data length``). Refusal
kinds (``FrameFieldError.rule``): ``below the minimum``, ``over the limit``,
``past the frame end``, ``not what the circuit was built for``, ``not a number`` (a NaN in a
range check), ``frame length disagrees``, ``cut short``.

The publisher is :mod:`rosfpga_lab.hw.publisherwalker`.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError, FrameTruncatedError
from rosfpga_lab.hw.layoutlengths import LengthRule, length_rules
from rosfpga_lab.hw.layoutsteps import Action, CheckOp, Layout, Step, StepKind
from rosfpga_lab.hw.layouttokens import Token, scalar_format

STAGE = "interpreter"  # as the Image interpreter: refusals read the same


@dataclass
class Extracted:
    """What the subscriber circuit took from one frame.

    Attributes:
        tokens: every value in walk order (``tokens(layout, deserialize(body))`` equals it).
        stream: the streamed array's elements (the element dtype).
        frame_length: the 4-byte frame length.
        stream_offset: byte offset of the stream's first element in the frame.
    """

    tokens: list[Token]
    stream: np.ndarray
    frame_length: int
    stream_offset: int

    def carried(self, layout: Layout) -> list[Token]:
        """The tokens the circuit keeps (everything but skipped fields and the stream)."""
        return [t for t in self.tokens if layout.steps[t.step].action in (Action.CARRY, Action.CHECK)]


def _decode(step: Step, data: bytes | memoryview) -> Any:
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        return struct.unpack(scalar_format(step.type), data)[0]
    if step.kind is StepKind.STRING:
        return bytes(data).decode("utf-8", "surrogateescape")
    return np.frombuffer(data, np.dtype(step.dtype))  # a read-only view (fast model: of the frame)


@dataclass
class LayoutInterpreter:
    """The subscriber circuit of ``layout`` (reference model: one byte per :meth:`push`).

    Attributes:
        pc: index of the step being read (``-1``: skipping the rest of a refused frame).
        offset: byte offset in the current frame of the next byte.
        frames: frames completed since construction.
        last: what the last complete frame gave.
    """

    layout: Layout
    frames: int = 0
    last: Extracted | None = None
    _rules: dict[int, LengthRule] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._rules = length_rules(self.layout)
        self.reset()

    def reset(self) -> None:
        """Back to waiting for a frame length."""
        self.pc = 0
        self.offset = 0
        self._buf = bytearray()
        self._field_start = 0
        self._loops: list[list[int]] = []     # [loop step, count, element index]
        self._counts: dict[int, int] = {}     # LENGTH step -> its last value
        self._tokens: list[Token] = []
        self._frame_length: int | None = None
        self._stream_offset = 0
        self._stream: np.ndarray | None = None
        self._skip = 0
        self._pad = 0                         # alignment bytes before the step (CDR only)

    # -- geometry -------------------------------------------------------------------------------
    @property
    def step(self) -> Step | None:
        """The step being read (``None`` while skipping)."""
        return self.layout.steps[self.pc] if self.pc >= 0 else None

    @property
    def indices(self) -> tuple[int, ...]:
        """Element indices of the enclosing loops."""
        return tuple(k for _s, _n, k in self._loops)

    def need(self, s: Step) -> int:
        """Bytes of step ``s`` in this frame."""
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH):
            return s.size
        n = s.count if s.count is not None else self._counts[s.length_step or 0]
        return s.size * n

    @property
    def _end(self) -> int:
        """Where the fields end (TCPROS: the frame's end)."""
        return self._sample_end

    @property
    def _sample_end(self) -> int:
        """Where the frame (sample) ends: its 4-byte length plus the length."""
        assert self._frame_length is not None
        return 4 + self._frame_length

    def _align(self, pc: int) -> int:
        """Bytes of padding before step ``pc`` at the current offset (TCPROS: none)."""
        return 0

    # -- the byte path --------------------------------------------------------------------------
    def push(self, byte: int) -> None:
        """Consume one byte (one clock).

        Raises:
            FrameFieldError: (or a subclass) the circuit refuses the frame; it has resynchronised.
        """
        if self.pc < 0:
            self._skip -= 1
            if self._skip == 0:
                self.reset()
            return
        s = self.layout.steps[self.pc]
        if not self._buf:
            self._field_start = self.offset
        self.offset += 1
        self._buf.append(byte)
        if len(self._buf) == self.need(s):
            data, self._buf = bytes(self._buf), bytearray()
            self._complete(s, data)
        elif self.pc > 0 and self.offset == self._end:
            self._fail(FrameLengthError(
                f"the frame length ({self._frame_length}) ends inside this field",
                s.label_at(self.indices), self._field_start, self._frame_length))

    def feed(self, data: bytes) -> None:
        """Push every byte of ``data`` (the first error propagates)."""
        for byte in data:
            self.push(byte)

    def trace(self, data: bytes) -> list[tuple[int, int, str, str]]:
        """Push bytes, recording ``(offset, byte, step ident, field label)`` before each."""
        rows = []
        for byte in data:
            s = self.step
            rows.append((self.offset, byte, s.ident if s else "(skip)",
                         s.label_at(self.indices) if s else "(skipping)"))
            self.push(byte)
        return rows

    def finish(self) -> None:
        """End of input: raise :class:`FrameTruncatedError` if a frame was left incomplete."""
        if self.pc == 0 and not self._buf:
            return
        s = self.step
        label = s.label_at(self.indices) if s else "frame"
        start = self._field_start if self._buf else self.offset
        got = len(self._buf)
        self.reset()
        raise FrameTruncatedError(f"the frame was cut short: {got} of this field's bytes had "
                                  "arrived", label, start)

    # -- steps ------------------------------------------------------------------------------------
    def _complete(self, s: Step, data: bytes | memoryview) -> None:
        self._accept(s, data)
        self._advance(s.index + 1)

    def _accept(self, s: Step, data: bytes | memoryview) -> None:
        """Decode a complete step, run its checks, record its token (no moving on)."""
        value = _decode(s, data)
        if s.index == 0:
            self._frame_length = value
        if s.kind is StepKind.LENGTH:
            self._counts[s.index] = value
        if s.check is not None:
            self._check(s, value)
        if s.kind is StepKind.LENGTH and s.index > 0:
            self._check_fits(s, value)
        if s.index > 0:
            self._tokens.append(Token(s.index, value, self.indices))
        if s.index == self.layout.stream_index:
            self._stream = value

    def _advance(self, pc: int) -> None:
        steps = self.layout.steps
        while True:
            if pc == len(steps):
                self._frame_done()
                return
            t = steps[pc]
            if t.kind is StepKind.LOOP:
                n = t.count if t.count is not None else self._counts[t.length_step or 0]
                assert t.partner is not None
                if n == 0:
                    pc = t.partner + 1
                    continue
                self._loops.append([pc, n, 0])
                pc += 1
                continue
            if t.kind is StepKind.END:
                top = self._loops[-1]
                top[2] += 1
                if top[2] < top[1]:
                    pc = top[0] + 1
                else:
                    self._loops.pop()
                    pc += 1
                continue
            self.pc = pc
            if self.need(t) == 0:  # an empty string or array completes at once (unaligned)
                if pc == self.layout.stream_index:
                    self._stream_offset = self.offset
                self._field_start = self.offset
                self._accept(t, b"")
                pc += 1
                continue
            self._pad = self._align(pc)
            if pc == self.layout.stream_index:
                self._stream_offset = self.offset + self._pad
            if self.offset + self._pad >= self._end:
                self._fail(FrameLengthError(
                    f"the frame length ({self._frame_length}) ends before this field",
                    t.label_at(self.indices), self.offset, self._frame_length))
            return

    def _frame_done(self) -> None:
        self._publish(self._extracted())

    def _extracted(self) -> Extracted:
        """The frame's values once its last field is read (refused if bytes are left over)."""
        if self.offset != self._end:
            left = self._end - self.offset
            self._fail(FrameLengthError(
                f"{self._frame_length} announces {left} bytes after the last field",
                "frame length", 0, self._frame_length))
        stream = self._stream if self._stream is not None else np.zeros(0, np.uint8)
        assert self._frame_length is not None
        return Extracted(self._tokens, stream, self._frame_length, self._stream_offset)

    def _publish(self, done: Extracted) -> None:
        self.last = done
        self.frames += 1
        self.reset()

    def _take_tail(self, view: memoryview) -> bool:
        """Fast model: take whatever follows the last field whole; ``True`` if the frame is
        complete (TCPROS: nothing follows)."""
        return False

    def _fail(self, error: FrameFieldError) -> None:
        remaining = self._sample_end - self.offset if self._frame_length is not None else 0
        self.reset()
        if remaining > 0:
            self.pc, self._skip = -1, remaining
        raise error

    def _refuse(self, s: Step, message: str, value: Any, rule: str,
                cls: type[FrameFieldError] = FrameFieldError) -> None:
        self._fail(cls(message, s.label_at(self.indices), self._field_start, value, STAGE,
                       rule=rule))

    def _check(self, s: Step, value: Any) -> None:
        c = s.check
        assert c is not None
        if s.index == 0:
            if value < c.low:
                self._refuse(s, f"{value} is shorter than the shortest {self.layout.type_name} "
                                f"the circuit accepts ({c.low} bytes)", value, "below the minimum",
                             FrameLengthError)
            if value > c.high:
                self._refuse(s, f"{value} exceeds the limit of {c.high} bytes "
                                "(hw.limits.MAX_FRAME_BYTES)", value, "over the limit",
                             FrameLengthError)
            return
        if c.op is CheckOp.MAX:
            if value > c.high:
                self._refuse(s, f"{value} exceeds the limit of {c.high} (limits: {s.path})",
                             value, "over the limit")
        elif c.op is CheckOp.EQUAL:
            if value != c.value:
                self._refuse(s, f"{value!r} but the circuit was built for {c.value!r}", value,
                             "not what the circuit was built for")
        else:
            if isinstance(value, float) and math.isnan(value):
                self._refuse(s, f"NaN is outside {c.describe()}", value, "not a number")
            if c.low is not None and value < c.low:
                self._refuse(s, f"{value} is below the minimum {c.low}", value,
                             "below the minimum")
            if c.high is not None and value > c.high:
                self._refuse(s, f"{value} exceeds the maximum {c.high}", value, "over the limit")

    def _check_fits(self, s: Step, value: int) -> None:
        left = self._end - self.offset
        rule = self._rules[s.index]
        need = value * rule.element_min
        fixed = rule.fixed_after
        if fixed is not None and need + fixed != left:
            self._fail(FrameLengthError(
                f"{self._frame_length} announces {left} bytes after the {s.label} field, but "
                f"{value} elements and the fields after them take {need + fixed}",
                "frame length", 0, self._frame_length))
        if need > left:
            self._refuse(s, f"{value} elements ({need} bytes at least) announced but the frame "
                            f"length leaves only {left}", value, "past the frame end",
                         FrameLengthError)


def extract_reference(layout: Layout, frame: bytes) -> Extracted:
    """Push ``frame`` (one TCPROS frame) a byte at a time.

    Raises:
        FrameFieldError: as the circuit refuses it; a frame cut short; bytes after the frame.
    """
    return run_reference(LayoutInterpreter(layout), frame, "frame")


def extract_fast(layout: Layout, frame: bytes) -> Extracted:
    """The same machine a whole step at a time (the stream as a numpy view of ``frame``).

    Raises:
        FrameFieldError: exactly as :func:`extract_reference` would.
    """
    return run_fast(LayoutInterpreter(layout), frame, "frame")


def run_reference(interp: LayoutInterpreter, frame: bytes, unit: str) -> Extracted:
    """Push ``frame`` (one ``unit``: "frame" or "sample") into ``interp`` a byte at a time.

    Raises:
        FrameFieldError: as the circuit refuses it; a ``unit`` cut short; bytes after it.
    """
    for byte in frame:
        interp.push(byte)
        if interp.frames:
            break
    if not interp.frames:
        if not frame:
            raise FrameTruncatedError("the input held no bytes at all", "frame length", 0)
        interp.finish()
    assert interp.last is not None
    _check_trailing(interp.last, len(frame), unit)
    return interp.last


def run_fast(interp: LayoutInterpreter, frame: bytes, unit: str) -> Extracted:
    """Run ``interp`` over ``frame`` a whole step at a time (the stream as a numpy view of it).

    Raises:
        FrameFieldError: exactly as :func:`run_reference` would.
    """
    view = memoryview(frame)
    if not frame:
        raise FrameTruncatedError("the input held no bytes at all", "frame length", 0)
    while not interp.frames:
        if interp._take_tail(view):
            break
        s = interp.layout.steps[interp.pc]
        n = interp.need(s)
        pos = interp.offset + interp._pad
        if interp.pc > 0 and pos + n > interp._end and interp._end <= len(view):
            interp._field_start = pos
            interp.offset = interp._end
            interp._pad = 0
            interp._fail(FrameLengthError(
                f"the frame length ({interp._frame_length}) ends inside this field",
                s.label_at(interp.indices), pos, interp._frame_length))
        if pos + n > len(view):
            got = max(0, len(view) - pos)
            label = s.label_at(interp.indices)
            interp.reset()
            raise FrameTruncatedError(f"the frame was cut short: {got} of this field's bytes "
                                      "had arrived", label, min(pos, len(view)))
        interp._field_start = pos
        interp.offset = pos + n
        interp._pad = 0
        interp._complete(s, view[pos:pos + n])
    assert interp.last is not None
    _check_trailing(interp.last, len(frame), unit)
    return interp.last


def _check_trailing(ex: Extracted, given: int, unit: str) -> None:
    left = given - 4 - ex.frame_length
    length = "frame length" if unit == "frame" else f"{unit} length"
    if left:
        raise FrameLengthError(
            f"the {length} ({ex.frame_length}) ends the {unit} at byte {4 + ex.frame_length}, "
            f"but {left} more bytes were given; pass one {unit} at a time", "frame length", 0,
            ex.frame_length)


__all__ = [
    "STAGE", "Extracted", "LayoutInterpreter", "extract_fast", "extract_reference", "run_fast",
    "run_reference",
]
