"""Capture files of a recorded conversation: every TCP connection as a real TCP stream.

How this works: trace events carry the exact bytes sent and the ``host:port`` of both ends of
their TCP connection (``local``/``remote``). :func:`capture_packets` groups the events of one or
more traces by connection, keeps one copy of every byte (the sender's record when both ends
recorded), and lays each connection out as TCP does: SYN, SYN-ACK, ACK (MSS and window-scale
options), data in segments of at most :data:`MSS` bytes with consistent sequence and
acknowledgement numbers, an ACK from the receiver after each write, and FIN/ACK both ways when
the trace saw the connection close (XML-RPC connections always close: ``Connection: close``).
:func:`write_capture` writes them with scapy (pcapng, or classic pcap for a ``.pcap`` name) on
an Ethernet link with zero MAC addresses, as ``tcpdump -i lo`` records loopback.

A trace keeps only the first ``frame_bytes`` body bytes of each TCPROS frame (and the first
``excerpt_bytes`` of a longer XML-RPC message or header). The capture then says so the way a
capture with a small snap length does: each segment keeps its true length on
the wire (so sequence numbers stay consistent and Wireshark's TCP analysis has nothing to
flag) but carries only the recorded bytes, and the first segment of such a frame has a pcapng
comment saying how many bytes the trace kept. Wireshark shows those packets as "[Packet size
limited during capture]". Record with ``Trace(frame_bytes=...)`` large enough for whole frames
when you want every byte (``rosfpga-lab demo --pcap-frame-bytes``). Events a trace evicted
(``Trace.dropped``) are missing from the file, and its first packet's comment says so.

Why scapy: of the well-kept packet libraries (scapy, dpkt, python-pcapng) it is the one whose
public writer records a packet's length on the wire apart from its captured bytes, and per-
packet comments, and that also builds the IP/TCP headers and reads pcap and pcapng back.
"""

from __future__ import annotations

import ipaddress
import zlib
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.trace import Trace, TraceEvent

#: Largest TCP payload of one segment: loopback's 65536-byte MTU less the 16-bit IP length cap
#: (65535) less 20 bytes of IPv4 and 20 of TCP header.
MSS = 65_495
#: Window scale the synthesized SYNs announce (a window of 65535 << 7, about 8 MB).
WINDOW_SCALE = 7
WINDOW = 65_535
#: Gap put between consecutive packets of one connection that the trace gave the same time.
TICK = 1e-6
#: Event kinds whose bytes go on a TCP stream.
BYTE_KINDS = ("xmlrpc", "tcpros_header", "tcpros_frame")


@dataclass
class Piece:
    """One write on a connection: ``data`` (the bytes recorded) of ``length`` bytes on the wire."""

    t: float
    from_client: bool
    data: bytes
    length: int
    what: str


@dataclass
class Connection:
    """The recorded bytes of one TCP connection, client (the end that connected) first."""

    client: str
    server: str
    pieces: list[Piece] = field(default_factory=list)
    opened: float | None = None
    closed: float | None = None
    client_closed_first: bool = False


@dataclass
class Packet:
    """One synthesized TCP segment (before it is built with scapy)."""

    t: float
    src: str
    dst: str
    seq: int
    ack: int
    flags: str
    data: bytes = b""
    length: int = 0          # payload bytes on the wire (>= len(data))
    options: tuple = ()
    comment: str = ""


def _split(endpoint: str) -> tuple[str, int]:
    host, _, port = endpoint.rpartition(":")
    return host.strip("[]"), int(port)


def _is_client(ev: TraceEvent) -> bool | None:
    """Whether the recorder of ``ev`` is the end that connected (None: this event cannot tell)."""
    if ev.kind == "xmlrpc":
        return ev.role == "client"
    if ev.kind == "tcp_connect":
        return ev.role == "out"
    return None


def connections(traces: Iterable[Trace]) -> list[Connection]:
    """Group the recorded bytes of ``traces`` by TCP connection (see the module docstring).

    Events without addresses (recorded before the trace kept them, or errors) are left out.
    """
    events = [e for tr in traces for e in tr.events if e.local and e.remote]
    by_pair: dict[frozenset, list[TraceEvent]] = {}
    for e in events:
        by_pair.setdefault(frozenset((e.local, e.remote)), []).append(e)
    out = []
    for evs in by_pair.values():
        client = None
        for e in evs:
            side = _is_client(e)
            if side is not None:
                client = e.local if side else e.remote
                break
        if client is None:
            # only the accepting end's TCPROS link recorded (its tcp_connect was evicted)
            client = evs[0].remote
        others = {a for e in evs for a in (e.local, e.remote)} - {client}
        server = min(others) if others else client
        out.append(_connection(client, server, evs))
    return sorted(out, key=lambda c: c.opened or 0.0)


def _http_length(raw: bytes) -> int | None:
    """Length of the HTTP message ``raw`` starts with (head + Content-Length), None if unknown."""
    end = raw.find(b"\r\n\r\n")
    for line in raw[:max(end, 0)].split(b"\r\n")[1:]:
        name, _, value = line.partition(b":")
        if name.strip().lower() == b"content-length" and value.strip().isdigit():
            return end + 4 + int(value.strip())
    return None


def _xmlrpc_lengths(e: TraceEvent) -> tuple[int, int]:
    """Bytes on the wire of an XML-RPC event's request and reply, also when the trace kept
    only excerpts of them (``size`` is then more than the bytes kept)."""
    request, reply = len(e.raw), len(e.raw_reply)
    if e.size > request + reply:
        request = max(_http_length(e.raw) or request, request)
        reply = max(e.size - request, reply) if e.raw_reply else 0
    return request, reply


def _connection(client: str, server: str, evs: list[TraceEvent]) -> Connection:
    conn = Connection(client, server)
    xml = [e for e in evs if e.kind == "xmlrpc" and e.raw]
    mine = [e for e in xml if e.role == "client"] or xml
    for e in mine:
        request, reply = _xmlrpc_lengths(e)
        conn.pieces.append(Piece(e.t0, True, e.raw, request, f"XML-RPC {e.method}"))
        if e.raw_reply:
            conn.pieces.append(Piece(e.t, False, e.raw_reply, reply, f"XML-RPC {e.method} reply"))
    if mine:
        conn.closed = max(e.t for e in mine)
    tcpros = [e for e in evs if e.kind in ("tcpros_header", "tcpros_frame") and e.raw]
    for from_client in (True, False):
        sender = client if from_client else server
        sent = [e for e in tcpros if (e.local if e.role == "out" else e.remote) == sender]
        chosen = [e for e in sent if e.role == "out"] or sent
        for e in chosen:
            length = e.size or len(e.raw)
            what = f"TCPROS {e.kind.split('_')[1]} {e.method}"
            conn.pieces.append(Piece(e.t0, from_client, e.raw, length, what))
    for e in evs:
        if e.kind == "tcp_connect":
            conn.opened = e.t0 if conn.opened is None else min(conn.opened, e.t0)
        elif e.kind == "tcp_close":
            if conn.closed is None or e.t < conn.closed:
                conn.closed = e.t
                recorder_is_client = e.local == client
                conn.client_closed_first = recorder_is_client == (e.role == "out")
    conn.pieces.sort(key=lambda p: p.t)
    if conn.pieces:
        first = conn.pieces[0].t
        conn.opened = first if conn.opened is None else min(conn.opened, first)
        if conn.closed is not None:
            conn.closed = max(conn.closed, conn.pieces[-1].t)
    return conn


def _isn(a: str, b: str) -> int:
    return zlib.crc32(f"{a}>{b}".encode()) & 0xFFFF_FFFF


def segments(conn: Connection) -> list[Packet]:
    """The TCP segments of one connection, in order, times never decreasing."""
    c, s = conn.client, conn.server
    nxt = {c: _isn(c, s), s: _isn(s, c)}
    out: list[Packet] = []
    last = [conn.opened or 0.0]

    def emit(t: float, src: str, flags: str, **kw) -> None:
        t = max(t, last[0] + TICK) if out else t
        last[0] = t
        dst = s if src == c else c
        out.append(Packet(t, src, dst, nxt[src], nxt[dst] if "A" in flags else 0, flags, **kw))

    syn_opts = (("MSS", MSS), ("NOP", None), ("WScale", WINDOW_SCALE))
    t0 = conn.opened or 0.0
    emit(t0, c, "S", options=syn_opts)
    nxt[c] += 1
    emit(t0, s, "SA", options=syn_opts)
    nxt[s] += 1
    emit(t0, c, "A")
    for p in conn.pieces:
        src = c if p.from_client else s
        for off in range(0, p.length, MSS):
            n = min(MSS, p.length - off)
            last_seg = off + n >= p.length
            comment = ""
            if off == 0 and len(p.data) < p.length:
                comment = (f"rosfpga-lab: the trace kept {len(p.data)} of the {p.length} bytes of "
                           f"this {p.what}; the packets of the rest carry their length only")
            emit(p.t, src, "PA" if last_seg else "A", data=p.data[off:off + n], length=n,
                 comment=comment)
            nxt[src] = (nxt[src] + n) & 0xFFFF_FFFF
        emit(p.t, s if src == c else c, "A")
    if conn.closed is not None:
        first, second = (c, s) if conn.client_closed_first else (s, c)
        emit(conn.closed, first, "FA")
        nxt[first] += 1
        emit(conn.closed, second, "FA")
        nxt[second] += 1
        emit(conn.closed, first, "A")
    return out


def capture_packets(*traces: Trace) -> list[Packet]:
    """Every TCP segment of every recorded connection of ``traces``, in time order."""
    packets = [p for conn in connections(traces) for p in segments(conn)]
    return sorted(packets, key=lambda p: p.t)  # stable: one connection's order is kept


def _build(p: Packet):  # -> scapy Packet
    from scapy.layers.inet import IP, TCP
    from scapy.layers.inet6 import IPv6
    from scapy.layers.l2 import Ether
    from scapy.packet import Raw

    (sh, sp), (dh, dp) = _split(p.src), _split(p.dst)
    v6 = ipaddress.ip_address(sh).version == 6
    tcp = TCP(sport=sp, dport=dp, seq=p.seq & 0xFFFF_FFFF, ack=p.ack & 0xFFFF_FFFF, flags=p.flags,
              window=WINDOW, options=list(p.options))
    ip = IPv6(src=sh, dst=dh) if v6 else IP(src=sh, dst=dh, flags="DF", ttl=64)
    pkt = Ether(src="00:00:00:00:00:00", dst="00:00:00:00:00:00") / ip / tcp
    if p.data:
        pkt = pkt / Raw(load=p.data)
    head = len(pkt) - len(p.data)
    truncated = p.length > len(p.data)
    if truncated:
        # true lengths in the headers; the checksum of bytes not recorded is unknown: zero
        if v6:
            pkt[IPv6].plen = len(tcp) - len(p.data) + p.length
        else:
            pkt[IP].len = head - 14 + p.length
        pkt[TCP].chksum = 0
    pkt.time = p.t
    pkt.wirelen = head + p.length
    if p.comment:
        pkt.comments = [p.comment.encode()]
    return pkt


def write_capture(path: str | Path, *traces: Trace) -> int:
    """Write the conversation of ``traces`` to a capture file; return the number of packets.

    Args:
        path: ``*.pcap`` for classic pcap (no comments), anything else pcapng.
        traces: one or more traces (e.g. the master's and every node's); bytes both ends
            recorded are written once.

    Raises:
        GraphError: the file cannot be written.
    """
    from scapy.utils import PcapNgWriter, PcapWriter

    path = Path(path)
    packets = capture_packets(*traces)
    dropped = sum(tr.dropped for tr in traces)
    if dropped and packets:
        # events the traces evicted are not in the file: say so where a reader looks first
        note = (f"rosfpga-lab: the traces had evicted {dropped} event(s) before this capture "
                f"was written; their bytes are missing from it")
        packets[0].comment = f"{note}. {packets[0].comment}" if packets[0].comment else note
    writer_class = PcapWriter if path.suffix.lower() == ".pcap" else PcapNgWriter
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        writer = (PcapWriter(str(path), linktype=1, snaplen=262_144) if writer_class is PcapWriter
                  else PcapNgWriter(str(path)))
        try:
            for p in packets:
                writer.write(_build(p))
        finally:
            writer.close()
    except OSError as exc:
        raise GraphError(f"cannot write the capture {path}: {exc.strerror or exc}") from None
    return len(packets)

