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

from dataclasses import dataclass

from rosfpga_lab.hw.errors import PipelineConfigError


@dataclass(frozen=True)
class PixelFormat:
    """The packing rule of one encoding.

    Attributes:
        encoding: the ROS encoding string.
        bytes_per_pixel: bytes of one pixel in the message (= channels, all are 8-bit).
        tkeep: the ``tkeep`` of every beat carrying one pixel.
        channels: channel names, byte 0 first.
    """

    encoding: str
    bytes_per_pixel: int
    tkeep: int
    channels: str


PIXEL_FORMATS: dict[str, PixelFormat] = {
    "rgba8": PixelFormat("rgba8", 4, 0b1111, "RGBA"),
    "bgra8": PixelFormat("bgra8", 4, 0b1111, "BGRA"),
    "rgb8": PixelFormat("rgb8", 3, 0b0111, "RGB"),
    "bgr8": PixelFormat("bgr8", 3, 0b0111, "BGR"),
    "mono8": PixelFormat("mono8", 1, 0b0001, "Y"),
}


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
