"""How each supported ``sensor_msgs/Image`` encoding is packed into 32-bit AXI4-Stream beats.

The rule, for every encoding: **one pixel per beat**, the pixel's bytes in the order they sit in
the ROS message, byte ``i`` of the pixel in ``tdata`` bits ``8i+7 .. 8i`` (little-endian byte
lanes, as the paper's Figure 7 does for 4-byte pixels), unused high lanes zero and marked null
with ``tkeep`` low. This is what Xilinx's HLS video cores do (one pixel per beat, channels in
the low bits).

========  ======  ==============================  ========
encoding  bytes   tdata (bits 31..0)              tkeep
========  ======  ==============================  ========
rgba8     4       A(31..24) B(23..16) G(15..8) R  0b1111
bgra8     4       A(31..24) R(23..16) G(15..8) B  0b1111
rgb8      3       0 (31..24) B(23..16) G(15..8) R 0b0111
bgr8      3       0 (31..24) R(23..16) G(15..8) B 0b0111
mono8     1       0 (31..8) Y(7..0)               0b0001
========  ======  ==============================  ========

The channels are never reordered: the morphology application treats each lane alike, so
``rgb8`` and ``bgr8`` pass through the same circuit.
"""

from __future__ import annotations

import numpy as np

from rosfpga_lab.config.vocabulary import PIXEL_FORMATS, PixelFormat
from rosfpga_lab.hw.errors import PipelineConfigError

__all__ = ["PIXEL_FORMATS", "PixelFormat", "pack_lanes", "pixel_format", "unpack_lanes"]


def pixel_format(encoding: str) -> PixelFormat:
    """The packing rule of ``encoding``.

    Raises:
        PipelineConfigError: the encoding is not supported.
    """
    try:
        return PIXEL_FORMATS[encoding]
    except KeyError:
        raise PipelineConfigError(
            f"unsupported encoding {encoding!r}; the circuit packs {', '.join(PIXEL_FORMATS)}"
        ) from None


def pack_lanes(pixels: np.ndarray) -> np.ndarray:
    """``tdata`` of one beat per pixel: byte ``i`` of each pixel in bits ``8i+7..8i``, rest zero.

    The fast models' packing rule, shared by ``fifo2axi`` and ``Mat2AXIvideo``. Lanes are
    copied one column at a time (a copy with an inner dimension of 3 is ~7x slower in numpy).

    Args:
        pixels: ``(n, bytes_per_pixel)`` uint8, 1 to 4 bytes per pixel.

    Returns:
        ``(n,)`` uint32; a view of ``pixels`` when it holds 4 contiguous bytes per pixel.
    """
    n, bpp = pixels.shape
    if bpp == 4:
        return np.ascontiguousarray(pixels).view(np.uint32).reshape(n)
    if bpp == 1:
        return pixels.reshape(n).astype(np.uint32)
    lanes = np.zeros((n, 4), np.uint8)
    for lane in range(bpp):
        lanes[:, lane] = pixels[:, lane]
    return lanes.view("<u4").reshape(n)


def unpack_lanes(tdata: np.ndarray, bpp: int) -> np.ndarray:
    """The low ``bpp`` byte lanes of every beat, the inverse of :func:`pack_lanes`.

    Returns:
        ``(n, bpp)`` uint8, C-contiguous; a view of ``tdata`` when ``bpp`` is 4.
    """
    n = tdata.shape[0]
    if bpp == 4:
        return tdata.view(np.uint8).reshape(n, 4)
    if bpp == 1:
        return tdata.astype(np.uint8).reshape(n, 1)  # keeps bits 7..0
    lanes = tdata.view(np.uint8).reshape(n, 4)
    out = np.empty((n, bpp), np.uint8)
    for lane in range(bpp):
        out[:, lane] = lanes[:, lane]
    return out
