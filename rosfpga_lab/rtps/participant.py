"""A DDS participant as a sans-IO state machine: datagrams in, datagrams out.

How this works: :class:`Participant` holds the RTPS state of one DDS domain participant
(what ``rmw_cyclonedds_cpp`` creates for a ROS 2 node). It owns no socket and no clock:
:meth:`Participant.receive` takes one UDP datagram and the time, :meth:`Participant.tick`
takes the time, :meth:`Participant.write` takes a serialized sample; each returns the datagrams
to send as ``(address, port, bytes)``. Received user samples queue up in
:attr:`Participant.samples`.

* SPDP: the participant announces itself (lease, locators, ``enclave=/;`` user data) to the
  discovery ports of indices 0..MAX_PARTICIPANT_INDEX of its domain and to every participant it
  knows; a participant whose lease runs out is forgotten with its endpoints. A full table makes
  room for each new participant (those that sent nothing but SPDP go first); a goodbye from
  another source than the peer's is suspect, and a peer forgotten by a goodbye (or evicted) whose
  traffic goes on is learned again (:mod:`~rosfpga_lab.rtps.spdp` says what an attacker can
  still do).
* SEDP: its writers and readers go out as reliable built-in samples (DATA, HEARTBEAT, ACKNACK),
  the peers' ones come in the same way; a remote endpoint on the same topic and type is matched
  when its QoS is compatible (RxO: offered reliability and durability at least what is
  requested), else the reason is logged once. An endpoint given a ROS 2 type hash announces it
  (USER_DATA ``typehash=RIHS01_...;``, as rmw does); a matched remote endpoint whose announced
  hash differs is logged once and matched all the same (rmw matches on the type name).
* User data: a writer keeps the last ``depth`` samples (KEEP_LAST, at most MAX_HISTORY_BYTES;
  VOLATILE, or TRANSIENT_LOCAL: a reader that joins late gets them), sends each as DATA
  or DATA_FRAG; reliable ones HEARTBEAT until acknowledged, resend on ACKNACK/NACK_FRAG within
  a budget and GAP what left the history or was acknowledged. It never blocks: a slow reader,
  KEEP_ALL or not, loses what left the history (rosfpga_lab.rtps.limits.MAX_HISTORY_BYTES). A reader puts fragments together (memory follows bytes received),
  delivers in order when reliable, asks again with ACKNACK/NACK_FRAG.
* The receiver's rules (RTPS 2.3 8.3.4, 8.3.6.3, 8.4.12.2, as Cyclone DDS's receiver follows
  them): INFO_SRC/INFO_DST set source and destination; a message of another major version is
  ignored; a malformed submessage drops itself and the rest of its datagram, not what came
  before; a final HEARTBEAT is answered only when samples are missing, a final liveliness one
  never; a GAP ahead of delivery is remembered until delivery gets there, one past what its
  writer announced (HEARTBEAT's last, data seen) is ignored there; whatever a known
  peer's endpoints send renews its lease, as SPDP does.

Where each part lives: :class:`Participant` is one class built from one class per part, each in
its own module on :class:`~rosfpga_lab.rtps.participant_base.ParticipantBase` (the state, notes
and output helpers): :mod:`~rosfpga_lab.rtps.writer_side`, :mod:`~rosfpga_lab.rtps.sedp`,
:mod:`~rosfpga_lab.rtps.spdp` (on SEDP: a new participant gets our endpoints, a forgotten one takes
its own along) and :mod:`~rosfpga_lab.rtps.reader_side` (on SEDP: SEDP samples arrive as samples).
This module joins them: the local endpoints, :meth:`Participant.tick`, and the receive loop that
hands each routed submessage (``RtpsMessage.routed``) to its part.
"""

from __future__ import annotations

import struct
from collections import deque

from rosfpga_lab.rtps import build as b
from rosfpga_lab.msg.typehash import RIHS_PATTERN
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, READER_KIND, SPDP_READER, SPDP_WRITER, SUB_READER, SUB_WRITER,
    WRITER_KIND, LocalEndpoint, Qos, ReaderProxy, Sample, Send, check_domain, discovery_port,
    incompatibility, user_port,
)
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.limits import HEARTBEAT_SECONDS, MAX_HEARTBEAT_SECONDS, MAX_HISTORY_DEPTH
from rosfpga_lab.rtps.message import (
    ANY_PARTICIPANT, AckNack, Data, DataFrag, Gap, Heartbeat, HeartbeatFrag, InfoDst, InfoSrc,
    NackFrag, parse_message,
)
from rosfpga_lab.rtps.reader_side import ReaderSide
from rosfpga_lab.rtps.spdp import ParticipantDiscovery
from rosfpga_lab.rtps.writer_side import WriterSide

__all__ = [
    "PUB_READER", "PUB_WRITER", "Participant", "Qos", "SPDP_READER", "SPDP_WRITER", "SUB_READER",
    "SUB_WRITER", "Sample", "Send", "check_domain", "discovery_port", "incompatibility",
    "user_port",
]


class Participant(ParticipantDiscovery, ReaderSide, WriterSide):
    """One DDS participant: call :meth:`receive`, :meth:`tick`, :meth:`write`; send what they return.
    Its constructor and its state are :class:`~rosfpga_lab.rtps.participant_base.ParticipantBase`'s."""

    # ---- local endpoints -----------------------------------------------------------------
    def _new_entity(self, kind: int) -> int:
        eid = (self._next_key << 8) | kind
        self._next_key += 1
        return eid

    @staticmethod
    def _check_hash(type_hash: str) -> str:
        if type_hash and not RIHS_PATTERN.fullmatch(type_hash):
            raise RtpsError(f"type hash {type_hash[:80]!r} is not RIHS01_ and 64 lowercase hex "
                            f"digits: pass rosfpga_lab.msg.typehash.type_hash(type), or ''")
        return type_hash

    def add_writer(self, topic: str, type_name: str, qos: Qos = Qos(), type_hash: str = "", *,
                   locator: tuple[str, int] | None = None) -> int:
        """A user writer on DDS topic ``topic`` (``rt/...`` for ROS 2); returns its entity id.
        ``type_hash`` (``RIHS01_...``, '' for none) goes out in its SEDP USER_DATA; ``locator``
        is the unicast locator its SEDP data announces, where its readers send their ACKNACKs
        (None: the participant's default user-data locator; this participant takes any
        submessage on any of its ports)."""
        ep = LocalEndpoint(self._new_entity(WRITER_KIND), "writer", topic, type_name,
                           Qos(qos.reliable, max(1, min(qos.depth, MAX_HISTORY_DEPTH)),
                               qos.transient_local), type_hash=self._check_hash(type_hash),
                           locator=locator)
        self.local[ep.entity_id] = ep
        self._announce_endpoint(ep)
        return ep.entity_id

    def add_reader(self, topic: str, type_name: str, qos: Qos = Qos(), type_hash: str = "") -> int:
        """A user reader; returns its entity id (its samples arrive in :attr:`samples`)."""
        ep = LocalEndpoint(self._new_entity(READER_KIND), "reader", topic, type_name,
                           Qos(qos.reliable, max(1, min(qos.depth, MAX_HISTORY_DEPTH)), False),
                           type_hash=self._check_hash(type_hash))
        self.local[ep.entity_id] = ep
        self._announce_endpoint(ep)
        return ep.entity_id

    def matched(self, entity_id: int) -> list[bytes]:
        """GUIDs of the remote endpoints matched with local endpoint ``entity_id``."""
        return [prefix + eid.to_bytes(4, "big") for prefix, eid in self.local[entity_id].proxies]

    # ---- periodic work ---------------------------------------------------------------------
    def tick(self, now: float) -> list[Send]:
        """Periodic work: SPDP announcements, lease expiry, HEARTBEATs of reliable writers."""
        out: list[Send] = self._take_outbox()
        if now - self._last_announce >= self.announce_period:
            self._last_announce = now
            out += self.announce()
        for prefix in [k for k, d in self.departed.items() if now > d.until]:
            del self.departed[prefix]
        for prefix, p in list(self.participants.items()):
            if now - p.last_seen > p.lease:
                self.note(f"lease-{prefix.hex()}", f"participant {prefix.hex()} ({p.name}) lease "
                          f"of {p.lease:g} s ran out: forgotten with its endpoints")
                self._forget(prefix)
        for ep in self.local.values():
            if ep.kind != "writer" or not ep.qos.reliable:
                continue
            for key, proxy in ep.proxies.items():
                assert isinstance(proxy, ReaderProxy)
                period = proxy.heartbeat_period or HEARTBEAT_SECONDS
                if proxy.acked <= ep.seq and now - proxy.last_heartbeat >= period:
                    proxy.last_heartbeat = now
                    proxy.heartbeat_period = min(period * 2, MAX_HEARTBEAT_SECONDS)
                    out += self._msg(proxy.locator, proxy.prefix, [self._heartbeat(ep, proxy)])
        return out

    # ---- the datagram entry point ------------------------------------------------------
    def receive(self, datagram: bytes, source: tuple[str, int], now: float) -> list[Send]:
        """Handle one UDP datagram from ``source``; return the datagrams to send.

        As RTPS 2.3 8.3.4.1 and 8.3.6.3 say: a message of another major protocol version is
        ignored whole; a malformed submessage is ignored with the rest of the message, and
        the submessages before it are handled."""
        try:
            msg = parse_message(datagram, keep_valid=True)
        except RtpsError as exc:
            self.note(f"malformed-{type(exc).__name__}", f"malformed datagram from "
                      f"{source[0]}:{source[1]} ignored ({exc}); further ones are counted")
            return []
        if msg.header.guid_prefix == self.guid_prefix:
            return []
        if msg.header.version[0] != b.PROTOCOL_VERSION[0]:
            major, minor = msg.header.version
            self.note(f"version-{major}", f"RTPS {major}.{minor} message from {source[0]}:"
                      f"{source[1]} ignored (this participant speaks RTPS "
                      f"{b.PROTOCOL_VERSION[0]}.x; RTPS 2.3 8.3.6.3)")
            return []
        if msg.error is not None:
            self.note(f"malformed-rest-{type(msg.error).__name__}", f"malformed submessage in a "
                      f"datagram from {source[0]}:{source[1]}: the {len(msg.submessages)} "
                      f"before it handled, it and the rest ignored ({msg.error}); further ones "
                      f"are counted")
        out: list[Send] = []
        routed = list(msg.routed())
        for prefix, destination, sub in routed:
            # what the datagram's writers announce counts for its GAPs wherever it stands in it
            # (a writer may send a GAP before the DATA that follows the samples it skips)
            if prefix in self.participants and destination in (self.guid_prefix, ANY_PARTICIPANT) \
                    and isinstance(sub, (Data, DataFrag, Heartbeat, HeartbeatFrag)) \
                    and not self._invalid(sub):
                last = sub.last if isinstance(sub, Heartbeat) else sub.seq
                self._written_up_to(prefix, sub.writer_id, sub.reader_id, last)
        for prefix, destination, sub in routed:
            if isinstance(sub, (InfoDst, InfoSrc)) or prefix == self.guid_prefix or \
                    destination not in (self.guid_prefix, ANY_PARTICIPANT):
                continue
            if prefix not in self.participants and not (
                    isinstance(sub, Data) and sub.writer_id == SPDP_WRITER):
                back = self._relearn(prefix, now)     # one that left, still speaking
                if not back:
                    self.note(f"unknown-{prefix.hex()}", f"submessages from participant "
                              f"{prefix.hex()} before its SPDP: ignored")
                    continue
                out += back
            try:
                out += self._on_submessage(prefix, sub, source, now)
            except RtpsError as exc:
                self.note(f"bad-{sub.name}", f"{sub.name} from {prefix.hex()} ignored ({exc})")
            except (struct.error, ValueError, IndexError, KeyError, UnicodeError) as exc:
                # a field this code did not expect in that shape: the submessage is dropped,
                # the participant goes on (a bug to report, never a way to stop the node)
                self.note(f"unexpected-{sub.name}-{type(exc).__name__}",
                          f"{sub.name} from {prefix.hex()} dropped: unexpected {type(exc).__name__}: "
                          f"{exc}")
        return out + self._take_outbox()

    @staticmethod
    def _invalid(sub: object) -> str:
        """Why a submessage is invalid by RTPS 2.3 8.3.7 (then it is ignored), or ''."""
        if isinstance(sub, Heartbeat) and (sub.first < 1 or sub.last < sub.first - 1):
            return f"HEARTBEAT first {sub.first} last {sub.last}"
        if isinstance(sub, Gap) and (sub.start < 1 or sub.list_base < 1):
            # gapList.base below gapStart is valid (8.3.7.4.3): the range is empty, the
            # listed samples still count (Cyclone DDS reads it so too)
            return f"GAP start {sub.start} base {sub.list_base}"
        if isinstance(sub, AckNack) and sub.base < 1 and (sub.base, sub.num_bits) != (0, 0):
            return f"ACKNACK base {sub.base}"
        if isinstance(sub, (Data, DataFrag)) and sub.seq < 1:
            return f"{'DATA' if isinstance(sub, Data) else 'DATA_FRAG'} sequence number {sub.seq}"
        return ""

    def _on_submessage(self, prefix: bytes, sub: object, source: tuple[str, int],
                       now: float) -> list[Send]:
        why = self._invalid(sub)
        if why:
            self.note(f"invalid-{type(sub).__name__}", f"invalid submessage from {prefix.hex()} "
                      f"ignored: {why} (RTPS 2.3 8.3.7)")
            return []
        known = self.participants.get(prefix)
        if known is not None and not (isinstance(sub, Data) and sub.writer_id == SPDP_WRITER):
            # its endpoints speak: it is alive (Cyclone DDS renews a peer's lease on its
            # DATA, HEARTBEAT, GAP, ACKNACK and NACK_FRAG too), so a lost or late SPDP
            # announcement does not drop a peer that is sending
            known.last_seen = max(known.last_seen, now)
            known.spoke = now
        if isinstance(sub, Data):
            if sub.writer_id == SPDP_WRITER:
                return self._on_spdp(prefix, sub, source, now)
            if sub.payload or sub.key or sub.inline_qos:
                self._on_sample(prefix, sub.reader_id, sub.writer_id, sub.seq, sub.payload,
                                sub.inline_qos, sub.little_endian)
        elif isinstance(sub, DataFrag):
            readers = self._readers_of(prefix, sub.writer_id, sub.reader_id)
            if not readers or all(wp.next and sub.seq < wp.next for _, wp in readers):
                return []     # no reader for it, or already delivered
            sample = self.assembler.add(prefix, sub)
            if sample is not None:
                self._on_sample(prefix, sub.reader_id, sub.writer_id, sub.seq, sample,
                                sub.inline_qos, sub.little_endian)
        elif isinstance(sub, Heartbeat):
            return self._on_heartbeat(prefix, sub)
        elif isinstance(sub, HeartbeatFrag):
            return self._on_heartbeat_frag(prefix, sub)
        elif isinstance(sub, AckNack):
            return self._on_acknack(prefix, sub, now)
        elif isinstance(sub, NackFrag):
            return self._on_nackfrag(prefix, sub, now)
        elif isinstance(sub, Gap):
            self._on_gap(prefix, sub)
        return []

    def take(self, reader_id: int | None = None) -> list[Sample]:
        """Remove and return the samples received (all, or ``reader_id``'s)."""
        if reader_id is None:
            out = list(self.samples)
            self.samples.clear()
            return out
        out = [s for s in self.samples if s.reader_id == reader_id]
        self.samples = deque(s for s in self.samples if s.reader_id != reader_id)
        return out
