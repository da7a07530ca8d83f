"""Small socket helpers shared by publishers and subscribers (the only I/O besides xmlrpc)."""

from __future__ import annotations

import socket

from rosfpga_lab.tcpros import frame_prefix

#: Bytes asked of each recv() on a TCPROS stream between frame bodies (handshake, length
#: prefixes, small frames). A body longer than what such a chunk holds is received straight
#: into its own buffer (``recv_into``), so this stays small: it bounds the part of a big frame
#: copied once, and the memory each recv() allocates.
RECV_CHUNK = 1 << 16


def send_frame(sock: socket.socket, body: bytes | bytearray | memoryview) -> int:
    """Send a 4-byte length prefix and ``body`` without joining them; return bytes sent."""
    view = memoryview(body).cast("B")
    parts = [memoryview(frame_prefix(len(view))), view]
    total = 4 + len(view)
    sent_total = 0
    while parts:
        sent = sock.sendmsg(parts)
        sent_total += sent
        while parts and sent >= len(parts[0]):
            sent -= len(parts[0])
            parts.pop(0)
        if parts and sent:
            parts[0] = parts[0][sent:]
    assert sent_total == total
    return total


def hard_close(sock: socket.socket) -> None:
    """Shut down both directions (wakes threads blocked in recv) and close."""
    try:
        sock.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass
    try:
        sock.close()
    except OSError:
        pass


def set_nodelay(sock: socket.socket) -> None:
    """Enable TCP_NODELAY (ignored where unsupported)."""
    try:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    except OSError:
        pass
