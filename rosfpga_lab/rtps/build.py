"""RTPS encoders: the bytes of the messages the lab's participant sends (the inverse of
:mod:`rosfpga_lab.rtps.message` and :mod:`rosfpga_lab.rtps.discovery`).

How this works: every submessage is written little endian (flag E set); a message is the
20-byte header (``RTPS``, version 2.3, vendor id, the sender's GUID prefix) followed by
submessages. SPDP/SEDP payloads are parameter lists (PL_CDR_LE) built with :func:`param_list`.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass

from rosfpga_lab.msg.parser import SEP
from rosfpga_lab.msg.typehash import MSG_NAMESPACE
from rosfpga_lab.rtps.message import HEARTBEAT_FINAL, HEARTBEAT_LIVELINESS, MAGIC

PROTOCOL_VERSION = (2, 3)
#: The lab announces "unknown vendor" (0x0000): it has no OMG-assigned vendor id.
VENDOR_ID = 0x0000
#: eProsima's vendor id (Fast DDS, under rmw_fastrtps_cpp, ROS 2's default middleware).
VENDOR_EPROSIMA = 0x010F

# submessage ids
PAD, ACKNACK, HEARTBEAT, GAP, INFO_TS, INFO_SRC, INFO_DST = 0x01, 0x06, 0x07, 0x08, 0x09, 0x0C, 0x0E
NACK_FRAG, HEARTBEAT_FRAG, DATA, DATA_FRAG = 0x12, 0x13, 0x15, 0x16
FLAG_LE = 0x01

# parameter ids (RTPS 2.3 table 9.12)
PID_SENTINEL = 0x0001
PID_PARTICIPANT_LEASE_DURATION = 0x0002
PID_TOPIC_NAME = 0x0005
PID_TYPE_NAME = 0x0007
PID_PROTOCOL_VERSION = 0x0015
PID_VENDORID = 0x0016
PID_RELIABILITY = 0x001A
PID_DURABILITY = 0x001D
PID_USER_DATA = 0x002C
PID_UNICAST_LOCATOR = 0x002F
PID_DEFAULT_UNICAST_LOCATOR = 0x0031
PID_METATRAFFIC_UNICAST_LOCATOR = 0x0032
PID_HISTORY = 0x0040
PID_PARTICIPANT_GUID = 0x0050
PID_BUILTIN_ENDPOINT_SET = 0x0058
PID_ENDPOINT_GUID = 0x005A
PID_ENTITY_NAME = 0x0062
PID_KEY_HASH = 0x0070
PID_STATUS_INFO = 0x0071
PID_DATA_REPRESENTATION = 0x0073
PID_DOMAIN_ID = 0x000F

LOCATOR_KIND_UDPV4 = 1
# QoS values on the wire
BEST_EFFORT, RELIABLE = 1, 2
VOLATILE, TRANSIENT_LOCAL = 0, 1
KEEP_LAST, KEEP_ALL = 0, 1
XCDR = 0

# built-in endpoint set bits (RTPS 8.5.3.2 / 9.3.2)
BUILTIN_ENDPOINTS = (1 << 0) | (1 << 1) | (1 << 2) | (1 << 3) | (1 << 4) | (1 << 5)

# encapsulations
PL_CDR_LE = b"\x00\x03\x00\x00"
CDR_LE = b"\x00\x01\x00\x00"


@dataclass(frozen=True)
class Locator:
    """A UDPv4 locator: address (dotted quad) and port."""

    address: str
    port: int

    def encode(self) -> bytes:
        octets = bytes(int(x) for x in self.address.split("."))
        return struct.pack("<iI", LOCATOR_KIND_UDPV4, self.port) + bytes(12) + octets

    @staticmethod
    def decode(value: bytes, little: bool = True) -> Locator | None:
        """A UDPv4 locator from a parameter value (None: another kind or too short)."""
        if len(value) < 24:
            return None
        kind, port = struct.unpack("<iI" if little else ">iI", value[:8])
        if kind != LOCATOR_KIND_UDPV4 or not 0 < port < 65536:
            return None
        return Locator(".".join(str(b) for b in value[20:24]), port)


def header(guid_prefix: bytes) -> bytes:
    """The 20-byte RTPS message header."""
    return MAGIC + bytes(PROTOCOL_VERSION) + VENDOR_ID.to_bytes(2, "big") + guid_prefix


def _sub(kind: int, flags: int, body: bytes) -> bytes:
    return struct.pack("<BBH", kind, flags | FLAG_LE, len(body)) + body


def _seq(n: int) -> bytes:
    return struct.pack("<iI", n >> 32, n & 0xFFFFFFFF)


def _eid(entity_id: int) -> bytes:
    return entity_id.to_bytes(4, "big")


def _bitmap(base: int, members: Iterable[int], num_bits: int) -> bytes:
    words = [0] * ((num_bits + 31) // 32)
    for m in members:
        i = m - base
        if 0 <= i < num_bits:
            words[i // 32] |= 1 << (31 - i % 32)
    return struct.pack(f"<I{len(words)}I", num_bits, *words)


def pad_payload(payload: bytes) -> bytes:
    """A serialized payload padded to 4 bytes, the count in its encapsulation options' low
    2 bits (XTypes 7.6.3.1.2; what Cyclone DDS does); :func:`unpad_payload` undoes it."""
    pad = -len(payload) % 4
    if not pad or len(payload) < 4:
        return payload
    return payload[:3] + bytes([(payload[3] & 0xFC) | pad]) + payload[4:] + bytes(pad)


def unpad_payload(payload: bytes) -> bytes:
    """The payload without the padding its encapsulation options declare (bytes as they came
    when it declares none or more than it has)."""
    if len(payload) < 4 or payload[0] != 0:
        return payload
    pad = payload[3] & 0x03
    if not pad or len(payload) < 4 + pad:
        return payload
    return payload[:3] + bytes([payload[3] & 0xFC]) + payload[4:len(payload) - pad]


def info_dst(guid_prefix: bytes) -> bytes:
    return _sub(INFO_DST, 0, guid_prefix)


def info_src(guid_prefix: bytes) -> bytes:
    """INFO_SRC: the submessages after it come from participant ``guid_prefix``."""
    return _sub(INFO_SRC, 0, bytes(4) + bytes(PROTOCOL_VERSION) + VENDOR_ID.to_bytes(2, "big")
                + guid_prefix)


def info_ts(seconds: float) -> bytes:
    sec = int(seconds)
    return _sub(INFO_TS, 0, struct.pack("<iI", sec, int((seconds - sec) * 2**32) & 0xFFFFFFFF))


def data(reader_id: int, writer_id: int, seq: int, payload: bytes, inline_qos: bytes = b"") -> bytes:
    """DATA with a serialized payload (flag D) and optional inline QoS (flag Q)."""
    flags = 0x04 | (0x02 if inline_qos else 0)
    body = struct.pack("<HH", 0, 16) + _eid(reader_id) + _eid(writer_id) + _seq(seq)
    return _sub(DATA, flags, body + inline_qos + payload + bytes(-len(payload) % 4))


def data_frag(reader_id: int, writer_id: int, seq: int, frag_start: int, frag_size: int,
              sample_size: int, fragments: bytes, frag_count: int) -> bytes:
    """DATA_FRAG carrying ``frag_count`` fragments from ``frag_start`` (1-based)."""
    body = (struct.pack("<HH", 0, 28) + _eid(reader_id) + _eid(writer_id) + _seq(seq)
            + struct.pack("<IHHI", frag_start, frag_count, frag_size, sample_size))
    return _sub(DATA_FRAG, 0, body + fragments + bytes(-len(fragments) % 4))


def heartbeat(reader_id: int, writer_id: int, first: int, last: int, count: int,
              final: bool = False, liveliness: bool = False) -> bytes:
    flags = (HEARTBEAT_FINAL if final else 0) | (HEARTBEAT_LIVELINESS if liveliness else 0)
    return _sub(HEARTBEAT, flags,
                _eid(reader_id) + _eid(writer_id) + _seq(first) + _seq(last) + struct.pack("<i", count))


def acknack(reader_id: int, writer_id: int, base: int, missing: Iterable[int], count: int,
            final: bool = False) -> bytes:
    """ACKNACK: every sample before ``base`` is here; ``missing`` (within 256 of base) asked again."""
    missing = sorted(m for m in missing if base <= m < base + 256)
    num_bits = (missing[-1] - base + 1) if missing else 0
    return _sub(ACKNACK, 0x02 if final else 0, _eid(reader_id) + _eid(writer_id) + _seq(base)
                + _bitmap(base, missing, num_bits) + struct.pack("<i", count))


def nack_frag(reader_id: int, writer_id: int, seq: int, missing: Iterable[int], count: int) -> bytes:
    missing = sorted(missing)
    base = missing[0] if missing else 1
    missing = [m for m in missing if m < base + 256]
    num_bits = (missing[-1] - base + 1) if missing else 0
    return _sub(NACK_FRAG, 0, _eid(reader_id) + _eid(writer_id) + _seq(seq)
                + struct.pack("<I", base) + _bitmap(base, missing, num_bits) + struct.pack("<i", count))


def gap(reader_id: int, writer_id: int, start: int, list_base: int,
        listed: Iterable[int] = ()) -> bytes:
    """GAP: samples ``start`` .. ``list_base - 1`` will never come, nor those in ``listed``
    (within 256 of ``list_base``)."""
    listed = sorted(m for m in listed if list_base <= m < list_base + 256)
    num_bits = (listed[-1] - list_base + 1) if listed else 0
    return _sub(GAP, 0, _eid(reader_id) + _eid(writer_id) + _seq(start) + _seq(list_base)
                + _bitmap(list_base, listed, num_bits))


# ---- parameter lists -------------------------------------------------------------------------

def _pad4(b: bytes) -> bytes:
    return b + bytes(-len(b) % 4)


def cdr_string(text: str) -> bytes:
    raw = text.encode() + b"\x00"
    return struct.pack("<I", len(raw)) + raw


def cdr_string_value(value: bytes, little: bool = True) -> str:
    """The text of a CDR string parameter value (length, bytes, NUL); '' when malformed."""
    if len(value) < 4:
        return ""
    (n,) = struct.unpack("<I" if little else ">I", value[:4])
    return value[4:4 + n].split(b"\x00")[0].decode("utf-8", "replace")


def param_list(params: Iterable[tuple[int, bytes]]) -> bytes:
    """A PL_CDR_LE parameter list (encapsulation header first, PID_SENTINEL last)."""
    out = bytearray(PL_CDR_LE)
    for pid, value in params:
        v = _pad4(value)
        out += struct.pack("<HH", pid, len(v)) + v
    out += struct.pack("<HH", PID_SENTINEL, 0)
    return bytes(out)


def inline_qos(params: Iterable[tuple[int, bytes]]) -> bytes:
    """An inline QoS parameter list (no encapsulation header)."""
    return param_list(params)[len(PL_CDR_LE):]


def octet_sequence(value: bytes) -> bytes:
    """A CDR ``sequence<octet>`` (uint32 count, the bytes), as USER_DATA's value is."""
    return struct.pack("<I", len(value)) + value


def duration(seconds: float) -> bytes:
    sec = int(seconds)
    return struct.pack("<iI", sec, int((seconds - sec) * 2**32) & 0xFFFFFFFF)


def spdp_payload(guid_prefix: bytes, meta: Locator, user: Locator, lease: float, name: str,
                 user_data: bytes, domain: int) -> bytes:
    """The SPDP participant data (SPDPdiscoveredParticipantData) of the lab's participant."""
    return param_list([
        (PID_PROTOCOL_VERSION, bytes(PROTOCOL_VERSION)),
        (PID_VENDORID, VENDOR_ID.to_bytes(2, "big")),
        (PID_PARTICIPANT_GUID, guid_prefix + _eid(0x000001C1)),
        (PID_DOMAIN_ID, struct.pack("<I", domain)),
        (PID_BUILTIN_ENDPOINT_SET, struct.pack("<I", BUILTIN_ENDPOINTS)),
        (PID_METATRAFFIC_UNICAST_LOCATOR, meta.encode()),
        (PID_DEFAULT_UNICAST_LOCATOR, user.encode()),
        (PID_PARTICIPANT_LEASE_DURATION, duration(lease)),
        (PID_ENTITY_NAME, cdr_string(name)),
        (PID_USER_DATA, octet_sequence(user_data)),
    ])


def sedp_payload(guid: bytes, topic: str, type_name: str, reliable: bool, depth: int,
                 locator: Locator, transient_local: bool = False, type_hash: str = "") -> bytes:
    """SEDP data of one of the lab's endpoints (publication or subscription); with a
    ``type_hash``, its USER_DATA says ``typehash=RIHS01_...;`` as ROS 2's rmw does."""
    user = ([(PID_USER_DATA, octet_sequence(type_hash_user_data(type_hash)))] if type_hash
            else [])
    return param_list([
        (PID_ENDPOINT_GUID, guid),
        (PID_PARTICIPANT_GUID, guid[:12] + _eid(0x000001C1)),
        (PID_TOPIC_NAME, cdr_string(topic)),
        (PID_TYPE_NAME, cdr_string(type_name)),
        (PID_RELIABILITY, struct.pack("<I", RELIABLE if reliable else BEST_EFFORT) + duration(0.1)),
        (PID_DURABILITY, struct.pack("<I", TRANSIENT_LOCAL if transient_local else VOLATILE)),
        (PID_HISTORY, struct.pack("<Ii", KEEP_LAST, depth)),
        (PID_DATA_REPRESENTATION, struct.pack("<Ih", 1, XCDR)),
        *user,
        (PID_UNICAST_LOCATOR, locator.encode()),
        (PID_PROTOCOL_VERSION, bytes(PROTOCOL_VERSION)),
        (PID_VENDORID, VENDOR_ID.to_bytes(2, "big")),
    ])


# ---- ROS 2 names (rmw_cyclonedds_cpp's conventions) -------------------------------------------

#: rmw's prefix of a topic's DDS name.
ROS_TOPIC_PREFIX = "rt"


def dds_topic(ros_name: str) -> str:
    """``/image_raw`` -> ``rt/image_raw`` (the DDS topic rmw puts a ROS 2 topic on)."""
    return f"{ROS_TOPIC_PREFIX}/{ros_name.lstrip('/')}"


def dds_type(ros_type: str) -> str:
    """``sensor_msgs/Image`` (or ``sensor_msgs/msg/Image``) -> ``sensor_msgs::msg::dds_::Image_``."""
    parts = ros_type.split(SEP)
    return f"{parts[0]}::{MSG_NAMESPACE}::dds_::{parts[-1]}_"


#: rmw's USER_DATA of an endpoint is ``key=value;`` pairs (rmw_dds_common); Iron and later
#: put the type hash under this key (``encode_type_hash_for_user_data_qos``).
TYPEHASH_KEY = "typehash"
#: Separators of those pairs.
USER_DATA_PAIR_END, USER_DATA_KEY_END = ";", "="


def type_hash_user_data(type_hash: str) -> bytes:
    """``RIHS01_...`` -> ``b"typehash=RIHS01_...;"`` (no NUL), the USER_DATA rmw sends."""
    return f"{TYPEHASH_KEY}{USER_DATA_KEY_END}{type_hash}{USER_DATA_PAIR_END}".encode("ascii")


# ---- the ROS 2 graph: which nodes a participant holds (rmw_dds_common) ------------------------

#: The DDS topic and type on which rmw tells the ROS 2 graph a participant's nodes (rmw_dds_common).
ROS_DISCOVERY_TOPIC = "ros_discovery_info"
ROS_DISCOVERY_TYPE = "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"
#: Bytes of rmw_dds_common/Gid (``char[16] data`` since rmw_dds_common 2.0: Iron, Jazzy and later;
#: Humble's 1.x used 24). rmw_cyclonedds puts the 16-byte DDS GUID there.
GID_BYTES = 16


def participant_entities_info(participant_guid: bytes,
                              nodes: Iterable[tuple[str, str, list[bytes], list[bytes]]]) -> bytes:
    """The CDR payload of rmw_dds_common/ParticipantEntitiesInfo: the participant's GID, then per
    node (namespace, name, reader GIDs, writer GIDs), in the field order of the .msg files."""
    def gid(g: bytes) -> bytes:
        return g[:GID_BYTES].ljust(GID_BYTES, b"\0")

    out = bytearray(CDR_LE) + gid(participant_guid)
    nodes = list(nodes)
    out += struct.pack("<I", len(nodes))
    for ns, name, readers, writers in nodes:
        for text in (ns, name):
            out += bytes(-(len(out) - 4) % 4)
            out += cdr_string(text)
        for gids in (readers, writers):
            out += bytes(-(len(out) - 4) % 4)
            out += struct.pack("<I", len(gids)) + b"".join(gid(g) for g in gids)
    return bytes(out)
