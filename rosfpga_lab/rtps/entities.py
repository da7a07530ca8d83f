"""The entities of a DDS participant as data: built-in entity ids, the RTPS port mapping, the
QoS the lab compares (and why two endpoints do not match), remote participants and endpoints,
and the proxies a writer keeps per matched reader and a reader per matched writer
(:mod:`rosfpga_lab.rtps.participant` runs them)."""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.limits import (
    DOMAIN_GAIN, MAX_DOMAIN_ID, OFFSET_DISCOVERY_MULTICAST, OFFSET_DISCOVERY_UNICAST,
    OFFSET_USER_UNICAST, PARTICIPANT_GAIN, PORT_BASE,
)

SPDP_WRITER, SPDP_READER = 0x000100C2, 0x000100C7
PUB_WRITER, PUB_READER = 0x000003C2, 0x000003C7
SUB_WRITER, SUB_READER = 0x000004C2, 0x000004C7
PARTICIPANT_ENTITY = 0x000001C1
#: User entity kinds: writer and reader without key (ROS 2 topics have no key).
WRITER_KIND, READER_KIND = 0x03, 0x04

Send = tuple[str, int, bytes]


def discovery_port(domain: int, index: int) -> int:
    """The unicast discovery (metatraffic) port of participant ``index`` in ``domain``."""
    return PORT_BASE + DOMAIN_GAIN * domain + OFFSET_DISCOVERY_UNICAST + PARTICIPANT_GAIN * index


def discovery_multicast_port(domain: int) -> int:
    """The SPDP multicast port of ``domain`` (every participant's announcements, when the
    network has multicast)."""
    return PORT_BASE + DOMAIN_GAIN * domain + OFFSET_DISCOVERY_MULTICAST


def user_port(domain: int, index: int) -> int:
    """The unicast user-data port of participant ``index`` in ``domain``."""
    return PORT_BASE + DOMAIN_GAIN * domain + OFFSET_USER_UNICAST + PARTICIPANT_GAIN * index


def check_domain(domain: int) -> None:
    if not 0 <= domain <= MAX_DOMAIN_ID:
        raise RtpsError(f"DDS domain {domain} out of range: use 0..{MAX_DOMAIN_ID} (the RTPS "
                        f"port mapping puts larger ids past port 65535)")


@dataclass(frozen=True)
class Qos:
    """The QoS the lab's endpoints use and compare: reliability, durability, history depth."""

    reliable: bool = True
    depth: int = 10
    transient_local: bool = False

    def describe(self) -> str:
        return (f"{'RELIABLE' if self.reliable else 'BEST_EFFORT'} KEEP_LAST {self.depth} "
                f"{'TRANSIENT_LOCAL' if self.transient_local else 'VOLATILE'}")


def incompatibility(offered: Qos, requested: Qos) -> str:
    """Why a writer offering ``offered`` cannot serve a reader requesting ``requested`` ('' if it can)."""
    if requested.reliable and not offered.reliable:
        return "a BEST_EFFORT writer never matches a RELIABLE reader (RELIABILITY offered < requested)"
    if requested.transient_local and not offered.transient_local:
        return "a VOLATILE writer never matches a TRANSIENT_LOCAL reader (DURABILITY offered < requested)"
    return ""


@dataclass
class RemoteParticipant:
    prefix: bytes
    meta: tuple[str, int]
    user: tuple[str, int]
    lease: float
    last_seen: float
    name: str = ""
    learned: float = 0.0          # when its SPDP was first taken
    spoke: float = -1e9           # when it last sent something besides SPDP (SEDP, HEARTBEAT...)
    source: tuple[str, int] = ("", 0)     # where the SPDP that taught it came from
    preemptive_base: int = 1      # its SEDP readers' preemptive ACKNACK base (Fast DDS: 0)


@dataclass
class RemoteEndpoint:
    guid: bytes
    kind: str                     # "writer" | "reader"
    topic: str
    type_name: str
    qos: Qos
    locator: tuple[str, int]
    type_hash: str = ""           # RIHS01_... its USER_DATA announced ('' if none)


@dataclass
class ReaderProxy:
    """A remote reader as one of the lab's writers sees it."""

    prefix: bytes
    reader_id: int
    locator: tuple[str, int]
    reliable: bool
    first_relevant: int
    acked: int = 1                # every sample before it is acknowledged
    last_count: int = 0
    last_frag_count: int = 0
    #: When retransmissions were last let through: key 0 for an ACKNACK's, a sample's sequence
    #: number for a NACK_FRAG's of that sample (only samples still in the history are kept).
    resent: dict[int, float] = field(default_factory=dict)
    last_heartbeat: float = -1.0
    heartbeat_period: float = 0.0     # 0: the first period; doubles while unanswered
    #: When each sample still in the history was last sent to it (written or resent): not
    #: again within NACK_SUPPRESSION_SECONDS (``WriterSide._suppressed``).
    sent: dict[int, float] = field(default_factory=dict)
    #: Bytes it may still be resent (``WriterSide._afford``): each sample written adds its size
    #: (times RESEND_PER_BYTE_WRITTEN), up to as many times the history's bytes; it starts at those.
    credit: float = 0.0


@dataclass
class WriterProxy:
    """A remote writer as one of the lab's readers sees it."""

    prefix: bytes
    writer_id: int
    reliable: bool
    next: int = 0                 # 0: nothing known yet
    announced: int = 0            # highest number the writer announced (HEARTBEAT last, data)
    pending: dict[int, bytes | None] = field(default_factory=dict)
    pending_bytes: int = 0
    gaps: dict[int, int] = field(default_factory=dict)   # GAP ranges start -> end ahead of next
    last_hb_count: int = -(1 << 31)
    last_hbfrag_count: int = -(1 << 31)   # HEARTBEAT_FRAG counts on their own (RTPS 2.3 8.3.7.6)
    acknack_count: int = 0
    nackfrag_count: int = 0


@dataclass
class Departed:
    """What a participant that said goodbye or was evicted leaves behind, to learn it again when
    its traffic goes on (``spdp._relearn``): its record, its endpoints, our SEDP readers' proxies
    of its SEDP writers (where they were), from when and until when its traffic counts."""

    participant: RemoteParticipant
    endpoints: list[RemoteEndpoint]
    sedp: dict[tuple[bytes, int], WriterProxy]
    relearn_from: float
    until: float


@dataclass
class LocalEndpoint:
    entity_id: int
    kind: str
    topic: str
    type_name: str
    qos: Qos
    seq: int = 0                                  # writer: last sequence number written
    history: OrderedDict[int, bytes] = field(default_factory=OrderedDict)
    history_bytes: int = 0                        # writer: bytes of the samples in history
    proxies: dict[tuple[bytes, int], ReaderProxy | WriterProxy] = field(default_factory=dict)
    hb_count: int = 0
    type_hash: str = ""                           # RIHS01_... announced in its USER_DATA
    #: the unicast locator its SEDP data announces (None: the participant's default user-data one)
    locator: tuple[str, int] | None = None

    @property
    def guid_tail(self) -> bytes:
        return self.entity_id.to_bytes(4, "big")


@dataclass(frozen=True)
class Sample:
    """A user sample delivered to one of the lab's readers."""

    reader_id: int
    writer_guid: bytes
    seq: int
    payload: bytes
