"""SEDP, the Simple Endpoint Discovery Protocol: the participant's writers and readers told to its
peers, the peers' ones learnt and matched.

How this works: each local user endpoint becomes one sample of a built-in SEDP writer
(publications for writers, subscriptions for readers): ``_announce_endpoint`` puts it in that
writer's history, which the reliable writer side delivers to every known participant. The peers'
SEDP samples come in through the built-in SEDP readers; ``_on_sedp`` reads one (topic, type,
reliability, durability, history depth, unicast locator, the type hash in USER_DATA) into a
:class:`~rosfpga_lab.rtps.entities.RemoteEndpoint`, or forgets the endpoint when the sample
disposes of it (``_forget_endpoint``). A participant announces only its own endpoints: a sample
about another's is ignored. ``_try_match`` pairs a local and a remote endpoint of opposite kinds on
one topic when the type names are equal, the local endpoint has room for another proxy and the QoS
are compatible (RxO: :func:`~rosfpga_lab.rtps.entities.incompatibility`); otherwise it logs the
reason once. A matched writer gets a ``ReaderProxy`` (TRANSIENT_LOCAL on both sides: its history
goes to the late reader at once, through the outbox), a matched reader a ``WriterProxy``. A
differing ROS 2 type hash is logged once and matched all the same, as rmw does.
"""

from __future__ import annotations

import struct

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.discovery import PL_CDR_BE, PL_CDR_LE, user_data_type_hash
from rosfpga_lab.rtps.entities import (
    PUB_WRITER, SUB_WRITER, LocalEndpoint, Qos, ReaderProxy, RemoteEndpoint, WriterProxy,
    incompatibility,
)
from rosfpga_lab.rtps.limits import MAX_MATCHED_PER_ENDPOINT, MAX_REMOTE_ENDPOINTS
from rosfpga_lab.rtps.participant_base import ParticipantBase


class EndpointDiscovery(ParticipantBase):
    """SEDP: announcing the local endpoints, learning the remote ones, matching them."""

    def _announce_endpoint(self, ep: LocalEndpoint) -> None:
        sedp = self.local[PUB_WRITER if ep.kind == "writer" else SUB_WRITER]
        self._keep(sedp, b.sedp_payload(self.guid_prefix + ep.guid_tail, ep.topic, ep.type_name,
                                        ep.qos.reliable, ep.qos.depth,
                                        b.Locator(*(ep.locator or self.user)),
                                        ep.qos.transient_local, ep.type_hash))
        for rem in list(self.remote.values()):
            self._try_match(ep, rem)

    def _forget_endpoint(self, guid: bytes) -> None:
        rem = self.remote.pop(guid, None)
        if rem is None:
            return
        key = (guid[:12], int.from_bytes(guid[12:], "big"))
        for ep in self.local.values():
            if ep.topic and ep.proxies.pop(key, None) is not None:
                self.note(f"unmatch-{guid.hex()}-{ep.entity_id}",
                          f"{ep.kind} {ep.topic}: remote {rem.kind} {guid.hex()} left")

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
            proxy = ReaderProxy(key[0], key[1], rem.locator, rem.qos.reliable, first, acked=first,
                                credit=ep.history_bytes)
            ep.proxies[key] = proxy
            subs: list[bytes] = []
            for seq, payload in ep.history.items():
                subs += self._sample_subs(proxy.reader_id, ep.entity_id, seq, payload)
            if ep.qos.reliable and proxy.reliable:
                subs.append(self._heartbeat(ep, proxy))
            self._outbox += self._msg(proxy.locator, proxy.prefix, subs)
        elif ep.kind == "writer":
            ep.proxies[key] = ReaderProxy(key[0], key[1], rem.locator, rem.qos.reliable, ep.seq + 1,
                                          acked=ep.seq + 1, credit=ep.history_bytes)
        else:
            ep.proxies[key] = WriterProxy(key[0], key[1], rem.qos.reliable)
        self.note(f"match-{rem.guid.hex()}-{ep.entity_id}", f"matched: {what}")
