"""STEP 3 glue: ``fifo2axi`` (bytes to AXI4-Stream beats) and ``axi2fifo`` (beats to bytes).

``fifo2axi`` is the paper's Figure 7 generalised by :mod:`rosfpga_lab.hw.encodings`: for every
pixel it reads ``bytes_per_pixel`` bytes from the 8-bit FIFO, byte ``i`` into ``tdata`` bits
``8i+7..8i``, sets ``tkeep`` to the encoding's lanes, ``tuser`` on the first pixel of the frame
and ``tlast`` on the last pixel of each line. The HLS C++ it mirrors::

    for (int y = 0; y < rows; y++)
      for (int x = 0; x < cols; x++) {
        ap_axiu<32,1,1,1> beat;
        beat.data = 0;
        for (int i = 0; i < BYTES_PER_PIXEL; i++)
          beat.data(8*i+7, 8*i) = in.read();
        beat.keep = KEEP;
        beat.user = (x == 0 && y == 0);
        beat.last = (x == cols - 1);
        out << beat;
      }

``axi2fifo`` undoes it: for each of ``rows*cols`` beats it writes the bytes of the lanes whose
``tkeep`` bit is set, lane 0 first. Both stages read one byte lane per clock (the FIFO side is
8 bits wide), so their cycle count is the number of data bytes.
"""

from __future__ import annotations

import numpy as np

from rosfpga_lab.hw.encodings import PixelFormat, pack_lanes, unpack_lanes
from rosfpga_lab.hw.errors import StreamStarvedError
from rosfpga_lab.hw.streams import Beat, Beats, ByteFIFO, Fifo, frame_flags

LANE = np.arange(4, dtype=np.uint8)


def fifo2axi_reference(inp: ByteFIFO, out: Fifo[Beat], rows: int, cols: int,
                       fmt: PixelFormat) -> None:
    """Reference model: one byte per read, one beat per pixel (mirrors the C++ above).

    Raises:
        StreamStarvedError: ``inp`` held fewer than ``rows*cols*bytes_per_pixel`` bytes;
            ``partial`` holds the beats made so far.
    """
    needed = rows * cols * fmt.bytes_per_pixel
    made: list[Beat] = []
    try:
        for y in range(rows):
            for x in range(cols):
                tdata = 0
                for i in range(fmt.bytes_per_pixel):
                    tdata |= inp.read("fifo2axi", needed) << (8 * i)
                beat = Beat(tdata, fmt.tkeep, tuser=(x == 0 and y == 0), tlast=(x == cols - 1))
                made.append(beat)
                out.write(beat)
    except StreamStarvedError as exc:
        exc.partial = Beats.from_list(made)
        raise


def fifo2axi_fast(data: np.ndarray, rows: int, cols: int, fmt: PixelFormat) -> tuple[Beats, int]:
    """Fast model of :func:`fifo2axi_reference`.

    Args:
        data: the pixel bytes (uint8).

    Returns:
        ``(beats, left)``: the beats, and how many bytes of ``data`` were not consumed.

    Raises:
        StreamStarvedError: as the reference model (same counts, same partial beats).
    """
    bpp = fmt.bytes_per_pixel
    needed = rows * cols * bpp
    data = np.asarray(data, dtype=np.uint8)
    if data.size < needed:
        whole = data.size // bpp
        partial = _pack(data[: whole * bpp], whole, 1, fmt).copy() if whole else Beats.empty()
        if whole:
            partial.tlast[:] = (np.arange(whole) % cols) == cols - 1
        raise StreamStarvedError(
            f"read from empty FIFO 'pixels_in' after {data.size} items of the {needed} needed: "
            "the upstream stage delivered too few (a lost byte, beat or TLAST?)",
            stage="fifo2axi", needed=needed, got=int(data.size), partial=partial)
    return _pack(data[:needed], rows, cols, fmt), int(data.size - needed)


def _pack(data: np.ndarray, rows: int, cols: int, fmt: PixelFormat) -> Beats:
    # rgba8/bgra8: no copy, the beats alias the frame's pixel bytes
    tdata = pack_lanes(data.reshape(rows * cols, fmt.bytes_per_pixel))
    tuser, tlast = frame_flags(rows, cols)
    return Beats(tdata, fmt.tkeep, tuser, tlast)


def axi2fifo_reference(inp: Fifo[Beat], out: ByteFIFO, beats: int) -> None:
    """Reference model: read ``beats`` beats, write the bytes of each kept lane, lane 0 first.

    Raises:
        StreamStarvedError: ``inp`` held fewer beats; ``partial`` holds the bytes made so far.
    """
    made = bytearray()
    try:
        for _ in range(beats):
            beat = inp.read("axi2fifo", beats)
            for lane in range(4):
                if (beat.tkeep >> lane) & 1:
                    byte = (beat.tdata >> (8 * lane)) & 0xFF
                    made.append(byte)
                    out.write(byte)
    except StreamStarvedError as exc:
        exc.partial = bytes(made)
        raise


def axi2fifo_fast(beats: Beats, count: int) -> tuple[np.ndarray, int]:
    """Fast model of :func:`axi2fifo_reference`.

    Returns:
        ``(data, left)``: the bytes (uint8) and how many beats were not consumed.

    Raises:
        StreamStarvedError: as the reference model.
    """
    use = min(count, len(beats))
    keep = beats.tkeep[:use]
    if use and int(keep[0]) in (0b0001, 0b0011, 0b0111, 0b1111) and beats.uniform_tkeep(use):
        data = unpack_lanes(beats.tdata[:use], int(keep[0]).bit_length()).reshape(-1)
    else:
        lanes = beats.tdata[:use].view(np.uint8).reshape(use, 4)
        mask = ((keep[:, None] >> LANE) & 1).astype(bool)
        data = lanes[mask]
    if len(beats) < count:
        raise StreamStarvedError(
            f"read from empty FIFO 'axis_out' after {len(beats)} items of the {count} needed: "
            "the upstream stage delivered too few (a lost byte, beat or TLAST?)",
            stage="axi2fifo", needed=count, got=len(beats), partial=data.tobytes())
    return data, len(beats) - use
