"""Framing of an AXI4-Stream video input: how a stage re-aligns a damaged beat stream.

As Xilinx's AXI4-Stream video IP, a stage emits exactly one well-formed frame (``rows * cols``
beats, TUSER on the first, TLAST at each line end) for every frame it starts, so the stages
after it keep their byte count, and sets sticky status flags for what it repaired:

* beats before a TUSER beat are dropped (wait for the start of frame): ``sof_missing``;
* TLAST before a line's last pixel: the rest of the line is zero pixels: ``eol_early``;
* no TLAST on a line's last pixel: the beats after it are dropped up to and with the next
  TLAST (a TUSER beat ends the dropping and starts a frame): ``eol_late``;
* TUSER inside a frame: the rest of the frame is zero pixels and the TUSER beat starts the
  next frame: ``sof_early``.

``rosfpga_lab/rtl/verilog/rfl_morph.v`` implements these rules at its input (its ``framing``
port holds the flags, bit ``i`` = :data:`FRAMING_FLAGS` ``[i]``). :func:`reframe_reference`
walks the beats one at a time as the circuit does; :func:`reframe_fast` cuts the stream into
lines with numpy (the tests hold the two equal, and both equal to the RTL).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.streams import Beats

#: The status flags, bit ``i`` of the circuit's ``framing`` port = entry ``i``
#: (Xilinx Video In / VDMA terminology).
FRAMING_FLAGS = ("sof_early", "eol_early", "eol_late", "sof_missing")
SOF_EARLY, EOL_EARLY, EOL_LATE, SOF_MISSING = (1 << i for i in range(len(FRAMING_FLAGS)))


def flag_names(flags: int) -> list[str]:
    """The names of the flags set in ``flags`` (bit order of :data:`FRAMING_FLAGS`)."""
    return [name for i, name in enumerate(FRAMING_FLAGS) if flags >> i & 1]


@dataclass
class Reframed:
    """What the framing stage made of a beat stream.

    Attributes:
        frames: one ``(rows * cols,)`` uint32 array of pixel words per frame completed
            (lanes beyond the pixel kept as they came; a padded pixel is 0).
        frame_flags: per completed frame, the flags raised while waiting for it and inside it.
        flags: the sticky flags after the whole stream (every frame's, and those of a frame
            begun but not completed, and of beats dropped after the last frame).
        used: beats consumed (taken as pixels or dropped); the rest wait in the stream.
    """

    frames: list[np.ndarray]
    frame_flags: list[int]
    flags: int
    used: int


def _check(rows: int, cols: int) -> None:
    if rows < 1 or cols < 1:
        raise PipelineConfigError(f"bad frame size {cols}x{rows}: both sides must be >= 1")


def reframe_reference(beats: Beats, rows: int, cols: int) -> Reframed:
    """Beat-at-a-time model of the framing rules (mirrors ``rfl_morph.v``'s input)."""
    _check(rows, cols)
    tdata, tuser, tlast = beats.tdata, beats.tuser, beats.tlast
    n = len(beats)
    i, drop, flags, mark = 0, False, 0, 0
    frames: list[np.ndarray] = []
    per_frame: list[int] = []
    while True:
        # wait for the start of frame
        while i < n and not tuser[i]:
            if drop:
                drop = not tlast[i]
            else:
                flags |= SOF_MISSING
            i += 1
        if i >= n:
            break
        drop = False
        pixels = np.zeros(rows * cols, np.uint32)
        padf, done = False, True
        for r in range(rows):
            padl = False
            for c in range(cols):
                if padf or padl:
                    continue                            # a zero pixel, no beat taken
                while drop and i < n and not tuser[i]:  # the rest of a too-long line
                    drop = not tlast[i]
                    i += 1
                if i >= n:
                    done = False
                    break
                drop = False
                if tuser[i] and (r, c) != (0, 0):       # a new frame inside this one
                    flags |= SOF_EARLY
                    padf = True
                    continue
                pixels[r * cols + c] = tdata[i]
                if tlast[i] and c != cols - 1:
                    flags |= EOL_EARLY
                    padl = True
                if not tlast[i] and c == cols - 1:
                    flags |= EOL_LATE
                    drop = True
                i += 1
            if not done:
                break
        if not done:
            break
        frames.append(pixels)
        per_frame.append(flags & ~mark)
        mark = flags
    while drop and i < n and not tuser[i]:     # beats dropped after the last frame
        drop = not tlast[i]
        i += 1
    return Reframed(frames, per_frame, flags, i)


def reframe_fast(beats: Beats, rows: int, cols: int) -> Reframed:
    """Fast model of :func:`reframe_reference`: whole lines cut out with numpy."""
    _check(rows, cols)
    tdata = np.asarray(beats.tdata, np.uint32)
    tuser = np.asarray(beats.tuser, bool)
    tlast = np.asarray(beats.tlast, bool)
    n = len(tdata)
    users = np.flatnonzero(tuser)
    lasts = np.flatnonzero(tlast)

    def next_of(idx: np.ndarray, start: int) -> int:
        k = int(np.searchsorted(idx, start))
        return int(idx[k]) if k < len(idx) else n

    def end_drop(i: int) -> int:           # the beat after the dropped ones
        return min(next_of(lasts, i) + 1, next_of(users, i))

    i, drop, flags, mark = 0, False, 0, 0
    frames: list[np.ndarray] = []
    per_frame: list[int] = []
    while True:
        start = next_of(users, i)
        if drop:
            j = end_drop(i)
            if j < start:                      # beats after the drop, before the TUSER
                flags |= SOF_MISSING
        elif start > i:
            flags |= SOF_MISSING
        if start >= n:
            i = n                              # every beat dropped while waiting
            break
        i, drop = start, False
        pixels = np.zeros(rows * cols, np.uint32)
        done = True
        for r in range(rows):
            if drop:
                i = end_drop(i)
                drop = False
            if i >= n:
                done = False
                break
            # the line runs up to the first TLAST or the next TUSER, at most cols beats
            first_user = next_of(users, i + 1 if r == 0 else i)
            stop = min(first_user, i + cols, n)
            last = next_of(lasts, i)
            take = min(stop, last + 1) - i
            pixels[r * cols: r * cols + take] = tdata[i: i + take]
            i += take
            if take == cols:
                if not tlast[i - 1]:
                    flags |= EOL_LATE
                    drop = True
                continue
            if take > 0 and tlast[i - 1]:
                flags |= EOL_EARLY              # the rest of the line is zero
                continue
            if i < n:                           # stopped at a TUSER: the frame is over
                flags |= SOF_EARLY
                break
            done = False                        # the stream ran out inside the line
            break
        if not done:
            break
        frames.append(pixels)
        per_frame.append(flags & ~mark)
        mark = flags
    return Reframed(frames, per_frame, flags, i)
