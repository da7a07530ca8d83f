"""CDR subscriber and publisher models of any message type, rendered from its CDR walk.

How this works: :class:`CdrInterpreter` is :class:`~rosfpga_lab.hw.walker.LayoutInterpreter`
(the reference model, one byte per clock) over :class:`~rosfpga_lab.hw.cdrlayout.CdrLayout`'s
steps with CDR's three additions: before a step it skips the step's alignment padding (counted
from after the encapsulation header), it checks the encapsulation header (representation
CDR little-endian; the options' low bits give the padding that ends the payload, skipped after
the last field) and a string's NUL, and a string takes ``length - 1`` bytes. After the last
field it also takes, when the options announce fewer (Cyclone DDS: none), the 1 to 3 bytes that
bring the serialized payload (header included) to a multiple of 4: RTPS 2.5 9.4.2.11 and
DDS-XTypes 1.3 7.6.3.1.2 ask for that padding, and Cyclone DDS sends it with options ``00 00``
(a 398-byte ``lab_msgs/Samples`` arrives as 400 bytes); like every padding byte, their values
are not looked at (CDR leaves them undefined); more bytes are refused. Refusals and
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
    END_ALIGN, OPTIONS_PADDING_MASK, TAIL_LABEL, CdrLayout, cdr_length_rules,
    cdr_marshal, to_base_tokens, to_cdr_tokens, unannounced_padding,
)
from rosfpga_lab.hw.errors import FrameLengthError, FrameTruncatedError
from rosfpga_lab.hw.layoutsteps import Step, StepKind
from rosfpga_lab.hw.layouttokens import Token
from rosfpga_lab.hw.publisherwalker import published_tokens, shift_out, value_size, write_value
from rosfpga_lab.hw.subscriberwalker import (
    Extracted, LayoutInterpreter, run_fast, run_reference,
)
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
        self._tail = 0
        self._tail_left = 0
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
        return self._sample_end - self._tail

    def _align(self, pc: int) -> int:
        """CDR alignment padding before step ``pc`` (counted from after the header)."""
        return self.cdr.pad(pc, self.offset)

    # -- the byte path --------------------------------------------------------------------------
    def push(self, byte: int) -> None:
        """Consume one byte (one clock).

        Raises:
            FrameFieldError: (or a subclass) the circuit refuses the sample; it has resynchronised.
        """
        if self._tail_left:
            self.offset += 1
            self._tail_left -= 1         # an end padding byte (its value is not looked at)
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

    def _frame_done(self) -> None:
        assert self._frame_length is not None
        if unannounced_padding(self.offset, self._end, self._sample_end):
            self._tail = self._sample_end - self.offset
        self._done = self._extracted()
        if self._tail:
            self._tail_left = self._tail
            self.pc = -1
            return
        self._publish_done()

    def _publish_done(self) -> None:
        assert self._done is not None
        self._publish(self._done)

    def _take_tail(self, view: memoryview) -> bool:
        """Fast model: take the end padding whole (its bytes are not looked at)."""
        if not self._tail_left:
            return False
        if self.offset + self._tail_left > len(view):
            raise FrameTruncatedError("the sample was cut short in its end padding",
                                      TAIL_LABEL, len(view))
        self.offset += self._tail_left
        self._tail_left = 0
        self._publish_done()
        return True


def extract_cdr_reference(cdr: CdrLayout, frame: bytes) -> Extracted:
    """Push ``frame`` (4-byte sample length + one CDR payload) a byte at a time.

    Raises:
        FrameFieldError: as the circuit refuses it; a sample cut short; bytes after it.
    """
    return run_reference(CdrInterpreter(cdr), frame, "sample")


def extract_cdr_fast(cdr: CdrLayout, frame: bytes) -> Extracted:
    """The same machine a whole step at a time (the stream as a numpy view of ``frame``).

    Raises:
        FrameFieldError: exactly as :func:`extract_cdr_reference` would.
    """
    return run_fast(CdrInterpreter(cdr), frame, "sample")


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
        n = value_size(s, t.value)
        if n:
            length += c.pad(t.step, length + 4) + n
        length += 1 if s.kind is StepKind.STRING else 0
    out = bytearray()
    shift_out(out, length, 4)
    for byte in (0x00, 0x01, 0x00, 0x00):
        out.append(byte)
    for t in out_toks:
        s = steps[t.step]
        if value_size(s, t.value):
            for _ in range(c.pad(t.step, len(out))):
                out.append(0)
        write_value(out, s, t.value)
        if s.kind is StepKind.STRING:
            out.append(0)
    return bytes(out)


__all__ = [
    "CdrInterpreter", "END_ALIGN", "TAIL_LABEL", "extract_cdr_fast", "extract_cdr_reference",
    "publish_cdr_fast", "publish_cdr_reference", "published_cdr_tokens",
]
