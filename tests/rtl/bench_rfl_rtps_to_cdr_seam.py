"""cocotb testbench of the seam alone, ``rfl_rtps_to_cdr`` (rtl/fabric), run by
tests/rtl/test_fabric_seam.py (not by pytest).

The case comes in a JSON file (``SEAM_CASE``): the sample packets (hex, TUSER on the last byte),
the expected output bytes and counters (the test's model), per-mille input gaps and output
backpressure, and what the input may wait:

- ``max_wait``: a bound on the clocks the input waited (TVALID high, TREADY low) over the run
  (None: no bound);
- ``hold``: the output's TREADY stays low until that many packets were taken whole, then for
  ``hold_clocks`` more, during which no byte of the next packet may be taken (the ring is full);
  the first ``hold`` packets must go in without waiting but for the ``grace`` clocks after each
  kept one (``kept``: the model's word).

One coroutine drives a byte a clock when offered, takes the output when ready, and checks that
a valid output byte stays unchanged until taken. It ends 100 quiet clocks after the expected
output, or at a bound on the clocks (a lock-up).
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def seam_records(dut) -> None:
    with open(os.environ["SEAM_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int, int]] = []           # (byte, TLAST, TUSER)
    kept = [p["kept"] for p in case["packets"]]
    for p in case["packets"]:
        raw = bytes.fromhex(p["data"])
        stream += [(x, int(k == len(raw) - 1), int(k == len(raw) - 1 and p["user"]))
                   for k, x in enumerate(raw)]
    want = bytes.fromhex(case["output"])
    hold, hold_clocks = case["hold"], case["hold_clocks"]
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = idle = clock = waits = done = held_for = 0
    since_kept = case["grace"] + 1                   # clocks since a kept packet's last byte
    out = bytearray()
    held = None
    limit = 12 * (len(stream) + len(want)) + hold_clocks + 2000
    while clock < limit and not (len(out) >= len(want) and idle >= 100):
        clock += 1
        since_kept += 1
        offer = i < len(stream) and (gap == 0 or prng.random() >= gap)
        dut.s_axis_tvalid.value = int(offer)
        if offer:
            dut.s_axis_tdata.value, dut.s_axis_tlast.value, dut.s_axis_tuser.value = stream[i]
        else:
            dut.s_axis_tdata.value = prng.getrandbits(8)
            dut.s_axis_tlast.value = prng.getrandbits(1)
            dut.s_axis_tuser.value = prng.getrandbits(1)
        holding = hold > 0 and (done < hold or held_for < hold_clocks)
        if hold > 0 and done >= hold:
            held_for += 1
        ready = not holding and (bp == 0 or prng.random() >= bp)
        dut.m_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_tvalid.value) == 1
        byte = int(dut.m_tdata.value) if valid else None
        if held is not None:
            assert byte == held, f"clock {clock}: a valid byte changed before it was taken"
        held = byte if valid and not ready else None
        if valid and ready:
            out.append(byte)
        taken = offer and int(dut.s_axis_tready.value) == 1
        if offer and not taken:
            waits += 1
            assert done >= hold or since_kept <= case["grace"], \
                f"clock {clock}: packet {done} waited, one of the first {hold}"
        if holding and done >= hold:
            assert not taken, f"clock {clock}: packet {done} taken while both buffers are held"
        if taken and stream[i][1]:
            since_kept = 0 if kept[done] else since_kept
            done += 1
        if taken:
            i += 1
        idle = idle + 1 if (i == len(stream) and not valid) else 0
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    assert len(out) == len(want), f"{len(out)} bytes out, {len(want)} expected"
    first = next((k for k in range(len(want)) if out[k] != want[k]), None)
    assert first is None, f"output byte {first} differs: {out[first]:#x}, expected {want[first]:#x}"
    counts = {name: int(getattr(dut, f"cnt_{name}").value) for name in case["counts"]}
    assert counts == case["counts"], f"counters {counts}, expected {case['counts']}"
    if case["max_wait"] is not None:
        assert waits <= case["max_wait"], \
            f"the input waited {waits} clocks, at most {case['max_wait']} allowed"
    dut._log.info("%d packets, %d bytes in, %d out, %d clocks, input waited %d clocks",
                  len(case["packets"]), len(stream), len(out), clock, waits)
