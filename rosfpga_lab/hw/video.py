"""``AXIvideo2Mat`` and ``Mat2AXIvideo``: between the AXI4-Stream video bus and an image matrix.

An ``hls::Mat`` is not memory but a stream of pixels in raster order, so :class:`Mat` is a
:class:`~rosfpga_lab.hw.streams.Fifo` of pixel tuples that knows its ``rows``, ``cols`` and
``channels``. The reference ``AXIvideo2Mat`` follows the HLS video library's loop structure:

* ``loop_wait_for_start``: read beats until one has ``tuser`` (start of frame);
* for each row, for each column: use the beat in hand if it is the start of frame or the
  previous beat ended the line, otherwise read the next one; flag ``ERROR_IO_SOF_EARLY`` for a
  ``tuser`` inside the frame and ``ERROR_IO_EOL_EARLY`` for a ``tlast`` before the last column;
* ``loop_wait_for_eol``: if the row ended without ``tlast``, read beats until one has it,
  flagging ``ERROR_IO_EOL_LATE``.

It returns those flags, as ``hls::AXIvideo2Mat`` does. A lost ``tuser`` or ``tlast`` makes the
circuit read past the frame and wait for ever; the model raises
:class:`~rosfpga_lab.hw.errors.StreamStarvedError` with the image made so far as ``partial``.
The fast model handles a well-formed stream with numpy and hands any other stream to the
reference model, so both agree on every input.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from rosfpga_lab.hw.encodings import PixelFormat, pack_lanes, unpack_lanes
from rosfpga_lab.hw.errors import StreamStarvedError
from rosfpga_lab.hw.streams import Beat, Beats, Fifo, frame_flags

ERROR_IO_EOL_EARLY = 1 << 0
ERROR_IO_EOL_LATE = 1 << 1
ERROR_IO_SOF_EARLY = 1 << 2
STATUS_NAMES = {ERROR_IO_EOL_EARLY: "ERROR_IO_EOL_EARLY", ERROR_IO_EOL_LATE: "ERROR_IO_EOL_LATE",
                ERROR_IO_SOF_EARLY: "ERROR_IO_SOF_EARLY"}

Pixel = tuple[int, ...]


def status_names(status: int) -> list[str]:
    """The names of the flags set in an ``AXIvideo2Mat`` status word."""
    return [name for bit, name in STATUS_NAMES.items() if status & bit]


class Mat(Fifo[Pixel]):
    """An ``hls::Mat``: a raster-order stream of pixels (tuples of channel values)."""

    def __init__(self, rows: int, cols: int, channels: int, name: str = "mat") -> None:
        super().__init__(None, name)
        self.rows, self.cols, self.channels = rows, cols, channels

    @classmethod
    def from_numpy(cls, image: np.ndarray, name: str = "mat") -> Mat:
        """A Mat holding ``image`` (shape ``(rows, cols)`` or ``(rows, cols, channels)``)."""
        img = image.reshape(image.shape[0], image.shape[1], -1)
        mat = cls(img.shape[0], img.shape[1], img.shape[2], name)
        mat.extend(tuple(p) for p in img.reshape(-1, img.shape[2]).tolist())
        return mat

    def to_numpy(self) -> np.ndarray:
        """The stored pixels as a ``(rows, cols, channels)`` uint8 array (not removed).

        Missing pixels (a stream cut short) are zero.
        """
        flat = np.zeros((self.rows * self.cols, self.channels), np.uint8)
        items = list(self)[: self.rows * self.cols]
        if items:
            flat[: len(items)] = np.asarray(items, dtype=np.uint8).reshape(len(items), self.channels)
        return flat.reshape(self.rows, self.cols, self.channels)


def axivideo2mat_reference(inp: Fifo[Beat], img: Mat) -> int:
    """Reference ``AXIvideo2Mat``: beats in, ``img.rows * img.cols`` pixels out.

    Returns:
        the status flags (``ERROR_IO_*``), 0 for a well-formed frame.

    Raises:
        StreamStarvedError: the stream ran dry (a lost ``tuser``/``tlast``/beat); ``partial`` is
            the image so far (zeros where no pixel came).
    """
    res = 0
    rows, cols, depth = img.rows, img.cols, 8
    needed = rows * cols
    waiting = "a start of frame (tuser)"   # what the stage waits for, for the error message
    try:
        sof = False
        while not sof:                                   # loop_wait_for_start
            axi = inp.read("axivideo2mat")
            sof = axi.tuser
        for i in range(rows):                            # loop_height
            eol = False
            waiting = f"the pixels of line {i}"
            for j in range(cols):                        # loop_width
                if sof or eol:
                    sof = False
                    eol = axi.tlast
                else:
                    axi = inp.read("axivideo2mat")
                    eol = axi.tlast
                    if axi.tuser:
                        res |= ERROR_IO_SOF_EARLY
                if eol and j != cols - 1:
                    res |= ERROR_IO_EOL_EARLY
                pix = tuple((axi.tdata >> (k * depth)) & 0xFF for k in range(img.channels))
                img.write(pix)
            waiting = f"the end of line {i} (tlast)"
            while not eol:                               # loop_wait_for_eol
                axi = inp.read("axivideo2mat")
                eol = axi.tlast
                res |= ERROR_IO_EOL_LATE
    except StreamStarvedError as exc:
        exc.partial = img.to_numpy()
        exc.needed, exc.got = needed, img.level
        exc.args = (f"{exc.args[0]} [AXIvideo2Mat was waiting for {waiting}; it had made "
                    f"{img.level} of the {needed} pixels of the frame]",)
        raise
    return res


def axivideo2mat_fast(beats: Beats, rows: int, cols: int, fmt: PixelFormat
                      ) -> tuple[np.ndarray, int, int]:
    """Fast ``AXIvideo2Mat``.

    Returns:
        ``(image, status, left)``: the ``(rows, cols, channels)`` image, the status flags and
        how many beats were left unread.
    """
    n = rows * cols
    if len(beats) >= n and _well_formed(beats, rows, cols):
        image = unpack_lanes(beats.tdata[:n], fmt.bytes_per_pixel).reshape(rows, cols, -1)
        return image, 0, len(beats) - n
    stream = beats_to_fifo(beats.to_list(), "axis_in")
    img = Mat(rows, cols, fmt.bytes_per_pixel)
    status = axivideo2mat_reference(stream, img)
    return img.to_numpy(), status, stream.level


def _well_formed(beats: Beats, rows: int, cols: int) -> bool:
    n = rows * cols
    tuser, tlast = frame_flags(rows, cols)
    if len(beats) == n and beats.tuser is tuser and beats.tlast is tlast:
        return True  # the (read-only) flags fifo2axi gives a well-formed frame
    if not beats.tuser[0] or beats.tuser[1:n].any():
        return False
    tlast = beats.tlast[:n].reshape(rows, cols)
    return bool(tlast[:, -1].all()) and not tlast[:, :-1].any()


def mat2axivideo_reference(img: Mat, out: Fifo[Beat], fmt: PixelFormat) -> None:
    """Reference ``Mat2AXIvideo``: one beat per pixel, ``tuser`` first, ``tlast`` at line end.

    ``tkeep`` follows the encoding's lanes (``hls::Mat2AXIvideo`` sets all ones; the lab keeps
    it consistent with ``fifo2axi`` so ``axi2fifo`` can rely on it).
    """
    for i in range(img.rows):
        for j in range(img.cols):
            pix = img.read("mat2axivideo", img.rows * img.cols)
            tdata = 0
            for k in range(img.channels):
                tdata |= pix[k] << (k * 8)
            out.write(Beat(tdata, fmt.tkeep, tuser=(i == 0 and j == 0), tlast=(j == img.cols - 1)))


def mat2axivideo_fast(image: np.ndarray, fmt: PixelFormat) -> Beats:
    """Fast ``Mat2AXIvideo`` of a ``(rows, cols, channels)`` uint8 image."""
    rows, cols = image.shape[:2]
    tdata = pack_lanes(image.reshape(rows * cols, -1))
    tuser, tlast = frame_flags(rows, cols)
    return Beats(tdata, fmt.tkeep, tuser, tlast)


def beats_to_fifo(beats: Iterable[Beat], name: str = "axis") -> Fifo[Beat]:
    """An unbounded :class:`Fifo` holding ``beats`` (for feeding a reference stage)."""
    fifo: Fifo[Beat] = Fifo(None, name)
    fifo.extend(beats)
    return fifo
