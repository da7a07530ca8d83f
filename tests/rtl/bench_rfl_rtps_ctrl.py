"""cocotb testbench of the answer path, ``rfl_rtps_ctrl`` into ``rfl_rtps_disc_answer``, inside
``rfl_fabric_node`` (its metatraffic side; run by tests/rtl/test_fabric_answer.py through
tests/support/fabrictools.py, not by pytest).

The case comes in a JSON file (``FABRIC_NODE_CASE``): the datagrams (hex; all metatraffic, TUSER
0) with the idle clocks after each, per-mille output backpressure, the credit's BURST and RATE.
One coroutine drives a byte a clock and collects the answers: every beat offered and not taken
held unchanged, TDEST and the destination prefix constant over a datagram, and at every clock
the answer bytes sent at most BURST + RATE x the bytes received. The discovery ROM's SPDP
announcements (TDEST 0; SEDP is never asked for, no user data comes in) are left out. The
answers and counters (rfl_rtps_ctrl's inside the node) go to ``FABRIC_NODE_OUT`` for the test to
compare with the model's.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge


@cocotb.test()
async def rtps_ctrl_answers(dut) -> None:
    with open(os.environ["FABRIC_NODE_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    stream: list[tuple[int, int, int]] = []       # (byte, last, idle clocks after)
    for dg, idle in case["datagrams"]:
        raw = bytes.fromhex(dg)
        stream += [(x, int(i == len(raw) - 1), idle if i == len(raw) - 1 else 0)
                   for i, x in enumerate(raw)]
    dut.cfg_reader.value = 0
    dut.cfg_writer.value = 0
    dut.cfg_time.value = 0
    dut.send_sedp.value = 0
    dut.s_axis_tuser.value = 0
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    dut.rst_n.value = 0
    dut.s_axis_tvalid.value = 0
    dut.s_axis_tdata.value = 0
    dut.s_axis_tlast.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.clk)
    dut.rst_n.value = 1
    bp = case["bp"] / 1000
    i = wait = received = sent = quiet = 0
    answers: list[dict] = []
    cur = bytearray()
    cur_dest = cur_prefix = None
    held = None
    while quiet < 4000:
        offer = i < len(stream) and wait == 0
        dut.s_axis_tvalid.value = int(offer)
        if offer:
            dut.s_axis_tdata.value, dut.s_axis_tlast.value = stream[i][0], stream[i][1]
        ready = prng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value),
                int(dut.m_axis_tdest.value), int(dut.m_dst_prefix.value)) if valid else None
        if held is not None:
            assert beat == held, f"a beat offered changed before it was taken: {held} -> {beat}"
        held = beat if valid and not ready else None
        if offer:
            received += 1
            wait = stream[i][2]
            i += 1
        elif wait:
            wait -= 1
        if valid and ready and beat[2] == 0:
            pass                                # the ROM's SPDP announcement
        elif valid and ready:
            sent += 1
            data, last, dest, prefix = beat
            if cur_dest is not None:
                assert (dest, prefix) == (cur_dest, cur_prefix), "TDEST or prefix moved"
            cur_dest, cur_prefix = dest, prefix
            cur.append(data)
            if last:
                answers.append({"dest": dest, "prefix": f"{prefix:024x}", "data": cur.hex()})
                cur, cur_dest, cur_prefix = bytearray(), None, None
        assert sent <= case["burst"] + case["rate"] * received, \
            f"{sent} bytes sent for {received} received: past the bound"
        quiet = quiet + 1 if i >= len(stream) and not valid else 0
        await RisingEdge(dut.clk)
    assert not cur, "the run ended inside an answer"
    out = {"answers": answers, "received": received, "sent": sent,
           "cnt_malformed": int(dut.cnt_ctrl_malformed.value),
           "cnt_bad_header": int(dut.cnt_ctrl_bad_header.value),
           **{name: int(getattr(dut, name).value) for name in (
               "cnt_requests", "cnt_busy", "cnt_answers", "cnt_no_credit")}}
    with open(os.environ["FABRIC_NODE_OUT"], "w") as f:
        json.dump(out, f)
