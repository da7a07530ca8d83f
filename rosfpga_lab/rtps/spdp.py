"""SPDP, the Simple Participant Discovery Protocol: participants find each other and keep each
other alive.

How this works: :meth:`ParticipantDiscovery.announce` sends this participant's SPDP sample (GUID,
metatraffic and user unicast locators, lease, name, ``enclave=/;`` user data) to the discovery
ports of indices 0..MAX_PARTICIPANT_INDEX on every peer address (no multicast) and to every
participant it knows; ``Participant.tick`` repeats it every announce period and forgets a
participant whose lease ran out. ``_on_spdp`` learns a new participant (reached at a loopback
locator or at its own address: ``_locator``), answers with its own SPDP sample and starts SEDP
with it: the built-in SEDP writers send it their history and a HEARTBEAT, the built-in SEDP
readers a preemptive ACKNACK (base 0 for Fast DDS, which answers only that form at once). A known
participant's SPDP sample renews its lease (one that announces none gets RTPS's default,
DEFAULT_LEASE_SECONDS; any is held within MIN_LEASE_SECONDS..MAX_LEASE_SECONDS). One that says
goodbye (:meth:`goodbye` sends ours: an SPDP sample disposed and unregistered) or whose lease runs
out is forgotten with its endpoints, its proxies and its partly received samples (``_forget``).
An SPDP sample about another participant than its sender is ignored.

A goodbye is easy to spoof (GUID prefixes are not secret), so two rules (``_on_goodbye``,
``_relearn``): a goodbye from a source that is neither where the participant's first SPDP came
from nor one of its locators is suspect: the participant stays, its lease cut to
SUSPECT_GOODBYE_LEASE_SECONDS (its traffic keeps renewing it; silent, it goes). A goodbye from
there forgets it at once, but keeps what it left (``departed``: its record, its endpoints, our
SEDP readers' state of its SEDP writers; bounded), and when its traffic goes on later than
GOODBYE_GRACE_SECONDS after the goodbye (what was in flight does not count) and within its lease,
it is learned again from that: its endpoints matched again, our SPDP sent to it (a peer that
answers a new participant's SPDP announces itself again) with our SEDP data. A participant
evicted from a full table is kept the same way, so one that speaks after its eviction is back at
once. What a spoofer of both GUID prefix and source port can still do: make the participant
forget a peer for GOODBYE_GRACE_SECONDS plus the time to its next datagram, as often as it sends
goodbyes.

The table holds MAX_REMOTE_PARTICIPANTS and never stops learning: a new participant in a full
table takes the place of the one of lowest standing (``_standing``, ``_evict``): first those with
no endpoint matched with a local one, the one whose last sign of life other than an SPDP
re-announcement (being learned, or sending SEDP, HEARTBEATs, data...) is oldest going first;
then matched ones, the one heard from least recently going first. What an SPDP flood from random
GUID prefixes can still do, at R new prefixes a second: make the table forget a new peer that
has not spoken within MAX_REMOTE_PARTICIPANTS - (matched peers) new prefixes, about 64 / R s (a
ROS 2 peer answers our SPDP with SEDP within milliseconds on one host, and one evicted that
speaks is learned again at once: ``_relearn``); shorten that by making its fakes speak too, one
datagram per fake after the newcomer arrived; keep each fake's lease (up to MAX_LEASE_SECONDS)
while the table is not full; and make the participant answer each new fake with its SPDP and
SEDP data (a few KB) sent to a locator on loopback or at the sender's own address
(``_locator``). Each flood SPDP costs about 60 us. To evict a matched peer it must match
MAX_REMOTE_PARTICIPANTS fakes with the lab's topics and keep them heard from more recently than
that peer.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    PARTICIPANT_ENTITY, PUB_READER, PUB_WRITER, SPDP_READER, SPDP_WRITER, SUB_READER, SUB_WRITER,
    Departed, ReaderProxy, RemoteParticipant, Send, WriterProxy, discovery_port,
)
from rosfpga_lab.rtps.limits import (
    DEFAULT_LEASE_SECONDS, GOODBYE_GRACE_SECONDS, MAX_LEASE_SECONDS, MAX_PARTICIPANT_INDEX,
    MAX_REMOTE_ENDPOINTS, MAX_REMOTE_PARTICIPANTS, MIN_LEASE_SECONDS, SUSPECT_GOODBYE_LEASE_SECONDS,
)
from rosfpga_lab.rtps.message import Data
from rosfpga_lab.rtps.sedp import EndpointDiscovery


class ParticipantDiscovery(EndpointDiscovery):
    """SPDP: announcing this participant, learning and forgetting the remote ones."""

    def spdp_payload(self) -> bytes:
        return b.spdp_payload(self.guid_prefix, b.Locator(*self.meta), b.Locator(*self.user),
                              self.lease, self.name, b"enclave=/;", self.domain)

    def _spdp(self, dst: tuple[str, int]) -> Send:
        key = (self.guid_prefix, self.lease, self.name, self.meta, self.user, self.domain)
        if self._spdp_msg[0] != key:       # built once (it is sent to every peer, every period)
            self._spdp_msg = (key, b.header(self.guid_prefix) + b.info_ts(0.0)
                              + b.data(SPDP_READER, SPDP_WRITER, 1, self.spdp_payload()))
        return (dst[0], dst[1], self._spdp_msg[1])

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

    def _standing(self) -> Callable[[RemoteParticipant], tuple[int, float]]:
        """What keeps a participant in a full table, lowest first: 0 and the later of when it
        was learned and when it last sent something besides SPDP, if none of its endpoints is
        matched with a local user endpoint (re-announcing its SPDP does not help it); 1 and when
        it was last heard, if one is."""
        matched = {key[0] for ep in self.local.values() if ep.topic for key in ep.proxies}

        def standing(p: RemoteParticipant) -> tuple[int, float]:
            return (1, p.last_seen) if p.prefix in matched else (0, max(p.learned, p.spoke))
        return standing

    def _evict(self) -> None:
        """Make room for a new participant in a full table: forget the one of lowest standing."""
        standing = self._standing()
        victim = min(self.participants.values(), key=standing)
        self.note("participants-evict", f"more than {MAX_REMOTE_PARTICIPANTS} remote "
                  f"participants: the one of lowest standing makes room for each new one (first "
                  f"{victim.prefix.hex()}, {'matched' if standing(victim)[0] else 'unmatched'})")
        self._depart(victim, -1e9, victim.last_seen + victim.lease)

    def _depart(self, p: RemoteParticipant, relearn_from: float, until: float) -> None:
        """Forget ``p``, keeping what learns it again in :attr:`departed` (bounded: at most
        MAX_REMOTE_PARTICIPANTS records and MAX_REMOTE_ENDPOINTS endpoints, the oldest go)."""
        endpoints = [rem for guid, rem in self.remote.items() if guid[:12] == p.prefix]
        sedp = {key: wp for rid in (PUB_READER, SUB_READER)
                for key, wp in self.local[rid].proxies.items()
                if key[0] == p.prefix and isinstance(wp, WriterProxy)}
        self._forget(p.prefix)
        self.departed.pop(p.prefix, None)
        self.departed[p.prefix] = Departed(p, endpoints, sedp, relearn_from, until)
        while len(self.departed) > MAX_REMOTE_PARTICIPANTS or \
                sum(len(d.endpoints) for d in self.departed.values()) > MAX_REMOTE_ENDPOINTS:
            self.departed.popitem(last=False)

    def _relearn(self, prefix: bytes, now: float) -> list[Send]:
        """Participant ``prefix`` left (goodbye, eviction) but its traffic goes on: learn it
        again from what it left, with its endpoints (matched again) and our SEDP readers where
        they were (its SEDP writers need send nothing again); send it our SPDP (as to a new
        participant: one that answers a new participant's SPDP announces itself) and our SEDP
        data. [] if it is not one to learn again (unknown, too early, too late)."""
        d = self.departed.get(prefix)
        if d is None or not d.relearn_from <= now <= d.until:
            return []
        del self.departed[prefix]
        if len(self.participants) >= MAX_REMOTE_PARTICIPANTS:
            self._evict()
        p = d.participant
        self.participants[prefix] = RemoteParticipant(prefix, p.meta, p.user, p.lease, now, p.name,
                                                      now, now, p.source, p.preemptive_base)
        self.note(f"back-{prefix.hex()}", f"participant {prefix.hex()} ({p.name}) left but its "
                  f"traffic goes on: learned again, our SPDP sent to {p.meta[0]}:{p.meta[1]}")
        out = self._greet(self.participants[prefix])
        for key, wp in d.sedp.items():           # where they were, not at sample 1 again
            self.local[PUB_READER if key[1] == PUB_WRITER else SUB_READER].proxies[key] = wp
        for rem in d.endpoints:
            if len(self.remote) < MAX_REMOTE_ENDPOINTS:
                self.remote[rem.guid] = rem
                for ep in list(self.local.values()):
                    if ep.topic:
                        self._try_match(ep, rem)
        return out + self._take_outbox()

    def _on_goodbye(self, prefix: bytes, source: tuple[str, int], now: float) -> None:
        known = self.participants.get(prefix)
        if known is None:
            self._forget(prefix)
            return
        if source not in (known.source, known.meta, known.user):
            # another address than its own: maybe a spoof. Its traffic keeps it alive; silent,
            # it goes soon
            known.lease = min(known.lease, SUSPECT_GOODBYE_LEASE_SECONDS)
            self.note(f"goodbye-suspect-{prefix.hex()}", f"goodbye of participant {prefix.hex()} "
                      f"from {source[0]}:{source[1]}, not where it spoke from: its lease cut to "
                      f"{SUSPECT_GOODBYE_LEASE_SECONDS:g} s (its traffic keeps it)")
            return
        self.note(f"left-{prefix.hex()}", f"participant {prefix.hex()} said goodbye")
        self._depart(known, now + GOODBYE_GRACE_SECONDS, now + known.lease)

    def _on_spdp(self, prefix: bytes, sub: Data, source: tuple[str, int], now: float) -> list[Send]:
        if not sub.payload or sub.key or self._status(sub.inline_qos, sub.little_endian) & 0x3:
            self._on_goodbye(prefix, source, now)
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
        lease_raw = params.get(b.PID_PARTICIPANT_LEASE_DURATION)
        if lease_raw:
            sec, frac = struct.unpack("<iI" if little else ">iI", lease_raw[0][:8].ljust(8, b"\0"))
            announced = sec + frac / 2**32
        else:
            announced = DEFAULT_LEASE_SECONDS    # a value, so either byte order gets it
        lease = min(max(announced, MIN_LEASE_SECONDS), MAX_LEASE_SECONDS)
        if known is not None:
            known.last_seen, known.lease = now, lease
            return []
        meta = self._locator(params.get(b.PID_METATRAFFIC_UNICAST_LOCATOR), little, source)
        user = self._locator(params.get(b.PID_DEFAULT_UNICAST_LOCATOR), little, source)
        if meta is None or user is None:
            self.note(f"spdp-nolocator-{prefix.hex()}", f"SPDP of {prefix.hex()} has no usable "
                      f"unicast locator: ignored")
            return []
        full = len(self.participants) >= MAX_REMOTE_PARTICIPANTS
        if full:
            self._evict()      # its note stands for the new one's (a flood fills no notes)
        self.departed.pop(prefix, None)
        name_raw = params.get(b.PID_ENTITY_NAME)
        name = b.cdr_string_value(name_raw[0], little) if name_raw else ""
        # Fast DDS answers a preemptive ACKNACK at once (a HEARTBEAT, then what we lack) only
        # in its own form, base 0 (which Cyclone DDS refuses from other vendors): without it,
        # SEDP data it sent before it knew us waits for its next periodic HEARTBEAT (~1 s)
        vendor = (params.get(b.PID_VENDORID) or [b""])[0][:2]
        base = 0 if vendor == b.VENDOR_EPROSIMA.to_bytes(2, "big") else 1
        p = self.participants[prefix] = RemoteParticipant(prefix, meta, user, lease, now, name, now,
                                                          -1e9, source, base)
        if not full:
            self.note(f"participant-{prefix.hex()}", f"participant {prefix.hex()} ({name}) at "
                      f"{meta[0]}:{meta[1]}, lease {lease:g} s")
        return self._greet(p)

    def _greet(self, p: RemoteParticipant) -> list[Send]:
        """What a participant just learned gets: our SPDP, and SEDP started with it (our SEDP
        writers send it their history and a HEARTBEAT, our SEDP readers a preemptive ACKNACK)."""
        out = [self._spdp(p.meta)]
        subs: list[bytes] = []
        for wid, rid in ((PUB_WRITER, PUB_READER), (SUB_WRITER, SUB_READER)):
            ep = self.local[wid]
            proxy = ReaderProxy(p.prefix, rid, p.meta, True, 1, credit=ep.history_bytes)
            ep.proxies[(p.prefix, rid)] = proxy
            for seq, payload in ep.history.items():
                subs += self._sample_subs(rid, wid, seq, payload)
            subs.append(self._heartbeat(ep, proxy))
        for rid, wid in ((PUB_READER, PUB_WRITER), (SUB_READER, SUB_WRITER)):
            self.local[rid].proxies[(p.prefix, wid)] = WriterProxy(p.prefix, wid, True, 1)
            subs.append(b.acknack(rid, wid, p.preemptive_base, [], self._next_count()))
        out += self._msg(p.meta, p.prefix, subs)
        return out
