"""cocotb testbench of ``rfl_fifo2axi`` alone (run by tests/rtl/test_fifo2axi.py, not by pytest).

The case comes in the environment (``FIFO2AXI_CASE``, JSON): image size, bytes per pixel,
frames, seed, per-mille input gaps and output backpressure. Frames of random bytes go in with
the start-of-frame marker on each frame's first byte, damaged in turn (a frame cut short by the
next marker, junk bytes before a marker), then a clean frame; every beat out must equal both hw
models' beats (``hw.axis.fifo2axi_stream_*``) and the ``framing`` port the flags of the damage.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge

from rosfpga_lab.hw.axis import fifo2axi_stream_fast, fifo2axi_stream_reference
from rosfpga_lab.hw.encodings import pixel_format
from rosfpga_lab.hw.framing import SOF_EARLY, SOF_MISSING

ENCODING = {4: "rgba8", 3: "rgb8", 1: "mono8"}


@cocotb.test()
async def fifo2axi_resync(dut) -> None:
    """Damaged byte streams through rfl_fifo2axi, beat for beat against the hw models."""
    case = json.loads(os.environ["FIFO2AXI_CASE"])
    prng = random.Random(case["seed"])
    rows, cols, bpp = case["height"], case["width"], case["bytes"]
    fmt = pixel_format(ENCODING[bpp])
    size = rows * cols * bpp
    data: list[int] = []
    marks: list[bool] = []
    want = 0
    for n in range(case["frames"]):
        kind = n % 3 if n < case["frames"] - 1 else 0
        frame = [prng.getrandbits(8) for _ in range(size)]
        if kind == 2 and size > 1:             # cut short by the next frame's marker
            frame = frame[:prng.randint(1, size - 1)]
            want |= SOF_EARLY
        elif kind == 1:                        # junk before the marker (after a whole frame)
            junk = prng.randint(1, 5)
            data += [prng.getrandbits(8) for _ in range(junk)]
            marks += [False] * junk
            want |= SOF_MISSING
        data += frame
        marks += [True] + [False] * (len(frame) - 1)
    mk = np.array(marks, bool)
    beats, framed = fifo2axi_stream_fast(bytes(data), mk, rows, cols, fmt)
    ref, ref_framed = fifo2axi_stream_reference(bytes(data), mk, rows, cols, fmt)
    assert beats == ref and framed.flags == ref_framed.flags, "fast and reference models differ"
    assert framed.flags == want, f"model flags {framed.flags:#06b}, by hand {want:#06b}"
    assert len(framed.frames) == case["frames"]
    expected = [(int(beats.tdata[i]), int(beats.tkeep[i]), int(beats.tuser[i]),
                 int(beats.tlast[i])) for i in range(len(beats))]

    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_tvalid.value = 0
    dut.s_tuser.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1

    async def drive() -> None:
        i = 0
        while i < len(data):
            valid = prng.random() >= case["gap"] / 1000
            dut.s_tvalid.value = int(valid)
            dut.s_tdata.value = data[i] if valid else prng.getrandbits(8)
            dut.s_tuser.value = int(marks[i]) if valid else prng.getrandbits(1)
            await ReadOnly()
            fire = valid and int(dut.s_tready.value) == 1
            await RisingEdge(dut.clk)
            i += fire
        dut.s_tvalid.value = 0

    cocotb.start_soon(drive())
    brng = random.Random(case["seed"] + 1)
    got: list[tuple[int, int, int, int]] = []
    held = None
    for clock in range(40 * len(data) + 200):
        if len(got) == len(expected):
            break
        ready = brng.random() >= case["bp"] / 1000
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tkeep.value),
                int(dut.m_axis_tuser.value), int(dut.m_axis_tlast.value)) if valid else None
        if held is not None:
            assert beat == held, f"clock {clock}: a valid beat changed before it was taken"
        if valid and ready:
            got.append(beat)
            held = None
        else:
            held = beat
        await RisingEdge(dut.clk)
    for _ in range(5):
        dut.m_axis_tready.value = 1
        await ReadOnly()
        assert int(dut.m_axis_tvalid.value) == 0, "rfl_fifo2axi sent more beats than pixels"
        await RisingEdge(dut.clk)
    for n, (g, e) in enumerate(zip(got, expected)):
        assert g == e, f"beat {n}: got {g}, expected {e}"
    assert len(got) == len(expected), f"{len(got)} beats of {len(expected)}"
    assert int(dut.framing.value) == want, f"framing {int(dut.framing.value):#06b}"
