"""The application circuit: rectangular dilate (``hls::Dilate``) and erode (``hls::Erode``).

The reference model is a streaming filter as HLS builds it: pixels arrive one per clock in
raster order; a *line buffer* keeps the last ``kh`` rows of every column; a ``kw x kh``
*window* slides along the row, taking one new column from the line buffer per clock. Window
cells outside the image hold ``None`` and are ignored, so each output is the maximum (dilate)
or minimum (erode) over the part of the rectangle inside the image: exactly ``cv2.dilate`` /
``cv2.erode`` with their default border (for a maximum or minimum, a replicated border, as
HLS line-buffer filters often use, gives the same result). The anchor is the kernel centre (``k // 2``), as
OpenCV's default; the output pixel at ``(r, c)`` can only be produced once input pixel
``(r + dy, c + dx)`` has arrived, so the loops run ``dy`` rows and ``dx`` columns past the
image (the flush) and the output lags the input by ``dy`` lines and ``dx`` pixels.

``ksize`` is ``(width, height)``, OpenCV's order. The fast model calls ``cv2.dilate`` /
``cv2.erode`` (the tests hold it equal to the reference).
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from rosfpga_lab.config.vocabulary import MODEL_OPS, PASSTHROUGH, canonical_op
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.encodings import PixelFormat, unpack_lanes
from rosfpga_lab.hw.framing import Reframed, reframe_fast, reframe_reference
from rosfpga_lab.hw.streams import Beat, Beats, Fifo
from rosfpga_lab.hw.video import Mat, mat2axivideo_fast, mat2axivideo_reference

#: Operations the models run (the configuration vocabulary's :data:`~rosfpga_lab.config.vocabulary.MODEL_OPS`).
OPS = MODEL_OPS


def check_op(op: str, ksize: tuple[int, int]) -> tuple[int, int]:
    """Validate ``op`` and ``ksize``; return ``ksize`` as a tuple of ints.

    ``op`` may be an accepted alias (``"copy"``); see :func:`canonical_op`.

    Raises:
        PipelineConfigError: unknown op, or a kernel side outside ``1..MAX_KSIZE``.
    """
    if canonical_op(op) not in OPS:
        raise PipelineConfigError(f"unknown op {op!r}; choose one of {', '.join(OPS)}")
    try:
        kw, kh = (int(k) for k in ksize)
    except (TypeError, ValueError):
        raise PipelineConfigError(f"ksize must be (width, height), got {ksize!r}") from None
    for name, k in (("width", kw), ("height", kh)):
        if not 1 <= k <= limits.MAX_KSIZE:
            raise PipelineConfigError(
                f"ksize {name} {k} is outside 1..{limits.MAX_KSIZE} (hw.limits.MAX_KSIZE)")
    return kw, kh


def flush_extent(ksize: tuple[int, int]) -> tuple[int, int]:
    """``(dx, dy)``: how far the window reaches right of and below its anchor."""
    kw, kh = ksize
    return kw - 1 - kw // 2, kh - 1 - kh // 2


def morph_reference(src: Mat, dst: Mat, op: str, ksize: tuple[int, int]) -> None:
    """Reference streaming dilate/erode/passthrough from ``src`` to ``dst`` (one pixel per clock)."""
    kw, kh = check_op(op, ksize)
    op = canonical_op(op)
    rows, cols, channels = src.rows, src.cols, src.channels
    if op == PASSTHROUGH:
        for _ in range(rows * cols):
            dst.write(src.read(op, rows * cols))
        return
    pick = max if op == "dilate" else min
    dx, dy = flush_extent((kw, kh))
    line_buffer: list[list[tuple[int, ...] | None]] = [[None] * cols for _ in range(kh)]
    for row in range(rows + dy):
        window: list[list[tuple[int, ...] | None]] = [[None] * kh for _ in range(kw)]
        for col in range(cols + dx):
            if col < cols:
                # 1. the next input pixel (none once the loop is past the last row)
                pixel = src.read(op, rows * cols) if row < rows else None
                # 2. shift this column of the line buffer up; the new pixel goes in at the bottom
                for k in range(kh - 1):
                    line_buffer[k][col] = line_buffer[k + 1][col]
                line_buffer[kh - 1][col] = pixel
                column = [line_buffer[k][col] for k in range(kh)]
            else:
                column = [None] * kh                     # right of the image
            # 3. slide the window one column left and bring the new column in on the right
            window = window[1:] + [column]
            # 4. once the window is centred on an image pixel, write one output pixel
            if row >= dy and col >= dx:
                inside = [p for c in window for p in c if p is not None]
                dst.write(tuple(pick(p[ch] for p in inside) for ch in range(channels)))


def morph_fast(image: np.ndarray, op: str, ksize: tuple[int, int],
               out: np.ndarray | None = None) -> np.ndarray:
    """Fast dilate/erode/passthrough of a ``(rows, cols, channels)`` uint8 image (OpenCV).

    Args:
        out: optional C-contiguous array of the image's shape to write into.
    """
    kw, kh = check_op(op, ksize)
    if out is None:
        out = np.empty(image.shape, np.uint8)
    if canonical_op(op) == PASSTHROUGH:
        np.copyto(out, image)
        return out
    fn = cv2.dilate if op == "dilate" else cv2.erode
    src = np.ascontiguousarray(image)
    dst = out if out.ndim == 2 or out.shape[2] > 1 else out.reshape(out.shape[:2])
    if src.ndim == 3 and src.shape[2] == 1:
        src = src.reshape(src.shape[:2])
    result = fn(src, _kernel(kw, kh), dst=dst)
    if result is not dst and not np.shares_memory(result, dst):
        np.copyto(dst, result)
    return out


@functools.lru_cache(maxsize=32)
def _kernel(kw: int, kh: int) -> np.ndarray:
    return np.ones((kh, kw), np.uint8)


def morph_stream_reference(beats: Beats, rows: int, cols: int, fmt: PixelFormat, op: str,
                           ksize: tuple[int, int]) -> tuple[Beats, Reframed]:
    """The application circuit on a beat stream, damaged or not (``rfl_morph.v``).

    The stream is framed by :func:`~rosfpga_lab.hw.framing.reframe_reference` (a damaged frame
    is padded or cut to ``rows x cols`` and flagged), each frame is filtered by
    :func:`morph_reference` and sent as well-formed beats.

    Returns:
        ``(beats out, framing)``: every completed frame's output beats, and what the framing did.
    """
    framed = reframe_reference(beats, rows, cols)
    out: Fifo[Beat] = Fifo(None, "morph_out")
    for pixels in framed.frames:
        src = Mat.from_numpy(unpack_lanes(pixels, fmt.bytes_per_pixel).reshape(rows, cols, -1))
        dst = Mat(rows, cols, src.channels)
        morph_reference(src, dst, op, ksize)
        mat2axivideo_reference(dst, out, fmt)
    return Beats.from_list(out.drain()), framed


def morph_stream_fast(beats: Beats, rows: int, cols: int, fmt: PixelFormat, op: str,
                      ksize: tuple[int, int]) -> tuple[Beats, Reframed]:
    """Fast model of :func:`morph_stream_reference` (numpy framing, OpenCV filter)."""
    framed = reframe_fast(beats, rows, cols)
    parts = []
    for pixels in framed.frames:
        image = unpack_lanes(pixels, fmt.bytes_per_pixel).reshape(rows, cols, -1)
        parts.append(mat2axivideo_fast(morph_fast(image, op, ksize), fmt))
    if not parts:
        return Beats.empty(), framed
    return Beats(np.concatenate([p.tdata for p in parts]), np.concatenate([p.tkeep for p in parts]),
                 np.concatenate([p.tuser for p in parts]),
                 np.concatenate([p.tlast for p in parts])), framed
