"""cocotb testbench of ``rfl_rtps_tx`` alone (run by tests/rtl/test_fabric_rtps_tx.py, not by
pytest).

The case comes in a JSON file (``RTPS_TX_CASE``): the records (hex: a length, LE32, then the
payload), per-mille input gaps and output backpressure. One coroutine offers a byte a clock
when the gap draw allows, drives ``cfg_time`` with a value that changes every clock (and notes
the one of the clock each record's first byte is taken: its INFO_TS), and takes the output when
the backpressure draw allows: every beat of a valid output held until taken, unchanged. What
came out (the datagrams, cut at TLAST), the times noted and the counters go to ``RTPS_TX_OUT``;
the test checks them against the lab's RTPS codecs.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


def _time(clock: int) -> int:
    """cfg_time in clock ``clock``: {seconds, fraction}, seconds below 2**20 (exact as a float)."""
    return ((1000 + clock) << 32) | ((clock * 0x9E3779B1) & 0xFFFFFFFF)


@cocotb.test()
async def rtps_tx_build(dut) -> None:
    with open(os.environ["RTPS_TX_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[int] = []
    starts: set[int] = set()
    for rec in case["records"]:
        starts.add(len(stream))
        stream += bytes.fromhex(rec)
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_tvalid.value = 0
    dut.m_axis_tready.value = 0
    dut.cfg_time.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = idle = clock = 0
    times: list[int] = []
    datagrams: list[str] = []
    cur = bytearray()
    held = None
    while idle < 200 and clock < 40 * len(stream) + 2000:     # a lock-up ends it too
        clock += 1
        now = _time(clock)
        dut.cfg_time.value = now
        offer = i < len(stream) and prng.random() >= gap
        dut.s_tvalid.value = int(offer)
        dut.s_tdata.value = stream[i] if offer else prng.getrandbits(8)
        ready = prng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value)) if valid else None
        if held is not None:
            assert beat == held, f"clock {clock}: a valid beat changed before it was taken"
        if offer and int(dut.s_tready.value):
            if i in starts:
                times.append(now)
            i += 1
        if valid and ready:
            cur.append(beat[0])
            if beat[1]:
                datagrams.append(cur.hex())
                cur = bytearray()
            held = None
        else:
            held = beat
        idle = idle + 1 if (i == len(stream) and not valid) else 0
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    assert not cur, f"{len(cur)} bytes out after the last TLAST"
    counts = {name: int(getattr(dut, f"cnt_{name}").value)
              for name in ("samples", "datagrams", "dropped")}
    with open(os.environ["RTPS_TX_OUT"], "w") as f:
        json.dump({"datagrams": datagrams, "times": times, "counts": counts,
                   "seq": int(dut.m_seq.value), "clocks": clock}, f)
    dut._log.info("%d bytes in, %d datagrams out, %d clocks, counters %s", len(stream),
                  len(datagrams), clock, counts)
