"""The state every part of a :class:`rosfpga_lab.rtps.participant.Participant` shares, and the
small helpers they all use.

How this works: :class:`ParticipantBase` holds one participant's RTPS state: its GUID prefix and
ports, the remote participants and endpoints it knows, its local endpoints (each with the proxies
of the remote endpoints matched with it), the samples received, and the notes. The parts built on
it (:mod:`~rosfpga_lab.rtps.writer_side`, :mod:`~rosfpga_lab.rtps.sedp`,
:mod:`~rosfpga_lab.rtps.spdp`, :mod:`~rosfpga_lab.rtps.reader_side`) change that state and
return the datagrams to send; for that they share what is here: :meth:`ParticipantBase.note` logs
once per key and counts every call (both bounded), ``_msg`` packs submessages after INFO_DST into
datagrams of at most MAX_MESSAGE_BYTES, ``_sample_subs`` cuts one sample into DATA or DATA_FRAGs,
``_heartbeat`` writes a writer's HEARTBEAT to one reader; ``_params``, ``_inline``, ``_status``
and ``_locator`` read what a peer announces (parameter lists, inline QoS, the disposed and
unregistered bits, where to reach it). Matching can produce datagrams inside a call that returns
none: they wait in ``_outbox`` until the next ``receive`` or ``tick``.
"""

from __future__ import annotations

import os
from collections import OrderedDict, deque

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.discovery import PL_CDR_BE, PL_CDR_LE, FragmentAssembler, parse_parameters
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, SUB_READER, SUB_WRITER, Departed, LocalEndpoint, Qos, ReaderProxy,
    RemoteEndpoint, RemoteParticipant, Sample, Send, check_domain, discovery_port, user_port,
)
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.limits import (
    ANNOUNCE_SECONDS, FRAGMENT_BYTES, LEASE_SECONDS, MAX_HISTORY_BYTES, MAX_MESSAGE_BYTES,
    MAX_NOTES, MAX_REMOTE_ENDPOINTS, RESEND_PER_BYTE_WRITTEN,
)


class ParticipantBase:
    """One participant's state and the helpers its parts share (use :class:`Participant`)."""

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
        #: Participants that said goodbye or were evicted, by prefix (``spdp._depart``).
        self.departed: OrderedDict[bytes, Departed] = OrderedDict()
        self._count = 0                   # the last ACKNACK / NACK_FRAG count sent
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
        self._spdp_msg: tuple[object, bytes] = (None, b"")     # our SPDP datagram, once built
        # built-in SEDP writers and readers (reliable, KEEP_ALL of the lab's own endpoints)
        for eid, kind in ((PUB_WRITER, "writer"), (SUB_WRITER, "writer"),
                          (PUB_READER, "reader"), (SUB_READER, "reader")):
            self.local[eid] = LocalEndpoint(eid, kind, "", "", Qos(True, MAX_REMOTE_ENDPOINTS))

    def _next_count(self) -> int:
        """The count of the next ACKNACK or NACK_FRAG: one counter for all of them, so the
        counts a remote writer sees from a reader only rise, even after the participant forgot
        and learned that writer again (a count already seen is ignored: RTPS 2.3 8.4.15.8)."""
        self._count += 1
        return self._count

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

    def _keep(self, ep: LocalEndpoint, payload: bytes) -> int:
        """Put the next sample of writer ``ep`` in its history (KEEP_LAST depth, and at most
        MAX_HISTORY_BYTES: the oldest go); each matched reader proxy earns its resend budget.
        Returns its sequence number."""
        ep.seq += 1
        ep.history[ep.seq] = payload
        ep.history_bytes += len(payload)
        while len(ep.history) > ep.qos.depth or \
                (ep.history_bytes > MAX_HISTORY_BYTES and len(ep.history) > 1):
            if len(ep.history) <= ep.qos.depth:
                self.note(f"history-bytes-{ep.entity_id}", f"writer {ep.topic or 'SEDP'}: its "
                          f"last {ep.qos.depth} samples exceed MAX_HISTORY_BYTES "
                          f"({MAX_HISTORY_BYTES} bytes): the oldest go first")
            ep.history_bytes -= len(ep.history.popitem(last=False)[1])
        for proxy in ep.proxies.values():
            if isinstance(proxy, ReaderProxy):
                proxy.credit = min(proxy.credit + len(payload) * RESEND_PER_BYTE_WRITTEN,
                                   ep.history_bytes * RESEND_PER_BYTE_WRITTEN)
        return ep.seq

    def _heartbeat(self, ep: LocalEndpoint, proxy: ReaderProxy) -> bytes:
        ep.hb_count += 1
        first = max(next(iter(ep.history), ep.seq + 1), proxy.first_relevant)
        return b.heartbeat(proxy.reader_id, ep.entity_id, first, ep.seq, ep.hb_count)

    # ---- what a peer announces ---------------------------------------------------------
    def _params(self, payload: bytes, what: str) -> tuple[dict[int, list[bytes]] | None, bool]:
        try:
            return parse_parameters(payload), payload[:2] == PL_CDR_LE
        except RtpsError as exc:
            self.note(f"bad-plist-{what}", f"{what} data not a parameter list ({exc}): ignored")
            return None, True

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

    def _take_outbox(self) -> list[Send]:
        out, self._outbox = self._outbox, []
        return out
