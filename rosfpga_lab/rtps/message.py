"""One RTPS message (one UDP datagram): the 20-byte header, then submessages.

How this works: the header is ``RTPS``, the protocol version, the vendor id and the sender's
12-byte GUID prefix. Each submessage starts with a 4-byte header (id, flags, length to the next
submessage); bit 0 of its flags says the byte order of the rest of the submessage (1: little
endian). A length of 0 on the last submessage means "up to the end of the message". Sequence
numbers are 64-bit (a signed high and an unsigned low 32-bit half); entity ids are 4 octets
(3 of key, 1 of kind) and read as a big-endian number, as Wireshark shows them.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass, field

from rosfpga_lab.rtps.errors import RtpsError, RtpsTruncatedError

MAGIC = b"RTPS"
HEADER_SIZE = 20
SUBMESSAGE_HEADER_SIZE = 4
#: HEARTBEAT flags besides E (RTPS 2.3 9.4.5.7): F (final) and L (liveliness).
HEARTBEAT_FINAL, HEARTBEAT_LIVELINESS = 0x02, 0x04

SUBMESSAGE_NAMES: dict[int, str] = {
    0x01: "PAD", 0x06: "ACKNACK", 0x07: "HEARTBEAT", 0x08: "GAP", 0x09: "INFO_TS",
    0x0C: "INFO_SRC", 0x0D: "INFO_REPLY_IP4", 0x0E: "INFO_DST", 0x0F: "INFO_REPLY",
    0x12: "NACK_FRAG", 0x13: "HEARTBEAT_FRAG", 0x15: "DATA", 0x16: "DATA_FRAG",
}
#: Built-in entity ids (RTPS 2.x, 9.3.1.2) -> names.
ENTITY_NAMES: dict[int, str] = {
    0x00000000: "ENTITYID_UNKNOWN",
    0x000001C1: "PARTICIPANT",
    0x000002C2: "SEDP_BUILTIN_TOPIC_WRITER", 0x000002C7: "SEDP_BUILTIN_TOPIC_READER",
    0x000003C2: "SEDP_BUILTIN_PUBLICATIONS_WRITER", 0x000003C7: "SEDP_BUILTIN_PUBLICATIONS_READER",
    0x000004C2: "SEDP_BUILTIN_SUBSCRIPTIONS_WRITER",
    0x000004C7: "SEDP_BUILTIN_SUBSCRIPTIONS_READER",
    0x000100C2: "SPDP_BUILTIN_PARTICIPANT_WRITER", 0x000100C7: "SPDP_BUILTIN_PARTICIPANT_READER",
    0x000200C2: "P2P_BUILTIN_PARTICIPANT_MESSAGE_WRITER",
    0x000200C7: "P2P_BUILTIN_PARTICIPANT_MESSAGE_READER",
}


def entity_name(entity_id: int) -> str:
    """A built-in entity's name, else ``user writer 0x...``/``user reader 0x...``."""
    if entity_id in ENTITY_NAMES:
        return ENTITY_NAMES[entity_id]
    kind = entity_id & 0xFF
    role = {0x02: "writer", 0x03: "writer", 0x04: "reader", 0x07: "reader"}.get(kind & 0x3F, "entity")
    return f"user {role} 0x{entity_id:08x}"


@dataclass(frozen=True)
class RtpsHeader:
    """The message header: version (major, minor), vendor id, the sender's GUID prefix."""

    version: tuple[int, int]
    vendor_id: int
    guid_prefix: bytes


@dataclass(frozen=True)
class Submessage:
    """Fields every submessage has: id, flags, position and size in the datagram."""

    kind: int
    flags: int
    offset: int
    size: int

    @property
    def name(self) -> str:
        """``DATA``, ``HEARTBEAT``, ... (``0x..`` for ids the lab does not know)."""
        return SUBMESSAGE_NAMES.get(self.kind, f"0x{self.kind:02x}")

    @property
    def little_endian(self) -> bool:
        """The E flag."""
        return bool(self.flags & 0x01)


@dataclass(frozen=True)
class InfoTs(Submessage):
    """INFO_TS: the source time of the submessages that follow (None: invalidated)."""

    timestamp: float | None = None


@dataclass(frozen=True)
class InfoDst(Submessage):
    """INFO_DST: the GUID prefix of the participant the following submessages are for."""

    guid_prefix: bytes = b""


@dataclass(frozen=True)
class InfoSrc(Submessage):
    """INFO_SRC: the participant (GUID prefix), protocol version and vendor the following
    submessages come from. A DDS that runs several participants in one process (Cyclone DDS
    does) packs their submessages into one datagram this way."""

    version: tuple[int, int] = (0, 0)
    vendor_id: int = 0
    guid_prefix: bytes = b""


@dataclass(frozen=True)
class Data(Submessage):
    """DATA: one sample (``payload``: its serialized payload, encapsulation header first)."""

    reader_id: int = 0
    writer_id: int = 0
    seq: int = 0
    inline_qos: bytes = b""
    payload: bytes = b""
    key: bool = False


@dataclass(frozen=True)
class DataFrag(Submessage):
    """DATA_FRAG: fragments ``frag_start`` .. ``frag_start + frag_count - 1`` (1-based) of a
    ``sample_size``-byte sample cut in ``frag_size``-byte fragments."""

    reader_id: int = 0
    writer_id: int = 0
    seq: int = 0
    frag_start: int = 0
    frag_count: int = 0
    frag_size: int = 0
    sample_size: int = 0
    inline_qos: bytes = b""
    payload: bytes = b""


@dataclass(frozen=True)
class Heartbeat(Submessage):
    """HEARTBEAT: the writer has samples ``first`` .. ``last``."""

    reader_id: int = 0
    writer_id: int = 0
    first: int = 0
    last: int = 0
    count: int = 0

    @property
    def final(self) -> bool:
        """The F flag: no ACKNACK is asked for (the reader answers only if it lacks samples)."""
        return bool(self.flags & HEARTBEAT_FINAL)

    @property
    def liveliness(self) -> bool:
        """The L flag: the writer asserts its liveliness (with F: nothing is asked for)."""
        return bool(self.flags & HEARTBEAT_LIVELINESS)


@dataclass(frozen=True)
class HeartbeatFrag(Submessage):
    """HEARTBEAT_FRAG: fragments 1 .. ``last_frag`` of sample ``seq`` are available."""

    reader_id: int = 0
    writer_id: int = 0
    seq: int = 0
    last_frag: int = 0
    count: int = 0


@dataclass(frozen=True)
class AckNack(Submessage):
    """ACKNACK: the reader has every sample before ``base``; ``missing`` are asked again."""

    reader_id: int = 0
    writer_id: int = 0
    base: int = 0
    num_bits: int = 0
    missing: tuple[int, ...] = ()
    count: int = 0


@dataclass(frozen=True)
class NackFrag(Submessage):
    """NACK_FRAG: fragments ``missing`` of sample ``seq`` are asked again."""

    reader_id: int = 0
    writer_id: int = 0
    seq: int = 0
    base: int = 0
    missing: tuple[int, ...] = ()
    count: int = 0


@dataclass(frozen=True)
class Gap(Submessage):
    """GAP: samples ``start`` .. ``list_base - 1`` and those in ``listed`` will never come."""

    reader_id: int = 0
    writer_id: int = 0
    start: int = 0
    list_base: int = 0
    listed: tuple[int, ...] = ()


@dataclass(frozen=True)
class Unknown(Submessage):
    """A submessage the lab does not decode (its body kept as bytes)."""

    body: bytes = b""


#: The destination of submessages before any INFO_DST: every participant that receives them.
ANY_PARTICIPANT = bytes(12)


@dataclass(frozen=True)
class RtpsMessage:
    """One RTPS message: header and submessages in order.

    ``error``: set only by ``parse_message(..., keep_valid=True)``: the submessage at
    ``error.offset`` is malformed, so it and the rest of the message are left out (RTPS 2.3
    8.3.4.1: a known but invalid submessage invalidates the rest of the message, not what came
    before it)."""

    header: RtpsHeader
    submessages: list[Submessage] = field(default_factory=list)
    error: RtpsError | None = None

    def routed(self) -> Iterator[tuple[bytes, bytes, Submessage]]:
        """Each submessage with the participant it comes from and the one it is for.

        This is the receiver state of RTPS 2.3 8.3.4: the source starts as the header's GUID
        prefix and the destination as ``ANY_PARTICIPANT``; INFO_SRC sets the source and
        INFO_DST the destination of the submessages after them (both are yielded too, with
        the state they set).
        """
        source, destination = self.header.guid_prefix, ANY_PARTICIPANT
        for sub in self.submessages:
            if isinstance(sub, InfoSrc):
                source = sub.guid_prefix
            elif isinstance(sub, InfoDst):
                destination = sub.guid_prefix
            yield source, destination, sub


class _Body:
    """A reader over one submessage body with its byte order."""

    def __init__(self, data: bytes, start: int, end: int, little: bool, what: str) -> None:
        self.data, self.pos, self.end = data, start, end
        self.order = "<" if little else ">"
        self.what = what

    def take(self, n: int, field_name: str) -> bytes:
        if self.pos + n > self.end:
            raise RtpsTruncatedError(
                f"{self.what} ends at byte {self.end}: {field_name} at byte {self.pos} needs {n} "
                f"byte(s)", self.pos)
        chunk = self.data[self.pos:self.pos + n]
        self.pos += n
        return chunk

    def unpack(self, fmt: str, field_name: str) -> tuple:
        st = struct.Struct(self.order + fmt)
        return st.unpack(self.take(st.size, field_name))

    def entity(self, field_name: str) -> int:
        return int.from_bytes(self.take(4, field_name), "big")

    def seq(self, field_name: str) -> int:
        high, low = self.unpack("iI", field_name)
        return (high << 32) | low

    def bitmap(self, base: int, field_name: str) -> tuple[int, tuple[int, ...]]:
        (num_bits,) = self.unpack("I", f"{field_name} numBits")
        if num_bits > 256:
            raise RtpsError(f"{self.what}: {field_name} has {num_bits} bits (at most 256)", self.pos - 4)
        words = self.unpack(f"{(num_bits + 31) // 32}I", f"{field_name} bitmap") if num_bits else ()
        members = tuple(base + i for i in range(num_bits) if words[i // 32] >> (31 - i % 32) & 1)
        return num_bits, members

    def rest(self) -> bytes:
        chunk = self.data[self.pos:self.end]
        self.pos = self.end
        return chunk


def _data_common(b: _Body) -> tuple[int, int, int, int]:
    _extra, to_qos = b.unpack("HH", "extraFlags/octetsToInlineQos")
    qos_at = b.pos + to_qos
    reader, writer, seq = b.entity("readerId"), b.entity("writerId"), b.seq("writerSN")
    return qos_at, reader, writer, seq


def _inline_qos(b: _Body, data: bytes) -> bytes:
    """Skip a parameter list (ending with PID_SENTINEL); return its bytes."""
    start = b.pos
    while True:
        pid, length = b.unpack("HH", "inline QoS parameter header")
        b.take(length, "inline QoS parameter")
        if pid == 0x0001:
            return data[start:b.pos]


def _submessage(data: bytes, kind: int, flags: int, offset: int, end: int) -> Submessage:
    little = bool(flags & 0x01)
    name = SUBMESSAGE_NAMES.get(kind, f"0x{kind:02x}")
    b = _Body(data, offset + SUBMESSAGE_HEADER_SIZE, end, little, f"{name} at byte {offset}")
    common = dict(kind=kind, flags=flags, offset=offset, size=end - offset)
    if kind == 0x09:  # INFO_TS
        if flags & 0x02:
            return InfoTs(**common, timestamp=None)
        sec, frac = b.unpack("iI", "timestamp")
        return InfoTs(**common, timestamp=sec + frac / 2**32)
    if kind == 0x0C:
        b.take(4, "unused")
        major, minor = b.take(2, "protocolVersion")
        vendor = int.from_bytes(b.take(2, "vendorId"), "big")    # octets, as in the header
        return InfoSrc(**common, version=(major, minor), vendor_id=vendor,
                       guid_prefix=b.take(12, "guidPrefix"))
    if kind == 0x0E:
        return InfoDst(**common, guid_prefix=b.take(12, "guidPrefix"))
    if kind == 0x15:  # DATA: Q=0x02 D=0x04 K=0x08
        if flags & 0x0C == 0x0C:
            raise RtpsError(f"DATA at byte {offset} has both the D (data) and K (key) flags: "
                            f"invalid in RTPS 2.x (8.3.7.2)", offset)
        qos_at, reader, writer, seq = _data_common(b)
        b.take(max(0, qos_at - b.pos), "the bytes before the inline QoS")
        qos = _inline_qos(b, data) if flags & 0x02 else b""
        payload = b.rest() if flags & 0x0C else b""
        return Data(**common, reader_id=reader, writer_id=writer, seq=seq, inline_qos=qos,
                    payload=payload, key=bool(flags & 0x08))
    if kind == 0x16:  # DATA_FRAG: Q=0x02 K=0x04
        qos_at, reader, writer, seq = _data_common(b)
        start, count, size, sample = b.unpack("IHHI", "fragment fields")
        b.take(max(0, qos_at - b.pos), "the bytes before the inline QoS")
        qos = _inline_qos(b, data) if flags & 0x02 else b""
        return DataFrag(**common, reader_id=reader, writer_id=writer, seq=seq, frag_start=start,
                        frag_count=count, frag_size=size, sample_size=sample, inline_qos=qos,
                        payload=b.rest())
    if kind == 0x07:
        reader, writer = b.entity("readerId"), b.entity("writerId")
        first, last = b.seq("firstSN"), b.seq("lastSN")
        (count,) = b.unpack("i", "count")
        return Heartbeat(**common, reader_id=reader, writer_id=writer, first=first, last=last,
                         count=count)
    if kind == 0x13:
        reader, writer, seq = b.entity("readerId"), b.entity("writerId"), b.seq("writerSN")
        last, count = b.unpack("Ii", "lastFragmentNum/count")
        return HeartbeatFrag(**common, reader_id=reader, writer_id=writer, seq=seq,
                             last_frag=last, count=count)
    if kind == 0x06:
        reader, writer = b.entity("readerId"), b.entity("writerId")
        base = b.seq("readerSNState base")
        num_bits, missing = b.bitmap(base, "readerSNState")
        (count,) = b.unpack("i", "count")
        return AckNack(**common, reader_id=reader, writer_id=writer, base=base,
                       num_bits=num_bits, missing=missing, count=count)
    if kind == 0x12:
        reader, writer, seq = b.entity("readerId"), b.entity("writerId"), b.seq("writerSN")
        (base,) = b.unpack("I", "fragmentNumberState base")
        _n, missing = b.bitmap(base, "fragmentNumberState")
        (count,) = b.unpack("i", "count")
        return NackFrag(**common, reader_id=reader, writer_id=writer, seq=seq, base=base,
                        missing=missing, count=count)
    if kind == 0x08:
        reader, writer = b.entity("readerId"), b.entity("writerId")
        start = b.seq("gapStart")
        base = b.seq("gapList base")
        _n, listed = b.bitmap(base, "gapList")
        return Gap(**common, reader_id=reader, writer_id=writer, start=start, list_base=base,
                   listed=listed)
    return Unknown(**common, body=b.rest())


def parse_message(data: bytes | bytearray | memoryview, keep_valid: bool = False) -> RtpsMessage:
    """Decode one RTPS message (a whole UDP datagram).

    With ``keep_valid`` a malformed submessage does not raise: the message keeps the
    submessages before it and says why in ``error`` (what a DDS receiver does, RTPS 2.3
    8.3.4.1). A bad header raises either way.

    Raises:
        RtpsError: not RTPS (bad magic), or a malformed field; a submessage that is not the
            last one and whose length is not a multiple of 4 (RTPS 2.3 9.4.1: every submessage
            starts on a 4-byte boundary; Cyclone DDS refuses it too).
        RtpsTruncatedError: the datagram ends inside the header or a submessage (a prefix of
            a message that ends between two submessages is itself a valid, shorter message).
    """
    data = bytes(data)
    if len(data) < HEADER_SIZE:
        if data[:4] != MAGIC[:len(data)]:
            raise RtpsError(f"not an RTPS message: starts with {data[:4]!r}, not {MAGIC!r}", 0)
        raise RtpsTruncatedError(f"RTPS header needs {HEADER_SIZE} bytes, the datagram has "
                                 f"{len(data)}", len(data))
    if data[:4] != MAGIC:
        raise RtpsError(f"not an RTPS message: starts with {data[:4]!r}, not {MAGIC!r}", 0)
    header = RtpsHeader((data[4], data[5]), int.from_bytes(data[6:8], "big"), data[8:20])
    subs: list[Submessage] = []
    try:
        _submessages(data, subs)
    except RtpsError as exc:
        if not keep_valid:
            raise
        return RtpsMessage(header, subs, exc)
    return RtpsMessage(header, subs)


def _submessages(data: bytes, subs: list[Submessage]) -> None:
    """Append the submessages of ``data`` (after the header) to ``subs``, in order."""
    pos = HEADER_SIZE
    while pos < len(data):
        if pos + SUBMESSAGE_HEADER_SIZE > len(data):
            raise RtpsTruncatedError(f"{len(data) - pos} byte(s) after the last submessage at byte "
                                     f"{pos}: too few for a submessage header", pos)
        kind, flags = data[pos], data[pos + 1]
        (length,) = struct.unpack("<H" if flags & 1 else ">H", data[pos + 2:pos + 4])
        # length 0: "to the end of the message", except for PAD and INFO_TS (really empty)
        end = len(data) if length == 0 and kind not in (0x01, 0x09) else pos + 4 + length
        if end > len(data):
            raise RtpsTruncatedError(
                f"{SUBMESSAGE_NAMES.get(kind, hex(kind))} at byte {pos} declares {length} bytes, "
                f"only {len(data) - pos - 4} left", pos)
        if length % 4 and end != len(data):
            raise RtpsError(f"{SUBMESSAGE_NAMES.get(kind, hex(kind))} at byte {pos} declares "
                            f"{length} bytes, not a multiple of 4, and is not the last submessage "
                            f"(RTPS 2.3 9.4.1: submessages start on 4-byte boundaries)", pos)
        subs.append(_submessage(data, kind, flags, pos, end))
        pos = end
