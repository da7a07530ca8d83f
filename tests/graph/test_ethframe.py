"""The fabric sim's host side of the wire (``rosfpga_lab.graph.ethframe``), checked with scapy's
Ethernet, IPv4, UDP and ARP (an independent encoder and decoder), and the SPDP peer reader of
the bridge (``component.fabricsim.spdp_peer``) on the lab participant's announcement."""

from __future__ import annotations

import struct
import zlib

from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import ARP, Ether

from rosfpga_lab.component.fabricsim import spdp_peer
from rosfpga_lab.graph.ethframe import (
    ArpRequest, BadFrame, UdpDatagram, arp_reply, group_mac, parse_frame, udp_frame,
)
from rosfpga_lab.rtps.participant import Participant

NODE, HOST = bytes.fromhex("0252464c0002"), bytes.fromhex("0252464c0001")


def _with_fcs(frame: bytes) -> bytes:
    frame = frame.ljust(60, b"\0")
    return frame + struct.pack("<I", zlib.crc32(frame))


def test_a_wrapped_datagram_is_what_scapy_reads() -> None:
    for payload in (b"", b"x", bytes(range(256)) * 5):
        frame = udp_frame(payload, src_mac=HOST, dst_mac=NODE, src_ip="127.0.0.1",
                          dst_ip="127.0.0.2", src_port=40000, dst_port=7410, ident=7)
        assert struct.unpack("<I", frame[-4:])[0] == zlib.crc32(frame[:-4])
        pkt = Ether(frame[:-4])
        assert (pkt.src, pkt.dst) == ("02:52:46:4c:00:01", "02:52:46:4c:00:02")
        assert (pkt[IP].src, pkt[IP].dst, pkt[IP].ttl, pkt[IP].id) == ("127.0.0.1", "127.0.0.2",
                                                                      64, 7)
        want = IP(bytes(pkt[IP])[:20])
        del want.chksum
        assert IP(bytes(want)).chksum == pkt[IP].chksum            # scapy's own checksum
        assert (pkt[UDP].sport, pkt[UDP].dport, pkt[UDP].len) == (40000, 7410, 8 + len(payload))
        assert bytes(pkt[UDP].payload)[:len(payload)] == payload
        assert len(frame) == max(60, 42 + len(payload)) + 4


def test_frames_from_scapy_parse_and_bad_ones_are_named() -> None:
    raw = bytes(Ether(src="02:52:46:4c:00:02", dst="02:52:46:4c:00:01") /
                IP(src="127.0.0.1", dst="127.0.0.1") / UDP(sport=7411, dport=7413) / b"RTPS..")
    got = parse_frame(_with_fcs(raw))
    assert got == UdpDatagram(NODE, HOST, "127.0.0.1", "127.0.0.1", 7411, 7413, b"RTPS..")
    bad = bytearray(_with_fcs(raw))
    bad[-1] ^= 1
    assert parse_frame(bytes(bad)) == BadFrame("fcs")
    broken = bytearray(raw)
    broken[24] ^= 0xFF                                                # the IPv4 checksum
    assert parse_frame(_with_fcs(bytes(broken))) == BadFrame("ipv4-checksum")
    assert parse_frame(b"\0" * 30) == BadFrame("runt")


def test_the_circuits_arp_request_is_answered_as_scapy_reads_it() -> None:
    ask = bytes(Ether(src="02:52:46:4c:00:02", dst="ff:ff:ff:ff:ff:ff") /
                ARP(op=1, hwsrc="02:52:46:4c:00:02", psrc="127.0.0.1", pdst="127.0.0.9"))
    req = parse_frame(_with_fcs(ask))
    assert req == ArpRequest(NODE, "127.0.0.1", "127.0.0.9")
    assert isinstance(req, ArpRequest)
    reply = Ether(arp_reply(req, HOST)[:-4])
    assert (reply.dst, reply[ARP].op, reply[ARP].hwsrc, reply[ARP].psrc, reply[ARP].hwdst,
            reply[ARP].pdst) == ("02:52:46:4c:00:02", 2, "02:52:46:4c:00:01", "127.0.0.9",
                                 "02:52:46:4c:00:02", "127.0.0.1")
    assert group_mac("239.255.0.1") == bytes.fromhex("01005e7f0001")


def test_the_bridge_reads_a_peers_locators_from_its_spdp() -> None:
    p = Participant(0, 3, "127.0.0.1", "peer", guid_prefix=bytes(range(12)))
    spdp = p.announce()[0][2]
    peer = spdp_peer(spdp, ("127.0.0.1", 55555))
    assert peer is not None
    assert (peer.guid_prefix, peer.meta, peer.user) == (bytes(range(12)), ("127.0.0.1", 7416),
                                                        ("127.0.0.1", 7417))
    assert spdp_peer(b"RTPS" + bytes(16), ("127.0.0.1", 1)) is None
    assert spdp_peer(b"not rtps", ("127.0.0.1", 1)) is None


def test_the_bridge_reads_a_readers_own_locator_from_sedp() -> None:
    """A reader's SEDP data (the lab's builder) with a unicast locator of its own, in a datagram
    from the subscriptions writer: the bridge learns its topic and locator; from another writer
    (publications) nothing."""
    from rosfpga_lab.component.fabricsim import sedp_reader_locators
    from rosfpga_lab.rtps import build as b
    from rosfpga_lab.rtps.entities import PUB_READER, PUB_WRITER, SUB_READER, SUB_WRITER

    prefix = bytes(range(12))
    data = b.sedp_payload(prefix + bytes.fromhex("00000104"), "ros_discovery_info",
                          "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_", True, 1,
                          b.Locator("127.0.0.1", 7000), transient_local=True)
    sub = b.header(prefix) + b.data(SUB_READER, SUB_WRITER, 1, b.pad_payload(data))
    assert sedp_reader_locators(sub, ("127.0.0.1", 40000)) == [("ros_discovery_info",
                                                                ("127.0.0.1", 7000))]
    pub = b.header(prefix) + b.data(PUB_READER, PUB_WRITER, 1, b.pad_payload(data))
    assert sedp_reader_locators(pub, ("127.0.0.1", 40000)) == []
