"""Captures in: a pcap/pcapng file of real ROS 1 traffic as TCP streams and as a :class:`Trace`.

How this works: scapy reads the packets; :func:`tcp_streams` puts each TCP connection's two
byte streams back together (in sequence-number order, repeats dropped; a stream stops at the
first byte the capture lacks, and says so). :func:`trace_from_capture` then reads each stream
as the lab's own nodes would: HTTP/XML-RPC requests and replies, or a TCPROS connection header
each way followed by frames (with the sans-IO codecs of ``rosfpga_lab.tcpros``), and records
them as trace events with the capture's times and addresses. Node names come from the traffic
itself: the ``caller_id`` of XML-RPC calls, the ``caller_api`` URIs given to the master, the
``callerid`` of TCPROS headers. The result goes wherever a trace goes (the sequence diagram,
the byte viewer, a table). UDP datagrams (RTPS) are read by :func:`udp_datagrams`.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.graph.errors import GraphError, XmlRpcError
from rosfpga_lab.graph.limits import TRACE_EXCERPT_BYTES
from rosfpga_lab.graph.limits import CAPTURE_MAX_STREAM_BYTES
from rosfpga_lab.graph.master import MASTER_ID
from rosfpga_lab.graph.trace import Trace, new_connection_id
from rosfpga_lab.graph.http import Body, Head, HttpDecoder
from rosfpga_lab.graph.xmlrpc import split_uri
from rosfpga_lab.graph.xmlrpccodec import parse_xmlrpc
from rosfpga_lab.tcpros import FrameDecoder, ProtocolError, decode_header

#: The lab's data/ folder and the real captures shipped in it (each made by the script beside it).
DATA_DIR = Path(__file__).resolve().parents[2] / "data"
ROS1_CAPTURE = DATA_DIR / "ros1_image.pcapng"
RTPS_CAPTURE = DATA_DIR / "rtps_image.pcapng"
#: Master API methods whose 4th parameter is the caller's XML-RPC URI.
_CALLER_API_METHODS = ("registerPublisher", "registerSubscriber", "unregisterPublisher",
                       "unregisterSubscriber", "registerService")


@dataclass
class TcpStream:
    """One TCP connection from a capture: the client (the end that sent SYN) and its bytes."""

    client: str
    server: str
    opened: float
    closed: float | None = None
    data: dict[bool, bytearray] = field(default_factory=lambda: {True: bytearray(), False: bytearray()})
    times: dict[bool, list[tuple[int, float]]] = field(default_factory=lambda: {True: [], False: []})
    complete: dict[bool, bool] = field(default_factory=lambda: {True: True, False: True})

    def time_at(self, from_client: bool, offset: int) -> float:
        """Capture time of the packet that carried byte ``offset`` of one direction."""
        marks = self.times[from_client]
        i = bisect.bisect_right(marks, (offset, float("inf"))) - 1
        return marks[max(i, 0)][1] if marks else self.opened


def _packets(path: str | Path):
    from scapy.error import Scapy_Exception
    from scapy.utils import PcapReader

    try:
        with PcapReader(str(path)) as reader:
            yield from reader
    except (OSError, Scapy_Exception) as exc:
        raise GraphError(f"cannot read the capture {path}: {exc}") from None


def _ip(pkt):
    from scapy.layers.inet import IP
    from scapy.layers.inet6 import IPv6

    return pkt[IP] if IP in pkt else pkt[IPv6] if IPv6 in pkt else None


def tcp_streams(path: str | Path) -> list[TcpStream]:
    """Every TCP connection in a capture file, its two directions reassembled."""
    from scapy.layers.inet import IP, TCP

    segs: dict[frozenset, list] = {}
    for pkt in _packets(path):
        if TCP not in pkt or (ip := _ip(pkt)) is None:
            continue
        tcp = pkt[TCP]
        src, dst = f"{ip.src}:{tcp.sport}", f"{ip.dst}:{tcp.dport}"
        wire = (ip.len - ip.ihl * 4 if IP in pkt else ip.plen) - tcp.dataofs * 4
        segs.setdefault(frozenset((src, dst)), []).append(
            (float(pkt.time), src, dst, tcp.seq, str(tcp.flags), bytes(tcp.payload)[:max(wire, 0)], wire))
    out = []
    for pair, items in segs.items():
        syn = next((s for s in items if "S" in s[4] and "A" not in s[4]), None)
        client = syn[1] if syn else items[0][1]
        server = next(iter(pair - {client}), client)
        st = TcpStream(client, server, items[0][0])
        for from_client in (True, False):
            src = client if from_client else server
            mine = [s for s in items if s[1] == src]
            if not mine:
                continue
            first_syn = next((s for s in mine if "S" in s[4]), None)
            data_segs = [s for s in mine if s[6] > 0]
            start = (first_syn[3] + 1) if first_syn else min((s[3] for s in data_segs), default=0)
            fins = [s for s in mine if "F" in s[4] or "R" in s[4]]
            if fins:
                st.closed = min(fins[0][0], st.closed or fins[0][0])
            buf, marks = st.data[from_client], st.times[from_client]
            for t, _s, _d, seq, _f, payload, wire in sorted(
                    data_segs, key=lambda s: ((s[3] - start) & 0xFFFF_FFFF, s[0])):
                off = (seq - start) & 0xFFFF_FFFF
                if off + wire <= len(buf):
                    continue                       # a repeat of bytes we have
                if off > len(buf) or len(buf) + wire > CAPTURE_MAX_STREAM_BYTES:
                    st.complete[from_client] = False   # a hole in the capture, or too much
                    break
                marks.append((len(buf), t))
                buf += payload[len(buf) - off:]
                if len(payload) < wire:            # cut by the capture's snap length
                    st.complete[from_client] = False
                    break
        out.append(st)
    return sorted(out, key=lambda s: s.opened)


def _http_messages(data: bytes) -> list[tuple[int, bytes, bytes]]:
    """``(offset, head, body)`` of each complete HTTP message in one direction's bytes (up to
    the first that is cut short or malformed, or has no ``Content-Length``)."""
    http = HttpDecoder(max_head=len(data) + 1, max_body=len(data))
    http.receive(data)
    http.receive(b"")
    out = []
    try:
        while True:
            start = http.consumed
            head = http.next_event()
            if not isinstance(head, Head):
                break
            body = http.next_event()
            if not isinstance(body, Body):
                break
            out.append((start, head.raw, body.data))
    except XmlRpcError:
        pass
    return out


def _hostport(uri: object) -> str | None:
    try:
        host, port, _path = split_uri(str(uri))
    except GraphError:
        return None
    return f"{host}:{port}"


def trace_from_capture(path: str | Path, *, frame_bytes: int = 1 << 20) -> Trace:
    """The ROS 1 conversation in a capture file (XML-RPC and TCPROS) as a :class:`Trace`.

    Args:
        path: a pcap or pcapng file (e.g. ``data/ros1_image.pcapng``).
        frame_bytes: body bytes of each TCPROS frame kept in its event's ``raw``. The trace is
            bounded as any (``max_events``, ``max_bytes``): its ``dropped`` counts what did
            not fit.

    Raises:
        GraphError: the file cannot be read.
    """
    tr = Trace(frame_bytes=frame_bytes, excerpt_bytes=max(TRACE_EXCERPT_BYTES, frame_bytes + 4))
    rec = "capture"
    for st in tcp_streams(path):
        c2s, s2c = bytes(st.data[True]), bytes(st.data[False])
        ends = {"local": st.client, "remote": st.server}
        if c2s.startswith(b"POST ") or s2c.startswith(b"HTTP/"):
            _xmlrpc(tr, st, c2s, s2c, ends)
            continue   # as the lab's own traces: an XML-RPC call is one event, no connect/close
        if c2s or s2c:
            _tcpros(tr, st, c2s, s2c, ends)
        if st.closed is not None:
            ev = tr.record("tcp_close", rec, role="out", src=st.client, dst=st.server,
                           t0=st.closed, **ends)
            if ev is not None:  # a full trace drops events
                ev.t = st.closed
    return tr


def _xmlrpc(tr: Trace, st: TcpStream, c2s: bytes, s2c: bytes, ends: dict) -> None:
    replies = _http_messages(s2c)
    for k, (off, head, body) in enumerate(_http_messages(c2s)):
        try:
            params, method = parse_xmlrpc(body)
        except XmlRpcError:
            params, method = (), None
        caller = params[0] if params and isinstance(params[0], str) else st.client
        tr.names.setdefault(st.client, caller)
        if method in _CALLER_API_METHODS and len(params) > 3:
            tr.names[st.server] = MASTER_ID
            if (api := _hostport(params[3])) is not None:
                tr.names[api] = caller
        raw_reply, result, t_end = b"", None, st.time_at(True, off)
        if k < len(replies):
            r_off, r_head, r_body = replies[k]
            raw_reply, t_end = r_head + r_body, st.time_at(False, r_off)
            try:
                res, _ = parse_xmlrpc(r_body)
                result = res[0] if len(res) == 1 else list(res)
            except XmlRpcError as exc:
                result = f"error: {exc}"
            if method == "requestTopic" and isinstance(result, list) and len(result) == 3:
                proto = result[2]
                if isinstance(proto, list) and len(proto) >= 3 and proto[0] == "TCPROS":
                    tr.names.setdefault(f"{proto[1]}:{proto[2]}", st.server)
        ev = tr.record("xmlrpc", "capture", role="client", src=st.client, dst=st.server,
                       method=method or "", args=list(params), result=result, raw=head + body,
                       raw_reply=raw_reply, size=len(head) + len(body) + len(raw_reply),
                       t0=st.time_at(True, off), **ends)
        if ev is not None:  # a full trace drops events
            ev.t = t_end


def _tcpros(tr: Trace, st: TcpStream, c2s: bytes, s2c: bytes, ends: dict) -> None:
    conn = new_connection_id()
    ev = tr.record("tcp_connect", "capture", role="out", src=st.client, dst=st.server,
                   conn=conn, t0=st.opened, **ends)
    if ev is not None:  # a full trace drops events
        ev.t = st.opened
    topic = ""
    for from_client, data in ((True, c2s), (False, s2c)):
        if not data:
            continue
        src, dst = (st.client, st.server) if from_client else (st.server, st.client)
        ends = {"local": src, "remote": dst}   # recorded as by the sender
        try:
            fields, used = decode_header(data)
        except ProtocolError:
            return
        topic = fields.get("topic", topic)
        if "callerid" in fields:
            tr.names[src] = fields["callerid"]
        ev = tr.record("tcpros_header", "capture", role="out", src=src, dst=dst, method=topic,
                       args=fields, raw=data[:used], size=used, conn=conn,
                       t0=st.time_at(from_client, 0), **ends)
        if ev is not None:  # a full trace drops events
            ev.t = ev.t0
        if from_client:
            continue
        dec = FrameDecoder(stream_offset=used)
        try:
            bodies = dec.feed(memoryview(data)[used:])
        except ProtocolError as exc:
            bodies = exc.partial
        for index, (body, start) in enumerate(zip(bodies, dec.starts)):
            ev = tr.record("tcpros_frame", "capture", role="out", src=src, dst=dst, method=topic,
                           raw=tr.frame_raw(body), size=4 + len(body), conn=conn, index=index,
                           offset=start, t0=st.time_at(False, start), **ends)
            if ev is not None:  # a full trace drops events
                ev.t = st.time_at(False, start + 4 + len(body) - 1)


def udp_datagrams(path: str | Path) -> list[tuple[float, str, str, bytes]]:
    """``(time, "src:port", "dst:port", payload)`` of every UDP datagram in a capture file
    (pcap or pcapng), e.g. RTPS messages for ``rosfpga_lab.rtps.parse_message``.

    Raises:
        GraphError: the file cannot be read as a capture.
    """
    from scapy.layers.inet import UDP

    out = []
    for pkt in _packets(path):
        if UDP not in pkt or (ip := _ip(pkt)) is None:
            continue
        udp = pkt[UDP]
        out.append((float(pkt.time), f"{ip.src}:{udp.sport}", f"{ip.dst}:{udp.dport}",
                    bytes(udp.payload)))
    return out
