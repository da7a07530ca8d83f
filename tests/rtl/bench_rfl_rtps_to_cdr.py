"""cocotb testbench of the fabric's receive path, ``rtps_cdr_top`` (tests/rtl/rtps_cdr_top.v):
RTPS datagrams in, the generated circuit's published records out (run by
tests/rtl/test_fabric_rtps_cdr.py, not by pytest).

The case comes in a JSON file (``RTPS_CDR_CASE``): the datagrams (hex), the configuration, the
expected output bytes, status names and counters (computed by the test from the lab's RTPS
decoder and CDR models), per-mille input gaps and output backpressure. One coroutine drives a
byte a clock when it is offered, takes the output when ready, and records each status pulse;
a valid output byte must stay unchanged until taken. It ends 200 quiet clocks after the expected
output (more bytes would show), or after a bound on the clocks (a lock-up).
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def rtps_to_cdr_records(dut) -> None:
    with open(os.environ["RTPS_CDR_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int]] = []
    for dg in case["datagrams"]:
        raw = bytes.fromhex(dg)
        stream += [(x, int(i == len(raw) - 1)) for i, x in enumerate(raw)]
    want = bytes.fromhex(case["output"])
    dut.cfg_prefix.value = int(case["local"], 16)
    dut.cfg_reader.value = case["reader"]
    dut.cfg_writer.value = case["writer"]
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = idle = clock = 0
    out = bytearray()
    statuses: list[int] = []
    held = None
    limit = 12 * (len(stream) + len(want)) + 5000          # a lock-up ends it too
    while clock < limit and not (len(out) >= len(want) and idle >= 200):
        clock += 1
        offer = i < len(stream) and prng.random() >= gap
        dut.s_axis_tvalid.value = int(offer)
        if offer:
            dut.s_axis_tdata.value, dut.s_axis_tlast.value = stream[i]
        else:
            dut.s_axis_tdata.value = prng.getrandbits(8)
            dut.s_axis_tlast.value = prng.getrandbits(1)
        ready = prng.random() >= bp
        dut.m_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_tvalid.value) == 1
        byte = int(dut.m_tdata.value) if valid else None
        if held is not None:
            assert byte == held, f"clock {clock}: a valid byte changed before it was taken"
        held = byte if valid and not ready else None
        if valid and ready:
            out.append(byte)
        if int(dut.status_valid.value):
            statuses.append(int(dut.status.value))
        if offer and int(dut.s_axis_tready.value):
            i += 1
        idle = idle + 1 if (i == len(stream) and not valid) else 0
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    if os.environ.get("RTPS_CDR_OUT"):                  # for a look after a failure
        with open(os.environ["RTPS_CDR_OUT"], "w") as f:
            json.dump({"output": out.hex(), "statuses": statuses}, f)
    assert len(out) == len(want), f"{len(out)} bytes out, {len(want)} expected"
    first = next((k for k in range(len(want)) if out[k] != want[k]), None)
    assert first is None, f"output byte {first} differs: {out[first]:#x}, expected {want[first]:#x}"
    assert statuses == case["statuses"], f"statuses {statuses}, expected {case['statuses']}"
    counts = {name: int(getattr(dut, f"cnt_{name}").value) for name in case["counts"]}
    assert counts == case["counts"], f"counters {counts}, expected {case['counts']}"
    dut._log.info("%d bytes in, %d out, %d clocks, statuses %s, counters %s", len(stream),
                  len(out), clock, statuses, counts)
