"""Checks of notebook 5: the dilate application and what its cycle count means."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type

#: Images :func:`check_dilate` runs the reader's function on: (rows, cols, channels).
DILATE_CASES = ((5, 7, 1), (6, 4, 4), (1, 5, 3), (9, 9, 1))


def _reference(image: np.ndarray) -> np.ndarray:
    out = cv2.dilate(image, np.ones((3, 3), np.uint8))
    return out.reshape(image.shape)


def check_dilate(fn: Callable[[np.ndarray], Any]) -> CheckResult:
    """Exercise 5.1: the reader's 3x3 dilate, ``fn(image) -> image``, against ``cv2.dilate``.

    ``image`` is ``(rows, cols, channels)`` uint8. Runs on :data:`DILATE_CASES` (random pixels).

    Raises:
        ExerciseError: wrong shape or dtype, or mismatching pixels (count and first position,
            with a hint when they sit on the border or look shifted).
    """
    ex = "5.1 (3x3 dilate)"
    require_answer(ex, "dilate", fn)
    if not callable(fn):
        raise fail(ex, "pass your function itself: check_dilate(my_dilate)")
    rng = np.random.default_rng(5)
    for rows, cols, ch in DILATE_CASES:
        image = rng.integers(0, 256, (rows, cols, ch), dtype=np.uint8)
        want = _reference(image)
        case = f"a {cols}x{rows} image with {ch} channel(s)"
        try:
            got = fn(image.copy())
        except Exception as exc:  # the reader's code
            raise fail(ex, f"on {case} your function raised {type(exc).__name__}: {exc}") from None
        if got is None:
            raise fail(ex, f"on {case} your function returned None: did you forget "
                           "'return out' at its end?")
        got = np.asarray(got)
        if got.shape != want.shape and got.size == want.size:
            got = got.reshape(want.shape)
        if got.shape != want.shape:
            hint = (" (dilate keeps the image size: handle the border, where the window is "
                    "partly outside)" if got.ndim >= 2 and got.shape[0] < rows else "")
            raise fail(ex, f"on {case} your output has shape {got.shape}, expected {want.shape}{hint}")
        if got.dtype != np.uint8:
            raise fail(ex, f"on {case} your output is {got.dtype}; keep uint8")
        bad = np.argwhere((got != want).any(axis=2))
        if bad.size:
            y, x = (int(v) for v in bad[0])
            c = int(np.flatnonzero(got[y, x] != want[y, x])[0])
            problems = [f"on {case}, {len(bad)} pixel(s) differ; first at x={x}, y={y}: channel {c} "
                        f"is {got[y, x, c]}, expected {want[y, x, c]} (the maximum of the 3x3 window "
                        "around it)"]
            border = (bad[:, 0] == 0) | (bad[:, 0] == rows - 1) | (bad[:, 1] == 0) | (bad[:, 1] == cols - 1)
            if border.all():
                problems.append("all of them are on the border: there only the part of the window "
                                "inside the image counts (no wrap-around as with np.roll)")
            else:
                for dy, dx in ((1, 1), (1, 0), (0, 1)):
                    shifted = np.zeros_like(want)
                    shifted[: rows - dy, : cols - dx] = want[dy:, dx:]
                    if np.array_equal(got[: rows - dy, : cols - dx], shifted[: rows - dy, : cols - dx]):
                        problems.append("your output looks shifted: the window is centred on its "
                                        "pixel (rows y-1..y+1, columns x-1..x+1)")
                        break
            raise fail(ex, *problems)
    return CheckResult(ex, ["equal to cv2.dilate with a 3x3 rectangle on "
                            f"{len(DILATE_CASES)} random images, borders included"])


def check_frame_timing(filter_cycles: Any, filter_ms: Any, bottleneck: Any, *, width: int = 640,
                       height: int = 480, bytes_per_pixel: int = 4,
                       clock_hz: float = 100e6) -> CheckResult:
    """Exercise 5.2: cycles of the 3x3 filter, its time per frame, and the slowest stage.

    Args:
        filter_cycles: cycles the filter needs for one frame (one pixel per clock, plus the
            flush: one more row and one more column for a 3x3 window).
        filter_ms: ``filter_cycles`` at ``clock_hz``, in milliseconds (the filter's time per
            frame, not the frame's: that is the byte-wide stages').
        bottleneck: ``"filter"`` or ``"byte-wide stages"`` (the 8-bit FIFO side).

    Raises:
        ExerciseError: the wrong figure, with the likely slip.
    """
    ex = "5.2 (cycles and time per frame)"
    require_type(ex, "filter_cycles", filter_cycles, int)
    require_type(ex, "filter_ms", filter_ms, (int, float))
    require_type(ex, "bottleneck", bottleneck, str)
    want_cycles = (height + 1) * (width + 1)
    want_ms = want_cycles / clock_hz * 1e3
    byte_ms = width * height * bytes_per_pixel / clock_hz * 1e3
    problems = []
    if filter_cycles != want_cycles:
        if filter_cycles == width * height:
            problems.append(f"filter_cycles {filter_cycles} is one clock per pixel; the window "
                            "also runs one row and one column past the image to flush (dy=dx=1)")
        elif filter_cycles == width * height * bytes_per_pixel:
            problems.append(f"filter_cycles {filter_cycles} counts bytes; the filter takes one "
                            "pixel (all 4 bytes on the 32-bit bus) per clock")
        else:
            problems.append(f"filter_cycles is {filter_cycles}, expected (rows + 1) x (cols + 1)")
    if abs(float(filter_ms) - want_ms) > 1e-3 * want_ms:
        if abs(float(filter_ms) - want_ms * 1e3) < 1e-3 * want_ms * 1e3:
            problems.append("filter_ms is in microseconds: divide by 1000")
        elif abs(float(filter_ms) * 1e3 - want_ms) < 1e-3 * want_ms:
            problems.append("filter_ms is in seconds: multiply by 1000")
        elif abs(float(filter_ms) - filter_cycles / clock_hz * 1e3) < 1e-6 and filter_cycles != want_cycles:
            pass  # follows from the wrong cycle count, already reported
        elif abs(float(filter_ms) - byte_ms) < 0.01 * byte_ms:
            problems.append(f"filter_ms is {float(filter_ms):.6g}: that is about the byte-wide "
                            f"stages' time, the frame's ({byte_ms:.3f} ms); filter_ms asks for the "
                            "filter's alone: filter_cycles / clock, in ms")
        else:
            problems.append(f"filter_ms is {float(filter_ms):.6g}, expected {want_ms:.4f} (cycles / "
                            f"{clock_hz / 1e6:g} MHz, in ms)")
    norm = bottleneck.strip().lower().replace("_", " ").replace("-", " ")
    if not any(word in norm for word in ("byte", "fifo", "interpreter", "walker", "subscriber",
                                         "publisher")):
        problems.append(f"bottleneck {bottleneck!r}: the byte-wide stages move one byte per clock, "
                        f"{width * height * bytes_per_pixel:,} clocks for the pixels alone, "
                        f"{bytes_per_pixel}x the filter's")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"filter: {want_cycles:,} cycles = {want_ms:.3f} ms at {clock_hz / 1e6:g} MHz",
                            f"byte-wide stages: {width * height * bytes_per_pixel:,}+ cycles: the 8-bit "
                            "FIFO, not the filter, sets the frame rate"])
