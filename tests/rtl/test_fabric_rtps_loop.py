"""The node in the fabric from RTPS to RTPS (issue #31): RTPS user-data datagrams into
``rfl_fabric_node``, through ``rfl_rtps_rx`` -> ``rfl_rtps_to_cdr`` -> the generated top of
``data/fpga_laserscan_min_cdr.yaml`` (``rosfpga-lab generate``) -> ``rfl_rtps_tx``, RTPS datagrams
out, under cocotb with random input gaps and output backpressure (tests/support/fabrictools.py,
tests/rtl/bench_rfl_fabric_node.py; the metatraffic side: tests/rtl/test_fabric_node.py).

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

import struct
import time
from pathlib import Path

import pytest

from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.hls.vectors import model_output_cdr
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.rtl.discrom import (
    DEST_SPDP, DEST_USER, DiscoveryRom, fabric_participant, render_rom, tx_parameters,
)
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE
from rosfpga_lab.rtps.build import dds_topic
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES
from rosfpga_lab.rtps.message import AckNack, parse_message
from rosfpga_lab.rtps.participant import Participant
from rosfpga_lab.rtps.rosnode import RosNodeEntities
from tests.rtl.test_fabric_rtps_cdr import CONFIG, MAX_BYTES, _record, case_of
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER, reference
from tests.rtl.test_fabric_rtps_tx import check_parsed, expected
from tests.support.fabrictools import generate_project, run_fabric_node
from tests.support.rtltools import TB_DIR

pytestmark = pytest.mark.rtl

LISTENER = bytes.fromhex("010f0000000000000000abcd")   # the software subscriber's GUID prefix
TIME = (1_700_000 << 32) | 0x8000_0000          # cfg_time: seconds below 2**21, exact as a float
PERIOD = 1_000_000                              # one SPDP announcement (at reset) in the run


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


def software_subscriber(config: NodeConfig, rom: DiscoveryRom,
                        datagrams: list[bytes]) -> tuple[list, list]:
    """A software ROS 2 node subscribed to the configuration's output topic, told of the fabric
    participant by its discovery ROM ``rom`` only, given ``datagrams``: the samples it takes and
    the ACKNACKs it answers with."""
    sub = Participant(0, 5, "127.0.0.1", "listener", guid_prefix=LISTENER)
    node = RosNodeEntities(sub, "listener", "/")
    rid = node.add_subscriber(config.publisher.topic, config.publisher.type,
                              registry=config.registry())
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
    monkeypatch.syspath_prepend(str(TB_DIR))
    gen = generate_project(CONFIG, tmp_path / "project")
    datagrams, payloads = published(seed)
    config = load_config(CONFIG)
    # the datagrams are for LOCAL: the node's GUID prefix, the ROMs' and the transmit path's
    rom = render_rom(config, guid_prefix=LOCAL)
    part, _node, wid, _rid = fabric_participant(config, guid_prefix=LOCAL)
    p = tx_parameters(rom)
    assert p["FRAG_BYTES"] == FRAGMENT_BYTES and p["INFO_TS"] == 1
    want = expected(payloads, [TIME] * len(payloads), FRAGMENT_BYTES, True, MAX_BYTES,
                    part.guid_prefix, wid, p["READER_ID"])
    assert len(payloads) == 5 and all(len(d) == 2 for d in want)   # each sample fragments
    case = {"seed": seed, "gap": gap, "bp": bp, "reader": READER, "writer": WRITER,
            "time": TIME, "datagrams": [(d.hex(), 1) for d in datagrams],
            "expect": sum(map(len, want)), "min_clocks": 0, "burst": ANSWER_BURST,
            "rate": ANSWER_RATE}
    out = run_fabric_node(gen, rom, case, tmp_path, period=PERIOD, max_bytes=MAX_BYTES)
    # user data only in: on the user-data destination the transmit path's datagrams, beside
    # them the one SPDP announcement at reset (no answers)
    assert [g["dest"] for g in out["datagrams"]].count(DEST_SPDP) == 1
    got = [bytes.fromhex(g["data"]) for g in out["datagrams"] if g["dest"] == DEST_USER]
    check_parsed(got, payloads, MAX_BYTES, part.guid_prefix, wid, p["READER_ID"], True)
    assert got == [d for dgs in want for d in dgs]
    assert out["counts"] == {"samples": 5, "answers": 0, "no_credit": 0}
    assert out["tx"] == {"datagrams": 10, "dropped": 0}
    taken, acks = software_subscriber(config, rom, got)
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
