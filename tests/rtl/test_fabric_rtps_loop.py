"""The node in the fabric from RTPS to RTPS (issue #31): RTPS datagrams in, through
``rfl_rtps_rx`` -> ``rfl_rtps_to_cdr`` -> the generated top of ``data/fpga_laserscan_min_cdr.yaml``
(``rosfpga-lab generate``) -> ``rfl_rtps_tx``, RTPS datagrams out, under cocotb with random input
gaps and output backpressure (tests/rtl/rtps_loop_top.v, tests/rtl/bench_rtps_loop_top.py).

The input is tests/rtl/test_fabric_rtps_cdr.py's case (sensor_msgs/LaserScan samples the lab's
CDR writer serialized, in DATA and DATA_FRAGs, one with a fragment missing, one the subscriber
refuses, one longer than the seam's buffer). Expected, from the lab's software only: the CDR
models' published records (``hls.generic.model_output_cdr``, also held against numpy there),
each sent as the lab's RTPS builders send it from the fabric participant's writer
(tests/rtl/test_fabric_rtps_tx.py's ``expected``: writerSN 1, 2, .., fragments of the software
participant's size, a HEARTBEAT each), byte for byte; and the decoder's view of what came out
(``rtps.parse_message``, ``FragmentAssembler``) is every record's payload. Last, the lab's
software ROS 2 subscriber (``rtps.participant.Participant`` with ``RosNodeEntities``, a RELIABLE
reader of the output topic) learns the fabric participant from its discovery ROM
(``rtl.discrom.render_rom``: SPDP, SEDP), matches its writer and takes every sample from the
circuit's datagrams, in order; its ACKNACKs to the HEARTBEATs (an empty history) ask for none.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.hls.vectors import model_output_cdr
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.rtl.discrom import (
    fabric_participant, render_rom, tx_parameters, verilog_parameters,
)
from rosfpga_lab.rtps.build import dds_topic
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES
from rosfpga_lab.rtps.message import AckNack, parse_message
from rosfpga_lab.rtps.participant import Participant
from rosfpga_lab.rtps.rosnode import RosNodeEntities
from tests.rtl.test_fabric_rtps_cdr import CONFIG, FABRIC, MAX_BYTES, _record, case_of
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER, reference
from tests.rtl.test_fabric_rtps_tx import check_parsed, expected
from tests.support.rtltools import TB_DIR, require_cocotb

pytestmark = pytest.mark.rtl

LISTENER = bytes.fromhex("010f0000000000000000abcd")   # the software subscriber's GUID prefix
TIME = (1_700_000 << 32) | 0x8000_0000          # cfg_time: seconds below 2**21, exact as a float


def split_records(stream: bytes) -> list[bytes]:
    """The payloads of a record stream (each a LE32 length, then the payload)."""
    out, at = [], 0
    while at < len(stream):
        (n,) = struct.unpack("<I", stream[at:at + 4])
        out.append(stream[at + 4:at + 4 + n])
        at += 4 + n
    assert at == len(stream)
    return out


def published(seed: int) -> tuple[list[bytes], list[bytes]]:
    """tests/rtl/test_fabric_rtps_cdr.py's datagrams of ``seed`` and the payloads the CDR models
    publish for them (each record's, in order)."""
    datagrams, oracle, _ = case_of(seed)
    walked, _counts = reference(datagrams)
    kept = [r for r in (_record(bytes.fromhex(s["data"])) for s in walked)
            if len(r) - 4 <= MAX_BYTES]
    config = load_config(CONFIG)
    out_records, _why = model_output_cdr(cdr_layout_from_config(config),
                                         config.application.op, config.application.ksize, kept)
    assert out_records == oracle
    return datagrams, split_records(out_records)


def software_subscriber(config: NodeConfig, datagrams: list[bytes]) -> tuple[list, list]:
    """A software ROS 2 node subscribed to the configuration's output topic, told of the fabric
    participant by its discovery ROM only, given ``datagrams``: the samples it takes and the
    ACKNACKs it answers with."""
    sub = Participant(0, 5, "127.0.0.1", "listener", guid_prefix=LISTENER)
    node = RosNodeEntities(sub, "listener", "/")
    rid = node.add_subscriber(config.publisher.topic, config.publisher.type,
                              registry=config.registry())
    rom = render_rom(config)
    for m in rom.messages:
        sub.receive(m.data, ("127.0.0.1", 7410), 0.0)
    assert sub.matched(rid), sub.notes
    acks = []
    for k, dg in enumerate(datagrams):
        for _host, _port, reply in sub.receive(dg, ("127.0.0.1", 7411), 0.1 + k / 1000):
            acks += [s for s in parse_message(reply).submessages if isinstance(s, AckNack)]
    return sub.take(rid), acks


@pytest.mark.parametrize("seed,gap,bp", [(5, 200, 300)])
def test_rtps_in_rtps_out_is_the_models_output_as_the_builders_send_it(
        seed: int, gap: int, bp: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    sim = require_cocotb()
    monkeypatch.syspath_prepend(str(TB_DIR))
    from cocotb_tools.runner import get_results, get_runner

    gen = tmp_path / "project"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(CONFIG), "-o",
                           str(gen), "-q"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    datagrams, payloads = published(seed)
    config = load_config(CONFIG)
    part, _node, wid, _rid = fabric_participant(config)
    p = tx_parameters(render_rom(config))
    assert p["FRAG_BYTES"] == FRAGMENT_BYTES and p["INFO_TS"] == 1
    want = expected(payloads, [TIME] * len(payloads), FRAGMENT_BYTES, True, MAX_BYTES,
                    part.guid_prefix, wid, p["READER_ID"])
    assert len(payloads) == 5 and all(len(d) == 2 for d in want)   # each sample fragments
    case = {"seed": seed, "gap": gap, "bp": bp, "local": LOCAL.hex(), "reader": READER,
            "writer": WRITER, "time": TIME, "datagrams": [d.hex() for d in datagrams],
            "expect": sum(map(len, want))}
    (tmp_path / "case.json").write_text(json.dumps(case))
    rtl = sorted(q for q in (gen / "rtl").glob("*.v") if q.name != "rfl_tb.v")
    sources = [FABRIC / "rfl_rtps_rx.v", FABRIC / "rfl_rtps_to_cdr.v", FABRIC / "rfl_rtps_tx.v",
               *rtl, TB_DIR / "rtps_loop_top.v"]
    runner = get_runner(sim)
    runner.build(sources=sources, includes=[gen / "rtl"], hdl_toplevel="rtps_loop_top",
                 parameters=dict(verilog_parameters(p), MAX_BYTES=str(MAX_BYTES)),
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    try:
        xml = runner.test(test_module="bench_rtps_loop_top", hdl_toplevel="rtps_loop_top",
                          build_dir=tmp_path / "build", test_dir=tmp_path,
                          extra_env={"RTPS_LOOP_CASE": str(tmp_path / "case.json"),
                                     "RTPS_LOOP_OUT": str(tmp_path / "out.json")},
                          log_file=tmp_path / "sim.log")
        total, failed = get_results(xml)
    except (SystemExit, RuntimeError):
        total, failed = 1, 1
    log = (tmp_path / "sim.log").read_text(errors="replace")
    assert total == 1 and failed == 0, log[-4000:]
    out = json.loads((tmp_path / "out.json").read_text())
    got = [bytes.fromhex(d) for d in out["datagrams"]]
    check_parsed(got, payloads, MAX_BYTES, part.guid_prefix, wid, p["READER_ID"], True)
    assert got == [d for dgs in want for d in dgs]
    assert out["counts"] == {"samples": 5, "datagrams": 10, "dropped": 0}
    taken, acks = software_subscriber(config, got)
    writer_guid = part.guid_prefix + wid.to_bytes(4, "big")
    assert [(s.writer_guid, s.seq, s.payload) for s in taken] == \
        [(writer_guid, n, pay) for n, pay in enumerate(payloads, 1)]
    assert acks and all(a.writer_id == wid and a.missing == () for a in acks), acks


@pytest.mark.timeout(60)
def test_cyclone_dds_takes_what_the_circuit_sends() -> None:
    """PyPI Cyclone DDS (configured as rmw_cyclonedds_cpp would be) with a default-QoS ROS 2
    reader (RELIABLE, VOLATILE, KEEP_LAST 10) of the output topic learns the fabric participant
    from its discovery ROM sent from a UDP socket as the circuit sends it
    (tests/rtl/test_discrom.py's RomSender), then takes every sample of the datagrams the
    circuit sends for the models' output (the builders' bytes: the test above holds the
    circuit's equal to them), DATA_FRAGs and empty-history HEARTBEATs included."""
    from tests.rtl.test_discrom import RomSender, _require_cyclonedds
    from tests.support.ros2tools import DOMAIN, cyclone, wait

    builtin, dds = _require_cyclonedds()
    types = cyclone()
    from tests.support.cdrtypes import LaserScan_

    config = load_config(CONFIG)
    _datagrams, payloads = published(5)
    part, _node, wid, _rid = fabric_participant(config)
    sender = RomSender(DOMAIN, CONFIG, part.guid_prefix)
    try:
        dp = dds.DomainParticipant(DOMAIN)
        P = types.Policy
        topic = types.Topic(dp, dds_topic(config.publisher.topic), LaserScan_)
        reader = types.DataReader(dp, topic, qos=types.Qos(
            P.Reliability.Reliable(100_000_000), P.Durability.Volatile, P.History.KeepLast(10)))
        pubs = builtin.BuiltinDataReader(dp, builtin.BuiltinTopicDcpsPublication)
        seen: list = []
        writer_key = part.guid_prefix + wid.to_bytes(4, "big")

        def matched() -> bool:
            seen.extend(pubs.take(N=64))
            return bool(sender.peers) and any(s.key.bytes == writer_key for s in seen)

        assert wait(matched, 10.0), (sender.peers, len(seen))
        time.sleep(0.3)              # Cyclone's reader matches the writer it learned
        want = expected(payloads, [TIME] * len(payloads), FRAGMENT_BYTES, True, MAX_BYTES,
                        part.guid_prefix, wid, 0)
        for dg in (d for dgs in want for d in dgs):
            sender.send_data(dg)
        got: list = []

        def taken() -> bool:
            got.extend(reader.take(N=16))
            return len(got) >= len(payloads)

        assert wait(taken, 10.0), f"{len(got)} of {len(payloads)} samples taken"
        assert [g.serialize() for g in got] == \
            [LaserScan_.deserialize(p).serialize() for p in payloads]
        dp = None
    finally:
        sender.close()
