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

from pathlib import Path

import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discanswer import AnswerModel
from rosfpga_lab.rtl.discrom import (
    DEST_META, DEST_SPDP, DEST_USER, fabric_participant, render_rom, tx_parameters,
)
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import PUB_READER, PUB_WRITER
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES
from rosfpga_lab.rtps.message import parse_message
from tests.rtl.test_fabric_answer import _names
from tests.rtl.test_fabric_rtps_cdr import CONFIG, MAX_BYTES
from tests.rtl.test_fabric_rtps_loop import TIME, published
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER
from tests.rtl.test_fabric_rtps_tx import check_parsed, expected
from tests.support.fabrictools import generate_project, run_fabric_node
from tests.support.rtltools import TB_DIR

pytestmark = pytest.mark.rtl

PEER = bytes.fromhex("010fcafe0000000100000001")
PERIOD = 6000           # clocks between SPDP announcements: several in one run
MIN_CLOCKS = 4 * PERIOD


@pytest.mark.timeout(120)
@pytest.mark.parametrize("seed,gap,bp", [(3, 200, 300), (8, 0, 700)])
def test_the_node_routes_answers_and_announces(seed: int, gap: int, bp: int, tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))
    gen = generate_project(CONFIG, tmp_path / "project")
    config = load_config(CONFIG)
    # the receive side's datagrams are for LOCAL: the node's GUID prefix, the ROMs' (one owner)
    rom = render_rom(config, guid_prefix=LOCAL)
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
    out = run_fabric_node(gen, rom, case, tmp_path, period=PERIOD, max_bytes=MAX_BYTES)
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
