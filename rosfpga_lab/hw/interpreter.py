"""STEP 2, subscriber side: the message interpreter, a byte-at-a-time state machine.

TCP payload bytes of one ``sensor_msgs/Image`` publication arrive one per clock from the 8-bit
receive FIFO. The interpreter, like the HLS subscriber circuit, hard-codes the Image layout: it
walks :data:`INTERPRETER_TABLE` (the one copy of the rules; notebooks draw it), collecting each
field little-endian, checking it when complete, and writing the pixel bytes of ``data`` to its
output :class:`~rosfpga_lab.hw.streams.ByteFIFO`.

Each row of the table is a state: the field it collects, how long the field is (4 bytes for
``u32``, 1 for ``u8``, or the value of an earlier length field for ``string``/``pixels``), the
next state and the check run on the finished field. States, field kinds and checks are names of
one vocabulary each (:class:`IState`, :class:`Kind`, :class:`Check`); the message generator and
the HLS templates use the same :class:`Kind` names. A zero-length string skips its state.

On a bad field the interpreter raises a :class:`~rosfpga_lab.hw.errors.FrameFieldError` naming
field and byte offset, then resynchronises: if the frame length was sane it skips the rest of
the frame (state ``SKIP``) so the next frame is decoded right; otherwise it waits for a new
frame length. :meth:`Interpreter.reset` starts afresh at once (what the pipeline does, since it
is handed whole frames). The fast model (:func:`interpret_fast`) runs the same state machine
over the header and takes the pixel bytes as one numpy slice.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from rosfpga_lab.hw import limits
from rosfpga_lab.hw.encodings import PIXEL_FORMATS
from rosfpga_lab.hw.errors import (
    FrameFieldError, FrameLengthError, FrameTruncatedError, PipelineConfigError,
    UnsupportedEncodingError,
)
from rosfpga_lab.hw.streams import ByteFIFO

STAGE = "interpreter"


class _Name(StrEnum):
    """A name of the tables' vocabulary: equal to its text and shown as it (like h11's sentinels)."""

    def __repr__(self) -> str:
        return self.value


class Kind(_Name):
    """How a field sits in the frame (the interpreter's and the generator's one vocabulary)."""

    U32 = "u32"        # 4 bytes, little-endian
    U8 = "u8"          # 1 byte
    STRING = "string"  # a string's bytes (its uint32 length is the field before)
    PIXELS = "pixels"  # the image bytes of ``data`` (its length is the field before)


class IState(_Name):
    """States of the interpreter: one per field, plus SKIP (the rest of a refused frame)."""

    FRAME_LEN = "FRAME_LEN"
    SEQ = "SEQ"
    STAMP_SECS = "STAMP_SECS"
    STAMP_NSECS = "STAMP_NSECS"
    FRAME_ID_LEN = "FRAME_ID_LEN"
    FRAME_ID = "FRAME_ID"
    HEIGHT = "HEIGHT"
    WIDTH = "WIDTH"
    ENCODING_LEN = "ENCODING_LEN"
    ENCODING = "ENCODING"
    IS_BIGENDIAN = "IS_BIGENDIAN"
    STEP = "STEP"
    DATA_LEN = "DATA_LEN"
    DATA = "DATA"
    SKIP = "SKIP"


class Check(_Name):
    """The checks run when a field completes (each has one method of :class:`Interpreter`)."""

    FRAME_LENGTH = "frame_length"
    FRAME_ID_LENGTH = "frame_id_length"
    HEIGHT = "height"
    WIDTH = "width"
    ENCODING_LENGTH = "encoding_length"
    ENCODING = "encoding"
    STEP = "step"
    DATA_LENGTH = "data_length"
    FRAME_END = "frame_end"


@dataclass(frozen=True)
class Transition:
    """One state of the interpreter.

    Attributes:
        state: the state's name.
        field: key of the value in :attr:`Interpreter.values`.
        label: the field as error messages and notebooks name it.
        kind: how the field sits in the frame (:class:`Kind`).
        length_of: for ``string``/``pixels``: the field whose value is the length.
        next: the state after this one.
        check: name of the check run when the field is complete (``None``: no check).
    """

    state: IState
    field: str
    label: str
    kind: Kind
    length_of: str | None
    next: IState
    check: Check | None


_R, S, K, C = Transition, IState, Kind, Check
INTERPRETER_TABLE: tuple[Transition, ...] = (
    _R(S.FRAME_LEN, "frame_length", "frame length", K.U32, None, S.SEQ, C.FRAME_LENGTH),
    _R(S.SEQ, "seq", "header.seq", K.U32, None, S.STAMP_SECS, None),
    _R(S.STAMP_SECS, "stamp_secs", "header.stamp.secs", K.U32, None, S.STAMP_NSECS, None),
    _R(S.STAMP_NSECS, "stamp_nsecs", "header.stamp.nsecs", K.U32, None, S.FRAME_ID_LEN, None),
    _R(S.FRAME_ID_LEN, "frame_id_length", "header.frame_id length", K.U32, None, S.FRAME_ID,
       C.FRAME_ID_LENGTH),
    _R(S.FRAME_ID, "frame_id", "header.frame_id", K.STRING, "frame_id_length", S.HEIGHT, None),
    _R(S.HEIGHT, "height", "height", K.U32, None, S.WIDTH, C.HEIGHT),
    _R(S.WIDTH, "width", "width", K.U32, None, S.ENCODING_LEN, C.WIDTH),
    _R(S.ENCODING_LEN, "encoding_length", "encoding length", K.U32, None, S.ENCODING,
       C.ENCODING_LENGTH),
    _R(S.ENCODING, "encoding", "encoding", K.STRING, "encoding_length", S.IS_BIGENDIAN,
       C.ENCODING),
    _R(S.IS_BIGENDIAN, "is_bigendian", "is_bigendian", K.U8, None, S.STEP, None),
    _R(S.STEP, "step", "step", K.U32, None, S.DATA_LEN, C.STEP),
    _R(S.DATA_LEN, "data_length", "data length", K.U32, None, S.DATA, C.DATA_LENGTH),
    _R(S.DATA, "data", "data", K.PIXELS, "data_length", S.FRAME_LEN, C.FRAME_END),
)
#: The subscriber circuit's status codes, in code order: ``SUB_OK`` (0), then one per checked
#: field of the table (``SUB_BAD_<FIELD>``), with the field's label. The generated HLS C++
#: (``enum subscriber_status``) and the Verilog (``rfl_status.vh``) number them from here.
SUBSCRIBER_STATUSES: tuple[tuple[str, str], ...] = (("SUB_OK", "frame accepted"),) + tuple(
    (f"SUB_BAD_{t.field.upper()}", t.label) for t in INTERPRETER_TABLE
    if t.check and t.check != "frame_end")
#: Extra state entered after an error when the rest of the bad frame can be skipped.
SKIP_STATE = IState.SKIP
_BY_STATE = {t.state: t for t in INTERPRETER_TABLE}
_FIXED = {Kind.U32: 4, Kind.U8: 1}
#: Bytes of an Image body with empty strings and no pixels (the smallest legal frame length).
MIN_BODY_BYTES = 4 + 4 + 4 + 4 + 4 + 4 + 4 + 1 + 4 + 4


def fixed_after(field_name: str, table: tuple[Transition, ...] = INTERPRETER_TABLE
                ) -> tuple[int, tuple[str, ...]]:
    """The fixed-size fields between ``field_name`` and the next variable-length one.

    The generated subscriber checks that a string *and* these fields fit in the frame before
    reading on, so it never reads past the frame's end.

    Returns:
        ``(bytes, labels)``: their total size and their labels, in wire order.
    """
    names = [t.field for t in table]
    size, labels = 0, []
    for t in table[names.index(field_name) + 1:]:
        if t.length_of is not None:
            break
        size += _FIXED[t.kind]
        labels.append(t.label)
    return size, tuple(labels)


def format_table(table: tuple[Transition, ...] = INTERPRETER_TABLE) -> str:
    """The state table as aligned text (what a notebook prints before drawing it)."""
    rows = [("state", "field", "bytes", "next", "check")]
    for t in table:
        size = str(_FIXED[t.kind]) if t.length_of is None else f"= {t.length_of}"
        rows.append((t.state, t.label, size, t.next, t.check or "-"))
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


@dataclass(frozen=True)
class ImageFields:
    """The decoded fields of one ``sensor_msgs/Image`` frame (everything but the pixels).

    ``frame_id`` is decoded as UTF-8 with ``surrogateescape``, so encoding it back the same way
    gives the exact bytes received.
    """

    seq: int
    stamp_secs: int
    stamp_nsecs: int
    frame_id: str
    height: int
    width: int
    encoding: str
    is_bigendian: int
    step: int
    data_length: int
    frame_length: int = 0
    data_offset: int = 0

    def as_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (what ``PipelineResult.fields`` holds)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass
class Interpreter:
    """The subscriber circuit's message interpreter (reference model: one byte per :meth:`push`).

    Args:
        out: where pixel bytes go (a fresh unbounded :class:`ByteFIFO` when omitted).
        width, height, encoding: what the circuit was built for; ``None`` accepts any legal
            value. A frame that disagrees is refused, naming the field.
        max_frame_id_bytes: longest ``header.frame_id`` the circuit keeps (the node
            configuration's ``frame_id_max``); a longer one is refused.

    Attributes:
        state: the current state (a ``Transition.state``, or ``IState.SKIP``).
        offset: byte offset in the current frame of the next byte.
        values: the fields decoded so far in this frame.
        frames: how many frames were completed since construction.
        fields: the :class:`ImageFields` of the last frame whose header was complete.
    """

    out: ByteFIFO = field(default_factory=lambda: ByteFIFO(name="pixels_in"))
    width: int | None = None
    height: int | None = None
    encoding: str | None = None
    table: tuple[Transition, ...] = INTERPRETER_TABLE
    max_frame_id_bytes: int = limits.MAX_FRAME_ID_BYTES

    def __post_init__(self) -> None:
        if not 1 <= self.max_frame_id_bytes <= limits.MAX_FRAME_ID_BYTES:
            raise PipelineConfigError(f"max_frame_id_bytes must be in 1..{limits.MAX_FRAME_ID_BYTES}, "
                                      f"got {self.max_frame_id_bytes}")
        if self.encoding is not None and self.encoding not in PIXEL_FORMATS:
            raise PipelineConfigError(
                f"unsupported encoding {self.encoding!r}; the circuit packs {', '.join(PIXEL_FORMATS)}")
        self.frames = 0
        self.fields: ImageFields | None = None
        self.reset()

    # -- state handling ---------------------------------------------------------------------
    def reset(self) -> None:
        """Back to waiting for a frame length (a synchronous reset of the state machine)."""
        self.state = IState.FRAME_LEN
        self.offset = 0
        self.values: dict[str, Any] = {}
        self._acc = 0            # little-endian accumulator of a number field
        self._buf = bytearray()  # bytes of a string field
        self._count = 0          # bytes of the current field taken so far
        self._field_start = 0
        self._skip = 0

    @property
    def transition(self) -> Transition | None:
        """The table row of the current state (``None`` in ``SKIP``)."""
        return _BY_STATE.get(self.state)

    def field_length(self, t: Transition) -> int:
        """Bytes of the field collected in state ``t``."""
        return _FIXED[t.kind] if t.length_of is None else int(self.values[t.length_of])

    # -- the byte path ----------------------------------------------------------------------
    def push(self, byte: int) -> None:
        """Consume one byte from the receive FIFO (one clock cycle).

        Raises:
            FrameFieldError: (or a subclass) a field has a value the circuit refuses; the
                interpreter has already resynchronised.
        """
        if self.state is IState.SKIP:
            self._skip -= 1
            if self._skip == 0:
                self.reset()
            return
        t = _BY_STATE[self.state]
        if self._count == 0:
            self._field_start = self.offset
        self.offset += 1
        if t.kind is Kind.PIXELS:
            self.out.write(byte)
        elif t.kind is Kind.STRING:
            self._buf.append(byte)
        else:
            self._acc |= byte << (8 * self._count)
        self._count += 1
        if self._count == self.field_length(t):
            self._complete(t)
        elif self.state is not IState.FRAME_LEN and self.offset == 4 + self.values["frame_length"]:
            self._fail(FrameLengthError(
                f"the frame length ({self.values['frame_length']}) ends inside this field",
                t.label, self._field_start, self.values["frame_length"]))

    def trace(self, data: bytes, limit: int | None = None) -> list[tuple[int, int, str, str]]:
        """Push bytes one at a time, recording ``(offset, byte, state, field label)`` before each.

        For notebooks: a table of what the state machine did with every byte. Errors propagate
        (the rows up to the bad byte are lost with them; trace a prefix to see them).

        Args:
            data: the bytes to push.
            limit: stop after this many bytes (``None``: all of them).
        """
        rows: list[tuple[int, int, str, str]] = []
        for byte in data[:limit] if limit is not None else data:
            t = self.transition
            rows.append((self.offset, byte, self.state, t.label if t else "(skipping)"))
            self.push(byte)
        return rows

    def feed(self, data: bytes) -> None:
        """Push every byte of ``data`` (stops at the first error, which propagates)."""
        for byte in data:
            self.push(byte)

    def finish(self) -> None:
        """Declare the end of input: raise if a frame was left incomplete (then reset).

        Raises:
            FrameTruncatedError: the input stopped inside a frame; names the field being read.
        """
        if self.state is IState.FRAME_LEN and self._count == 0:
            return
        t = self.transition
        label = t.label if t else "frame"
        start = self._field_start if self._count else self.offset
        error = FrameTruncatedError(
            f"the frame was cut short: input ended at byte {self.offset}, "
            f"{self._count} of this field's bytes had arrived", label, start,
        )
        self.reset()
        raise error

    def _complete(self, t: Transition) -> None:
        if t.kind is Kind.STRING:
            value: Any = bytes(self._buf).decode("utf-8", "surrogateescape")
        elif t.kind is Kind.PIXELS:
            value = None
        else:
            value = self._acc
        self.values[t.field] = value
        self._acc, self._buf, self._count = 0, bytearray(), 0
        if t.check is not None:
            _CHECKS[t.check](self, value, t)
        self.state = t.next
        if self.state is IState.DATA:
            self.fields = self._make_fields()
        if t.kind is Kind.PIXELS:
            self.frames += 1
            self.reset()
            return
        nxt = _BY_STATE[self.state]
        if self.offset == 4 + self.values["frame_length"]:
            self._fail(FrameLengthError(
                f"the frame length ({self.values['frame_length']}) ends before this field",
                nxt.label, self.offset, self.values["frame_length"]))
        if nxt.length_of is not None and self.field_length(nxt) == 0:
            self._field_start = self.offset
            self._complete(nxt)  # an empty string (or empty data) completes at once

    def _make_fields(self) -> ImageFields:
        v = self.values
        return ImageFields(v["seq"], v["stamp_secs"], v["stamp_nsecs"], v["frame_id"],
                           v["height"], v["width"], v["encoding"], v["is_bigendian"], v["step"],
                           v["data_length"], v["frame_length"], self.offset)

    def _fail(self, error: FrameFieldError) -> None:
        """Resynchronise, then raise ``error``."""
        frame_length = self.values.get("frame_length")
        remaining = 4 + frame_length - self.offset if frame_length is not None else 0
        self.reset()
        if remaining > 0:
            self.state, self._skip = IState.SKIP, remaining
        raise error

    # -- the checks run when a field completes ------------------------------------------------
    def _refuse(self, t: Transition, message: str, value: Any, cls: type = FrameFieldError, *,
                rule: str = "") -> None:
        self._fail(cls(message, t.label, self._field_start, value, rule=rule))

    def _check_frame_length(self, value: int, t: Transition) -> None:
        if value < MIN_BODY_BYTES:
            self._refuse(t, f"{value} is shorter than the smallest sensor_msgs/Image "
                            f"({MIN_BODY_BYTES} bytes)", value, FrameLengthError,
                         rule="below the minimum")
        if value > limits.MAX_FRAME_BYTES:
            self._refuse(t, f"{value} exceeds the limit of {limits.MAX_FRAME_BYTES} bytes "
                            "(hw.limits.MAX_FRAME_BYTES)", value, FrameLengthError,
                         rule="over the limit")

    def _check_string(self, value: int, t: Transition, limit: int, limit_name: str) -> None:
        if value > limit:
            self._refuse(t, f"{value} exceeds the limit of {limit} bytes ({limit_name})", value,
                         rule="over the limit")
        left = 4 + self.values["frame_length"] - self.offset
        if value > left:
            self._refuse(t, f"{value} bytes announced but the frame length leaves only {left}",
                         value, FrameLengthError, rule="past the frame end")

    def _check_frame_id_length(self, value: int, t: Transition) -> None:
        self._check_string(value, t, self.max_frame_id_bytes, "max_frame_id_bytes")

    def _check_encoding_length(self, value: int, t: Transition) -> None:
        self._check_string(value, t, limits.MAX_ENCODING_BYTES, "hw.limits.MAX_ENCODING_BYTES")

    def _check_dimension(self, value: int, t: Transition, limit: int, configured: int | None) -> None:
        if value == 0:
            self._refuse(t, "is 0: an image needs at least one row and one column", value,
                         rule="zero")
        if value > limit:
            self._refuse(t, f"{value} exceeds the limit of {limit} (hw.limits.MAX_{t.field.upper()})",
                         value, rule="over the limit")
        if configured is not None and value != configured:
            self._refuse(t, f"{value} but the circuit was built for {t.field} {configured}", value,
                         rule="not what the circuit was built for")

    def _check_height(self, value: int, t: Transition) -> None:
        self._check_dimension(value, t, limits.MAX_HEIGHT, self.height)

    def _check_width(self, value: int, t: Transition) -> None:
        self._check_dimension(value, t, limits.MAX_WIDTH, self.width)

    def _check_encoding(self, value: str, t: Transition) -> None:
        if value not in PIXEL_FORMATS:
            self._refuse(t, f"{value!r} is not supported; the circuit packs "
                            f"{', '.join(PIXEL_FORMATS)}", value, UnsupportedEncodingError)
        if self.encoding is not None and value != self.encoding:
            self._refuse(t, f"{value!r} but the circuit was built for {self.encoding!r}", value,
                         UnsupportedEncodingError, rule="not what the circuit was built for")

    def _check_step(self, value: int, t: Transition) -> None:
        row = self.values["width"] * PIXEL_FORMATS[self.values["encoding"]].bytes_per_pixel
        if value != row:
            self._refuse(t, f"{value} but width {self.values['width']} x "
                            f"{PIXEL_FORMATS[self.values['encoding']].bytes_per_pixel} bytes/pixel "
                            f"({self.values['encoding']}) = {row}; padded rows are not supported",
                         value, rule="not width x bytes per pixel")

    def _check_data_length(self, value: int, t: Transition) -> None:
        expected = self.values["step"] * self.values["height"]
        if value != expected:
            self._refuse(t, f"{value} but step x height = {self.values['step']} x "
                            f"{self.values['height']} = {expected}", value,
                         rule="not step x height")
        left = 4 + self.values["frame_length"] - self.offset
        if value != left:
            self._fail(FrameLengthError(
                f"{self.values['frame_length']} announces {left} bytes after the data length "
                f"field, but data length is {value}", "frame length", 0,
                self.values["frame_length"]))

    def _check_frame_end(self, value: None, t: Transition) -> None:
        # data_length was checked against the frame length, so the frame ends exactly here.
        assert self.offset == 4 + self.values["frame_length"]


#: The method that runs each check (one per :class:`Check`; a test holds the two equal).
_CHECKS: dict[Check, Callable[[Interpreter, Any, Transition], None]] = {
    Check.FRAME_LENGTH: Interpreter._check_frame_length,
    Check.FRAME_ID_LENGTH: Interpreter._check_frame_id_length,
    Check.HEIGHT: Interpreter._check_height,
    Check.WIDTH: Interpreter._check_width,
    Check.ENCODING_LENGTH: Interpreter._check_encoding_length,
    Check.ENCODING: Interpreter._check_encoding,
    Check.STEP: Interpreter._check_step,
    Check.DATA_LENGTH: Interpreter._check_data_length,
    Check.FRAME_END: Interpreter._check_frame_end,
}


def interpret_reference(rx: ByteFIFO, out: ByteFIFO, *, width: int | None = None,
                        height: int | None = None, encoding: str | None = None,
                        max_frame_id_bytes: int = limits.MAX_FRAME_ID_BYTES) -> ImageFields:
    """Run the reference interpreter over every byte in ``rx`` (one frame).

    Returns:
        the decoded fields; the pixel bytes are in ``out``.

    Raises:
        FrameFieldError: a bad field, a frame cut short, or bytes left after the frame.
    """
    interp = Interpreter(out, width, height, encoding, max_frame_id_bytes=max_frame_id_bytes)
    while not rx.empty:
        interp.push(rx.read(STAGE))
        if interp.frames:
            break
    interp.finish()
    require_frame(interp)
    check_trailing(interp, rx.level)
    assert interp.fields is not None
    return interp.fields


def interpret_fast(frame: bytes, *, width: int | None = None, height: int | None = None,
                   encoding: str | None = None,
                   max_frame_id_bytes: int = limits.MAX_FRAME_ID_BYTES) -> tuple[ImageFields, np.ndarray]:
    """Fast model: the same state machine over the header, the pixels as one numpy slice.

    Returns:
        ``(fields, pixels)`` with ``pixels`` a uint8 array (a view of ``frame``).

    Raises:
        FrameFieldError: exactly as :func:`interpret_reference` would.
    """
    interp = Interpreter(ByteFIFO(name="pixels_in"), width, height, encoding,
                         max_frame_id_bytes=max_frame_id_bytes)
    view = memoryview(frame)
    pos = 0
    while pos < len(view) and interp.state is not IState.DATA and not interp.frames:
        interp.push(view[pos])
        pos += 1
    if interp.state is IState.DATA:
        n = interp.values["data_length"]
        if len(view) - pos < n:
            got = len(view) - pos
            raise FrameTruncatedError(
                f"the frame was cut short: input ended at byte {len(view)}, "
                f"{got} of this field's bytes had arrived", "data", pos)
        pixels = np.frombuffer(frame, np.uint8, n, pos)
        pos += n
        interp.frames += 1
        interp.reset()
    else:
        interp.finish()
        require_frame(interp)
        pixels = np.zeros(0, np.uint8)
    check_trailing(interp, len(view) - pos)
    assert interp.fields is not None
    return interp.fields, pixels


def require_frame(interp: Interpreter, frames_before: int = 0) -> None:
    """Raise :class:`FrameTruncatedError` when the input ended before any frame began."""
    if interp.frames == frames_before:
        raise FrameTruncatedError("the input held no bytes at all", "frame length", 0)


def check_trailing(interp: Interpreter, left: int) -> None:
    """Raise :class:`FrameLengthError` when ``left`` bytes follow the decoded frame."""
    if left:
        fields = interp.fields
        length = fields.frame_length if fields else 0
        raise FrameLengthError(
            f"the frame length ({length}) ends the frame at byte {4 + length}, but {left} more "
            "bytes were given; pass one frame at a time", "frame length", 0, length)
