"""The XML-RPC server under bursts (issue 23, items 16 and 17): a listen backlog that holds a
burst (a lost SYN costs its client a 1 s retransmit), and one budget for the bytes of every
request body in flight. Figures beside rosmaster: tests/benchmarks/bench_master_load.py.
"""

from __future__ import annotations

import socket
import time

from rosfpga_lab.graph.limits import LISTEN_BACKLOG
from rosfpga_lab.graph.xmlrpc import XmlRpcServer

BURST = 250


class RecordingSocket(socket.socket):
    """A socket that remembers the backlog it was asked to listen with."""

    backlogs: list[int] = []

    def listen(self, backlog: int = 0) -> None:  # type: ignore[override]
        RecordingSocket.backlogs.append(backlog)
        super().listen(backlog)


def test_servers_listen_with_a_backlog_that_holds_a_burst(monkeypatch) -> None:
    """The kernel queues at most ``backlog`` (capped by somaxconn) connections before accept();
    past that, a burst's handshakes are dropped and retried after 1 s: with 64, the slowest of
    250 concurrent calls took 1.1-1.3 s (bench_master_load.py: 0.11-0.15 s with 1024). Every
    server the graph layer opens (XML-RPC, TCPROS, services) listens with LISTEN_BACKLOG."""
    from rosfpga_lab.graph import EmbeddedMaster, Node

    assert LISTEN_BACKLOG >= BURST
    RecordingSocket.backlogs.clear()
    monkeypatch.setattr(socket, "socket", RecordingSocket)
    with EmbeddedMaster(port=0) as master, Node("/backlog", master=master) as node:
        node.advertise_service("~s", "roscpp/Empty", lambda req: {})
    assert len(RecordingSocket.backlogs) == 4   # master, node XML-RPC, TCPROS, services
    assert min(RecordingSocket.backlogs) >= BURST, RecordingSocket.backlogs


def _post_head(port: int, length: int) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", port), timeout=10)
    s.sendall(b"POST / HTTP/1.0\r\nContent-Type: text/xml\r\nContent-Length: %d\r\n\r\n" % length)
    return s


def _reply(s: socket.socket) -> bytes:
    out = bytearray()
    while chunk := s.recv(65536):
        out += chunk
    return bytes(out)


def test_bodies_in_flight_share_one_budget() -> None:
    import xmlrpc.client

    body = xmlrpc.client.dumps(("/x", "b" * 600_000), methodname="getPid").encode()
    server = XmlRpcServer(lambda m, p: [1, "", 0], body_budget=1 << 20)
    server.start()
    try:
        first = _post_head(server.port, len(body))
        first.sendall(body[:1000])          # holds 600 kB of the budget while it drips
        deadline = time.monotonic() + 5
        while server.bodies_in_flight == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert server.bodies_in_flight == len(body)
        second = _post_head(server.port, len(body))
        second.sendall(body)                # the refused body is read into nothing
        refused = _reply(second)
        assert refused.startswith(b"HTTP/1.1 503 ")
        assert b"MAX_XMLRPC_BODIES_IN_FLIGHT" in refused
        assert server.over_budget == 1
        first.sendall(body[1000:])
        assert _reply(first).startswith(b"HTTP/1.1 200 ")
        first.close()
        second.close()
        assert server.bodies_in_flight == 0
        third = _post_head(server.port, len(body))
        third.sendall(body)
        assert _reply(third).startswith(b"HTTP/1.1 200 ")
        third.close()
    finally:
        server.stop()
