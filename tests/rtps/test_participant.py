"""The sans-IO DDS participant: two lab participants over an in-memory network (with loss),
the real Cyclone DDS capture replayed whole, byte by byte and with trailing bytes, and hostile
peers (spoofed GUIDs, absurd fragments, SPDP floods, ACKNACK storms): nothing crashes, stalls or
grows past its limit, and each problem is logged once."""

from __future__ import annotations

import random
import struct
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.graph.capture_read import udp_datagrams
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps import parse_message
from rosfpga_lab.rtps.limits import (
    GOODBYE_GRACE_SECONDS, MAX_HISTORY_BYTES, MAX_NOTES, MAX_OUT_OF_ORDER, MAX_PENDING_BYTES,
    MAX_REMOTE_ENDPOINTS, MAX_REMOTE_PARTICIPANTS, NACK_SUPPRESSION_SECONDS, RESEND_PER_BYTE_WRITTEN,
    SUSPECT_GOODBYE_LEASE_SECONDS,
)
from rosfpga_lab.rtps.message import AckNack, Data, DataFrag, Gap, Heartbeat, InfoDst, NackFrag
from rosfpga_lab.rtps.participant import (
    PUB_READER, PUB_WRITER, SPDP_READER, SPDP_WRITER, Participant, Qos, discovery_port, incompatibility,
    user_port,
)

CAPTURE = Path(__file__).resolve().parents[2] / "data" / "rtps_image.pcapng"
DATAGRAMS = [d[3] for d in udp_datagrams(CAPTURE)]
TOPIC, TYPE = "rt/cam", "sensor_msgs::msg::dds_::Image_"


class Net:
    """Delivers what participants send, by destination port; ``drop(datagram)`` loses some."""

    def __init__(self, *parts: Participant, drop=lambda d: False) -> None:
        self.parts = parts
        self.drop = drop
        self.now = 0.0
        self.sent = 0
        self.kinds: set[str] = set()      # submessage kinds that went over the network

    def port_owner(self, port: int) -> Participant | None:
        for p in self.parts:
            if port in (p.meta[1], p.user[1]):
                return p
        return None

    def run(self, out: list, steps: int = 200, dt: float = 0.01) -> None:
        queue = list(out)
        for _ in range(steps):
            for p in self.parts:
                queue += p.tick(self.now)
            while queue:
                host, port, data = queue.pop(0)
                self.sent += 1
                self.kinds |= {sub.name for sub in parse_message(data).submessages}
                dst = self.port_owner(port)
                if dst is None or self.drop(data):
                    continue
                src = next(p for p in self.parts if p is not dst)
                queue += dst.receive(data, src.user, self.now)
            self.now += dt


def pair(qw: Qos = Qos(), qr: Qos = Qos()) -> tuple[Participant, Participant, int, int]:
    a = Participant(domain=7, index=0, announce=0.1)
    c = Participant(domain=7, index=1, announce=0.1)
    w = a.add_writer(TOPIC, TYPE, qw)
    r = c.add_reader(TOPIC, TYPE, qr)
    return a, c, w, r


def test_port_mapping_is_the_rtps_standard() -> None:
    assert (discovery_port(0, 0), user_port(0, 0)) == (7410, 7411)
    assert (discovery_port(1, 2), user_port(1, 2)) == (7400 + 250 + 10 + 4, 7400 + 250 + 11 + 4)


def test_encoders_decode_back() -> None:
    prefix = bytes(range(12))
    msg = (b.header(prefix) + b.info_dst(bytes(12)) + b.data(1, 0x103, 5, b"\x00\x01\x00\x00abc")
           + b.heartbeat(4, 0x103, 2, 9, 3) + b.acknack(0x104, 0x103, 4, [4, 6], 2)
           + b.gap(4, 0x103, 2, 4) + b.nack_frag(4, 0x103, 7, [3, 5], 1)
           + b.data_frag(4, 0x103, 8, 3, 4, 10, b"abcd", 1))
    m = parse_message(msg)
    assert m.header.guid_prefix == prefix
    d, hb, an, gap, nf, df = m.submessages[1:]
    assert isinstance(d, Data) and (d.writer_id, d.seq, d.payload[:7]) == (0x103, 5, b"\x00\x01\x00\x00abc")
    assert isinstance(hb, Heartbeat) and (hb.first, hb.last, hb.count) == (2, 9, 3)
    assert isinstance(an, AckNack) and (an.base, an.missing, an.count) == (4, (4, 6), 2)
    assert isinstance(gap, Gap) and (gap.start, gap.list_base) == (2, 4)
    assert isinstance(nf, NackFrag) and (nf.seq, nf.missing) == (7, (3, 5))
    assert isinstance(df, DataFrag) and (df.frag_start, df.frag_size, df.sample_size) == (3, 4, 10)


def test_two_participants_discover_match_and_deliver_in_order() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    assert len(a.matched(w)) == 1 and len(c.matched(r)) == 1
    payloads = [b"\x00\x01\x00\x00" + bytes([k]) * (k + 1) for k in range(5)]
    out = []
    for p in payloads:
        out += a.write(w, p, net.now)
    net.run(out, steps=5)
    assert [s.payload for s in c.take(r)] == payloads


def test_reliable_recovers_lost_datagrams_and_fragments() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    rng = random.Random(1)
    big = b"\x00\x01\x00\x00" + bytes(rng.randrange(256) for _ in range(40000))   # 30 fragments
    small = [b"\x00\x01\x00\x00" + bytes([k]) * 8 for k in range(4)]
    net.drop = lambda d: rng.random() < 0.3           # lose 30% of everything, both ways
    out = a.write(w, small[0], net.now) + a.write(w, big, net.now)
    for s in small[1:]:
        out += a.write(w, s, net.now)
    net.run(out, steps=300)
    assert [s.payload for s in c.take(r)] == [small[0], big, *small[1:]]
    assert c.assembler.held == 0
    assert {"DATA", "DATA_FRAG", "HEARTBEAT", "ACKNACK", "NACK_FRAG"} <= net.kinds, net.kinds


def test_keep_last_history_gaps_what_left_it() -> None:
    a, c, w, r = pair(Qos(True, 2))
    net = Net(a, c)
    net.run([], steps=20)
    lost = True
    net.drop = lambda d: lost and any(isinstance(s, Data) and s.writer_id == w
                                      for s in parse_message(d).submessages)
    out = []
    for k in range(5):
        out += a.write(w, b"\x00\x01\x00\x00" + bytes([k]), net.now)
    net.run(out, steps=1)
    lost = False
    net.run([], steps=50)
    # only the last 2 stayed in the writer's history; 1..3 were GAPped, the reader moved on
    assert [s.payload[-1] for s in c.take(r)] == [3, 4]


@pytest.mark.parametrize("qw,qr,why", [
    (Qos(False), Qos(True), "BEST_EFFORT writer never matches a RELIABLE reader"),
    (Qos(True), Qos(True, transient_local=True), "VOLATILE writer never matches a TRANSIENT_LOCAL"),
])
def test_incompatible_qos_is_not_matched_and_said_once(qw: Qos, qr: Qos, why: str) -> None:
    assert why in incompatibility(qw, qr)
    a, c, w, r = pair(qw, Qos(qr.reliable))
    if qr.transient_local:   # the lab's readers are VOLATILE; announce a TRANSIENT_LOCAL one
        c.local[r] = type(c.local[r])(r, "reader", TOPIC, TYPE, qr)
        c.local[0x4C2].history.clear()
        c._announce_endpoint(c.local[r])
    net = Net(a, c)
    net.run([], steps=40)
    assert a.matched(w) == [] and c.matched(r) == []
    side = a if qw.reliable else c
    assert sum(why in n for n in side.notes) == 1, side.notes


def test_best_effort_reader_matches_a_reliable_writer() -> None:
    a, c, w, r = pair(Qos(True), Qos(False))
    net = Net(a, c)
    net.run([], steps=20)
    net.run(a.write(w, b"\x00\x01\x00\x00x", net.now), steps=3)
    assert [s.payload for s in c.take(r)] == [b"\x00\x01\x00\x00x"]


def test_lease_expiry_forgets_a_silent_peer() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    assert c.participants
    # half a fragmented sample arrives, then a falls silent: the fragments go with it
    half = [d for _, _, d in a.write(w, b"\x00\x01\x00\x00" + bytes(30000), net.now)][:1]
    c.receive(half[0], a.user, net.now)
    assert c.assembler.held > 0
    net.parts = (c,)                              # a falls silent
    net.run([], steps=int(a.lease / 0.01) + 50)
    assert not c.participants and c.matched(r) == []
    assert c.assembler.held == 0
    assert any("lease" in n for n in c.notes)


# ---- the real Cyclone capture, whole / byte by byte / with trailing bytes ------------------

def fresh() -> Participant:
    return Participant(domain=0, index=5)


def test_replaying_cyclone_capture_learns_its_participants() -> None:
    p = fresh()
    for d in DATAGRAMS:
        p.receive(d, ("127.0.0.1", 7411), 0.0)
    assert len(p.participants) == 2
    # SEDP samples addressed (INFO_DST) to the other participant are not for this one
    found = {(e.kind, e.topic, e.type_name) for e in p.remote.values()}
    assert found and found <= {("writer", "rt/image_raw", TYPE), ("reader", "rt/image_raw", TYPE)}


def test_every_prefix_and_trailing_bytes_of_every_datagram_is_handled() -> None:
    p = fresh()
    for d in DATAGRAMS[:60]:
        for n in range(0, min(len(d), 400)):
            p.receive(d[:n], ("127.0.0.1", 7411), 0.0)
        p.receive(d + b"\x00\x01\x02", ("127.0.0.1", 7411), 0.0)
        p.receive(d + b"\xff" * 7, ("127.0.0.1", 7411), 0.0)
    assert len(p.notes) <= MAX_NOTES + 1
    assert any("malformed" in n for n in p.notes)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(DATAGRAMS[:80]), st.integers(0, 2000), st.binary(min_size=1, max_size=8))
def test_mutated_datagrams_never_raise(d: bytes, at: int, junk: bytes) -> None:
    p = fresh()
    at %= len(d)
    p.receive(d[:at] + junk + d[at + len(junk):], ("127.0.0.1", 7411), 0.0)


# ---- hostile peers ---------------------------------------------------------------------------

def spdp(prefix: bytes, guid_prefix: bytes | None = None, port: int = 7999) -> bytes:
    payload = b.spdp_payload(guid_prefix or prefix, b.Locator("127.0.0.1", port),
                             b.Locator("127.0.0.1", port + 1), 10.0, "evil", b"", 0)
    return b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)


def test_spoofed_spdp_guid_is_ignored_and_logged_once() -> None:
    p = fresh()
    for k in range(50):
        p.receive(spdp(b"E" * 12, guid_prefix=bytes([k]) * 12), ("127.0.0.1", 7999), 0.0)
    assert p.participants == {}
    assert sum("announces only itself" in n for n in p.notes) == 1
    assert p.counts["spdp-spoof"] == 50


# ---- INFO_SRC: several participants of one process in one datagram (Cyclone DDS does it) -------
#: Made by data/capture_cyclone_info_src.py: Cyclone's header names one participant, INFO_SRC
#: the other, whose SPDP follows; all of it is addressed (INFO_DST) to the lab's participant LAB.
CYCLONE_INFO_SRC = Path(__file__).resolve().parents[2] / "data" / "cyclone_info_src_spdp.bin"
LAB = bytes.fromhex("010fb4edbcfd6003fa1936d9")


def test_both_participants_of_a_cyclone_datagram_with_info_src_are_learned() -> None:
    dg = CYCLONE_INFO_SRC.read_bytes()
    msg = parse_message(dg)
    first, second = msg.header.guid_prefix, bytes.fromhex("0110972927d126a60dd1d6af")
    p = Participant(domain=0, index=5, guid_prefix=LAB)
    p.receive(dg, ("127.0.0.1", 7410), 0.0)
    # before INFO_SRC was read, the second SPDP was "SPDP from <first> announces <second>"
    assert set(p.participants) == {first, second}, p.notes
    assert not any("announces only itself" in n for n in p.notes)
    # the same datagram addressed (INFO_DST) to another participant is not for this one
    q = Participant(domain=0, index=5, guid_prefix=b"Q" * 12)
    q.receive(dg, ("127.0.0.1", 7410), 0.0)
    assert q.participants == {}


def test_info_src_is_held_to_what_its_participant_may_say() -> None:
    p = fresh()
    # INFO_SRC naming this participant: its own submessages, ignored as if sent by itself
    own = b.header(b"E" * 12) + b.info_src(p.guid_prefix) + spdp(p.guid_prefix)[20:]
    p.receive(own, ("127.0.0.1", 7999), 0.0)
    assert p.participants == {}
    # after INFO_SRC F, an SPDP announcing G is a spoof (of F, not of the header's E)
    payload = b.spdp_payload(b"G" * 12, b.Locator("127.0.0.1", 7999), b.Locator("127.0.0.1", 8000),
                             10.0, "evil", b"", 0)
    p.receive(b.header(b"E" * 12) + b.info_src(b"F" * 12) + b.data(SPDP_READER, SPDP_WRITER, 1, payload),
              ("127.0.0.1", 7999), 0.0)
    assert p.participants == {}
    assert any(f"SPDP from {(b'F' * 12).hex()} announces" in n for n in p.notes)
    # an SEDP endpoint after INFO_SRC is the INFO_SRC participant's, held to its GUID prefix
    p.add_reader(TOPIC, TYPE)
    p.receive(spdp(b"E" * 12), ("127.0.0.1", 7999), 0.0)
    p.receive(spdp(b"F" * 12, port=8001), ("127.0.0.1", 8001), 0.0)
    guid = b"F" * 12 + (0x1203).to_bytes(4, "big")
    sedp = b.sedp_payload(guid, TOPIC, TYPE, True, 10, b.Locator("127.0.0.1", 8002))
    p.receive(b.header(b"E" * 12) + b.info_src(b"F" * 12) + b.data(PUB_READER, PUB_WRITER, 1, sedp),
              ("127.0.0.1", 7999), 0.1)
    assert guid in p.remote and p.remote[guid].locator == ("127.0.0.1", 8002)


def test_spoofed_sedp_endpoint_of_another_participant_is_ignored() -> None:
    p = fresh()
    p.add_reader(TOPIC, TYPE)
    p.receive(spdp(b"E" * 12), ("127.0.0.1", 7999), 0.0)
    victim = b"V" * 12 + (0x103).to_bytes(4, "big")
    sedp = b.sedp_payload(victim, TOPIC, TYPE, True, 10, b.Locator("127.0.0.1", 8000))
    p.receive(b.header(b"E" * 12) + b.data(0x3C7, PUB_WRITER, 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert p.remote == {}
    assert sum("announces only its own endpoints" in n for n in p.notes) == 1


def test_spdp_flood_is_bounded() -> None:
    p = fresh()
    for k in range(MAX_REMOTE_PARTICIPANTS * 4):
        p.receive(spdp(struct.pack(">I", k) + b"F" * 8), ("127.0.0.1", 7999), 0.0)
    assert len(p.participants) == MAX_REMOTE_PARTICIPANTS
    assert sum("makes room" in n for n in p.notes) == 1
    assert len(p.notes) <= MAX_REMOTE_PARTICIPANTS + 2


def test_sedp_flood_is_bounded() -> None:
    p = fresh()
    prefix = b"S" * 12
    p.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    for k in range(MAX_REMOTE_ENDPOINTS + 100):
        guid = prefix + ((k << 8) | 0x03).to_bytes(4, "big")
        sedp = b.sedp_payload(guid, f"rt/t{k}", TYPE, True, 10, b.Locator("127.0.0.1", 8000))
        p.receive(b.header(prefix) + b.data(0x3C7, PUB_WRITER, k + 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert len(p.remote) == MAX_REMOTE_ENDPOINTS


def test_absurd_fragments_hold_only_bytes_received() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    # a matched writer declares a 60 MB sample in 1-byte fragments, 65535 per submessage
    frag = b.data_frag(r, w, 1, 1, 1, 60_000_000, b"x" * 100, 65535)
    evil = b.header(a.guid_prefix) + b.info_dst(c.guid_prefix) + frag
    for _ in range(20):
        c.receive(evil, a.user, 1.0)
    assert c.assembler.held == 100      # the bytes that came, never the declared size
    frag = b.data_frag(r, w, 2, 1, 64000, MAX_PENDING_BYTES * 4, b"y" * 64000, 1)
    for k in range(2, 40):
        sub = b.data_frag(r, w, k, 1, 64000, 60_000_000, b"y" * 12000, 1)
        c.receive(b.header(a.guid_prefix) + sub, a.user, 1.0)
    assert c.assembler.held <= MAX_PENDING_BYTES
    assert len(c.assembler._pending) <= c.assembler.max_pending


def test_acknack_storm_is_paced_and_duplicates_ignored() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    for k in range(10):
        a.write(w, b"\x00\x01\x00\x00" + bytes(5000), net.now)
    reader_guid_eid = r
    sent_bytes = 0
    for k in range(2000):       # 2000 ACKNACKs asking for all 10 samples, within 10 ms
        msg = b.header(c.guid_prefix) + b.acknack(reader_guid_eid, w, 1, range(1, 11), 100 + k)
        sent_bytes += sum(len(d) for _, _, d in a.receive(msg, c.user, 5.0 + k * 0.000005))
    # paced: at most one retransmission per MIN_RESEND_SECONDS, not 2000 of them
    assert sent_bytes < 4 * 10 * 5100
    dup = b.header(c.guid_prefix) + b.acknack(r, w, 1, range(1, 11), 5)
    assert a.receive(dup, c.user, 9.0) == []
    assert any("paced" in n for n in a.notes)


def test_notes_and_counts_stay_bounded_under_random_prefixes() -> None:
    p = fresh()
    rng = random.Random(3)
    for _ in range(3000):
        prefix = bytes(rng.randrange(256) for _ in range(12))
        p.receive(b.header(prefix) + b.heartbeat(0, 0x103, 1, 5, 1), ("127.0.0.1", 7999), 0.0)
    assert len(p.notes) <= MAX_NOTES + 1 and len(p.counts) <= MAX_NOTES + 1
    assert sum(p.counts.values()) == 3000


def test_acknack_for_samples_not_yet_written_never_gaps_them() -> None:
    """A (spoofed) ACKNACK asking for numbers past the last written used to GAP them, so the
    real reader skipped every later sample."""
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    evil = b.header(c.guid_prefix) + b.acknack(r, w, 1, range(1, 100), 10_000)
    out = a.receive(evil, c.user, net.now)
    assert not any(isinstance(s, Gap) for _, _, d in out for s in parse_message(d).submessages)
    net.run(out, steps=2)
    net.run(a.write(w, b"\x00\x01\x00\x00late", net.now), steps=20)
    assert [s.payload for s in c.take(r)] == [b"\x00\x01\x00\x00late"]


def test_transient_local_history_goes_only_to_transient_local_readers() -> None:
    a, c, w, r = pair(Qos(True, 3, transient_local=True), Qos(True))
    for k in range(5):
        a.write(w, b"\x00\x01\x00\x00" + bytes([k]), 0.0)
    r_tl = c._new_entity(0x04)      # a TRANSIENT_LOCAL reader (the lab's own are VOLATILE)
    c.local[r_tl] = type(c.local[r])(r_tl, "reader", TOPIC, TYPE, Qos(True, 10, True))
    c._announce_endpoint(c.local[r_tl])
    net = Net(a, c)
    net.run([], steps=40)
    assert [s.payload[-1] for s in c.take(r_tl)] == [2, 3, 4]
    assert c.take(r) == []                      # the VOLATILE reader: nothing from before
    net.run(a.write(w, b"\x00\x01\x00\x00\x05", net.now), steps=5)
    assert [s.payload[-1] for s in c.take(r)] == [5]


def test_a_volatile_reader_asking_for_older_samples_gets_a_gap_not_the_samples() -> None:
    """Cyclone's first ACKNACK asks for everything from 1: the writer used to resend its
    history to a VOLATILE reader that matched after it was written."""
    a, c, w, r = pair(Qos(True, 5))
    net = Net(a, c)
    for k in range(3):
        a.write(w, b"\x00\x01\x00\x00" + bytes([k]), 0.0)   # before anyone matched
    net.run([], steps=20)
    out = a.receive(b.header(c.guid_prefix) + b.acknack(r, w, 1, [1, 2, 3], 50), c.user, net.now)
    subs = [s for _, _, d in out for s in parse_message(d).submessages]
    assert not any(isinstance(s, Data) and s.writer_id == w for s in subs)
    assert any(isinstance(s, Gap) and (s.start, s.list_base) == (1, 4) for s in subs)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([b.PID_RELIABILITY, b.PID_DURABILITY, b.PID_HISTORY,
                                           b.PID_TOPIC_NAME, b.PID_TYPE_NAME, b.PID_UNICAST_LOCATOR,
                                           b.PID_ENDPOINT_GUID, 0x0071]),
                          st.binary(max_size=24)), max_size=8))
def test_sedp_with_odd_parameter_values_never_raises(params: list) -> None:
    """Short or odd QoS values (a 2-byte PID_RELIABILITY, ...) used to raise struct.error out of
    the receive path, which stops the node's thread."""
    p = fresh()
    prefix = b"P" * 12
    p.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    guid = prefix + (0x103).to_bytes(4, "big")
    payload = b.param_list([(b.PID_ENDPOINT_GUID, guid), (b.PID_TOPIC_NAME, b.cdr_string(TOPIC))]
                           + params)
    p.receive(b.header(prefix) + b.data(0x3C7, PUB_WRITER, 1, payload), ("127.0.0.1", 7999), 0.0)
    assert not any(k.startswith("unexpected") for k in p.counts), p.notes


def test_invalid_heartbeat_and_gap_are_ignored_and_delivery_goes_on() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    net.run(a.write(w, b"\x00\x01\x00\x00one", net.now), steps=3)
    bad = (b.header(a.guid_prefix) + b.heartbeat(r, w, 0, -5, 99)       # first < 1, last < first-1
           + b.gap(r, w, -3, 1 << 40) + b.gap(r, w, 5, 2))               # start < 1; base < start
    c.receive(bad, a.user, net.now)
    net.run(a.write(w, b"\x00\x01\x00\x00two", net.now), steps=3)
    assert [s.payload[4:] for s in c.take(r)] == [b"one", b"two"]
    assert sum("RTPS 2.3 8.3.7" in n for n in c.notes) == 2     # one note per kind


def test_heartbeats_to_a_reader_that_never_answers_back_off() -> None:
    a = Participant(domain=7, index=0, announce=100.0)
    a.add_writer(TOPIC, TYPE)
    a.receive(spdp(b"Z" * 12), ("127.0.0.1", 7999), 0.0)       # a peer that will never ACK
    beats = 0
    for k in range(1000):                                        # 10 s of ticks
        for _, _, d in a.tick(k * 0.01):
            beats += sum(isinstance(s, Heartbeat) for s in parse_message(d).submessages)
    # 2 SEDP writers; at a fixed 50 ms period that would be 400 HEARTBEATs
    assert 2 <= beats <= 2 * 16, beats


def test_heartbeat_after_absurd_fragments_costs_no_more_than_what_came() -> None:
    """A sample declaring 60 M one-byte fragments, then HEARTBEAT/HEARTBEAT_FRAG: listing the
    missing fragments used to walk all 60 M numbers (seconds per heartbeat)."""
    import time

    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    head = b.header(a.guid_prefix) + b.info_dst(c.guid_prefix)
    c.receive(head + b.data_frag(r, w, 1, 1, 1, 60_000_000, b"x" * 100, 100), a.user, 1.0)
    hbf = struct.pack("<BBH", 0x13, 1, 24) + r.to_bytes(4, "big") + w.to_bytes(4, "big") \
        + struct.pack("<iIIi", 0, 1, 60_000_000, 1)
    t0 = time.perf_counter()
    out = c.receive(head + b.heartbeat(r, w, 1, 1, 500), a.user, 1.1)
    out += c.receive(head + hbf, a.user, 1.2)
    assert time.perf_counter() - t0 < 0.5
    nacks = [s for _, _, d in out for s in parse_message(d).submessages if isinstance(s, NackFrag)]
    assert nacks and all(len(n.missing) <= 256 and n.missing[0] == 101 for n in nacks)


def test_fake_readers_cannot_multiply_a_frame_without_bound() -> None:
    from rosfpga_lab.rtps.limits import MAX_MATCHED_PER_ENDPOINT

    a = fresh()
    w = a.add_writer(TOPIC, TYPE, Qos(False))
    prefix = b"R" * 12
    a.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    for k in range(200):           # 200 readers on the topic from one participant
        guid = prefix + ((k << 8) | 0x04).to_bytes(4, "big")
        sedp = b.sedp_payload(guid, TOPIC, TYPE, False, 1, b.Locator("127.0.0.1", 9))
        a.receive(b.header(prefix) + b.data(0x4C7, 0x4C2, k + 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert len(a.matched(w)) == MAX_MATCHED_PER_ENDPOINT
    assert len(a.write(w, b"\x00\x01\x00\x00" + bytes(100), 1.0)) == MAX_MATCHED_PER_ENDPOINT
    assert sum("already has" in n for n in a.notes) == 1


def test_goodbye_makes_the_peer_forget_at_once() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    assert a.guid_prefix in c.participants and c.matched(r)
    for _, _, d in a.goodbye():
        c.receive(d, a.meta, net.now)
    assert a.guid_prefix not in c.participants and c.matched(r) == []


# ---- Fast DDS (ROS 2 Jazzy's rmw_fastrtps_cpp): what tests/flow/test_ros2_realros2.py found ----------
#: One SPDP datagram of a real rclpy node (ROS 2 Jazzy, Fast DDS 2.14, PyPI wheels) sent to the
#: lab's discovery port over loopback: its UDP locators name only the host's LAN address
#: (192.0.2.2, ports 29162/29163) and its vendor is eProsima (01 0f). Made by
#: data/capture_fastdds_spdp.py.
FASTDDS_SPDP = Path(__file__).resolve().parents[2] / "data" / "fastdds_jazzy_spdp.bin"


def test_a_fast_dds_peer_on_this_host_is_reached_over_loopback() -> None:
    dg = FASTDDS_SPDP.read_bytes()
    prefix = parse_message(dg).header.guid_prefix
    p = fresh()
    out = p.receive(dg, ("127.0.0.1", 40000), 0.0)
    # the old code ignored it: "SPDP ... has no usable unicast locator"
    assert p.participants[prefix].meta == ("127.0.0.1", 29162), p.notes
    assert p.participants[prefix].user == ("127.0.0.1", 29163)
    assert out and {(host, port) for host, port, _ in out} == {("127.0.0.1", 29162)}
    assert sum("of a peer on this host" in n for n in p.notes) == 1
    # its endpoints' locators (LAN too) are reached over loopback as well
    guid = prefix + (0x1303).to_bytes(4, "big")
    sedp = b.sedp_payload(guid, TOPIC, TYPE, True, 10, b.Locator("192.0.2.2", 29163))
    p.receive(b.header(prefix) + b.data(0x3C7, PUB_WRITER, 1, sedp), ("127.0.0.1", 40000), 0.1)
    assert p.remote[guid].locator == ("127.0.0.1", 29163)
    # the same datagram from another host: 192.0.2.2 is not where it came from, so not reachable
    q = fresh()
    q.receive(dg, ("198.51.100.7", 40000), 0.0)
    assert q.participants == {} and any("ignored" in n for n in q.notes)


def test_preemptive_acknack_in_fast_dds_form_only_to_fast_dds() -> None:
    """Fast DDS answers at once (HEARTBEAT, then the SEDP data it sent before it knew us) only a
    preemptive ACKNACK of base 0; Cyclone DDS refuses base 0 from other vendors: base 1 there."""
    def preemptive_bases(dg: bytes, source: tuple[str, int]) -> set[int]:
        p = fresh()
        return {s.base for _, _, d in p.receive(dg, source, 0.0)
                for s in parse_message(d).submessages if isinstance(s, AckNack)}

    assert preemptive_bases(FASTDDS_SPDP.read_bytes(), ("127.0.0.1", 40000)) == {0}
    assert preemptive_bases(spdp(b"C" * 12), ("127.0.0.1", 7999)) == {1}


def test_a_preemptive_acknack_gets_a_heartbeat_and_is_not_invalid() -> None:
    a = fresh()
    w = a.add_writer(TOPIC, TYPE)
    prefix = b"F" * 12
    a.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    rguid = prefix + (0x1404).to_bytes(4, "big")
    sedp = b.sedp_payload(rguid, TOPIC, TYPE, True, 10, b.Locator("127.0.0.1", 8000))
    a.receive(b.header(prefix) + b.data(0x4C7, 0x4C2, 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert a.matched(w) == [rguid]
    out = a.receive(b.header(prefix) + b.acknack(0x1404, w, 0, [], 7), ("127.0.0.1", 8000), 0.1)
    beats = [s for _, _, d in out for s in parse_message(d).submessages if isinstance(s, Heartbeat)]
    assert [(s.writer_id, s.reader_id) for s in beats] == [(w, 0x1404)]
    assert not any("8.3.7" in n for n in a.notes), a.notes


# ---- the receiver's rules (RTPS 2.3 8.3.4.1, 8.3.6.3, 8.4.12.2; Cyclone DDS's ddsi_receive.c) ----

def spdp_data(prefix: bytes, port: int = 7999) -> bytes:
    """The SPDP DATA submessage of ``spdp(prefix)`` alone."""
    return spdp(prefix, port=port)[20:]


def with_version(datagram: bytes, major: int, minor: int) -> bytes:
    return datagram[:4] + bytes([major, minor]) + datagram[6:]


def test_a_message_of_another_major_version_is_ignored_whole() -> None:
    p = fresh()
    for major, minor in ((3, 0), (1, 0), (255, 1)):
        p.receive(with_version(spdp(b"V" * 12), major, minor), ("127.0.0.1", 7999), 0.0)
    assert p.participants == {}
    assert sum("RTPS 3.0 message" in n for n in p.notes) == 1 and p.counts["version-3"] == 1
    p.receive(with_version(spdp(b"V" * 12), 2, 5), ("127.0.0.1", 7999), 0.0)   # newer minor: read
    assert set(p.participants) == {b"V" * 12}


def test_a_malformed_submessage_drops_itself_and_the_rest_not_what_came_before() -> None:
    bad_heartbeat = b"\x07\x01\x08\x00" + bytes(8)            # declares 8 bytes; it needs 28
    dg = (spdp(b"A" * 12) + bad_heartbeat + b.info_src(b"B" * 12) + spdp_data(b"B" * 12, 7997))
    p = fresh()
    p.receive(dg, ("127.0.0.1", 7999), 0.0)
    assert set(p.participants) == {b"A" * 12}, p.notes          # before: nothing was learned
    assert p.counts["malformed-rest-RtpsTruncatedError"] == 1
    # a submessage that is not the last and whose length is not a multiple of 4 is malformed
    # too (RTPS 2.3 9.4.1; Cyclone DDS refuses it): what follows it is not read
    misaligned = b"\x80\x01\x03\x00abc"
    q = fresh()
    q.receive(spdp(b"A" * 12) + misaligned + b.info_src(b"B" * 12) + spdp_data(b"B" * 12, 7997),
              ("127.0.0.1", 7999), 0.0)
    assert set(q.participants) == {b"A" * 12}, q.notes


def test_spdp_data_with_both_data_and_key_flags_does_not_make_the_peer_leave() -> None:
    p = fresh()
    p.receive(spdp(b"K" * 12), ("127.0.0.1", 7999), 0.0)
    assert b"K" * 12 in p.participants
    dk = bytearray(spdp(b"K" * 12))
    dk[21] |= 0x08                     # DATA flags: D and K (RTPS 2.3 8.3.7.2: invalid)
    p.receive(bytes(dk), ("127.0.0.1", 7999), 1.0)
    # before: read as a key-only DATA, i.e. "disposed": the peer was forgotten
    assert b"K" * 12 in p.participants, p.notes
    assert not any("said goodbye" in n for n in p.notes)


def test_pad_info_reply_and_vendor_submessages_do_not_stop_the_datagram() -> None:
    p = fresh()
    skipped = (b"\x01\x01\x00\x00" + b"\x0f\x01\x04\x00" + bytes(4) + b"\x0d\x01\x08\x00" + bytes(8)
               + b"\x09\x03\x00\x00" + b"\x81\x01\x04\x00abcd")
    p.receive(b.header(b"S" * 12) + skipped + spdp_data(b"S" * 12), ("127.0.0.1", 7999), 0.0)
    assert set(p.participants) == {b"S" * 12}, p.notes


def acknacks(out: list, writer_id: int) -> list[AckNack]:
    return [s for _, _, d in out for s in parse_message(d).submessages
            if isinstance(s, AckNack) and s.writer_id == writer_id]


def test_final_and_liveliness_heartbeats_get_an_acknack_only_when_the_rules_ask() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    net.run(a.write(w, b"\x00\x01\x00\x00one", net.now), steps=3)
    assert [s.payload[4:] for s in c.take(r)] == [b"one"]

    def hb(first: int, last: int, count: int, **flags: bool) -> list:
        return c.receive(b.header(a.guid_prefix) + b.heartbeat(r, w, first, last, count, **flags),
                         a.user, net.now)

    # F set, nothing missing: no ACKNACK (Cyclone DDS piggybacks such HEARTBEATs on its data;
    # before, every one of them was answered)
    assert acknacks(hb(1, 1, 1000, final=True), w) == []
    (ack,) = acknacks(hb(1, 1, 1001), w)                     # F not set: must answer
    assert (ack.base, ack.missing) == (2, ())
    # F and L set (a liveliness assertion): no ACKNACK, even with samples missing
    assert acknacks(hb(1, 3, 1002, final=True, liveliness=True), w) == []
    (ack,) = acknacks(hb(1, 3, 1003, final=True), w)         # F set, samples missing: ask
    assert (ack.base, ack.missing) == (2, (2, 3))
    assert acknacks(hb(1, 3, 1003), w) == []                 # a count already seen: ignored


def test_a_gap_ahead_of_delivery_is_remembered() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)

    def send(*subs: bytes) -> list:
        return c.receive(b.header(a.guid_prefix) + b"".join(subs), a.user, net.now)

    def sample(k: int) -> bytes:
        return b"\x00\x01\x00\x00" + bytes([k]) * 4

    send(b.data(r, w, 1, sample(1)))
    # 3 and 4 will never come; 2 is still on its way (the writer announced 5: a GAP past what
    # it announced is ignored, test_a_gap_past_what_the_writer_announced_is_ignored)
    send(b.heartbeat(r, w, 1, 5, 999, final=True), b.gap(r, w, 3, 5))
    send(b.data(r, w, 2, sample(2)), b.data(r, w, 5, sample(5)))
    # before: the GAP was dropped (it did not start at the next sample): 5 waited for 3 and 4
    assert [s.payload for s in c.take(r)] == [sample(1), sample(2), sample(5)]
    (ack,) = acknacks(send(b.heartbeat(r, w, 1, 5, 1000)), w)
    assert (ack.base, ack.missing) == (6, ())
    # GAP ranges ahead are bounded; past the bound they are asked for again, never lost
    send(b.heartbeat(r, w, 1, 420, 1001, final=True))
    for k in range(200):
        send(b.gap(r, w, 10 + 2 * k, 11 + 2 * k))
    wp = c.local[r].proxies[(a.guid_prefix, w)]
    assert len(wp.gaps) <= MAX_OUT_OF_ORDER and c.counts[f"gaps-full-{r}"] > 0
    (ack,) = acknacks(send(b.heartbeat(r, w, 1, 12, 1002)), w)
    assert (ack.base, ack.missing) == (6, (6, 7, 8, 9, 11))


#: Made by data/capture_cyclone_sedp_dispose.py: what a lab participant received from Cyclone DDS
#: while a Cyclone writer of rt/chatter appeared, was matched with the lab's reader and was
#: deleted (its last datagram: the SEDP DATA with K flag and PID_STATUS_INFO "disposed and
#: unregistered"), all addressed (INFO_DST) to the lab participant that recorded it.
SEDP_DISPOSE = [d[3] for d in udp_datagrams(CAPTURE.parent / "cyclone_sedp_dispose.pcapng")]


def test_a_cyclone_writer_deleted_is_unmatched_at_once() -> None:
    (lab,) = {s.guid_prefix for s in parse_message(SEDP_DISPOSE[0]).submessages
              if isinstance(s, InfoDst)}
    p = Participant(domain=79, index=0, guid_prefix=lab)
    r = p.add_reader("rt/chatter", "std_msgs::msg::dds_::String_")
    for d in SEDP_DISPOSE[:-1]:
        p.receive(d, ("127.0.0.1", 7410), 0.0)
    (writer,) = p.matched(r)
    assert p.remote[writer].kind == "writer"
    (dispose,) = [s for s in parse_message(SEDP_DISPOSE[-1]).submessages if isinstance(s, Data)]
    assert dispose.key and dispose.writer_id == PUB_WRITER and dispose.inline_qos
    p.receive(SEDP_DISPOSE[-1], ("127.0.0.1", 7410), 1.0)
    # the endpoint goes, not only when its participant's lease runs out
    assert p.matched(r) == [] and writer not in p.remote and len(p.participants) == 1
    assert any(writer.hex() in n and "left" in n for n in p.notes)


def test_the_lease_a_peer_announced_is_the_one_that_runs_out() -> None:
    p = fresh()                                    # its own lease: 10 s
    for prefix, lease in ((b"S" * 12, 2.0), (b"L" * 12, 30.0)):
        payload = b.spdp_payload(prefix, b.Locator("127.0.0.1", 7999), b.Locator("127.0.0.1", 8000),
                                 lease, "peer", b"", 0)
        p.receive(b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload),
                  ("127.0.0.1", 7999), 0.0)
    assert {k: v.lease for k, v in p.participants.items()} == {b"S" * 12: 2.0, b"L" * 12: 30.0}
    p.tick(2.5)
    assert set(p.participants) == {b"L" * 12}
    p.tick(20.0)
    assert set(p.participants) == {b"L" * 12}
    p.tick(30.5)
    assert p.participants == {}


def test_a_peer_whose_endpoints_speak_is_alive_between_its_announcements() -> None:
    a, c, w, r = pair(Qos(False), Qos(False))      # best effort: DATA only, no HEARTBEAT
    a.lease = 2.0                                   # what a announces
    net = Net(a, c)
    net.run([], steps=20)
    assert c.participants[a.guid_prefix].lease == 2.0 and c.matched(r)
    a.announce_period = 1000.0                      # its SPDP stops (lost, or late) ...
    net.parts = (c,)
    for k in range(8):                              # ... while its writer goes on for 4 s
        for d in a.write(w, b"\x00\x01\x00\x00" + bytes([k]) * 4, net.now) + a.tick(net.now):
            c.receive(d[2], a.user, net.now)
        net.run([], steps=50)                       # 0.5 s
    # before: forgotten 2 s after its last SPDP, its samples still arriving (only SPDP and
    # HEARTBEAT renewed a lease)
    assert a.guid_prefix in c.participants and len(c.take(r)) == 8
    net.run([], steps=250)                          # silent for 2.5 s: its lease runs out
    assert a.guid_prefix not in c.participants


def test_an_acknack_from_reader_unknown_is_ignored() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    a.write(w, b"\x00\x01\x00\x00one!", net.now)           # lost on its way
    for reader_id in (0, r):                          # ENTITYID_UNKNOWN, then the real reader
        ask = b.header(c.guid_prefix) + b.acknack(reader_id, w, 1, [1], 500 + reader_id)
        out = a.receive(ask, c.user, net.now + 1.0)
        sent = [s for _, _, d in out for s in parse_message(d).submessages if isinstance(s, Data)]
        assert [s.seq for s in sent] == ([] if reader_id == 0 else [1])
    assert a.counts[f"acknack-unknown-{c.guid_prefix.hex()}"] == 1


def test_a_gap_whose_list_starts_before_its_range_still_counts_its_list() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    one, four = b"\x00\x01\x00\x00" + b"1" * 4, b"\x00\x01\x00\x00" + b"4" * 4
    c.receive(b.header(a.guid_prefix) + b.data(r, w, 1, one), a.user, net.now)
    # gapList.base (2) below gapStart (9): an empty range, and 2 and 3 listed (valid: RTPS 2.3
    # 8.3.7.4.3 lists only gapStart < 1 and an invalid gapList; Cyclone DDS reads it so)
    c.receive(b.header(a.guid_prefix) + b.gap(r, w, 9, 2, [2, 3]) + b.data(r, w, 4, four),
              a.user, net.now)
    # before: refused as invalid, so 4 waited for 2 and 3
    assert [s.payload for s in c.take(r)] == [one, four]
    assert not any("invalid" in n for n in c.notes)


def test_a_gap_past_what_the_writer_announced_is_ignored() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)

    def send(*subs: bytes) -> None:
        c.receive(b.header(a.guid_prefix) + b"".join(subs), a.user, net.now)

    def sample(k: int) -> bytes:
        return b"\x00\x01\x00\x00" + bytes([k]) * 4

    send(b.data(r, w, 1, sample(1)), b.heartbeat(r, w, 1, 1, 900, final=True))
    # a spoofed GAP for the next 30 samples, none written yet, and a listed one past them
    send(b.gap(r, w, 2, 32, [40]))
    for k in range(2, 6):
        send(b.data(r, w, k, sample(k)))
    # before: delivery jumped to 32, so 2..5 were dropped as already gapped
    assert [s.payload for s in c.take(r)] == [sample(k) for k in range(1, 6)]
    assert c.counts[f"gap-ahead-{r}"] == 1
    # a GAP within what the HEARTBEAT announced still counts (7 and 8 never come) ...
    send(b.heartbeat(r, w, 1, 9, 901, final=True), b.gap(r, w, 7, 9), b.data(r, w, 6, sample(6)),
         b.data(r, w, 9, sample(9)))
    assert [s.payload for s in c.take(r)] == [sample(6), sample(9)]
    # ... and one that reaches past it counts up to what was announced, not beyond
    send(b.gap(r, w, 10, 20))
    send(b.heartbeat(r, w, 1, 12, 902, final=True), b.gap(r, w, 10, 12))
    send(b.data(r, w, 12, sample(12)), b.data(r, w, 13, sample(13)))
    assert [s.payload for s in c.take(r)] == [sample(12), sample(13)]


# ---- the resend budget (issue 30 row 1: 10,000 ACKNACKs pulled 218 MB) -------------------------

def resent_data_bytes(out: list) -> int:
    return sum(len(s.payload) for _, _, d in out for s in parse_message(d).submessages
               if isinstance(s, Data))


def test_acknacks_in_the_real_readers_name_for_samples_it_acknowledged_get_gaps() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    sample = b"\x00\x01\x00\x00" + bytes(5000)
    out = []
    for _ in range(10):
        out += a.write(w, sample, net.now)
    net.run(out, steps=5)
    assert len(c.take(r)) == 10                      # delivered and acknowledged
    bytes_in = bytes_out = data = 0
    for k in range(2000):       # one every 6 ms: each one past MIN_RESEND_SECONDS's pacing
        ask = b.header(c.guid_prefix) + b.acknack(r, w, 1, range(1, 11), 100 + k)
        got = a.receive(ask, c.user, net.now + 0.006 * k)
        bytes_in += len(ask)
        bytes_out += sum(len(d) for _, _, d in got)
        data += resent_data_bytes(got)
    # before: every one of them resent all 10 samples (50 KB out per 60-byte ACKNACK)
    assert data == 0 and bytes_out <= 2 * bytes_in, (data, bytes_out, bytes_in)
    assert any("acknowledged: GAP" in n for n in a.notes)
    net.run(a.write(w, sample[:-1] + b"!", net.now + 13.0), steps=5)
    assert [s.payload[-1:] for s in c.take(r)] == [b"!"]


def test_a_reader_that_never_acknowledges_is_resent_no_more_than_was_written() -> None:
    a = fresh()
    w = a.add_writer(TOPIC, TYPE)
    prefix = b"R" * 12                  # a fake reader, its locator a victim's port
    a.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    guid = prefix + (0x1404).to_bytes(4, "big")
    sedp = b.sedp_payload(guid, TOPIC, TYPE, True, 10, b.Locator("127.0.0.1", 9))
    a.receive(b.header(prefix) + b.data(0x4C7, 0x4C2, 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert a.matched(w) == [guid]
    sample = b"\x00\x01\x00\x00" + bytes(5000)
    written = resent = 0
    for round_ in range(3):
        for _ in range(10):
            a.write(w, sample, 1.0 + round_)
            written += len(sample)
        for k in range(500):             # ACKNACKs asking for everything, never acknowledging
            ask = b.header(prefix) + b.acknack(0x1404, w, 1, range(1, 31), 1000 * round_ + k + 1)
            resent += resent_data_bytes(a.receive(ask, ("127.0.0.1", 9), 1.0 + round_ + 0.0019 * k))
        # before: 500 * 10 samples resent per round (about 25 MB for 50 KB written)
        assert 0 < resent <= written * RESEND_PER_BYTE_WRITTEN, (round_, resent, written)
    assert any("budget" in n for n in a.notes)


# ---- the participant table under an SPDP flood (issue 30 row 2: locked at 64, a late peer never
# discovered) ---------------------------------------------------------------------------------

def test_an_spdp_flood_cannot_lock_the_table_and_matched_peers_stay() -> None:
    p = fresh()
    r = p.add_reader(TOPIC, TYPE)
    cam, talker = b"C" * 12, b"T" * 12
    p.receive(spdp(cam), ("127.0.0.1", 7999), 0.0)
    sedp = b.sedp_payload(cam + (0x103).to_bytes(4, "big"), TOPIC, TYPE, True, 10,
                          b.Locator("127.0.0.1", 8000))
    p.receive(b.header(cam) + b.data(PUB_READER, PUB_WRITER, 1, sedp), ("127.0.0.1", 7999), 0.0)
    p.receive(spdp(talker, port=7997), ("127.0.0.1", 7997), 0.0)
    p.receive(b.header(talker) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 0, 1), ("127.0.0.1", 7997), 0.0)
    rng = random.Random(30)
    for k in range(MAX_REMOTE_PARTICIPANTS * 10):     # random GUID prefixes, 10 s leases
        p.receive(spdp(bytes(rng.randrange(256) for _ in range(12))), ("127.0.0.1", 7999), k * 1e-3)
        if k % 20 == 0:                                # the talker goes on speaking
            p.receive(b.header(talker) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 0, 2 + k),
                      ("127.0.0.1", 7997), k * 1e-3)
    assert len(p.participants) == MAX_REMOTE_PARTICIPANTS
    # the matched camera and the peer that speaks (SEDP HEARTBEATs) stayed; the flood made room
    # for itself among the ones that sent nothing but SPDP
    assert cam in p.participants and talker in p.participants and len(p.matched(r)) == 1
    # a late peer is discovered (before: "new ones are ignored until a lease runs out") ...
    late = b"L" * 12
    out = p.receive(spdp(late, port=7995), ("127.0.0.1", 7995), 1.0)
    assert late in p.participants and ("127.0.0.1", 7995) in {(h, port) for h, port, _ in out}
    # ... and it has MAX_REMOTE_PARTICIPANTS - 2 more new prefixes' time to speak (the talker
    # speaking meanwhile): the oldest silent ones go first, whatever the flood re-announces
    p.receive(b.header(talker) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 0, 4000), ("127.0.0.1", 7997), 1.05)
    for k in range(MAX_REMOTE_PARTICIPANTS - 3):
        p.receive(spdp(bytes(rng.randrange(256) for _ in range(12))), ("127.0.0.1", 7999), 1.1)
    for prefix in list(p.participants):
        p.receive(spdp(prefix), ("127.0.0.1", 7999), 1.2)        # re-announced: no standing
    p.receive(b.header(talker) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 0, 5000), ("127.0.0.1", 7997), 1.2)
    assert late in p.participants
    p.receive(spdp(b"N" * 12), ("127.0.0.1", 7999), 1.3)
    assert late not in p.participants and {cam, talker, b"N" * 12} <= set(p.participants)
    assert p.counts["participants-evict"] == MAX_REMOTE_PARTICIPANTS * 10 - 62 + 1 + 61 + 1


# ---- a spoofed goodbye (issue 30 row 3: a live camera forgotten, no recovery in 45 s) ------------

def test_a_goodbye_from_elsewhere_is_suspect_and_one_whose_traffic_goes_on_is_learned_again() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    a.announce_period = c.announce_period = 1000.0        # no SPDP comes to the rescue
    (bye,) = [d for host, port, d in a.goodbye() if port == c.meta[1]]

    def frame(k: int) -> list[int]:
        """a writes sample k; what c delivers then."""
        for _, _, d in a.write(w, b"\x00\x01\x00\x00" + bytes([k]) * 4, net.now):
            c.receive(d, a.user, net.now)
        return [s.payload[-1] for s in c.take(r)]

    assert frame(1) == [1]
    # a goodbye in a's name from another port: suspect, a stays (before: forgotten, unmatched,
    # its samples ignored until its next SPDP)
    c.receive(bye, ("127.0.0.1", 6666), net.now)
    assert a.guid_prefix in c.participants and c.matched(r), c.notes
    assert c.participants[a.guid_prefix].lease == SUSPECT_GOODBYE_LEASE_SECONDS
    assert frame(2) == [2]
    # from where a speaks (a spoofed source port, or a real goodbye): forgotten at once ...
    c.receive(bye, a.user, net.now)
    assert a.guid_prefix not in c.participants and c.matched(r) == []
    net.now += GOODBYE_GRACE_SECONDS / 2
    assert frame(3) == []                # ... what was in flight does not bring it back ...
    net.now += GOODBYE_GRACE_SECONDS
    out = []
    for _, _, d in a.write(w, b"\x00\x01\x00\x00" + bytes([4]) * 4, net.now):
        out += c.receive(d, a.user, net.now)
    # ... but traffic after that learns it again: matched at once, our SPDP sent to it
    assert a.guid_prefix in c.participants and len(c.matched(r)) == 1
    assert any(port == a.meta[1] and SPDP_WRITER.to_bytes(4, "big") in d for _, port, d in out)
    net.run(out, steps=30)
    assert [s.payload[-1] for s in c.take(r)][-1:] == [4] and frame(5) == [5]
    # a silent participant that said goodbye stays gone
    c.receive(bye, a.user, net.now)
    net.parts = (c,)
    net.run([], steps=int(a.lease / 0.01) + 10)
    assert a.guid_prefix not in c.participants and not c.departed


# ---- a RELIABLE (KEEP_ALL) reader that consumes slowly (issue 30 row 5) --------------------------

def test_a_reader_that_never_acknowledges_leaves_the_writer_bounded_and_unblocked() -> None:
    a = fresh()
    w = a.add_writer(TOPIC, TYPE, Qos(True, 1000))              # KEEP_LAST 1000 (the most)
    prefix = b"K" * 12                  # a KEEP_ALL RELIABLE reader that never acknowledges
    a.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    guid = prefix + (0x1404).to_bytes(4, "big")
    sedp = b.sedp_payload(guid, TOPIC, TYPE, True, 0, b.Locator("127.0.0.1", 9))
    a.receive(b.header(prefix) + b.data(0x4C7, 0x4C2, 1, sedp), ("127.0.0.1", 7999), 0.0)
    assert a.matched(w) == [guid]
    size = 1 << 20
    sent = 0
    for k in range(80):                 # 80 MiB written, no write waits for the reader
        sent += len(a.write(w, b"\x00\x01\x00\x00" + bytes([k]) * (size - 4), 1.0 + k * 0.01))
        a.tick(1.0 + k * 0.01)
    ep = a.local[w]
    # before: all 80 samples kept (the history was bounded by depth alone)
    assert ep.history_bytes == sum(map(len, ep.history.values())) <= MAX_HISTORY_BYTES
    assert list(ep.history) == list(range(81 - MAX_HISTORY_BYTES // size, 81))
    assert sent >= 80 and sum("MAX_HISTORY_BYTES" in n for n in a.notes) == 1
    # what it asks for that left the history is GAPped; what is held, resent within its budget
    out = a.receive(b.header(prefix) + b.acknack(0x1404, w, 1, [1, 2, 80], 1), ("127.0.0.1", 9), 2.0)
    subs = [s for _, _, d in out for s in parse_message(d).submessages]
    assert [(g.start, g.list_base) for g in subs if isinstance(g, Gap)] == [(1, 81 - MAX_HISTORY_BYTES // size)]
    assert {s.seq for s in subs if isinstance(s, DataFrag)} == {80}


def test_a_sample_on_its_way_is_not_resent_within_the_nack_suppression_time() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    t = net.now
    data = 0
    for k in range(20):          # each sample asked for by ACKNACKs in c's name while on its way
        a.write(w, b"\x00\x01\x00\x00" + bytes([k]) * 5000, t + k * 0.1)
        for j in range(1, 8):    # 6 ms apart: past MIN_RESEND_SECONDS's pacing, within 50 ms
            ask = b.header(c.guid_prefix) + b.acknack(r, w, k + 1, [k + 1], 100 * k + j)
            data += resent_data_bytes(a.receive(ask, c.user, t + k * 0.1 + 0.006 * j))
    # before: resent as often as the pacing let (and then within the budget: once per sample)
    assert data == 0 and a.counts[f"nack-suppressed-{c.guid_prefix.hex()}"] == 20 * 7
    ask = b.header(c.guid_prefix) + b.acknack(r, w, 20, [20], 5000)     # later: resent
    assert resent_data_bytes(a.receive(ask, c.user, t + 1.9 + 1.5 * NACK_SUPPRESSION_SECONDS)) == 5004


def test_a_peer_evicted_while_silent_is_back_with_its_endpoints_when_it_speaks() -> None:
    p = fresh()
    peer = b"E" * 12
    p.receive(spdp(peer), ("127.0.0.1", 7999), 0.0)
    guid = peer + (0x1103).to_bytes(4, "big")
    sedp = b.sedp_payload(guid, "rt/other", TYPE, True, 10, b.Locator("127.0.0.1", 8000))
    p.receive(b.header(peer) + b.data(PUB_READER, PUB_WRITER, 1, sedp), ("127.0.0.1", 7999), 0.1)
    assert guid in p.remote
    rng = random.Random(31)
    for k in range(MAX_REMOTE_PARTICIPANTS):          # newer than its last word: it goes
        p.receive(spdp(bytes(rng.randrange(256) for _ in range(12))), ("127.0.0.1", 7999), 1.0)
    assert peer not in p.participants and guid not in p.remote
    out = p.receive(b.header(peer) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 1, 9), ("127.0.0.1", 7999), 2.0)
    # before: never evicted (the table was locked); now back at once, its endpoint with it, and
    # its SEDP writer not asked for sample 1 again (our reader is where it was)
    assert peer in p.participants and p.remote[guid].topic == "rt/other"
    assert len(p.participants) == MAX_REMOTE_PARTICIPANTS
    assert not any(isinstance(s, AckNack) and s.writer_id == PUB_WRITER and 1 in s.missing
                   for _, _, d in out for s in parse_message(d).submessages)
