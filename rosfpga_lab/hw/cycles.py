"""Cycle accounting of one frame, checked against the Verilog RTL (``rosfpga_lab.rtl``).

For each stage, ``cycles`` is the clocks it needs for one frame on its own and ``latency`` the
clocks from its first input to its first output *in the running circuit*. The byte-wide stages
(interpreter, ``fifo2axi``, ``axi2fifo``, generator) move one *byte* per clock, so an AXI4-Stream
beat carries a pixel every ``bytes_per_pixel`` clocks: 4 clocks per ``rgba8`` beat, 3 per
``rgb8`` beat, 1 per ``mono8`` beat. The video stages could take a pixel per clock, and the
HLS filter's loop runs ``dy`` rows and ``dx`` columns past the image to flush its window
(``cycles``), but in the circuit they wait for the byte-wide stages: the filter's first output
comes once ``filt_latency`` pixels have arrived, ``(filt_latency - 1) * bytes_per_pixel + 1``
clocks after its first input.

The stages run concurrently, so a frame takes (``total``, first byte in to last byte out)::

    max(in_frame_bytes + latency[filter],           the pixel path: bytes in, the filter's lag
        data_offset                                 the publisher starts once the header is
          + max(out_header / ready, latency[filter])  checked, writes its header, waits for
          + data / ready)                           the filter's first pixel; one byte per
                                                    clock the output is ready (share ``ready``)

The RTL simulation confirms this within a few clocks per frame plus, under random
backpressure, its randomness (``tests/rtl/test_cycles.py`` states the tolerance).
``sequential`` (the sum of all cycles) is what it would take without overlap. For 640x480
``rgba8`` at 100 MHz the byte-wide stages need 1.23 M cycles (12.3 ms) while the filter needs
0.31 M (3.1 ms): the 8-bit FIFO, not the filter, sets the frame rate, and it is slower than
gigabit Ethernet (9.8 ms for the payload).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rosfpga_lab.config.vocabulary import PASSTHROUGH, canonical_op
from rosfpga_lab.hw.encodings import PIXEL_FORMATS
from rosfpga_lab.hw.interpreter import ImageFields
from rosfpga_lab.hw.morph import flush_extent


@dataclass(frozen=True)
class CycleReport:
    """Cycle figures of one frame.

    Attributes:
        cycles: per stage, clocks to process the frame on its own.
        latency: per stage, clocks from first input to first output in the running circuit.
        total: clocks from the frame's first byte in to its last byte out (see the module).
        sequential: ``sum(cycles)``.
        clocks_per_beat: clocks between AXI4-Stream beats (= bytes per pixel).
        ready: share of clocks the output was assumed ready.
    """

    cycles: dict[str, int]
    latency: dict[str, int]
    total: int
    sequential: int
    clocks_per_beat: int = 1
    ready: float = 1.0

    @property
    def bottleneck(self) -> str:
        """The stage with the most cycles."""
        return max(self.cycles, key=self.cycles.__getitem__)


def account(fields: ImageFields, op: str, ksize: tuple[int, int], in_frame_bytes: int,
            out_frame_bytes: int, ready: float = 1.0) -> CycleReport:
    """Cycles and latency of every stage for one frame described by ``fields``.

    Args:
        fields: the frame's decoded fields.
        op: the application (``dilate``, ``erode``, ``copy``).
        ksize: its kernel.
        in_frame_bytes, out_frame_bytes: the TCPROS frames' sizes.
        ready: share of clocks the receiver takes a byte (1.0: no backpressure).
    """
    if not 0 < ready <= 1:
        raise ValueError(f"ready must be in (0, 1], got {ready}")
    rows, cols = fields.height, fields.width
    pixels = rows * cols
    bpp = PIXEL_FORMATS[fields.encoding].bytes_per_pixel
    data = pixels * bpp
    if canonical_op(op) == PASSTHROUGH:
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
        op: (filt_latency - 1) * bpp + 1,
        "mat2axivideo": 1,
        "axi2fifo": 1,
        "generator": 1,
    }
    head_out = out_frame_bytes - data
    total = max(in_frame_bytes + latency[op],
                fields.data_offset + max(math.ceil(head_out / ready), latency[op])
                + math.ceil(data / ready))
    return CycleReport(cycles, latency, total, sum(cycles.values()), bpp, ready)
