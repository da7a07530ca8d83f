"""The whole node in the fabric (issue #31): ``rfl_fabric_node`` (rosfpga_lab/rtl/fabric/
rfl_fabric_node.v) behind one UDP payload interface, under cocotb with random input gaps and
output backpressure (tests/rtl/bench_rfl_fabric_node.py), the generated top of
``data/fpga_laserscan_min_cdr.yaml`` inside.

In: tests/rtl/test_fabric_rtps_loop.py's user datagrams (LaserScan samples the lab's CDR writer
serialized, DATA_FRAGs, one fragment missing, one refused, one too long) with, among them, a
peer's ACKNACK built with the lab's RTPS encoders on the metatraffic side, and the node's own
messages looped back (a user datagram and an ACKNACK from its GUID prefix: the one the ROMs
are rendered with, the node's GUID_PREFIX, dropped on both sides). Expected, from the
lab's software only: on the user-data destination, the CDR models' records as the lab's RTPS
builders send them from the fabric participant's writer, byte for byte and reassembled by the
lab's parser; on the metatraffic destination, the answers named here (both DATA(w) the ACKNACK
asks for), byte for byte the answer model's (``rtl.discanswer``), to the asker; on the SPDP
destination, the ROM's announcement, again every PERIOD clocks; no datagram cut by another (the
bench cuts at TLAST with TDEST held), the answers' bytes within the credit of ``rtl/limits.py``
at every clock (the bench asserts it).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discanswer import AnswerModel
from rosfpga_lab.rtl.discrom import (
    ANSWER_FILE, ANSWER_TABLE_FILE, DEST_META, DEST_SPDP, DEST_USER, ROM_FILE, TABLE_FILE,
    answer_params, fabric_participant, render_rom, tx_parameters, verilog_parameters, write_rom,
)
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE
from rosfpga_lab.rtl.proofs import FABRIC_NODE
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import PUB_READER, PUB_WRITER
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES
from rosfpga_lab.rtps.message import parse_message
from tests.rtl.test_fabric_answer import _names
from tests.rtl.test_fabric_rtps_cdr import CONFIG, FABRIC, MAX_BYTES
from tests.rtl.test_fabric_rtps_loop import TIME, published
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER
from tests.rtl.test_fabric_rtps_tx import check_parsed, expected
from tests.support.rtltools import TB_DIR, require_cocotb

pytestmark = pytest.mark.rtl

PEER = bytes.fromhex("010fcafe0000000100000001")
PERIOD = 6000           # clocks between SPDP announcements: several in one run
MIN_CLOCKS = 4 * PERIOD


@pytest.mark.timeout(120)
@pytest.mark.parametrize("seed,gap,bp", [(3, 200, 300), (8, 0, 700)])
def test_the_node_routes_answers_and_announces(seed: int, gap: int, bp: int, tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    sim = require_cocotb()
    monkeypatch.syspath_prepend(str(TB_DIR))
    from cocotb_tools.runner import get_results, get_runner

    gen = tmp_path / "project"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(CONFIG), "-o",
                           str(gen), "-q"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    config = load_config(CONFIG)
    # the receive side's datagrams are for LOCAL: the node's GUID prefix, the ROMs' (one owner)
    rom = render_rom(config, guid_prefix=LOCAL)
    write_rom(rom, tmp_path)
    part, _node, wid, _rid = fabric_participant(config, guid_prefix=LOCAL)
    assert part.guid_prefix == rom.guid_prefix == LOCAL
    user, payloads = published(5)
    ack = b.header(PEER) + b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 1)   # no INFO_DST
    # the node's own messages looped back (its prefix in the header) are dropped on both sides:
    # taken by a receive side of another prefix, they would add a sample, or answers
    own = [user[0][:8] + LOCAL + user[0][20:], b.header(LOCAL) + ack[20:]]
    assert own[0] != user[0] and user[0][8:20] != LOCAL
    datagrams = [(d.hex(), 1) for d in user[:3]] + [(ack.hex(), 0), (own[1].hex(), 0)] + \
        [(own[0].hex(), 1)] + [(d.hex(), 1) for d in user[3:]]
    p = tx_parameters(rom)
    want_user = [d for dgs in expected(payloads, [TIME] * len(payloads), FRAGMENT_BYTES, True,
                                       MAX_BYTES, part.guid_prefix, wid, p["READER_ID"])
                 for d in dgs]
    answers = AnswerModel(rom).receive(ack)
    assert [rom.answers[i].name for i in _names(rom, answers)] == \
        ["publications_1", "publications_2"]
    case = {"seed": seed, "gap": gap, "bp": bp, "reader": READER,
            "writer": WRITER, "time": TIME, "datagrams": datagrams,
            "expect": len(want_user) + len(answers), "min_clocks": MIN_CLOCKS,
            "burst": ANSWER_BURST, "rate": ANSWER_RATE}
    (tmp_path / "case.json").write_text(json.dumps(case))
    a = answer_params(rom)
    params = dict(verilog_parameters(p), MAX_BYTES=str(MAX_BYTES), PERIOD=str(PERIOD),
                  USER_DEST=str(DEST_USER), ROM_FILE=f'"{ROM_FILE}"',
                  TABLE_FILE=f'"{TABLE_FILE}"', ROM_BYTES=str(len(rom.image())),
                  MESSAGES=str(len(rom.messages)), ANSWER_FILE=f'"{ANSWER_FILE}"',
                  ANSWER_TABLE_FILE=f'"{ANSWER_TABLE_FILE}"',
                  **{k: str(a[k]) for k in ("SLOTS", "SLOT_IDS", "SLOT_MSGS", "SLOT_LASTS",
                                            "ANSWER_BYTES", "ANSWERS", "DST_AT", "BASE_AT",
                                            "COUNT_START", "BURST", "RATE")})
    rtl = sorted(q for q in (gen / "rtl").glob("*.v") if q.name != "rfl_tb.v")
    sources = [FABRIC / m for m in FABRIC_NODE] + rtl
    runner = get_runner(sim)
    runner.build(sources=sources, includes=[gen / "rtl"], hdl_toplevel="rfl_fabric_node",
                 parameters=params, build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    try:
        xml = runner.test(test_module="bench_rfl_fabric_node", hdl_toplevel="rfl_fabric_node",
                          build_dir=tmp_path / "build", test_dir=tmp_path,
                          extra_env={"FABRIC_NODE_CASE": str(tmp_path / "case.json"),
                                     "FABRIC_NODE_OUT": str(tmp_path / "out.json")},
                          log_file=tmp_path / "sim.log")
        total, failed = get_results(xml)
    except (SystemExit, RuntimeError):
        total, failed = 1, 1
    log = (tmp_path / "sim.log").read_text(errors="replace")
    assert total == 1 and failed == 0, log[-4000:]
    out = json.loads((tmp_path / "out.json").read_text())
    got = out["datagrams"]
    assert {g["dest"] for g in got} <= {DEST_SPDP, DEST_META, DEST_USER}
    sent = [bytes.fromhex(g["data"]) for g in got if g["dest"] == DEST_USER]
    assert sent == want_user
    check_parsed(sent, payloads, MAX_BYTES, part.guid_prefix, wid, p["READER_ID"], True)
    assert [(bytes.fromhex(g["prefix"]), bytes.fromhex(g["data"]))
            for g in got if g["dest"] == DEST_META] == [(x.prefix, x.data) for x in answers]
    assert all(x.prefix == PEER for x in answers)
    spdp = [g for g in got if g["dest"] == DEST_SPDP]
    assert all(bytes.fromhex(g["data"]) == rom.messages[0].data for g in spdp)
    parse_message(rom.messages[0].data)
    starts = [g["clock"] for g in spdp]
    # one at reset, then one a PERIOD; each may wait behind the two other sources' datagrams
    # (round robin: at most two, rfl_frame_arbiter's proof) and its own under backpressure
    late = 3 * p["MAX_DATAGRAM"] * 1000 // (1000 - bp)
    assert len(starts) >= out["clocks"] // PERIOD, (starts, out["clocks"])
    assert all(PERIOD - late <= y - x <= PERIOD + late for x, y in zip(starts, starts[1:])), \
        starts
    assert out["counts"] == {"samples": len(payloads), "answers": len(answers),
                             "no_credit": 0}
