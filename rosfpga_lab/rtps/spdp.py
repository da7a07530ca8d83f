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

The table holds MAX_REMOTE_PARTICIPANTS and never stops learning: a new participant in a full
table takes the place of the one of lowest standing (``_standing``, ``_evict``): first those that
sent nothing but SPDP, the one learned first going first (re-announcing does not help it); then
those that spoke (SEDP, HEARTBEATs, ...) but have no endpoint matched with a local one, then
matched ones, each the one heard from least recently going first. What an SPDP flood from random
GUID prefixes can still do, at R announcements a second: make the table forget a new peer that
has not spoken within MAX_REMOTE_PARTICIPANTS - (peers that spoke) new prefixes, i.e. about
64 / R s (a ROS 2 peer answers our SPDP with SEDP within milliseconds on one host; one forgotten
is learned again at its next SPDP); keep every learned fake's lease (up to MAX_LEASE_SECONDS);
and make the participant answer each new fake with its SPDP and SEDP data (a few KB) sent to a
locator on loopback or at the sender's own address (``_locator``). To evict a peer that spoke
or is matched it must make MAX_REMOTE_PARTICIPANTS fakes speak (or match the lab's topics) and
keep them heard from more recently than that peer.
"""

from __future__ import annotations

import struct

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    PARTICIPANT_ENTITY, PUB_READER, PUB_WRITER, SPDP_READER, SPDP_WRITER, SUB_READER, SUB_WRITER,
    ReaderProxy, RemoteParticipant, Send, WriterProxy, discovery_port,
)
from rosfpga_lab.rtps.limits import (
    DEFAULT_LEASE_SECONDS, MAX_LEASE_SECONDS, MAX_PARTICIPANT_INDEX, MAX_REMOTE_PARTICIPANTS,
    MIN_LEASE_SECONDS,
)
from rosfpga_lab.rtps.message import Data
from rosfpga_lab.rtps.sedp import EndpointDiscovery


class ParticipantDiscovery(EndpointDiscovery):
    """SPDP: announcing this participant, learning and forgetting the remote ones."""

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

    def _standing(self, p: RemoteParticipant) -> tuple[int, float]:
        """What keeps ``p`` in a full table, lowest first: 0 and when it was learned, if it
        sent nothing but SPDP; 1 and when it was last heard, if it spoke but none of its
        endpoints is matched with a local user endpoint; 2 and when it was last heard, if one is."""
        if any(key[0] == p.prefix for ep in self.local.values() if ep.topic for key in ep.proxies):
            return (2, p.last_seen)
        return (1, p.last_seen) if p.spoke else (0, p.learned)

    def _evict(self) -> None:
        """Make room for a new participant in a full table: forget the one of lowest standing."""
        victim = min(self.participants.values(), key=self._standing)
        self.note("participants-evict", f"more than {MAX_REMOTE_PARTICIPANTS} remote "
                  f"participants: the one of lowest standing makes room for each new one (first "
                  f"{victim.prefix.hex()}, {'matched' if self._standing(victim)[0] == 2 else 'unmatched'})")
        self._forget(victim.prefix)

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
        name_raw = params.get(b.PID_ENTITY_NAME)
        name = b.cdr_string_value(name_raw[0], little) if name_raw else ""
        self.participants[prefix] = RemoteParticipant(prefix, meta, user, lease, now, name, now)
        if not full:
            self.note(f"participant-{prefix.hex()}", f"participant {prefix.hex()} ({name}) at "
                      f"{meta[0]}:{meta[1]}, lease {lease:g} s")
        out = [self._spdp(meta)]
        # the built-in SEDP endpoints: send ours, ask for theirs (preemptive ACKNACK)
        subs: list[bytes] = []
        for wid, rid in ((PUB_WRITER, PUB_READER), (SUB_WRITER, SUB_READER)):
            ep = self.local[wid]
            proxy = ReaderProxy(prefix, rid, meta, True, 1, credit=ep.history_bytes)
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
