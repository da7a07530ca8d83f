"""The sans-IO participant's fragment-level reliability (HEARTBEAT_FRAG in, NACK_FRAG out, NACK_FRAG
in, fragments out) follows the same rules as its sample-level one (HEARTBEAT / ACKNACK), and the
lease of a peer that announces none is RTPS's default in either byte order."""

from __future__ import annotations

import struct
from pathlib import Path

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps import parse_message
from rosfpga_lab.rtps.limits import MIN_RESEND_SECONDS, NACK_SUPPRESSION_SECONDS
from rosfpga_lab.rtps.message import DataFrag, NackFrag
from rosfpga_lab.rtps.participant import PUB_READER, PUB_WRITER, SPDP_READER, SPDP_WRITER, Participant, Qos

from tests.rtps.test_participant import Net, fresh, pair
from tests.support.wiretools import tshark_fields


def heartbeat_frag(reader_id: int, writer_id: int, seq: int, last_frag: int, count: int) -> bytes:
    """A HEARTBEAT_FRAG (RTPS 2.3 9.4.5.7; little endian): fragments 1..last_frag of sample seq
    are available (the lab never sends one; Cyclone DDS and Fast DDS may)."""
    return (struct.pack("<BBH", b.HEARTBEAT_FRAG, b.FLAG_LE, 24) + reader_id.to_bytes(4, "big")
            + writer_id.to_bytes(4, "big") + struct.pack("<iIIi", seq >> 32, seq & 0xFFFFFFFF,
                                                         last_frag, count))


def nack_frags(out: list) -> list[NackFrag]:
    return [s for _, _, d in out for s in parse_message(d).submessages if isinstance(s, NackFrag)]


def resent_fragments(out: list, writer_id: int) -> list[int]:
    return [s.frag_start for _, _, d in out for s in parse_message(d).submessages
            if isinstance(s, DataFrag) and s.writer_id == writer_id]


def first_fragment_only(a: Participant, c: Participant, r: int, w: int, seq: int, now: float) -> None:
    """c gets fragment 1 of 3 (100 bytes each) of sample ``seq`` of a's writer ``w``."""
    frag = b.data_frag(r, w, seq, 1, 100, 300, b"\x00\x01\x00\x00" + b"x" * 96, 1)
    c.receive(b.header(a.guid_prefix) + b.info_dst(c.guid_prefix) + frag, a.user, now)


# ---- HEARTBEAT_FRAG: answered as HEARTBEAT is -----------------------------------------------

def test_a_heartbeat_frag_count_already_seen_gets_no_second_nack_frag() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    first_fragment_only(a, c, r, w, 1, net.now)
    head = b.header(a.guid_prefix) + b.info_dst(c.guid_prefix)

    def hbf(count: int) -> list[NackFrag]:
        return nack_frags(c.receive(head + heartbeat_frag(r, w, 1, 3, count), a.user, net.now))

    (nf,) = hbf(5)
    assert (nf.seq, nf.missing) == (1, (2, 3))
    # the same count again (a duplicate, e.g. over a second path), and an older one: ignored
    # (RTPS 2.3 8.3.7.6: the count lets the reader detect duplicate HEARTBEAT_FRAGs); before,
    # each was answered again
    assert hbf(5) == [] and hbf(4) == []
    (nf,) = hbf(6)                                   # a new one: answered
    assert (nf.seq, nf.missing) == (1, (2, 3))
    # its count is its own, not HEARTBEAT's: a HEARTBEAT of a higher count does not silence it
    c.receive(head + b.heartbeat(r, w, 1, 1, 1000), a.user, net.now)
    assert len(hbf(7)) == 1


def test_a_best_effort_reader_sends_no_nack_frag() -> None:
    a, c, w, r = pair(Qos(True), Qos(False))      # a reliable writer, a best-effort reader
    net = Net(a, c)
    net.run([], steps=20)
    assert c.matched(r)
    first_fragment_only(a, c, r, w, 1, net.now)
    head = b.header(a.guid_prefix) + b.info_dst(c.guid_prefix)
    # before: the writer's reliability alone was checked, so it asked for fragments it does not
    # wait for (as it sends no ACKNACK for a HEARTBEAT)
    assert nack_frags(c.receive(head + heartbeat_frag(r, w, 1, 3, 5), a.user, net.now)) == []
    assert nack_frags(c.receive(head + b.heartbeat(r, w, 1, 1, 5), a.user, net.now)) == []


def test_a_built_in_sedp_reader_answers_a_heartbeat_frag_on_the_metatraffic_port() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    # a's SEDP publications writer has sent sample 1 (its writer); sample 2 comes in fragments
    first_fragment_only(a, c, PUB_READER, PUB_WRITER, 2, net.now)
    head = b.header(a.guid_prefix) + b.info_dst(c.guid_prefix)
    out = c.receive(head + heartbeat_frag(PUB_READER, PUB_WRITER, 2, 3, 5), a.user, net.now)
    (nf,) = nack_frags(out)
    assert (nf.reader_id, nf.writer_id, nf.seq, nf.missing) == (PUB_READER, PUB_WRITER, 2, (2, 3))
    # as its ACKNACKs go (before: to the user port, where a built-in writer does not listen)
    assert {(host, port) for host, port, _ in out} == {a.meta}
    acks = c.receive(head + b.heartbeat(PUB_READER, PUB_WRITER, 1, 2, 5), a.user, net.now)
    assert acks and {(host, port) for host, port, _ in acks} == {a.meta}


# ---- NACK_FRAG: its retransmissions paced as ACKNACK's are ------------------------------------

def test_nack_frags_with_rising_counts_are_paced() -> None:
    a, c, w, r = pair()
    net = Net(a, c)
    net.run([], steps=20)
    a.write(w, b"\x00\x01\x00\x00" + bytes(40000), net.now)       # 30 fragments, seq 1
    t = net.now + 1.0

    def nack(count: int, now: float) -> list[int]:
        ask = b.header(c.guid_prefix) + b.nack_frag(r, w, 1, range(1, 31), count)
        return resent_fragments(a.receive(ask, c.user, now), w)

    assert nack(10, t) == list(range(1, 31))
    # a higher count within MIN_RESEND_SECONDS: paced (before: all 30 fragments again, for
    # every NACK_FRAG of 40 bytes a peer sends)
    assert nack(11, t + MIN_RESEND_SECONDS / 2) == []
    assert sum("paced" in n and "NACK_FRAG" in n for n in a.notes) == 1
    # after it: again, once the writer has written again (the resend budget: each byte written
    # pays for RESEND_PER_BYTE_WRITTEN bytes resent; NACK suppression holds this one back)
    assert nack(12, t + MIN_RESEND_SECONDS * 1.5) == []
    # (and NACK suppression: a sample is not sent to a reader again within
    # NACK_SUPPRESSION_SECONDS of its last sending)
    a.write(w, b"\x00\x01\x00\x00" + bytes(40000), net.now)
    assert nack(13, t + NACK_SUPPRESSION_SECONDS / 2) == []
    assert nack(14, t + NACK_SUPPRESSION_SECONDS * 1.5) == list(range(1, 31))
    # a storm is counted, logged once
    for k in range(200):
        nack(100 + k, t + NACK_SUPPRESSION_SECONDS * 1.5 + MIN_RESEND_SECONDS * 0.1)
    assert sum("paced" in n and "NACK_FRAG" in n for n in a.notes) == 1
    assert a.counts["nackfrag-storm"] == 201


def test_an_acknack_and_a_nack_frag_in_one_datagram_are_both_answered() -> None:
    """Cyclone DDS's reader asks in one datagram for the whole samples it lacks (ACKNACK) and the
    fragments of the first partly received one (NACK_FRAG): the pacing of one kind must not
    swallow the other."""
    a, c, w, r = pair(Qos(True, 5))
    net = Net(a, c)
    net.run([], steps=20)
    a.write(w, b"\x00\x01\x00\x00small", net.now)
    a.write(w, b"\x00\x01\x00\x00" + bytes(40000), net.now)
    ask = (b.header(c.guid_prefix) + b.acknack(r, w, 1, [1], 50)
           + b.nack_frag(r, w, 2, [3, 4], 50))
    out = a.receive(ask, c.user, net.now + 1.0)
    subs = [s for _, _, d in out for s in parse_message(d).submessages]
    assert [s.seq for s in subs if type(s).__name__ == "Data" and s.writer_id == w] == [1]
    assert resent_fragments(out, w) == [3, 4]


def test_nack_frags_for_several_samples_in_one_datagram_are_all_answered() -> None:
    """The lab's own reader asks for the fragments of up to 8 partly received samples in one
    datagram: each sample is paced on its own, so all are resent (before: only the first
    within MIN_RESEND_SECONDS), and the same sample asked again at once is still paced."""
    a, c, w, r = pair(Qos(True, 5))
    net = Net(a, c)
    net.run([], steps=20)
    for k in range(3):
        a.write(w, b"\x00\x01\x00\x00" + bytes([k]) * 40000, net.now)
    t = net.now + 1.0
    ask = b.header(c.guid_prefix) + b"".join(b.nack_frag(r, w, seq, [2, 5], 60 + seq)
                                             for seq in (1, 2, 3))
    out = a.receive(ask, c.user, t)
    frags = [(s.seq, s.frag_start) for _, _, d in out for s in parse_message(d).submessages
             if isinstance(s, DataFrag) and s.writer_id == w]
    assert frags == [(1, 2), (1, 5), (2, 2), (2, 5), (3, 2), (3, 5)]
    again = b.header(c.guid_prefix) + b.nack_frag(r, w, 2, [2], 70)
    assert resent_fragments(a.receive(again, c.user, t + MIN_RESEND_SECONDS / 2), w) == []
    assert resent_fragments(a.receive(again[:20] + b.nack_frag(r, w, 2, [2], 71), c.user,
                                      t + NACK_SUPPRESSION_SECONDS * 1.5), w) == [2]


# ---- SPDP without PID_PARTICIPANT_LEASE_DURATION ------------------------------------------------

def spdp_without_lease(prefix: bytes, little: bool) -> bytes:
    """An SPDP sample with no lease, written as a big- (PL_CDR_BE) or little-endian peer does."""
    o = "<" if little else ">"

    def loc(port: int) -> bytes:
        return struct.pack(o + "iI", b.LOCATOR_KIND_UDPV4, port) + bytes(12) + bytes([127, 0, 0, 1])

    params = [(b.PID_PARTICIPANT_GUID, prefix + (0x1C1).to_bytes(4, "big")),
              (b.PID_METATRAFFIC_UNICAST_LOCATOR, loc(7999)),
              (b.PID_DEFAULT_UNICAST_LOCATOR, loc(8000))]
    encapsulation = b"\x00\x03\x00\x00" if little else b"\x00\x02\x00\x00"   # PL_CDR_LE / _BE
    payload = (encapsulation + b"".join(struct.pack(o + "HH", pid, len(v)) + v for pid, v in params)
               + struct.pack(o + "HH", b.PID_SENTINEL, 0))
    return b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)


def test_a_peer_announcing_no_lease_gets_the_rtps_default_in_either_byte_order() -> None:
    p = fresh()
    for prefix, little in ((b"B" * 12, False), (b"L" * 12, True)):
        p.receive(spdp_without_lease(prefix, little), ("127.0.0.1", 7999), 0.0)
    # RTPS's default leaseDuration is 100 s (Cyclone DDS: "PARTICIPANT_LEASE_DURATION defaulting
    # to 100s"); before, the big-endian one got 1,677,721,600 s, cut to the 300 s believed at most
    assert {k: v.lease for k, v in p.participants.items()} == {b"B" * 12: 100.0, b"L" * 12: 100.0}
    assert p.participants[b"B" * 12].meta == ("127.0.0.1", 7999)      # the rest read big endian
    p.tick(99.0)
    assert len(p.participants) == 2
    p.tick(100.5)
    assert p.participants == {}


def test_the_big_endian_spdp_above_is_what_wireshark_reads(tmp_path: Path) -> None:
    """The test's own big-endian encoder checked against a real decoder: tshark reads its GUID
    and its locators' ports (PL_CDR_BE: read little endian they would be absurd) as a
    big-endian peer meant them, and no lease."""
    from scapy.all import IP, UDP, Ether, Raw, wrpcap

    capture = tmp_path / "spdp_be.pcap"
    wrpcap(str(capture), [Ether() / IP(src="127.0.0.1", dst="127.0.0.1")
                          / UDP(sport=7410, dport=7412) / Raw(spdp_without_lease(b"B" * 12, False))])
    [[guid, ports, lease]] = tshark_fields(
        capture, ["rtps.param.participant_guid", "rtps.locator.port",
                  "rtps.participant_lease_duration"], display_filter="rtps")
    assert (guid, ports, lease) == ((b"B" * 12).hex() + "000001c1", "7999|8000", "")
