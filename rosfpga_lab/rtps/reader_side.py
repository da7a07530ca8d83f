"""The reader side of a participant: samples in, delivered in order, and what it asks for again.

How this works: ``_on_sample`` gets each whole sample (one DATA, or the DATA_FRAGs the
:class:`~rosfpga_lab.rtps.discovery.FragmentAssembler` put together) for every local reader
matched with its writer (``_readers_of``); an SEDP sample goes to
:mod:`~rosfpga_lab.rtps.sedp` as it arrives. A best-effort reader takes anything newer than what
it has, in arrival order. A reliable one delivers in sequence order: ``wp.next`` is the sample it
waits for; samples ahead of it wait in ``wp.pending`` (bounded: MAX_OUT_OF_ORDER samples,
MAX_OUT_OF_ORDER_BYTES, 256 numbers ahead); a GAP says which samples will never come (its range
up to gapList.base, and the listed ones), and a range ahead of delivery is remembered in
``wp.gaps`` until delivery gets there (``_drain``). A GAP counts only up to what its writer
announced (``wp.announced``: its HEARTBEATs' last, the DATA/DATA_FRAGs seen, in that datagram or
before; ``_written_up_to``): past that it is ignored, so a spoofed GAP cannot skip samples not
yet written (Cyclone DDS 11.0.1, PyPI, skips them: tests/benchmarks/bench_rtps_attacks.py, row
gap). ``_on_heartbeat`` answers a writer's HEARTBEAT
with an ACKNACK naming what is missing and NACK_FRAGs for partly received samples (RTPS 2.3
8.4.12.2: a final HEARTBEAT only when something is missing, a final liveliness one never);
``_on_heartbeat_frag`` asks for the missing fragments of one sample with a NACK_FRAG. Both follow
one set of rules (``_heard``, ``_answer``): only a reliable reader of a reliable writer answers, a
count already seen (each kind its own) is not answered again, and a built-in SEDP reader answers
on the peer's metatraffic port, a user reader on its user port. Delivered samples queue in
``samples``, at most KEEP_LAST ``depth`` per reader not taken (the oldest dropped).
"""

from __future__ import annotations

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, SUB_READER, SUB_WRITER, LocalEndpoint, Sample, Send, WriterProxy,
)
from rosfpga_lab.rtps.limits import MAX_OUT_OF_ORDER, MAX_OUT_OF_ORDER_BYTES
from rosfpga_lab.rtps.message import Gap, Heartbeat, HeartbeatFrag
from rosfpga_lab.rtps.sedp import EndpointDiscovery


class ReaderSide(EndpointDiscovery):
    """Receiving samples (in order when reliable, GAPs) and answering HEARTBEATs."""

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

    def _written_up_to(self, prefix: bytes, writer_id: int, reader_id: int, seq: int) -> None:
        """Remote writer ``writer_id`` announced sample ``seq`` (its HEARTBEAT's last, or a
        DATA/DATA_FRAG of it): a GAP may name it from now on."""
        for _, wp in self._readers_of(prefix, writer_id, reader_id):
            wp.announced = max(wp.announced, seq)

    def _on_gap(self, prefix: bytes, sub: Gap) -> None:
        for ep, wp in self._readers_of(prefix, sub.writer_id, sub.reader_id):
            if wp.next == 0:
                continue
            # only samples the writer announced can be irrelevant: a GAP past its HEARTBEAT's
            # last and past the data seen is cut there, else one spoofed GAP skips samples
            # not yet written
            end = min(sub.list_base, wp.announced + 1)
            listed = [s for s in sub.listed if s <= wp.announced]
            if end < sub.list_base or len(listed) < len(sub.listed):
                self.note(f"gap-ahead-{ep.entity_id}", f"reader {ep.topic or 'SEDP'}: GAP from "
                          f"{prefix.hex()} names samples past {wp.announced}, the last its writer "
                          f"announced: those ignored")
            if sub.start <= wp.next < end:
                self._skip_to(ep, wp, end)
            elif wp.next < sub.start < end:
                # a later range (RTPS 2.3 8.3.7.4: gapStart .. gapList.base - 1 are irrelevant):
                # remembered until delivery gets there, never asked for again
                if sub.start in wp.gaps or len(wp.gaps) < MAX_OUT_OF_ORDER:
                    wp.gaps[sub.start] = max(end, wp.gaps.get(sub.start, 0))
                else:
                    self.note(f"gaps-full-{ep.entity_id}", f"reader {ep.topic or 'SEDP'}: more "
                              f"than {MAX_OUT_OF_ORDER} GAP ranges ahead of delivery: later ones "
                              f"asked again")
            for s in listed:
                if s >= wp.next and s not in wp.pending and len(wp.pending) < MAX_OUT_OF_ORDER:
                    wp.pending[s] = None
            self._drain(ep, wp)

    def _heard(self, prefix: bytes, writer_id: int, reader_id: int, count: int,
               frag: bool) -> list[tuple[LocalEndpoint, WriterProxy]]:
        """The local readers that answer a HEARTBEAT (a HEARTBEAT_FRAG when ``frag``) of
        ``count`` from ``writer_id``: reliable ones matched with a reliable writer (a best-effort
        reader asks for nothing), for which the count is new. A count not greater than the last
        one seen is a duplicate and is ignored (RTPS 2.3 8.3.7.5 and 8.3.7.6; HEARTBEAT and
        HEARTBEAT_FRAG count apart); a new one is remembered."""
        found = []
        for ep, wp in self._readers_of(prefix, writer_id, reader_id):
            if not wp.reliable or not ep.qos.reliable:
                continue
            if count <= (wp.last_hbfrag_count if frag else wp.last_hb_count):
                continue
            if frag:
                wp.last_hbfrag_count = count
            else:
                wp.last_hb_count = count
            found.append((ep, wp))
        return found

    def _answer(self, prefix: bytes, ep: LocalEndpoint, subs: list[bytes]) -> list[Send]:
        """Datagrams of reader ``ep``'s answer (ACKNACK, NACK_FRAG) to participant ``prefix``'s
        writer: a built-in SEDP reader answers on its metatraffic port, a user reader on its
        user port."""
        owner = self.participants.get(prefix)
        if owner is None or not subs:
            return []
        return self._msg(owner.meta if not ep.topic else owner.user, prefix, subs)

    def _nack_frag(self, prefix: bytes, ep: LocalEndpoint, wp: WriterProxy, seq: int,
                   last: int = 0) -> list[bytes]:
        """A NACK_FRAG naming the first 256 fragments of sample ``seq`` not here (up to fragment
        ``last`` if given), or none when none is missing or no fragment of it is here."""
        frags = self.assembler.missing(prefix, wp.writer_id, seq, last)[:256]
        if not frags:
            return []
        wp.nackfrag_count = self._next_count()
        return [b.nack_frag(ep.entity_id, wp.writer_id, seq, frags, wp.nackfrag_count)]

    def _on_heartbeat(self, prefix: bytes, sub: Heartbeat) -> list[Send]:
        out: list[Send] = []
        for ep, wp in self._heard(prefix, sub.writer_id, sub.reader_id, sub.count, frag=False):
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
            wp.acknack_count = self._next_count()
            subs.append(b.acknack(ep.entity_id, sub.writer_id, wp.next,
                                  [s for s in missing if s not in partial], wp.acknack_count,
                                  final=not missing))
            for s in sorted(partial & set(missing))[:8]:
                subs += self._nack_frag(prefix, ep, wp, s)
            out += self._answer(prefix, ep, subs)
        return out

    def _on_heartbeat_frag(self, prefix: bytes, sub: HeartbeatFrag) -> list[Send]:
        out: list[Send] = []
        for ep, wp in self._heard(prefix, sub.writer_id, sub.reader_id, sub.count, frag=True):
            out += self._answer(prefix, ep, self._nack_frag(prefix, ep, wp, sub.seq, sub.last_frag))
        return out
