"""A ROS 2 node's recording (``Ros2Node.record``): what notebook 11 draws as a sequence diagram.

Two of the lab's own ROS 2 nodes on 127.0.0.1 (no Cyclone DDS needed): the recording holds both
directions of the discovery and of the data, the matching decisions with their times, stays
within its bounds, and ``widgets.events_from_recording`` draws it with the nodes' names.
"""

from __future__ import annotations

import os

import pytest

from tests.support.ros2tools import wait  # the ROS 2 tests' one polling helper
from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.ros2 import Ros2Node
from rosfpga_lab.rtps import parse_message
from rosfpga_lab.rtps.participant import Qos, discovery_port, user_port
from rosfpga_lab.widgets import events_from_recording

pytestmark = pytest.mark.timeout(60)

#: A DDS domain of this test process's own, apart from the other ROS 2 tests' (100..219).
DOMAIN = 10 + os.getpid() % 80
PAYLOAD = b"\x00\x01\x00\x00" + (5).to_bytes(4, "little") + b"hello\x00\x00\x00"


def test_the_recording_holds_discovery_matching_and_data_both_ways() -> None:
    got: list[bytes] = []
    with Ros2Node("talker", DOMAIN) as talker:
        with pytest.raises(GraphError, match="call record"):
            talker.recorded()
        talker.record()
        with Ros2Node("listener", DOMAIN) as listener:
            pub = talker.create_publisher("/chatter", "std_msgs/String", Qos(True, 10))
            best_effort = talker.create_publisher("/chatter", "std_msgs/String", Qos(False, 10))
            listener.create_subscriber("/chatter", "std_msgs/String",
                                       lambda payload, sample: got.append(payload), Qos(True, 10))
            assert pub.wait_for_subscribers(1, 10)
            pub.publish(PAYLOAD)
            assert wait(lambda: got and pub.unacknowledged() == 0)
            run = talker.recorded()
            me, other = talker.participant.guid_prefix, listener.participant.guid_prefix
    assert got == [PAYLOAD]
    assert best_effort.matched() == 0
    assert run.names[me] == "talker" and run.names[other] == "listener"
    assert run.dropped == 0 and run.kept_bytes == sum(len(d) for *_, d in run.datagrams)
    sent = [d for d in run.datagrams if parse_message(d[3]).header.guid_prefix == me]
    received = [d for d in run.datagrams if parse_message(d[3]).header.guid_prefix == other]
    assert sent and received and len(sent) + len(received) == len(run.datagrams)
    # sent from the talker's user port; received on its discovery or user port
    talker_ports = {f"127.0.0.1:{discovery_port(DOMAIN, talker.index)}",
                    f"127.0.0.1:{user_port(DOMAIN, talker.index)}"}
    assert {src for _, src, _, _ in sent} == {f"127.0.0.1:{user_port(DOMAIN, talker.index)}"}
    assert {dst for _, _, dst, _ in received} <= talker_ports
    # SPDP went to the probed discovery port of the listener's index
    assert any(dst == f"127.0.0.1:{discovery_port(DOMAIN, listener.index)}" for _, _, dst, _ in sent)
    names = {s.name for *_, d in run.datagrams for s in parse_message(d).submessages}
    assert {"DATA", "HEARTBEAT", "ACKNACK"} <= names
    notes = [text for _, text in run.notes]
    assert any(n.startswith("matched: writer rt/chatter (RELIABLE") for n in notes), notes
    assert any(n.startswith("not matched: writer rt/chatter (BEST_EFFORT") and
               "a BEST_EFFORT writer never matches a RELIABLE reader" in n for n in notes), notes
    times = [t for t, *_ in run.datagrams]
    assert times == sorted(times)

    events = events_from_recording(run)
    drawn = {(e.src, e.dst) for e in events}
    assert ("talker", "peers") in drawn and ("listener", "talker") in drawn
    assert ("talker", "listener") in drawn
    labels = [e.label for e in events]
    assert "SPDP participant" in labels and any("SEDP reader rt/chatter" in lab for lab in labels)
    decisions = [e for e in events if e.kind == "rtps_match"]
    assert [e.label for e in decisions].count("matched rt/chatter") >= 1
    assert "not matched rt/chatter" in [e.label for e in decisions]
    assert all(e.src == e.dst == "talker" for e in decisions)
    assert [e.t for e in events if e.t] == sorted(e.t for e in events if e.t)


def test_the_recording_is_bounded_and_counts_what_it_leaves_out() -> None:
    with Ros2Node("talker", DOMAIN + 1) as talker:
        rec = talker.record(max_datagrams=3, max_bytes=1 << 20)
        with Ros2Node("listener", DOMAIN + 1):
            assert wait(lambda: talker.recorded().dropped > 0)
        run = talker.recorded()
    assert len(run.datagrams) == 3 and run.dropped > 0
    assert rec is not run                       # recorded() is a copy
    with Ros2Node("small", DOMAIN + 1) as node:
        node.record(max_datagrams=100, max_bytes=10)   # no datagram is that small
        assert wait(lambda: node.recorded().dropped > 0)
        assert node.recorded().datagrams == [] and node.recorded().kept_bytes == 0


def test_a_datagram_of_two_participants_is_drawn_as_an_arrow_from_each() -> None:
    """Cyclone DDS packs the submessages of a process's participants into one datagram, the
    second after INFO_SRC (data/capture_cyclone_info_src.py made this one): one arrow each."""
    from pathlib import Path

    from rosfpga_lab.widgets.wire import events_from_rtps

    dg = (Path(__file__).resolve().parents[2] / "data" / "cyclone_info_src_spdp.bin").read_bytes()
    first, second = parse_message(dg).header.guid_prefix, bytes.fromhex("0110972927d126a60dd1d6af")
    names = {first: "camera", second: "viewer", bytes.fromhex("010fb4edbcfd6003fa1936d9"): "component"}
    events = events_from_rtps([(0.0, "127.0.0.1:7410", "127.0.0.1:7412", dg)], names=names)
    # one arrow per sender and destination, in the order each first speaks
    assert [(e.src, e.dst, e.label) for e in events] == [
        ("camera", "component", "ACKNACK, HEARTBEAT, SPDP participant"),
        ("viewer", "component", "SPDP participant")]
    assert all(e.raw == dg for e in events)
    # each arrow its own submessages' bytes (issue 32: both said the whole 836), counted from
    # the datagram's submessage table: the camera's INFO_DST 16, ACKNACK 28 + 28, HEARTBEAT
    # 32 + 32 and, after its INFO_SRC 24 and INFO_TS 12, DATA 304; the viewer's INFO_SRC 24,
    # INFO_TS 12, DATA 304 (the 20-byte RTPS header is neither's)
    assert len(dg) == 836
    assert [e.bytes_drawn for e in events] == [16 + 28 + 28 + 32 + 32 + 24 + 12 + 304, 24 + 12 + 304]
