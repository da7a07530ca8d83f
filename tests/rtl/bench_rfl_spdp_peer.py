"""cocotb testbench of ``rfl_spdp_peer`` (run by tests/rtl/test_fabric_spdp_peer.py, not by
pytest): the case's datagrams (``SPDP_PEER_CASE``: hex, each with the idle clocks after it and
its IPv4 source) go in a byte a clock; every send_sedp pulse is recorded with the clock and the
peer registers then, and at the end the registers and counters, into ``SPDP_PEER_OUT``. The
watcher must always be ready (asserted at every beat)."""

from __future__ import annotations

import json
import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge, Timer


def _peer(dut) -> list[int]:
    return [int(dut.peer_known.value), int(dut.peer_meta_ip.value),
            int(dut.peer_meta_port.value), int(dut.peer_user_ip.value),
            int(dut.peer_user_port.value)]


@cocotb.test()
async def spdp_peer(dut) -> None:
    with open(os.environ["SPDP_PEER_CASE"]) as f:
        case = json.load(f)
    dut.cfg_prefix.value = int(case["prefix"], 16)
    dut.s_axis_tvalid.value = 0
    dut.s_axis_tdata.value = 0
    dut.s_axis_tlast.value = 0
    dut.s_src_ip.value = 0
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    clock = 0
    pulses: list[dict] = []
    ends: list[int] = []

    async def tick() -> None:
        nonlocal clock
        await RisingEdge(dut.clk)
        await ReadOnly()
        clock += 1
        if int(dut.send_sedp.value):
            pulses.append({"clock": clock, "peer": _peer(dut)})

    for raw, idle, src in case["datagrams"]:
        data = bytes.fromhex(raw)
        for i, x in enumerate(data):
            await _drive(dut, x, i == len(data) - 1, src)
            assert int(dut.s_axis_tready.value) == 1
            await tick()
        ends.append(clock)
        await _drive(dut, None, False, 0)
        for _ in range(idle):
            await tick()
    out = {"pulses": pulses, "ends": ends, "peer": _peer(dut),
           "counters": [int(dut.cnt_learned.value), int(dut.cnt_refused.value),
                        int(dut.cnt_other.value)]}
    with open(os.environ["SPDP_PEER_OUT"], "w") as f:
        json.dump(out, f)


async def _drive(dut, byte: int | None, last: bool, src: int) -> None:
    """Offer ``byte`` (None: nothing) from IPv4 source ``src`` for the next clock (out of the
    read-only phase first)."""
    await Timer(1, unit="ns")
    dut.s_src_ip.value = src
    dut.s_axis_tvalid.value = int(byte is not None)
    dut.s_axis_tdata.value = byte or 0
    dut.s_axis_tlast.value = int(last)
