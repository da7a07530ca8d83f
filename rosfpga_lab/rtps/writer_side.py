"""The writer side of a participant: samples out, and the reliable protocol that sees them arrive.

How this works: :meth:`WriterSide.write` keeps the sample in its writer's history (KEEP_LAST
``depth``: the oldest goes; ``_keep``) and sends it, after an INFO_TS, as DATA or DATA_FRAGs to
every matched reader, with a HEARTBEAT (the first and last sequence numbers held) to the reliable
ones. A reliable reader answers with an ACKNACK: its base acknowledges everything before it, its
bits name the samples it lacks. ``_on_acknack`` resends those it may get and GAPs the others;
``_on_nackfrag`` does the same for the fragments a NACK_FRAG names. The rules, in order:

* an ACKNACK or NACK_FRAG count already seen is not answered again (RTPS 2.3 8.4.15.8); a
  preemptive ACKNACK (base 0, Fast DDS's form) gets a HEARTBEAT; numbers never written are
  ignored, never GAPped;
* pacing (``_paced``): a reader proxy gets retransmissions at most once per MIN_RESEND_SECONDS,
  an ACKNACK's and each sample's NACK_FRAG's apart;
* ``_floor``: a sample written before a VOLATILE reader matched, one that left the history, and
  one the reader already acknowledged (below the highest ACKNACK base it sent) are never resent:
  one GAP names them. So ACKNACKs in the real reader's name, asking again for what it has, get a
  GAP of a few bytes each, never the samples (issue 30: 10,000 of them pulled 218 MB);
* NACK suppression (``_suppressed``, NACK_SUPPRESSION_SECONDS, RTPS's nackSuppressionDuration):
  a sample is not sent to a reader again within that of its last sending, so ACKNACKs in its
  name cannot pull a sample while it is on its way (a reader that lost it asks again at the next
  HEARTBEAT);
* the resend budget (``_afford``, RESEND_PER_BYTE_WRITTEN): a reader proxy is resent at most
  RESEND_PER_BYTE_WRITTEN times what was written to the history since it matched (plus the
  history then); what it cannot afford waits for the writer's next samples. A fake reader that
  never acknowledges, its locator a victim's, gets at most that multiple of the stream it is
  sent anyway.

What an attacker who knows a reader's GUID can still do: acknowledge samples in its name (a
sample the real reader lost is then GAPped to it, or waits until it leaves the history) and spend
its budget (its own lost samples then wait for the next writes). The periodic HEARTBEATs (their
period doubling up to MAX_HEARTBEAT_SECONDS until the reader answers) go out from
``Participant.tick``.
"""

from __future__ import annotations

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import LocalEndpoint, ReaderProxy, Send
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES, MIN_RESEND_SECONDS, NACK_SUPPRESSION_SECONDS
from rosfpga_lab.rtps.message import AckNack, NackFrag
from rosfpga_lab.rtps.participant_base import ParticipantBase


class WriterSide(ParticipantBase):
    """Writing samples, and a reliable writer's answers to ACKNACK and NACK_FRAG."""

    def write(self, writer_id: int, payload: bytes, now: float = 0.0,
              stamp: float | None = None) -> list[Send]:
        """Send one serialized sample (encapsulation header first) on writer ``writer_id``
        (``now``: the clock :meth:`tick` gets; ``stamp``: the source time for INFO_TS)."""
        ep = self.local[writer_id]
        self._keep(ep, bytes(payload))
        out: list[Send] = []
        oldest = next(iter(ep.history))
        for proxy in ep.proxies.values():
            assert isinstance(proxy, ReaderProxy)
            while proxy.sent and next(iter(proxy.sent)) < oldest:
                del proxy.sent[next(iter(proxy.sent))]      # left the history
            proxy.sent[ep.seq] = now
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

    def _afford(self, proxy: ReaderProxy, cost: int) -> bool:
        """Whether ``proxy``'s resend budget (RESEND_PER_BYTE_WRITTEN) still holds ``cost``
        bytes; if so they are spent. What it cannot afford waits until the writer writes again
        (counted, logged once)."""
        if cost > proxy.credit:
            self.note(f"resend-budget-{proxy.prefix.hex()}", f"reader {proxy.prefix.hex()}:"
                      f"{proxy.reader_id:08x} asked for more retransmissions than its budget "
                      f"(RESEND_PER_BYTE_WRITTEN of what was written): the rest waits for new "
                      f"samples")
            return False
        proxy.credit -= cost
        return True

    def _suppressed(self, proxy: ReaderProxy, seq: int, now: float) -> bool:
        """Whether sample ``seq`` went to ``proxy`` less than NACK_SUPPRESSION_SECONDS ago
        (then it is not sent again: counted, logged once); if not, it goes now."""
        if now - proxy.sent.get(seq, -1e9) < NACK_SUPPRESSION_SECONDS:
            self.note(f"nack-suppressed-{proxy.prefix.hex()}", f"reader {proxy.prefix.hex()}:"
                      f"{proxy.reader_id:08x} asked again for a sample sent to it less than "
                      f"{NACK_SUPPRESSION_SECONDS} s ago: not resent yet (NACK suppression)")
            return True
        if seq in proxy.sent:
            proxy.sent[seq] = now
        return False

    @staticmethod
    def _floor(ep: LocalEndpoint, proxy: ReaderProxy) -> int:
        """The first sample ``proxy`` may be resent: not one written before a VOLATILE reader
        matched, nor one that left the history, nor one it already acknowledged (ACKNACK base:
        it has every sample before it; asked again, it gets a GAP)."""
        return max(proxy.first_relevant, proxy.acked, next(iter(ep.history), ep.seq + 1))

    def _on_acknack(self, prefix: bytes, sub: AckNack, now: float) -> list[Send]:
        ep = self.local.get(sub.writer_id)
        proxy = ep.proxies.get((prefix, sub.reader_id)) if ep and ep.kind == "writer" else None
        if ep is None or not isinstance(proxy, ReaderProxy):
            self.note(f"acknack-unknown-{prefix.hex()}", f"ACKNACK from {prefix.hex()} for no "
                      f"matched reader of writer 0x{sub.writer_id:08x}: ignored")
            return []
        proxy.heartbeat_period = 0.0     # it answers: back to the short period
        if sub.count <= proxy.last_count:
            # a count already seen (RTPS 8.4.15.8): no retransmission. Its acknowledgement
            # still counts, so a spoofed high count cannot silence the real reader for good.
            proxy.acked = min(max(proxy.acked, sub.base), ep.seq + 1)
            self.note("acknack-dup", "ACKNACK with a count already seen: no retransmission")
            return []
        proxy.last_count = sub.count
        if sub.base == 0:
            # a preemptive ACKNACK (base 0, no bits: Fast DDS's form) asks for a HEARTBEAT
            return self._msg(proxy.locator, proxy.prefix, [self._heartbeat(ep, proxy)])
        floor = self._floor(ep, proxy)      # before this ACKNACK's base counts
        proxy.acked = min(max(proxy.acked, sub.base), ep.seq + 1)
        # only what was written can be missing: later numbers are ignored, never GAPped
        missing = [s for s in sub.missing if s <= ep.seq]
        if len(missing) < len(sub.missing):
            self.note(f"acknack-future-{prefix.hex()}", f"ACKNACK from {prefix.hex()} asks for "
                      f"samples past {ep.seq}, the last written: those ignored")
        if not missing or self._paced(proxy, 0, now):
            return []
        subs: list[bytes] = []
        never = [s for s in missing if s < floor]
        if never:
            # not for it (VOLATILE), gone, or already acknowledged: it will never come again
            subs.append(b.gap(proxy.reader_id, ep.entity_id, min(never), floor))
            if any(proxy.first_relevant <= s < proxy.acked and s in ep.history for s in never):
                self.note(f"acknack-acked-{prefix.hex()}", f"ACKNACK from {prefix.hex()} asks "
                          f"again for samples it acknowledged: GAP, not the samples")
        for s in missing:
            if s < floor or self._suppressed(proxy, s, now):
                continue
            if not self._afford(proxy, len(ep.history[s])):
                break
            subs += self._sample_subs(proxy.reader_id, ep.entity_id, s, ep.history[s])
        if not subs:
            return []
        subs.append(self._heartbeat(ep, proxy))
        return self._msg(proxy.locator, proxy.prefix, subs)

    def _on_nackfrag(self, prefix: bytes, sub: NackFrag, now: float) -> list[Send]:
        ep = self.local.get(sub.writer_id)
        proxy = ep.proxies.get((prefix, sub.reader_id)) if ep and ep.kind == "writer" else None
        if ep is None or not isinstance(proxy, ReaderProxy) or sub.count <= proxy.last_frag_count:
            return []
        proxy.last_frag_count = sub.count
        if sub.seq > ep.seq or sub.seq < 1 or not sub.missing:
            return []          # never written: nothing to resend, nothing to GAP
        if self._paced(proxy, sub.seq, now, next(iter(ep.history), ep.seq + 1)):
            return []
        if sub.seq < self._floor(ep, proxy):
            return self._msg(proxy.locator, proxy.prefix,
                             [b.gap(proxy.reader_id, ep.entity_id, sub.seq, sub.seq + 1)])
        if self._suppressed(proxy, sub.seq, now):
            return []
        payload = ep.history[sub.seq]
        frags: list[int] = []
        for n in sub.missing:     # each fragment costs the sample bytes it carries
            if not self._afford(proxy, len(payload[(n - 1) * FRAGMENT_BYTES:n * FRAGMENT_BYTES])):
                break
            frags.append(n)
        if not frags:
            return []
        return self._msg(proxy.locator, proxy.prefix,
                         self._sample_subs(proxy.reader_id, ep.entity_id, sub.seq, payload, frags))
