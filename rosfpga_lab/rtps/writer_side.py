"""The writer side of a participant: samples out, and the reliable protocol that sees them arrive.

How this works: :meth:`WriterSide.write` keeps the sample in its writer's history (KEEP_LAST
``depth``: the oldest goes) and sends it, after an INFO_TS, as DATA or DATA_FRAGs to every matched
reader, with a HEARTBEAT (the first and last sequence numbers held) to the reliable ones. A
reliable reader answers with an ACKNACK: its base acknowledges everything before it, its bits name
the samples it lacks. ``_on_acknack`` resends those still in the history, GAPs those that left it
(and those written before a VOLATILE reader matched), ignores numbers never written, and paces
resends; an ACKNACK count already seen is not answered again (RTPS 2.3 8.4.15.8), and a
preemptive ACKNACK (base 0, Fast DDS's form) gets a HEARTBEAT. ``_on_nackfrag`` resends the
fragments a NACK_FRAG names (a count already seen: none), or GAPs a sample no longer held. Both
pace their resends per reader proxy (``_paced``: MIN_RESEND_SECONDS apart, each sample's
fragments apart from the others'). The periodic HEARTBEATs
(their period doubling up to MAX_HEARTBEAT_SECONDS until the reader answers) go out from
``Participant.tick``.
"""

from __future__ import annotations

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import ReaderProxy, Send
from rosfpga_lab.rtps.limits import MIN_RESEND_SECONDS
from rosfpga_lab.rtps.message import AckNack, NackFrag
from rosfpga_lab.rtps.participant_base import ParticipantBase


class WriterSide(ParticipantBase):
    """Writing samples, and a reliable writer's answers to ACKNACK and NACK_FRAG."""

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

    def _paced(self, proxy: ReaderProxy, seq: int, now: float, oldest: int = 0) -> bool:
        """Whether a retransmission asked of ``proxy`` must wait: ``seq`` 0 for what an ACKNACK
        asks, else the fragments of sample ``seq`` a NACK_FRAG asks.

        Each is let through at most once per MIN_RESEND_SECONDS, else a peer raising its count
        gets every resend it asks for (a request of a few bytes in, whole samples or fragments
        out); paced ones are counted, logged once per kind. ACKNACK and each sample's NACK_FRAG
        are paced apart: a reader asks for several in one datagram (Cyclone DDS: an ACKNACK for
        the whole samples it lacks and a NACK_FRAG for the first partly received one; the lab's
        reader: NACK_FRAGs for up to 8 samples), and what it may get per interval stays bounded
        by the history, as an ACKNACK's resend is. Samples before ``oldest`` (no longer held)
        are forgotten."""
        if now - proxy.resent.get(seq, -1.0) < MIN_RESEND_SECONDS:
            kind = "NACK_FRAG" if seq else "ACKNACK"
            self.note(f"{kind.replace('_', '').lower()}-storm", f"{kind}s from "
                      f"{proxy.prefix.hex()} faster than one per {MIN_RESEND_SECONDS} s: "
                      f"retransmissions paced")
            return True
        for gone in [s for s in proxy.resent if 0 < s < oldest]:
            del proxy.resent[gone]
        proxy.resent[seq] = now
        return False

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
        if not missing or self._paced(proxy, 0, now):
            return []
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
        if not sub.missing or self._paced(proxy, sub.seq, now, next(iter(ep.history))):
            return []
        return self._msg(proxy.locator, proxy.prefix,
                         self._sample_subs(proxy.reader_id, ep.entity_id, sub.seq, payload,
                                           list(sub.missing)))
