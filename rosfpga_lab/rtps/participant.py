"""A DDS participant as a sans-IO state machine: datagrams in, datagrams out.

How this works: :class:`Participant` holds the RTPS state of one DDS domain participant
(what ``rmw_cyclonedds_cpp`` creates for a ROS 2 node). It owns no socket and no clock:
:meth:`Participant.receive` takes one UDP datagram and the time, :meth:`Participant.tick`
takes the time, :meth:`Participant.write` takes a serialized sample; each returns the datagrams
to send as ``(address, port, bytes)``. Received user samples queue up in
:attr:`Participant.samples`.

* SPDP: the participant announces itself (lease, locators, ``enclave=/;`` user data) to the
  discovery ports of indices 0..MAX_PARTICIPANT_INDEX of its domain and to every participant it
  knows; a participant whose lease runs out is forgotten with its endpoints.
* SEDP: its writers and readers go out as reliable built-in samples (DATA, HEARTBEAT, ACKNACK),
  the peers' ones come in the same way; a remote endpoint on the same topic and type is matched
  when its QoS is compatible (RxO: offered reliability and durability at least what is
  requested), else the reason is logged once. An endpoint given a ROS 2 type hash announces it
  (USER_DATA ``typehash=RIHS01_...;``, as rmw does); a matched remote endpoint whose announced
  hash differs is logged once and matched all the same (rmw matches on the type name).
* User data: a writer keeps the last ``depth`` samples (KEEP_LAST; VOLATILE, or TRANSIENT_LOCAL:
  a reader that joins late gets them), sends each as DATA
  or DATA_FRAG; reliable ones HEARTBEAT until acknowledged, resend on ACKNACK/NACK_FRAG and GAP
  what left the history. A reader puts fragments together (memory follows bytes received),
  delivers in order when reliable, asks again with ACKNACK/NACK_FRAG.
* The receiver's rules (RTPS 2.3 8.3.4, 8.3.6.3, 8.4.12.2, as Cyclone DDS's receiver follows
  them): INFO_SRC/INFO_DST set source and destination; a message of another major version is
  ignored; a malformed submessage drops itself and the rest of its datagram, not what came
  before; a final HEARTBEAT is answered only when samples are missing, a final liveliness one
  never; a GAP ahead of delivery is remembered until delivery gets there; whatever a known
  peer's endpoints send renews its lease, as SPDP does.
"""

from __future__ import annotations

import os
import struct
from collections import deque

from rosfpga_lab.rtps import build as b
from rosfpga_lab.msg.typehash import RIHS_PATTERN
from rosfpga_lab.rtps.discovery import (
    PL_CDR_BE, PL_CDR_LE, FragmentAssembler, parse_parameters, user_data_type_hash,
)
from rosfpga_lab.rtps.entities import (
    PARTICIPANT_ENTITY, PUB_READER, PUB_WRITER, READER_KIND, SPDP_READER, SPDP_WRITER, SUB_READER, SUB_WRITER,
    WRITER_KIND, LocalEndpoint, Qos, ReaderProxy, RemoteEndpoint, RemoteParticipant, Sample, Send,
    WriterProxy, check_domain, discovery_port, incompatibility, user_port,
)
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.limits import (
    ANNOUNCE_SECONDS, FRAGMENT_BYTES, HEARTBEAT_SECONDS, LEASE_SECONDS, MAX_HEARTBEAT_SECONDS,
    MAX_HISTORY_DEPTH, MAX_LEASE_SECONDS, MAX_MATCHED_PER_ENDPOINT, MAX_MESSAGE_BYTES, MAX_NOTES,
    MAX_OUT_OF_ORDER, MAX_OUT_OF_ORDER_BYTES, MAX_PARTICIPANT_INDEX, MAX_REMOTE_ENDPOINTS,
    MAX_REMOTE_PARTICIPANTS, MIN_RESEND_SECONDS,
)
from rosfpga_lab.rtps.message import (
    ANY_PARTICIPANT, AckNack, Data, DataFrag, Gap, Heartbeat, HeartbeatFrag, InfoDst, InfoSrc,
    NackFrag, parse_message,
)

__all__ = [
    "PUB_READER", "PUB_WRITER", "Participant", "Qos", "SPDP_READER", "SPDP_WRITER", "SUB_READER",
    "SUB_WRITER", "Sample", "Send", "check_domain", "discovery_port", "incompatibility",
    "user_port",
]


class Participant:
    """One DDS participant: call :meth:`receive`, :meth:`tick`, :meth:`write`; send what they return."""

    def __init__(self, domain: int = 0, index: int = 0, address: str = "127.0.0.1",
                 name: str = "rosfpga_lab", guid_prefix: bytes | None = None,
                 lease: float = LEASE_SECONDS, announce: float = ANNOUNCE_SECONDS,
                 peers: tuple[str, ...] = ("127.0.0.1",)) -> None:
        check_domain(domain)
        self.domain, self.index, self.address, self.name = domain, index, address, name
        self.guid_prefix = guid_prefix or (b"\x01\x0f" + os.urandom(10))
        self.lease, self.announce_period = lease, announce
        self.peers = peers
        self.meta = (address, discovery_port(domain, index))
        self.user = (address, user_port(domain, index))
        self.participants: dict[bytes, RemoteParticipant] = {}
        self.remote: dict[bytes, RemoteEndpoint] = {}
        self.local: dict[int, LocalEndpoint] = {}
        self.samples: deque[Sample] = deque()
        self.notes: list[str] = []
        self.counts: dict[str, int] = {}
        self._noted: set[str] = set()
        self._next_key = 1
        self._last_announce = -1e9
        self.assembler = FragmentAssembler()
        self._outbox: list[Send] = []     # what matching produced (sent with the next result)
        # built-in SEDP writers and readers (reliable, KEEP_ALL of the lab's own endpoints)
        for eid, kind in ((PUB_WRITER, "writer"), (SUB_WRITER, "writer"),
                          (PUB_READER, "reader"), (SUB_READER, "reader")):
            self.local[eid] = LocalEndpoint(eid, kind, "", "", Qos(True, MAX_REMOTE_ENDPOINTS))

    # ---- notes ---------------------------------------------------------------------------
    def note(self, key: str, text: str) -> None:
        """Log ``text`` once per ``key``; every call is counted in :attr:`counts`. Both are
        bounded: past MAX_NOTES distinct keys, new ones are counted under ``notes-full``."""
        if key not in self._noted and len(self._noted) >= MAX_NOTES:
            key, text = "notes-full", f"more than {MAX_NOTES} distinct notes; further ones are counted only"
        self.counts[key] = self.counts.get(key, 0) + 1
        if key in self._noted:
            return
        self._noted.add(key)
        self.notes.append(text)

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

    def add_writer(self, topic: str, type_name: str, qos: Qos = Qos(), type_hash: str = "") -> int:
        """A user writer on DDS topic ``topic`` (``rt/...`` for ROS 2); returns its entity id.
        ``type_hash`` (``RIHS01_...``, '' for none) goes out in its SEDP USER_DATA."""
        ep = LocalEndpoint(self._new_entity(WRITER_KIND), "writer", topic, type_name,
                           Qos(qos.reliable, max(1, min(qos.depth, MAX_HISTORY_DEPTH)),
                               qos.transient_local), type_hash=self._check_hash(type_hash))
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

    def _announce_endpoint(self, ep: LocalEndpoint) -> None:
        sedp = self.local[PUB_WRITER if ep.kind == "writer" else SUB_WRITER]
        sedp.seq += 1
        sedp.history[sedp.seq] = b.sedp_payload(self.guid_prefix + ep.guid_tail, ep.topic,
                                                ep.type_name, ep.qos.reliable, ep.qos.depth,
                                                b.Locator(*self.user), ep.qos.transient_local,
                                                ep.type_hash)
        for rem in list(self.remote.values()):
            self._try_match(ep, rem)

    def matched(self, entity_id: int) -> list[bytes]:
        """GUIDs of the remote endpoints matched with local endpoint ``entity_id``."""
        return [prefix + eid.to_bytes(4, "big") for prefix, eid in self.local[entity_id].proxies]

    # ---- output helpers ------------------------------------------------------------------
    def _msg(self, dst: tuple[str, int], prefix: bytes, subs: list[bytes]) -> list[Send]:
        """Pack submessages after INFO_DST into datagrams of at most MAX_MESSAGE_BYTES."""
        out: list[Send] = []
        head = b.header(self.guid_prefix) + b.info_dst(prefix)
        cur = bytearray(head)
        for s in subs:
            if len(cur) + len(s) > MAX_MESSAGE_BYTES and len(cur) > len(head):
                out.append((dst[0], dst[1], bytes(cur)))
                cur = bytearray(head)
            cur += s
        if len(cur) > len(head):
            out.append((dst[0], dst[1], bytes(cur)))
        return out

    def _sample_subs(self, reader_id: int, writer_id: int, seq: int, payload: bytes,
                     frags: list[int] | None = None) -> list[bytes]:
        """DATA, or DATA_FRAGs (all, or those numbered in ``frags``), of one sample."""
        payload = b.pad_payload(payload)
        room = MAX_MESSAGE_BYTES - 20 - 16 - 32 - 4
        if len(payload) <= room and frags is None:
            return [b.data(reader_id, writer_id, seq, payload)]
        total = -(-len(payload) // FRAGMENT_BYTES)
        numbers = range(1, total + 1) if frags is None else [n for n in frags if 1 <= n <= total]
        return [b.data_frag(reader_id, writer_id, seq, n, FRAGMENT_BYTES, len(payload),
                            payload[(n - 1) * FRAGMENT_BYTES:n * FRAGMENT_BYTES], 1)
                for n in numbers]

    # ---- SPDP ----------------------------------------------------------------------------
    def spdp_payload(self) -> bytes:
        return b.spdp_payload(self.guid_prefix, b.Locator(*self.meta), b.Locator(*self.user),
                              self.lease, self.name, b"enclave=/;", self.domain)

    def _spdp(self, dst: tuple[str, int]) -> Send:
        msg = (b.header(self.guid_prefix) + b.info_ts(0.0)
               + b.data(SPDP_READER, SPDP_WRITER, 1, self.spdp_payload()))
        return (dst[0], dst[1], msg)

    def announce(self) -> list[Send]:
        """SPDP to the probed discovery ports of every peer address and to every known participant."""
        dsts = {(peer, discovery_port(self.domain, i)) for peer in self.peers
                for i in range(MAX_PARTICIPANT_INDEX + 1)}
        dsts.discard(self.meta)
        dsts |= {p.meta for p in self.participants.values()}
        return [self._spdp(d) for d in sorted(dsts)]

    def goodbye(self) -> list[Send]:
        """SPDP "disposed and unregistered" to every known participant: they forget this one
        now instead of when its lease runs out (send it before closing the sockets)."""
        guid = self.guid_prefix + PARTICIPANT_ENTITY.to_bytes(4, "big")
        qos = b.inline_qos([(b.PID_KEY_HASH, guid), (b.PID_STATUS_INFO, b"\x00\x00\x00\x03")])
        key = b.param_list([(b.PID_PARTICIPANT_GUID, guid)])
        msg = (b.header(self.guid_prefix) + b.info_ts(0.0)
               + b.data(SPDP_READER, SPDP_WRITER, 2, key, qos))
        return [(p.meta[0], p.meta[1], msg) for p in self.participants.values()]

    def tick(self, now: float) -> list[Send]:
        """Periodic work: SPDP announcements, lease expiry, HEARTBEATs of reliable writers."""
        out: list[Send] = self._take_outbox()
        if now - self._last_announce >= self.announce_period:
            self._last_announce = now
            out += self.announce()
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

    def _heartbeat(self, ep: LocalEndpoint, proxy: ReaderProxy) -> bytes:
        ep.hb_count += 1
        first = max(next(iter(ep.history), ep.seq + 1), proxy.first_relevant)
        return b.heartbeat(proxy.reader_id, ep.entity_id, first, ep.seq, ep.hb_count)

    def _forget(self, prefix: bytes) -> None:
        self.participants.pop(prefix, None)
        writers = {k[1] for ep in self.local.values() if ep.kind == "reader"
                   for k in ep.proxies if k[0] == prefix}
        for guid in [g for g in self.remote if g[:12] == prefix]:
            self._forget_endpoint(guid)
        for ep in self.local.values():
            for key in [k for k in ep.proxies if k[0] == prefix]:
                del ep.proxies[key]
        for writer_id in writers:       # its partly received samples go too
            for seq in self.assembler.partial(prefix, writer_id):
                self.assembler.discard(prefix, writer_id, seq)

    def _forget_endpoint(self, guid: bytes) -> None:
        rem = self.remote.pop(guid, None)
        if rem is None:
            return
        key = (guid[:12], int.from_bytes(guid[12:], "big"))
        for ep in self.local.values():
            if ep.topic and ep.proxies.pop(key, None) is not None:
                self.note(f"unmatch-{guid.hex()}-{ep.entity_id}",
                          f"{ep.kind} {ep.topic}: remote {rem.kind} {guid.hex()} left")

    def _locator(self, value: list[bytes] | None, little: bool,
                 source: tuple[str, int]) -> tuple[str, int] | None:
        """Where to reach a peer: a loopback locator, or one at the sender's own address; else,
        when the sender is on this host (a loopback source), its locator's port at the sender's
        address (Fast DDS, rmw_fastrtps_cpp's DDS, announces only the host's LAN addresses and
        listens on all of them, loopback included, as it does for its own peers on one host)."""
        found = [loc for loc in (b.Locator.decode(raw, little) for raw in value or [])
                 if loc is not None]
        for loc in found:
            if loc.address.startswith("127.") or loc.address == source[0]:
                return (loc.address, loc.port)
        if found and source[0].startswith("127."):
            loc = found[0]
            self.note(f"locator-local-{loc.address}", f"locator {loc.address}:{loc.port} of a "
                      f"peer on this host (it spoke from {source[0]}): reached at "
                      f"{source[0]}:{loc.port}")
            return (source[0], loc.port)
        for loc in found:
            self.note(f"locator-{loc.address}", f"locator {loc.address}:{loc.port} ignored: the "
                      f"lab sends only to loopback or to the sender's own address")
        return None

    def _on_spdp(self, prefix: bytes, sub: Data, source: tuple[str, int], now: float) -> list[Send]:
        if not sub.payload or sub.key or self._status(sub.inline_qos, sub.little_endian) & 0x3:
            if prefix in self.participants:
                self.note(f"left-{prefix.hex()}", f"participant {prefix.hex()} said goodbye")
            self._forget(prefix)
            return []
        params, little = self._params(sub.payload, "SPDP")
        if params is None:
            return []
        guid = (params.get(b.PID_PARTICIPANT_GUID) or [b""])[0]
        if guid[:12] != prefix:
            self.note("spdp-spoof", f"SPDP from {prefix.hex()} announces participant "
                      f"{guid[:12].hex()}: ignored (a participant announces only itself)")
            return []
        known = self.participants.get(prefix)
        lease_raw = (params.get(b.PID_PARTICIPANT_LEASE_DURATION) or [struct.pack("<iI", 100, 0)])[0]
        sec, frac = struct.unpack("<iI" if little else ">iI", lease_raw[:8].ljust(8, b"\0"))
        lease = min(max(sec + frac / 2**32, 0.1), MAX_LEASE_SECONDS)
        if known is not None:
            known.last_seen, known.lease = now, lease
            return []
        if len(self.participants) >= MAX_REMOTE_PARTICIPANTS:
            self.note("participants-full", f"more than {MAX_REMOTE_PARTICIPANTS} remote "
                      f"participants: new ones are ignored until a lease runs out")
            return []
        meta = self._locator(params.get(b.PID_METATRAFFIC_UNICAST_LOCATOR), little, source)
        user = self._locator(params.get(b.PID_DEFAULT_UNICAST_LOCATOR), little, source)
        if meta is None or user is None:
            self.note(f"spdp-nolocator-{prefix.hex()}", f"SPDP of {prefix.hex()} has no usable "
                      f"unicast locator: ignored")
            return []
        name_raw = params.get(b.PID_ENTITY_NAME)
        name = b.cdr_string_value(name_raw[0], little) if name_raw else ""
        self.participants[prefix] = RemoteParticipant(prefix, meta, user, lease, now, name)
        self.note(f"participant-{prefix.hex()}", f"participant {prefix.hex()} ({name}) at "
                  f"{meta[0]}:{meta[1]}, lease {lease:g} s")
        out = [self._spdp(meta)]
        # the built-in SEDP endpoints: send ours, ask for theirs (preemptive ACKNACK)
        subs: list[bytes] = []
        for wid, rid in ((PUB_WRITER, PUB_READER), (SUB_WRITER, SUB_READER)):
            ep = self.local[wid]
            proxy = ReaderProxy(prefix, rid, meta, True, 1)
            ep.proxies[(prefix, rid)] = proxy
            for seq, payload in ep.history.items():
                subs += self._sample_subs(rid, wid, seq, payload)
            subs.append(self._heartbeat(ep, proxy))
        # Fast DDS answers a preemptive ACKNACK at once (a HEARTBEAT, then what we lack) only
        # in its own form, base 0 (which Cyclone DDS refuses from other vendors): without it,
        # SEDP data it sent before it knew us waits for its next periodic HEARTBEAT (~1 s)
        vendor = (params.get(b.PID_VENDORID) or [b""])[0][:2]
        base = 0 if vendor == b.VENDOR_EPROSIMA.to_bytes(2, "big") else 1
        for rid, wid in ((PUB_READER, PUB_WRITER), (SUB_READER, SUB_WRITER)):
            wp = WriterProxy(prefix, wid, True, 1)
            self.local[rid].proxies[(prefix, wid)] = wp
            subs.append(b.acknack(rid, wid, base, [], 1))
        out += self._msg(meta, prefix, subs)
        return out

    def _params(self, payload: bytes, what: str) -> tuple[dict[int, list[bytes]] | None, bool]:
        try:
            return parse_parameters(payload), payload[:2] == PL_CDR_LE
        except RtpsError as exc:
            self.note(f"bad-plist-{what}", f"{what} data not a parameter list ({exc}): ignored")
            return None, True

    # ---- SEDP ----------------------------------------------------------------------------
    def _on_sedp(self, prefix: bytes, kind: str, payload: bytes, inline_qos: bytes,
                 little_sub: bool) -> None:
        status = self._status(inline_qos, little_sub)
        params, little = self._params(payload, "SEDP") if payload[:2] in (PL_CDR_LE, PL_CDR_BE) \
            else ({}, True)
        if params is None:
            return
        guid = (params.get(b.PID_ENDPOINT_GUID) or [b""])[0][:16]
        if not guid and inline_qos:
            guid = (self._inline(inline_qos, little_sub).get(b.PID_KEY_HASH) or [b""])[0][:16]
        if len(guid) != 16 or guid[:12] != prefix:
            self.note("sedp-spoof", f"SEDP from {prefix.hex()} about endpoint {guid.hex()}: "
                      f"ignored (a participant announces only its own endpoints)")
            return
        if status & 0x3 or b.PID_TOPIC_NAME not in params:
            self._forget_endpoint(guid)
            return
        if guid not in self.remote and len(self.remote) >= MAX_REMOTE_ENDPOINTS:
            self.note("endpoints-full", f"more than {MAX_REMOTE_ENDPOINTS} remote endpoints: "
                      f"new ones are ignored")
            return
        order = "<" if little else ">"

        def u32(pid: int, at: int = 0) -> int | None:   # None: absent or too short
            value = (params.get(pid) or [b""])[0]
            return struct.unpack(order + "I", value[at:at + 4])[0] if len(value) >= at + 4 else None

        rel = u32(b.PID_RELIABILITY)
        reliable = rel == b.RELIABLE if rel is not None else kind == "writer"
        durability = u32(b.PID_DURABILITY) or b.VOLATILE
        depth = u32(b.PID_HISTORY, 4) or 1
        owner = self.participants.get(prefix)
        loc = self._locator(params.get(b.PID_UNICAST_LOCATOR), little,
                            owner.meta if owner else (self.address, 0)) \
            or (owner.user if owner else None)
        if loc is None:
            return
        rem = RemoteEndpoint(guid, kind, b.cdr_string_value(params[b.PID_TOPIC_NAME][0], little),
                             b.cdr_string_value((params.get(b.PID_TYPE_NAME) or [b""])[0], little),
                             Qos(reliable, depth, durability >= b.TRANSIENT_LOCAL), loc,
                             user_data_type_hash((params.get(b.PID_USER_DATA) or [b""])[0], little))
        self.remote[guid] = rem
        for ep in list(self.local.values()):
            if ep.topic:
                self._try_match(ep, rem)

    def _try_match(self, ep: LocalEndpoint, rem: RemoteEndpoint) -> None:
        if ep.kind == rem.kind or ep.topic != rem.topic:
            return
        key = (rem.guid[:12], int.from_bytes(rem.guid[12:], "big"))
        if key in ep.proxies:
            return
        what = f"{ep.kind} {ep.topic} ({ep.qos.describe()}) and remote {rem.kind} " \
               f"{rem.guid.hex()} ({rem.qos.describe()})"
        if ep.type_name != rem.type_name:
            self.note(f"type-{rem.guid.hex()}-{ep.entity_id}", f"not matched: {what}: type "
                      f"{rem.type_name} is not {ep.type_name}")
            return
        if len(ep.proxies) >= MAX_MATCHED_PER_ENDPOINT:
            self.note(f"matched-full-{ep.entity_id}", f"not matched: {what}: {ep.kind} {ep.topic} "
                      f"already has {MAX_MATCHED_PER_ENDPOINT} matched remote endpoints")
            return
        offered, requested = (ep.qos, rem.qos) if ep.kind == "writer" else (rem.qos, ep.qos)
        why = incompatibility(offered, requested)
        if why:
            self.note(f"qos-{rem.guid.hex()}-{ep.entity_id}", f"not matched: {what}: {why}")
            return
        if ep.type_hash and rem.type_hash and ep.type_hash != rem.type_hash:
            # rmw matches on the type name alone and only tells; so does the lab
            self.note(f"typehash-{rem.guid.hex()}-{ep.entity_id}",
                      f"type hash differs: {what}: remote {rem.type_name} announces "
                      f"{rem.type_hash}, ours is {ep.type_hash} (matched anyway, as ROS 2's rmw "
                      f"does; the two definitions of {rem.type_name} differ, e.g. another ROS 2 "
                      f"distribution's)")
        if ep.kind == "writer" and ep.qos.transient_local and rem.qos.transient_local and ep.history:
            # TRANSIENT_LOCAL both sides: a reader that joins late gets the history (KEEP_LAST
            # depth); a VOLATILE reader gets only what is written after it matched
            first = next(iter(ep.history))
            proxy = ReaderProxy(key[0], key[1], rem.locator, rem.qos.reliable, first, acked=first)
            ep.proxies[key] = proxy
            subs: list[bytes] = []
            for seq, payload in ep.history.items():
                subs += self._sample_subs(proxy.reader_id, ep.entity_id, seq, payload)
            if ep.qos.reliable and proxy.reliable:
                subs.append(self._heartbeat(ep, proxy))
            self._outbox += self._msg(proxy.locator, proxy.prefix, subs)
        elif ep.kind == "writer":
            ep.proxies[key] = ReaderProxy(key[0], key[1], rem.locator, rem.qos.reliable, ep.seq + 1,
                                          acked=ep.seq + 1)
        else:
            ep.proxies[key] = WriterProxy(key[0], key[1], rem.qos.reliable)
        self.note(f"match-{rem.guid.hex()}-{ep.entity_id}", f"matched: {what}")

    @staticmethod
    def _inline(raw: bytes, little: bool) -> dict[int, list[bytes]]:
        try:
            return parse_parameters((PL_CDR_LE if little else PL_CDR_BE) + b"\0\0" + raw)
        except RtpsError:
            return {}

    def _status(self, inline_qos: bytes, little: bool) -> int:
        if not inline_qos:
            return 0
        raw = self._inline(inline_qos, little).get(b.PID_STATUS_INFO)
        return int.from_bytes(raw[0][:4], "big") if raw else 0

    # ---- writing -------------------------------------------------------------------------
    def write(self, writer_id: int, payload: bytes, now: float = 0.0,
              stamp: float | None = None) -> list[Send]:
        """Send one serialized sample (encapsulation header first) on writer ``writer_id``
        (``now``: the clock :meth:`tick` gets; ``stamp``: the source time for INFO_TS)."""
        ep = self.local[writer_id]
        ep.seq += 1
        ep.history[ep.seq] = bytes(payload)
        while len(ep.history) > ep.qos.depth:
            ep.history.popitem(last=False)
        out: list[Send] = []
        for proxy in ep.proxies.values():
            assert isinstance(proxy, ReaderProxy)
            subs = [b.info_ts(now if stamp is None else stamp)] + self._sample_subs(proxy.reader_id, ep.entity_id, ep.seq, payload)
            if ep.qos.reliable and proxy.reliable:
                subs.append(self._heartbeat(ep, proxy))
                proxy.last_heartbeat = now
            out += self._msg(proxy.locator, proxy.prefix, subs)
        return out

    def _on_acknack(self, prefix: bytes, sub: AckNack, now: float) -> list[Send]:
        ep = self.local.get(sub.writer_id)
        proxy = ep.proxies.get((prefix, sub.reader_id)) if ep and ep.kind == "writer" else None
        if ep is None or not isinstance(proxy, ReaderProxy):
            self.note(f"acknack-unknown-{prefix.hex()}", f"ACKNACK from {prefix.hex()} for no "
                      f"matched reader of writer 0x{sub.writer_id:08x}: ignored")
            return []
        proxy.acked = min(max(proxy.acked, sub.base), ep.seq + 1)
        proxy.heartbeat_period = 0.0     # it answers: back to the short period
        if sub.count <= proxy.last_count:
            # a count already seen (RTPS 8.4.15.8): no retransmission. Its acknowledgement
            # still counts, so a spoofed high count cannot silence the real reader for good.
            self.note("acknack-dup", "ACKNACK with a count already seen: no retransmission")
            return []
        proxy.last_count = sub.count
        if sub.base == 0:
            # a preemptive ACKNACK (base 0, no bits: Fast DDS's form) asks for a HEARTBEAT
            return self._msg(proxy.locator, proxy.prefix, [self._heartbeat(ep, proxy)])
        # only what was written can be missing: later numbers are ignored, never GAPped
        missing = [s for s in sub.missing if s <= ep.seq]
        if len(missing) < len(sub.missing):
            self.note(f"acknack-future-{prefix.hex()}", f"ACKNACK from {prefix.hex()} asks for "
                      f"samples past {ep.seq}, the last written: those ignored")
        # what was written before a VOLATILE reader matched is not for it: GAP, never resend
        early = [s for s in missing if s < proxy.first_relevant]
        missing = [s for s in missing if s >= proxy.first_relevant]
        if early and not missing:
            return self._msg(proxy.locator, proxy.prefix,
                             [b.gap(proxy.reader_id, ep.entity_id, min(early), proxy.first_relevant),
                              self._heartbeat(ep, proxy)])
        if not missing:
            return []
        if now - proxy.last_resend < MIN_RESEND_SECONDS:
            self.note("acknack-storm", f"ACKNACKs from {prefix.hex()} faster than one per "
                      f"{MIN_RESEND_SECONDS} s: retransmissions paced")
            return []
        proxy.last_resend = now
        subs: list[bytes] = []
        gone = [s for s in missing if s not in ep.history]
        for s in missing:
            if s in ep.history:
                subs += self._sample_subs(proxy.reader_id, ep.entity_id, s, ep.history[s])
        if gone:
            # everything asked for that left the history (or never was) will never come
            subs.insert(0, b.gap(proxy.reader_id, ep.entity_id, min(gone), max(gone) + 1)
                        if len(gone) == max(gone) - min(gone) + 1 else
                        b.gap(proxy.reader_id, ep.entity_id, min(gone),
                              next(iter(ep.history), ep.seq + 1)))
        if early:
            subs.insert(0, b.gap(proxy.reader_id, ep.entity_id, min(early), proxy.first_relevant))
        subs.append(self._heartbeat(ep, proxy))
        return self._msg(proxy.locator, proxy.prefix, subs)

    def _on_nackfrag(self, prefix: bytes, sub: NackFrag, now: float) -> list[Send]:
        ep = self.local.get(sub.writer_id)
        proxy = ep.proxies.get((prefix, sub.reader_id)) if ep and ep.kind == "writer" else None
        if ep is None or not isinstance(proxy, ReaderProxy) or sub.count <= proxy.last_frag_count:
            return []
        proxy.last_frag_count = sub.count
        payload = ep.history.get(sub.seq)
        if sub.seq > ep.seq or sub.seq < 1:
            return []          # never written: nothing to resend, nothing to GAP
        if payload is None:
            return self._msg(proxy.locator, proxy.prefix,
                             [b.gap(proxy.reader_id, ep.entity_id, sub.seq, sub.seq + 1)])
        return self._msg(proxy.locator, proxy.prefix,
                         self._sample_subs(proxy.reader_id, ep.entity_id, sub.seq, payload,
                                           list(sub.missing)))

    # ---- reading -------------------------------------------------------------------------
    def _readers_of(self, prefix: bytes, writer_id: int, reader_id: int) -> list[tuple[LocalEndpoint, WriterProxy]]:
        found = []
        for ep in self.local.values():
            if ep.kind != "reader" or (reader_id and ep.entity_id != reader_id):
                continue
            wp = ep.proxies.get((prefix, writer_id))
            if isinstance(wp, WriterProxy):
                found.append((ep, wp))
        return found

    def _deliver(self, ep: LocalEndpoint, wp: WriterProxy, seq: int, payload: bytes | None) -> None:
        if payload is None:
            return
        if ep.entity_id in (PUB_READER, SUB_READER):
            return   # SEDP samples are handled on arrival
        self.samples.append(Sample(ep.entity_id, wp.prefix + wp.writer_id.to_bytes(4, "big"),
                                   seq, b.unpad_payload(payload)))
        mine = sum(1 for s in self.samples if s.reader_id == ep.entity_id)
        if mine > ep.qos.depth:
            for i, s in enumerate(self.samples):
                if s.reader_id == ep.entity_id:
                    del self.samples[i]
                    self.note(f"overrun-{ep.entity_id}", f"reader {ep.topic}: samples not taken "
                              f"beyond KEEP_LAST {ep.qos.depth}: the oldest dropped")
                    break

    def _on_sample(self, prefix: bytes, reader_id: int, writer_id: int, seq: int,
                   payload: bytes, inline_qos: bytes, little: bool) -> None:
        if writer_id in (PUB_WRITER, SUB_WRITER):
            sedp_reader = PUB_READER if writer_id == PUB_WRITER else SUB_READER
            if (prefix, writer_id) in self.local[sedp_reader].proxies:
                self._on_sedp(prefix, "writer" if writer_id == PUB_WRITER else "reader",
                              payload, inline_qos, little)
        for ep, wp in self._readers_of(prefix, writer_id, reader_id):
            if seq < 1:
                continue
            if not wp.reliable or not ep.qos.reliable:
                if seq >= wp.next:       # best effort: anything newer, in arrival order
                    wp.next = seq + 1
                    self._deliver(ep, wp, seq, payload)
                continue
            if wp.next == 0:
                wp.next = seq
            if seq < wp.next or seq in wp.pending:
                continue
            if seq == wp.next:
                self._deliver(ep, wp, seq, payload)
                wp.next += 1
                self._drain(ep, wp)
            elif len(wp.pending) < MAX_OUT_OF_ORDER and \
                    wp.pending_bytes + len(payload) <= MAX_OUT_OF_ORDER_BYTES and seq < wp.next + 256:
                wp.pending[seq] = payload
                wp.pending_bytes += len(payload)
            else:
                self.note(f"ooo-full-{ep.entity_id}", f"reader {ep.topic or 'SEDP'}: out-of-order "
                          f"samples beyond {MAX_OUT_OF_ORDER}: later ones asked again")

    def _drain(self, ep: LocalEndpoint, wp: WriterProxy) -> None:
        while True:
            if wp.next in wp.pending:
                payload = wp.pending.pop(wp.next)
                wp.pending_bytes -= len(payload or b"")
                self._deliver(ep, wp, wp.next, payload)
                wp.next += 1
                continue
            end = max((e for s, e in wp.gaps.items() if s <= wp.next < e), default=0)
            for s in [s for s, e in wp.gaps.items() if e <= max(end, wp.next + 1)]:
                del wp.gaps[s]           # reached (or passed): forgotten
            if not end:
                return
            self._advance(wp, end)

    def _advance(self, wp: WriterProxy, first: int) -> None:
        """Samples from ``wp.next`` to before ``first`` will never come: drop what is held."""
        for s in [s for s in wp.pending if s < first]:
            wp.pending_bytes -= len(wp.pending.pop(s) or b"")
        for s in range(wp.next, min(first, wp.next + 256)):
            self.assembler.discard(wp.prefix, wp.writer_id, s)
        wp.next = first

    def _skip_to(self, ep: LocalEndpoint, wp: WriterProxy, first: int) -> None:
        """Samples before ``first`` will never come."""
        if first <= wp.next:
            return
        self._advance(wp, first)
        self._drain(ep, wp)

    @staticmethod
    def _gapped(wp: WriterProxy, seq: int) -> bool:
        return any(s <= seq < e for s, e in wp.gaps.items())

    def _on_gap(self, prefix: bytes, sub: Gap) -> None:
        for ep, wp in self._readers_of(prefix, sub.writer_id, sub.reader_id):
            if wp.next == 0:
                continue
            if sub.start <= wp.next < sub.list_base:
                self._skip_to(ep, wp, sub.list_base)
            elif wp.next < sub.start < sub.list_base:
                # a later range (RTPS 2.3 8.3.7.4: gapStart .. gapList.base - 1 are irrelevant):
                # remembered until delivery gets there, never asked for again
                if sub.start in wp.gaps or len(wp.gaps) < MAX_OUT_OF_ORDER:
                    wp.gaps[sub.start] = max(sub.list_base, wp.gaps.get(sub.start, 0))
                else:
                    self.note(f"gaps-full-{ep.entity_id}", f"reader {ep.topic or 'SEDP'}: more "
                              f"than {MAX_OUT_OF_ORDER} GAP ranges ahead of delivery: later ones "
                              f"asked again")
            for s in sub.listed:
                if s >= wp.next and s not in wp.pending and len(wp.pending) < MAX_OUT_OF_ORDER:
                    wp.pending[s] = None
            self._drain(ep, wp)

    def _on_heartbeat(self, prefix: bytes, sub: Heartbeat) -> list[Send]:
        out: list[Send] = []
        for ep, wp in self._readers_of(prefix, sub.writer_id, sub.reader_id):
            if not wp.reliable or not ep.qos.reliable or sub.count <= wp.last_hb_count:
                continue
            wp.last_hb_count = sub.count
            if wp.next == 0:
                wp.next = sub.first if ep.topic == "" else max(sub.first, 1)
            if sub.first > wp.next:
                self._skip_to(ep, wp, sub.first)
            top = min(sub.last, wp.next + 255)
            missing = [s for s in range(wp.next, top + 1)
                       if s not in wp.pending and not self._gapped(wp, s)]
            # RTPS 2.3 8.4.12.2 (the reliable reader's HEARTBEAT transitions): F (final) not set:
            # an ACKNACK must go; F set: only when something is missing; F and L (liveliness)
            # both set: none (a liveliness assertion asks for nothing). Cyclone DDS piggybacks
            # final HEARTBEATs on its data and answers only those without F itself.
            if sub.final and (sub.liveliness or not missing):
                continue
            partial = set(self.assembler.partial(prefix, sub.writer_id))
            subs: list[bytes] = []
            wp.acknack_count += 1
            subs.append(b.acknack(ep.entity_id, sub.writer_id, wp.next,
                                  [s for s in missing if s not in partial], wp.acknack_count,
                                  final=not missing))
            for s in sorted(partial & set(missing))[:8]:
                frags = self.assembler.missing(prefix, sub.writer_id, s)[:256]
                if frags:
                    wp.nackfrag_count += 1
                    subs.append(b.nack_frag(ep.entity_id, sub.writer_id, s, frags, wp.nackfrag_count))
            owner = self.participants.get(prefix)
            if owner is not None:
                out += self._msg(owner.meta if not ep.topic else owner.user, prefix, subs)
        return out

    def _on_heartbeat_frag(self, prefix: bytes, sub: HeartbeatFrag) -> list[Send]:
        out: list[Send] = []
        for ep, wp in self._readers_of(prefix, sub.writer_id, sub.reader_id):
            frags = self.assembler.missing(prefix, sub.writer_id, sub.seq, sub.last_frag)[:256]
            owner = self.participants.get(prefix)
            if frags and owner is not None and wp.reliable:
                wp.nackfrag_count += 1
                out += self._msg(owner.user, prefix, [b.nack_frag(ep.entity_id, sub.writer_id,
                                                                  sub.seq, frags, wp.nackfrag_count)])
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
        for prefix, destination, sub in msg.routed():
            if isinstance(sub, (InfoDst, InfoSrc)) or prefix == self.guid_prefix or \
                    destination not in (self.guid_prefix, ANY_PARTICIPANT):
                continue
            if prefix not in self.participants and not (
                    isinstance(sub, Data) and sub.writer_id == SPDP_WRITER):
                self.note(f"unknown-{prefix.hex()}", f"submessages from participant "
                          f"{prefix.hex()} before its SPDP: ignored")
                continue
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

    def _take_outbox(self) -> list[Send]:
        out, self._outbox = self._outbox, []
        return out

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
