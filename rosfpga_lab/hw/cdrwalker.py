"""CDR subscriber and publisher models of any message type, rendered from its CDR walk.

How this works: :class:`CdrInterpreter` is :class:`~rosfpga_lab.hw.walker.LayoutInterpreter`
(the reference model, one byte per clock) over :class:`~rosfpga_lab.hw.cdrlayout.CdrLayout`'s
steps with CDR's three additions: before a step it skips the step's alignment padding (counted
from after the encapsulation header), it checks the encapsulation header (representation
CDR little-endian; the options' low bits give the padding that ends the payload, skipped after
the last field) and a string's NUL, and a string takes ``length - 1`` bytes. After the last
field it also takes, when the options announce fewer (Cyclone DDS: none), the 1 to 3 *zero* bytes that bring the serialized
payload (header included) to a multiple of 4: RTPS 2.5 9.4.2.11 and DDS-XTypes 1.3 7.6.3.1.2
ask for that padding, and Cyclone DDS sends it with options ``00 00`` (a 398-byte
``lab_msgs/Samples`` arrives as 400 bytes); a non-zero byte there, or more bytes, is refused. Refusals and
resynchronisation are the walker's: the field, its byte offset (in the input, 0 = the first
byte of the sample length) and the rule; a refused sample is skipped to its end.
:func:`extract_cdr_fast` runs the same machine a whole step at a time.

The publisher (:func:`publish_cdr_fast`, :func:`publish_cdr_reference`) runs the walker's own
publisher logic on the base walk (carried values, the stream, defaults of skipped fields,
another output type) and writes CDR: encapsulation ``00 01 00 00``, padding, each string's
length + 1 and its NUL.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rosfpga_lab.hw.cdrlayout import (
    ALIGN_ORIGIN, END_ALIGN, OPTIONS_PADDING_MASK, TAIL_LABEL, CdrLayout, cdr_length_rules,
    cdr_marshal, to_base_tokens, to_cdr_tokens,
)
from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError, FrameTruncatedError
from rosfpga_lab.hw.layout import Step, StepKind, Token, encode_token
from rosfpga_lab.hw.walker import STAGE, Extracted, LayoutInterpreter, published_tokens
from rosfpga_lab.msg.cdr import CDR_BE


def _representation(value: int) -> str:
    if value == int.from_bytes(CDR_BE[:2], "big"):
        return "CDR big-endian"
    if value in (0x0006, 0x0007, 0x0008, 0x0009, 0x000a, 0x000b):
        return "XCDR2 / parameter list"
    return "an unknown representation"


class CdrInterpreter(LayoutInterpreter):
    """The CDR subscriber circuit of ``cdr`` (reference model: one byte per :meth:`push`)."""

    def __init__(self, cdr: CdrLayout) -> None:
        self.cdr = cdr
        super().__init__(cdr.layout)

    def __post_init__(self) -> None:
        self._rules = cdr_length_rules(self.cdr)
        self.reset()

    def reset(self) -> None:
        """Back to waiting for a sample length."""
        super().reset()
        self._pad = 0
        self._tail = 0
        self._tail_left = 0
        self._tail_zero = False     # the end padding is unannounced: its bytes must be zero
        self._done: Extracted | None = None

    @property
    def step(self) -> Step | None:
        """The step being read (``None`` while skipping or in the end padding)."""
        return None if self._tail_left else super().step

    def need(self, s: Step) -> int:
        """Bytes of step ``s`` in this sample (its padding not counted)."""
        if s.kind is StepKind.STRING:
            return self._counts[s.length_step or 0] - 1
        return super().need(s)

    @property
    def _end(self) -> int:
        """Where the fields end: the sample's end less its end padding."""
        assert self._frame_length is not None
        return 4 + self._frame_length - self._tail

    # -- the byte path --------------------------------------------------------------------------
    def push(self, byte: int) -> None:
        """Consume one byte (one clock).

        Raises:
            FrameFieldError: (or a subclass) the circuit refuses the sample; it has resynchronised.
        """
        if self._tail_left:
            self.offset += 1
            self._tail_left -= 1
            if self._tail_zero and byte:
                self._nonzero_tail(self.offset - 1, byte)
            if not self._tail_left:
                self._publish_done()
            return
        if self.pc >= 0 and self._pad and not self._buf:
            self.offset += 1     # an alignment byte (its value is not looked at)
            self._pad -= 1
            return
        super().push(byte)

    def finish(self) -> None:
        """End of input: raise :class:`FrameTruncatedError` if a sample was left incomplete."""
        if self._tail_left:
            offset = self.offset
            self.reset()
            raise FrameTruncatedError("the sample was cut short in its end padding",
                                      TAIL_LABEL, offset)
        super().finish()

    # -- steps ------------------------------------------------------------------------------------
    def _accept(self, s: Step, data: bytes | memoryview) -> None:
        if s.kind is StepKind.ENCAPSULATION:
            raw = bytes(data)
            rep = int.from_bytes(raw[:2], "big")
            assert s.check is not None
            if rep != s.check.value:
                self._refuse(s, f"representation 0x{rep:04x} ({_representation(rep)}), but the "
                                f"circuit reads CDR little-endian (0x{s.check.value:04x})", rep,
                             "not what the circuit was built for")
            tail = int.from_bytes(raw[2:], "big") & OPTIONS_PADDING_MASK
            if tail > self._end - self.offset:
                self._fail(FrameLengthError(
                    f"the options announce {tail} bytes of end padding but the sample length "
                    f"leaves only {self._end - self.offset}", "frame length", 0,
                    self._frame_length))
            self._tail = tail
            return
        if s.kind is StepKind.NUL:
            if data[0] != 0:
                self._refuse(s, f"byte 0x{data[0]:02x} where the string's NUL should be",
                             data[0], "no NUL")
            return
        super()._accept(s, data)

    def _check(self, s: Step, value: Any) -> None:
        c = s.check
        if s.kind is StepKind.LENGTH and s.index > 0 and c is not None and c.low == 1 and \
                value == 0:
            self._refuse(s, "0, but a CDR string's length counts its NUL (1 for \"\")", value,
                         "below the minimum")
        super()._check(s, value)

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
            if self.need(t) == 0:  # an empty string or array completes at once, unaligned
                if pc == self.layout.stream_index:
                    self._stream_offset = self.offset
                self._field_start = self.offset
                self._accept(t, b"")
                pc += 1
                continue
            self._pad = self.cdr.pad(pc, self.offset)
            if pc == self.layout.stream_index:
                self._stream_offset = self.offset + self._pad
            if self.offset + self._pad >= self._end:
                self._fail(FrameLengthError(
                    f"the frame length ({self._frame_length}) ends before this field",
                    t.label_at(self.indices), self.offset, self._frame_length))
            return

    def _frame_done(self) -> None:
        assert self._frame_length is not None
        after = 4 + self._frame_length - self.offset   # bytes after the last field
        if after != self._tail and 0 < after < END_ALIGN and \
                after == -(self.offset - ALIGN_ORIGIN) % END_ALIGN:
            self._tail, self._tail_zero = after, True   # unannounced alignment to 4: zeros
        if self.offset != self._end:
            left = self._end - self.offset
            self._fail(FrameLengthError(
                f"{self._frame_length} announces {left} bytes after the last field",
                "frame length", 0, self._frame_length))
        stream = self._stream if self._stream is not None else np.zeros(0, np.uint8)
        assert self._frame_length is not None
        self._done = Extracted(self._tokens, stream, self._frame_length, self._stream_offset)
        if self._tail:
            self._tail_left = self._tail
            self.pc = -1
            return
        self._publish_done()

    def _nonzero_tail(self, at: int, byte: int) -> None:
        self._fail(FrameFieldError(
            f"byte 0x{byte:02x} after the last field, where only zero bytes may pad the payload "
            f"to a multiple of {END_ALIGN} (the encapsulation options announce no end padding)",
            TAIL_LABEL, at, byte, STAGE, rule="not zero"))

    def _publish_done(self) -> None:
        assert self._done is not None
        self.last = self._done
        self.frames += 1
        self.reset()

    def _fail(self, error: FrameFieldError) -> None:
        remaining = 4 + self._frame_length - self.offset if self._frame_length is not None else 0
        self.reset()
        if remaining > 0:
            self.pc, self._skip = -1, remaining
        raise error

    def _refuse(self, s: Step, message: str, value: Any, rule: str,
                cls: type[FrameFieldError] = FrameFieldError) -> None:
        self._fail(cls(message, s.label_at(self.indices), self._field_start, value, STAGE,
                       rule=rule))


def extract_cdr_reference(cdr: CdrLayout, frame: bytes) -> Extracted:
    """Push ``frame`` (4-byte sample length + one CDR payload) a byte at a time.

    Raises:
        FrameFieldError: as the circuit refuses it; a sample cut short; bytes after it.
    """
    interp = CdrInterpreter(cdr)
    for byte in frame:
        interp.push(byte)
        if interp.frames:
            break
    if not interp.frames:
        if not frame:
            raise FrameTruncatedError("the input held no bytes at all", "frame length", 0)
        interp.finish()
    assert interp.last is not None
    _check_trailing(interp.last, len(frame))
    return interp.last


def extract_cdr_fast(cdr: CdrLayout, frame: bytes) -> Extracted:
    """The same machine a whole step at a time (the stream as a numpy view of ``frame``).

    Raises:
        FrameFieldError: exactly as :func:`extract_cdr_reference` would.
    """
    interp = CdrInterpreter(cdr)
    view = memoryview(frame)
    if not frame:
        raise FrameTruncatedError("the input held no bytes at all", "frame length", 0)
    while not interp.frames:
        if interp._tail_left:
            if interp.offset + interp._tail_left > len(view):
                raise FrameTruncatedError("the sample was cut short in its end padding",
                                          TAIL_LABEL, len(view))
            if interp._tail_zero:
                tail = view[interp.offset:interp.offset + interp._tail_left]
                for k, byte in enumerate(tail):
                    if byte:
                        interp.offset += k + 1
                        interp._nonzero_tail(interp.offset - 1, byte)
            interp.offset += interp._tail_left
            interp._tail_left = 0
            interp._publish_done()
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
    _check_trailing(interp.last, len(frame))
    return interp.last


def _check_trailing(ex: Extracted, given: int) -> None:
    left = given - 4 - ex.frame_length
    if left:
        raise FrameLengthError(
            f"the sample length ({ex.frame_length}) ends the sample at byte "
            f"{4 + ex.frame_length}, but {left} more bytes were given; pass one sample at a time",
            "frame length", 0, ex.frame_length)


# -- publisher ------------------------------------------------------------------------------------

def published_cdr_tokens(cdr: CdrLayout, toks: list[Token], stream: np.ndarray,
                         out_cdr: CdrLayout | None = None) -> list[Token]:
    """What the CDR publisher writes, in its CDR walk's order: the walker's
    :func:`~rosfpga_lab.hw.walker.published_tokens` on the base walks (a skipped string is
    ``""``: length 1)."""
    base = published_tokens(cdr.base, to_base_tokens(cdr, toks), stream,
                            out_cdr.base if out_cdr is not None else None,
                            cdr.registry if out_cdr is not None else None)
    return to_cdr_tokens(out_cdr or cdr, base)


def publish_cdr_fast(cdr: CdrLayout, toks: list[Token], stream: np.ndarray,
                     out_cdr: CdrLayout | None = None) -> bytes:
    """The output record (4-byte sample length + CDR payload), each field packed whole."""
    return cdr_marshal(out_cdr or cdr, published_cdr_tokens(cdr, toks, stream, out_cdr))


def publish_cdr_reference(cdr: CdrLayout, toks: list[Token], stream: np.ndarray,
                          out_cdr: CdrLayout | None = None) -> bytes:
    """The output record written a byte per clock, as the generated publisher does: the
    sample length (computed from the values first), the header, then per field its padding
    zeros and its bytes (numbers shifted out little-endian), a NUL after each string."""
    out_toks = published_cdr_tokens(cdr, toks, stream, out_cdr)
    c = out_cdr or cdr
    steps = c.layout.steps
    length = 4          # the encapsulation header
    for t in out_toks:
        s = steps[t.step]
        n = _size(s, t.value)
        if n:
            length += c.pad(t.step, length + 4) + n
        length += 1 if s.kind is StepKind.STRING else 0
    out = bytearray()
    for k in range(4):
        out.append((length >> (8 * k)) & 0xFF)
    for byte in (0x00, 0x01, 0x00, 0x00):
        out.append(byte)
    for t in out_toks:
        s = steps[t.step]
        if _size(s, t.value):
            for _ in range(c.pad(t.step, len(out))):
                out.append(0)
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH):
            bits = int.from_bytes(encode_token(s, t.value), "little")  # the register's bits
            for k in range(s.size):
                out.append((bits >> (8 * k)) & 0xFF)
        else:
            for byte in encode_token(s, t.value):
                out.append(byte)
        if s.kind is StepKind.STRING:
            out.append(0)
    return bytes(out)


def _size(step: Step, value: Any) -> int:
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        return step.size
    if step.kind is StepKind.STRING:
        return len(value.encode("utf-8", "surrogateescape")) if isinstance(value, str) else len(value)
    return step.size * len(value)


__all__ = [
    "CdrInterpreter", "END_ALIGN", "TAIL_LABEL", "extract_cdr_fast", "extract_cdr_reference",
    "publish_cdr_fast", "publish_cdr_reference", "published_cdr_tokens",
]
