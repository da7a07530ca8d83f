"""Ethernet II frames carrying IPv4/UDP datagrams and ARP, sans-IO: what a host's network stack
does for the simulated PHY of the node in the fabric (``rosfpga-lab fabric sim``).

How this works: :func:`udp_frame` wraps one UDP datagram into a whole frame as a PHY receives
it: Ethernet II header, IPv4 header (no options, the header checksum of RFC 791), UDP header
(checksum 0: none, which IPv4 allows), padding to the 60-byte minimum and the FCS (IEEE 802.3
CRC-32, least significant byte first). :func:`parse_frame` takes a frame the circuit sent (FCS
included) and says what it is: a UDP datagram (:class:`UdpDatagram`), an ARP request
(:class:`ArpRequest`, which :func:`arp_reply` answers), or why it is dropped
(:class:`BadFrame`: FCS, IPv4 header checksum, lengths, another protocol).
:func:`group_mac` is the Ethernet address of an IPv4 multicast group (RFC 1112).
"""

from __future__ import annotations

import ipaddress
import struct
import zlib
from dataclasses import dataclass

__all__ = ["ArpRequest", "BadFrame", "UdpDatagram", "arp_reply", "fcs", "group_mac",
           "ipv4_checksum", "mac_bytes", "parse_frame", "udp_frame"]

ETHERTYPE_IPV4, ETHERTYPE_ARP = 0x0800, 0x0806
PROTO_UDP = 17
#: The shortest frame without its FCS (padding fills up to it).
MIN_FRAME = 60
IP_TTL = 64


def mac_bytes(mac: str | int) -> bytes:
    """A MAC (``02:52:46:4c:00:02`` or a 48-bit number) as 6 bytes."""
    if isinstance(mac, int):
        return mac.to_bytes(6, "big")
    return bytes(int(x, 16) for x in mac.split(":"))


def fcs(frame: bytes) -> bytes:
    """``frame`` padded to :data:`MIN_FRAME` bytes, with its FCS appended."""
    frame = frame.ljust(MIN_FRAME, b"\x00")
    return frame + struct.pack("<I", zlib.crc32(frame))


def ipv4_checksum(header: bytes) -> int:
    """The one's complement of the one's complement sum of the header's 16-bit words."""
    total = sum(struct.unpack(f">{len(header) // 2}H", header))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def group_mac(group: str) -> bytes:
    """The Ethernet address of IPv4 multicast group ``group``: 01:00:5e and its low 23 bits."""
    low = int(ipaddress.IPv4Address(group)) & 0x7FFFFF
    return b"\x01\x00\x5e" + low.to_bytes(3, "big")


def udp_frame(payload: bytes, *, src_mac: bytes, dst_mac: bytes, src_ip: str, dst_ip: str,
              src_port: int, dst_port: int, ident: int = 0) -> bytes:
    """One UDP datagram as a whole Ethernet frame (FCS included)."""
    udp = struct.pack(">HHHH", src_port, dst_port, 8 + len(payload), 0) + payload
    head = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), ident & 0xFFFF, 0x4000,
                       IP_TTL, PROTO_UDP, 0, ipaddress.IPv4Address(src_ip).packed,
                       ipaddress.IPv4Address(dst_ip).packed)
    head = head[:10] + struct.pack(">H", ipv4_checksum(head)) + head[12:]
    return fcs(dst_mac + src_mac + struct.pack(">H", ETHERTYPE_IPV4) + head + udp)


@dataclass(frozen=True)
class UdpDatagram:
    """A UDP datagram out of a frame."""

    src_mac: bytes
    dst_mac: bytes
    src_ip: str
    dst_ip: str
    src_port: int
    dst_port: int
    payload: bytes


@dataclass(frozen=True)
class ArpRequest:
    """Who has ``target_ip``? asked by ``sender_mac``/``sender_ip``."""

    sender_mac: bytes
    sender_ip: str
    target_ip: str


@dataclass(frozen=True)
class BadFrame:
    """A frame dropped, and why."""

    reason: str


def arp_reply(request: ArpRequest, mac: bytes) -> bytes:
    """The ARP reply (a whole frame) saying ``request.target_ip`` is at ``mac``."""
    body = struct.pack(">HHBBH6s4s6s4s", 1, ETHERTYPE_IPV4, 6, 4, 2, mac,
                       ipaddress.IPv4Address(request.target_ip).packed, request.sender_mac,
                       ipaddress.IPv4Address(request.sender_ip).packed)
    return fcs(request.sender_mac + mac + struct.pack(">H", ETHERTYPE_ARP) + body)


def parse_frame(frame: bytes) -> UdpDatagram | ArpRequest | BadFrame:
    """What a whole frame (FCS included) carries, or why it is dropped."""
    if len(frame) < MIN_FRAME + 4:
        return BadFrame("runt")
    if struct.pack("<I", zlib.crc32(frame[:-4])) != frame[-4:]:
        return BadFrame("fcs")
    dst, src, (etype,) = frame[0:6], frame[6:12], struct.unpack(">H", frame[12:14])
    body = frame[14:-4]
    if etype == ETHERTYPE_ARP:
        htype, ptype, hlen, plen, op = struct.unpack(">HHBBH", body[:8])
        if (htype, ptype, hlen, plen, op) != (1, ETHERTYPE_IPV4, 6, 4, 1):
            return BadFrame("arp")
        return ArpRequest(body[8:14], str(ipaddress.IPv4Address(body[14:18])),
                          str(ipaddress.IPv4Address(body[24:28])))
    if etype != ETHERTYPE_IPV4:
        return BadFrame("ethertype")
    if len(body) < 28 or body[0] != 0x45:
        return BadFrame("ipv4-header")
    if ipv4_checksum(body[:20]) != 0:
        return BadFrame("ipv4-checksum")
    (total,) = struct.unpack(">H", body[2:4])
    if body[9] != PROTO_UDP:
        return BadFrame("protocol")
    if not 28 <= total <= len(body):
        return BadFrame("ipv4-length")
    sport, dport, length = struct.unpack(">HHH", body[20:26])
    if length != total - 20:
        return BadFrame("udp-length")
    return UdpDatagram(src, dst, str(ipaddress.IPv4Address(body[12:16])),
                       str(ipaddress.IPv4Address(body[16:20])), sport, dport,
                       bytes(body[28:20 + length]))
