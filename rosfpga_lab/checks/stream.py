"""Checks of notebook 4 (STEP 3): packing pixels into AXI4-Stream beats (Figure 7)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type
from rosfpga_lab.hw import Beat, Beats, fifo2axi_fast, pixel_format

#: The cases :func:`check_fifo2axi` runs: (encoding, rows, cols).
FIFO2AXI_CASES = (("rgba8", 2, 3), ("mono8", 3, 2), ("rgb8", 2, 4))


def check_tdata(answer: Any, pixel: Sequence[int]) -> CheckResult:
    """Exercise 4.1: the 32-bit ``tdata`` of one rgba8 pixel (byte 0 = R in bits 7..0).

    Args:
        answer: the reader's ``tdata`` (int).
        pixel: the pixel's bytes as they sit in the message, e.g. ``(R, G, B, A)``.

    Raises:
        ExerciseError: the wrong lane order (big-endian) or wrong lanes (named by bits).
    """
    ex = "4.1 (one pixel into tdata)"
    require_type(ex, "tdata", answer, int,
                 "a number, not text: write a hex literal without quotes, or convert with "
                 "int(text, 16)" if isinstance(answer, str) else "a number such as 0xCAFE")
    answer = int(answer)
    pix = [int(b) for b in pixel]
    want = sum(b << (8 * i) for i, b in enumerate(pix))
    if answer == want:
        return CheckResult(ex, [f"tdata = 0x{want:08x}: byte i of the pixel in bits 8i+7..8i "
                                "(little-endian byte lanes)"])
    if answer == sum(b << (8 * (len(pix) - 1 - i)) for i, b in enumerate(pix)):
        raise fail(ex, f"0x{answer:08x} puts byte 0 ({pix[0]:#04x}) in the high bits; Figure 7 "
                       "puts byte 0 in bits 7..0 (lane 0), byte 1 in bits 15..8, ...")
    if not 0 <= answer < 2**32:
        raise fail(ex, f"tdata {answer} does not fit in 32 bits")
    problems = []
    names = pixel_format("rgba8").channels if len(pix) == 4 else "0123"
    for i in range(4):
        have, lane = (answer >> (8 * i)) & 0xFF, (want >> (8 * i)) & 0xFF
        if have != lane:
            problems.append(f"bits {8 * i + 7}..{8 * i} hold 0x{have:02x}, expected 0x{lane:02x} "
                            f"(byte {i}, {names[i]})")
    raise fail(ex, *problems)


def _flags(exercise: str, name: str, value: Any, n: int) -> np.ndarray:
    require_answer(exercise, name, value)
    try:
        arr = np.asarray(value).astype(bool).reshape(-1)
    except (TypeError, ValueError):
        raise fail(exercise, f"{name} should be a list of {n} booleans (one per beat)") from None
    if arr.size != n:
        raise fail(exercise, f"{name} has {arr.size} entries; a {n}-pixel frame has {n} beats "
                             "(one pixel per beat)")
    return arr


def check_markers(tuser: Any, tlast: Any, width: int, height: int) -> CheckResult:
    """Exercise 4.2: ``tuser`` and ``tlast`` of every beat of a ``width x height`` frame.

    Raises:
        ExerciseError: beats with a wrong flag, with the pixel they carry.
    """
    ex = "4.2 (TUSER and TLAST)"
    n = width * height
    u = _flags(ex, "tuser", tuser, n)
    last = _flags(ex, "tlast", tlast, n)
    problems = []
    for beat in range(n):
        x, y = beat % width, beat // width
        if u[beat] != (beat == 0):
            problems.append(f"beat {beat} (pixel x={x}, y={y}) has tuser={int(u[beat])}; "
                            + ("the first beat of a frame has tuser=1 (start of frame)" if beat == 0
                               else "only the frame's first beat has tuser=1"))
        if last[beat] != (x == width - 1):
            problems.append(f"beat {beat} (pixel x={x}, y={y}) has tlast={int(last[beat])}; "
                            + (f"it is the last pixel of row {y}: tlast=1 (end of line)"
                               if x == width - 1 else
                               f"tlast=1 marks the end of a line (x={width - 1}), not this pixel"))
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"tuser on beat 0 only; tlast on beats {width - 1}, {2 * width - 1}, ... "
                            f"(every {width}th: the end of each line)"])


def _as_beats(exercise: str, value: Any) -> Beats:
    if isinstance(value, Beats):
        return value
    try:
        items = list(value)
        beats = [b if isinstance(b, Beat) else Beat(int(b[0]), int(b[1]), bool(b[2]), bool(b[3]))
                 for b in items]
    except (TypeError, ValueError, IndexError):
        raise fail(exercise, "your function should return a list of (tdata, tkeep, tuser, tlast) "
                             "tuples (or hw.Beat / hw.Beats)") from None
    return Beats.from_list(beats)


def check_fifo2axi(fn: Callable[..., Any]) -> CheckResult:
    """Exercise 4.3: the reader's ``fifo2axi(data, rows, cols, bytes_per_pixel)``.

    It is run on rgba8, mono8 and rgb8 frames (:data:`FIFO2AXI_CASES`) and compared beat by beat
    with the lab's model.

    Raises:
        ExerciseError: the first beat that differs, signal by signal.
    """
    ex = "4.3 (fifo2axi for every encoding)"
    require_answer(ex, "fifo2axi", fn)
    if not callable(fn):
        raise fail(ex, "pass your function itself: check_fifo2axi(my_fifo2axi)")
    rng = np.random.default_rng(7)
    done = []
    for encoding, rows, cols in FIFO2AXI_CASES:
        fmt = pixel_format(encoding)
        data = rng.integers(0, 256, rows * cols * fmt.bytes_per_pixel, dtype=np.uint8)
        want, _left = fifo2axi_fast(data, rows, cols, fmt)
        case = f"{encoding} {cols}x{rows}"
        try:
            result = fn(bytes(data), rows, cols, fmt.bytes_per_pixel)
        except Exception as exc:  # the reader's code: report, do not crash the check
            raise fail(ex, f"on {case} your function raised {type(exc).__name__}: {exc}") from None
        got = _as_beats(ex, result)
        if got == want:
            done.append(case)
            continue
        if len(got) != len(want):
            raise fail(ex, f"on {case}: {len(got)} beats, expected {len(want)} (one beat per pixel)")
        i = got.first_difference(want)
        assert i is not None
        g, w = got[i], want[i]
        problems = [f"on {case}, beat {i} (pixel x={i % cols}, y={i // cols}) is {g!r}, expected {w!r}"]
        if g.tdata != w.tdata:
            problems.append(f"tdata: byte j of the pixel goes to bits 8j+7..8j; unused high lanes "
                            f"are 0 ({fmt.bytes_per_pixel} byte(s) per pixel)")
        if g.tkeep != w.tkeep:
            problems.append(f"tkeep: one bit per byte lane used: 0b{w.tkeep:04b} for "
                            f"{fmt.bytes_per_pixel} byte(s) per pixel")
        if (g.tuser, g.tlast) != (w.tuser, w.tlast):
            problems.append("tuser on the first beat only, tlast on the last pixel of each line")
        raise fail(ex, *problems)
    return CheckResult(ex, [f"beat-for-beat equal to the lab's fifo2axi on {', '.join(done)}"])
