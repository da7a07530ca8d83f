"""cocotb testbench of ``rfl_node`` (run by tests/rtl/test_cocotb.py, not by pytest directly).

cocotbext-axi's AXI4-Stream source and sink drive the 8-bit byte streams (``s_*`` in, ``m_*``
out) with random pauses: gaps on the input, backpressure on the output. The frames and the
expected output bytes come from files named in the environment (RFL_FRAMES, RFL_EXPECTED,
RFL_STATUS); the statuses the subscriber reports are written to RFL_STATUS_OUT.
"""

from __future__ import annotations

import itertools
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, RisingEdge
from cocotbext.axi import AxiStreamBus, AxiStreamFrame, AxiStreamSink, AxiStreamSource


def pauses(seed: int, share: float):
    rng = random.Random(seed)
    return itertools.cycle([rng.random() < share for _ in range(4099)])


@cocotb.test()
async def frames_through_the_circuit(dut) -> None:
    frames = open(os.environ["RFL_FRAMES"], "rb").read()
    expected = open(os.environ["RFL_EXPECTED"], "rb").read()
    seed = int(os.environ.get("RFL_SEED", "1"))
    cocotb.start_soon(Clock(dut.clk, 10, unit="ns").start())
    source = AxiStreamSource(AxiStreamBus.from_prefix(dut, "s"), dut.clk, dut.rst_n,
                             reset_active_level=False)
    sink = AxiStreamSink(AxiStreamBus.from_prefix(dut, "m"), dut.clk, dut.rst_n,
                         reset_active_level=False)
    source.set_pause_generator(pauses(seed, 0.3))
    sink.set_pause_generator(pauses(seed + 1, 0.5))
    statuses = []

    async def watch_status() -> None:
        while True:
            await RisingEdge(dut.clk)
            if int(dut.status_valid.value):
                statuses.append(int(dut.status.value))

    dut.rst_n.value = 0
    await ClockCycles(dut.clk, 4)
    dut.rst_n.value = 1
    cocotb.start_soon(watch_status())
    await source.send(AxiStreamFrame(frames))
    got = bytearray()
    idle = 0
    while len(got) < len(expected) and idle < 20000:
        if sink.empty():
            await RisingEdge(dut.clk)
            idle += 1
            continue
        idle = 0
        got += bytes(sink.recv_nowait().tdata)
    await ClockCycles(dut.clk, 50)
    while not sink.empty():
        got += bytes(sink.recv_nowait().tdata)
    with open(os.environ["RFL_STATUS_OUT"], "w") as f:
        f.write(" ".join(str(s) for s in statuses))
    assert bytes(got) == expected, f"{len(got)} bytes out, {len(expected)} expected"
