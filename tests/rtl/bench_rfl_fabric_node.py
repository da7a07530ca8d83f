"""cocotb testbench of the whole node in the fabric, ``rfl_fabric_node``
(rosfpga_lab/rtl/fabric/rfl_fabric_node.v; run by tests/support/fabrictools.py for
tests/rtl/test_fabric_node.py and tests/rtl/test_fabric_rtps_loop.py, not by pytest).

The case comes in a JSON file (``FABRIC_NODE_CASE``): the datagrams in (hex, kind: 1 user data,
0 metatraffic), the receive side's configuration, ``cfg_time``, how many datagrams other than
the SPDP announcement must come out, the clocks to run at least, per-mille input gaps and output
backpressure, and the answers' credit (BURST, RATE). One coroutine drives a byte a clock when
offered (TUSER, the kind, on a packet's first beat, random on its other beats) and takes the
output when ready (a valid beat, its TDEST and prefix must stay unchanged until taken), cutting
it into datagrams at TLAST, each with its TDEST, prefix and first clock. At every clock the
metatraffic bytes out (TDEST 1: the answers, SEDP is never asked for) are at most BURST + RATE x
the metatraffic bytes in (rtl/limits.py's credit). It ends 300 clocks after all this (more
datagrams would show), or after a bound on the clocks (a lock-up).
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def fabric_node(dut) -> None:
    with open(os.environ["FABRIC_NODE_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int, int]] = []
    for dg, kind in case["datagrams"]:
        raw = bytes.fromhex(dg)
        stream += [(x, int(i == len(raw) - 1), kind) for i, x in enumerate(raw)]
    dut.cfg_reader.value = case["reader"]
    dut.cfg_writer.value = case["writer"]
    dut.cfg_time.value = case["time"]
    dut.send_sedp.value = 0
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    i = clock = meta_in = meta_out = 0
    out: list[dict] = []
    cur = bytearray()
    start = 0
    held = None
    others = 0
    done_at = None
    limit = 20 * len(stream) + case["min_clocks"] + 20000
    while clock < limit:
        if done_at is None and i == len(stream) and others >= case["expect"] \
                and clock >= case["min_clocks"]:
            done_at = clock
        if done_at is not None and clock >= done_at + 300 and not cur:
            break
        clock += 1
        offer = i < len(stream) and prng.random() >= gap
        dut.s_axis_tvalid.value = int(offer)
        if offer:
            dut.s_axis_tdata.value, dut.s_axis_tlast.value, kind = stream[i]
            first = i == 0 or stream[i - 1][1] == 1
            # TUSER counts on a packet's first beat only: random on the others
            dut.s_axis_tuser.value = kind if first else prng.getrandbits(1)
        else:
            dut.s_axis_tdata.value = prng.getrandbits(8)
            dut.s_axis_tlast.value = prng.getrandbits(1)
            dut.s_axis_tuser.value = prng.getrandbits(1)
        ready = prng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value),
                int(dut.m_axis_tdest.value), int(dut.m_dst_prefix.value)) if valid else None
        if held is not None:
            assert beat == held, f"clock {clock}: a valid beat changed before it was taken"
        held = beat if valid and not ready else None
        if valid and ready:
            if not cur:
                start, dest, prefix = clock, beat[2], beat[3]
            assert (beat[2], beat[3]) == (dest, prefix), f"clock {clock}: TDEST moved in a datagram"
            cur.append(beat[0])
            meta_out += int(beat[2] == 1)
            if beat[1]:
                out.append({"data": cur.hex(), "dest": dest, "prefix": f"{prefix:024x}",
                            "clock": start})
                others += int(dest != 0)
                cur = bytearray()
        if offer and int(dut.s_axis_tready.value):
            meta_in += int(stream[i][2] == 0)
            i += 1
        assert meta_out <= case["burst"] + case["rate"] * meta_in, \
            f"clock {clock}: {meta_out} answer bytes out for {meta_in} metatraffic bytes in"
        await RisingEdge(dut.clk)
    assert i == len(stream), f"{len(stream) - i} input bytes never taken (locked up)"
    assert done_at is not None, f"{others} of {case['expect']} datagrams out (locked up)"
    counts = {name: int(getattr(dut, f"cnt_{name}").value)
              for name in ("samples", "answers", "no_credit")}
    # the transmit path's own counters (inside the node: its cnt_datagrams, cnt_dropped)
    tx = {name: int(getattr(dut, f"cnt_{name}").value) for name in ("datagrams", "dropped")}
    with open(os.environ["FABRIC_NODE_OUT"], "w") as f:
        json.dump({"datagrams": out, "counts": counts, "tx": tx, "clocks": clock,
                   "meta": [meta_in, meta_out]}, f)
    dut._log.info("%d bytes in, %d datagrams out, %d clocks, counters %s",
                  len(stream), len(out), clock, counts)
