"""cocotb testbench of the node in the fabric from RTPS to RTPS, ``rtps_loop_top``
(tests/rtl/rtps_loop_top.v; run by tests/rtl/test_fabric_rtps_loop.py, not by pytest).

The case comes in a JSON file (``RTPS_LOOP_CASE``): the datagrams in (hex), the receive side's
configuration, ``cfg_time``, how many datagrams must come out, per-mille input gaps and output
backpressure. One coroutine drives a byte a clock when it is offered and takes the output when
ready (a valid beat must stay unchanged until taken), cutting it into datagrams at TLAST, and
records each status pulse. It ends 300 quiet clocks after the expected datagrams (more would
show), or after a bound on the clocks (a lock-up). The datagrams, statuses and counters go to
``RTPS_LOOP_OUT``; the test checks them against the lab's RTPS codecs and CDR models.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def rtps_loop(dut) -> None:
    with open(os.environ["RTPS_LOOP_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int]] = []
    for dg in case["datagrams"]:
        raw = bytes.fromhex(dg)
        stream += [(x, int(i == len(raw) - 1)) for i, x in enumerate(raw)]
    dut.cfg_prefix.value = int(case["local"], 16)
    dut.cfg_reader.value = case["reader"]
    dut.cfg_writer.value = case["writer"]
    dut.cfg_time.value = case["time"]
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = idle = clock = 0
    out: list[str] = []
    cur = bytearray()
    statuses: list[int] = []
    held = None
    limit = 20 * len(stream) + 20000                       # a lock-up ends it too
    while clock < limit and not (len(out) >= case["expect"] and idle >= 300):
        clock += 1
        offer = i < len(stream) and prng.random() >= gap
        dut.s_axis_tvalid.value = int(offer)
        if offer:
            dut.s_axis_tdata.value, dut.s_axis_tlast.value = stream[i]
        else:
            dut.s_axis_tdata.value = prng.getrandbits(8)
            dut.s_axis_tlast.value = prng.getrandbits(1)
        ready = prng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value)) if valid else None
        if held is not None:
            assert beat == held, f"clock {clock}: a valid beat changed before it was taken"
        held = beat if valid and not ready else None
        if valid and ready:
            cur.append(beat[0])
            if beat[1]:
                out.append(cur.hex())
                cur = bytearray()
        if int(dut.status_valid.value):
            statuses.append(int(dut.status.value))
        if offer and int(dut.s_axis_tready.value):
            i += 1
        idle = idle + 1 if (i == len(stream) and not valid) else 0
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    assert not cur, f"{len(cur)} bytes out after the last TLAST"
    counts = {name: int(getattr(dut, f"cnt_{name}").value)
              for name in ("samples", "datagrams", "dropped")}
    with open(os.environ["RTPS_LOOP_OUT"], "w") as f:
        json.dump({"datagrams": out, "statuses": statuses, "counts": counts, "clocks": clock}, f)
    dut._log.info("%d bytes in, %d datagrams out, %d clocks, statuses %s, counters %s",
                  len(stream), len(out), clock, statuses, counts)
