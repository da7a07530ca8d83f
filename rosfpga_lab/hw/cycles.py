"""Cycle accounting under an initiation interval of 1 (one item per clock in every stage).

For each stage, ``cycles`` is the clocks it needs for one frame and ``latency`` the clocks from
its first input to its first output. The byte-wide stages (interpreter, ``fifo2axi``,
``axi2fifo``, generator) move one *byte* per clock, the video stages one *pixel* per clock, and
the filter runs ``dy`` rows and ``dx`` columns past the image to flush its window.

The stages run concurrently (an HLS dataflow region), so a frame takes about the slowest
stage's cycles plus the others' fill latency: ``total = max(cycles) + sum(latency)`` (an upper
estimate). ``sequential`` (the sum of all cycles) is what it would take without overlap.
For 640x480 ``rgba8`` at 100 MHz the byte-wide stages need 1.23 M cycles (12.3 ms) while the
filter needs 0.31 M (3.1 ms): the 8-bit FIFO, not the filter, sets the frame rate, and it is
slower than gigabit Ethernet (9.8 ms for the payload).
"""

from __future__ import annotations

from dataclasses import dataclass

from rosfpga_lab.hw.encodings import PIXEL_FORMATS
from rosfpga_lab.hw.interpreter import ImageFields
from rosfpga_lab.hw.morph import flush_extent


@dataclass(frozen=True)
class CycleReport:
    """Cycle figures of one frame.

    Attributes:
        cycles: per stage, clocks to process the frame.
        latency: per stage, clocks from first input to first output.
        total: ``max(cycles) + sum(latency)``, the dataflow estimate.
        sequential: ``sum(cycles)``.
    """

    cycles: dict[str, int]
    latency: dict[str, int]
    total: int
    sequential: int

    @property
    def bottleneck(self) -> str:
        """The stage with the most cycles."""
        return max(self.cycles, key=self.cycles.__getitem__)


def account(fields: ImageFields, op: str, ksize: tuple[int, int], in_frame_bytes: int,
            out_frame_bytes: int) -> CycleReport:
    """Cycles and latency of every stage for one frame described by ``fields``."""
    rows, cols = fields.height, fields.width
    pixels = rows * cols
    bpp = PIXEL_FORMATS[fields.encoding].bytes_per_pixel
    data = pixels * bpp
    if op == "copy":
        filt, filt_latency = pixels, 1
    else:
        dx, dy = flush_extent(ksize)
        filt = (rows + dy) * (cols + dx)
        filt_latency = dy * (cols + dx) + dx + 1
    cycles = {
        "interpreter": in_frame_bytes,
        "fifo2axi": data,
        "axivideo2mat": pixels,
        op: filt,
        "mat2axivideo": pixels,
        "axi2fifo": data,
        "generator": out_frame_bytes,
    }
    latency = {
        "interpreter": fields.data_offset + 1,
        "fifo2axi": bpp,
        "axivideo2mat": 1,
        op: filt_latency,
        "mat2axivideo": 1,
        "axi2fifo": 1,
        "generator": 1,
    }
    return CycleReport(cycles, latency, max(cycles.values()) + sum(latency.values()),
                       sum(cycles.values()))
