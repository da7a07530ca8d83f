"""cocotb testbench of ``rfl_rtps_rx`` alone (run by tests/rtl/test_fabric_rtps_rx.py, not by pytest).

The case comes in a JSON file (``RTPS_RX_CASE``): the datagrams (hex), the configuration, the
expected samples and counters (computed by the test from the lab's RTPS decoder, or written
by hand; a counter expected as null is not checked beyond the packets dropped), per-mille
input gaps and output backpressure. One coroutine drives a byte a clock when it is offered and
collects the output: every beat of a valid output held until taken, the sideband constant over
a packet, TUSER only with TLAST, output beats never more than input bytes taken; the packets
without TUSER must be the expected samples, byte for byte, with their writer GUID, writerSN
and timestamp, and the counters the expected counts.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def rtps_rx_walk(dut) -> None:
    with open(os.environ["RTPS_RX_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int]] = []
    for dg in case["datagrams"]:
        raw = bytes.fromhex(dg)
        stream += [(x, int(i == len(raw) - 1)) for i, x in enumerate(raw)]
    dut.cfg_prefix.value = int(case["local"], 16)
    dut.cfg_reader.value = case["reader"]
    dut.cfg_writer.value = case["writer"]
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = taken = sent = idle = 0
    packets: list[dict] = []
    cur: dict | None = None
    held = None
    clock = 0
    while idle < 60 and clock < 20 * len(stream) + 1000:     # a lock-up ends it too
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
        beat = None
        if valid:
            beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value),
                    int(dut.m_axis_tuser.value), int(dut.m_sample_guid.value),
                    int(dut.m_sample_seq.value), 0, int(dut.m_sample_ts_valid.value))
            if beat[6]:                     # the time is meaningful with its valid flag only
                beat = beat[:5] + (int(dut.m_sample_ts.value),) + beat[6:]
            assert not beat[2] or beat[1], f"clock {clock}: TUSER without TLAST"
        if held is not None:
            assert beat == held, f"clock {clock}: a valid beat changed before it was taken"
        if offer and int(dut.s_axis_tready.value):
            i += 1
            taken += 1
        if valid and ready:
            sent += 1
            assert sent <= taken, f"clock {clock}: {sent} beats out for {taken} bytes in"
            if cur is None:
                cur = {"data": bytearray(), "meta": beat[3:]}
            assert beat[3:] == cur["meta"], f"clock {clock}: the sideband changed in a packet"
            cur["data"].append(beat[0])
            if beat[1]:
                cur["drop"] = beat[2]
                packets.append(cur)
                cur = None
            held = None
        else:
            held = beat
        idle = idle + 1 if (i == len(stream) and not valid) else 0
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    if cur is not None:            # a fragmented sample still waiting for its fragments
        cur["drop"] = 1
        packets.append(cur)
    good = [p for p in packets if not p["drop"]]
    if os.environ.get("RTPS_RX_OUT"):                 # for a look after a failure
        with open(os.environ["RTPS_RX_OUT"], "w") as f:
            json.dump([{"data": p["data"].hex(), "drop": p["drop"], "guid": f"{p['meta'][0]:032x}",
                        "seq": p["meta"][1]} for p in packets], f, indent=0)
    want = case["samples"]
    for n, (g, w) in enumerate(zip(good, want)):
        guid, seq, ts, ts_valid = g["meta"]
        assert g["data"].hex() == w["data"], f"sample {n}: bytes differ"
        assert (f"{guid:032x}", seq, ts_valid) == (w["guid"], w["seq"], int(w["ts"] is not None)), \
            f"sample {n}: sideband {guid:032x} {seq} {ts_valid}, expected {w}"
        if w["ts"] is not None:
            assert ts == w["ts"], f"sample {n}: timestamp {ts:#x}, expected {w['ts']:#x}"
    assert len(good) == len(want), f"{len(good)} samples out, {len(want)} expected"
    counts = {name: int(getattr(dut, f"cnt_{name}").value) for name in case["counts"]}
    assert counts["dropped"] >= len(packets) - len(good)
    want_counts = dict(case["counts"])
    if want_counts["dropped"] is None:                # not predicted by the reference
        want_counts["dropped"] = counts["dropped"]
    assert counts == want_counts, f"counters {counts}, expected {want_counts}"
    dut._log.info("%d bytes, %d clocks, %d samples, %d dropped packets, counters %s",
                  len(stream), clock, len(good), len(packets) - len(good), counts)
