"""Small socket helpers shared by publishers and subscribers (the only I/O besides xmlrpc)."""

from __future__ import annotations

import logging
import socket
import time
from collections.abc import Callable

from rosfpga_lab.graph.limits import ACCEPT_BACKOFF_FIRST, ACCEPT_BACKOFF_MAX, ACCEPT_LOG_INTERVAL
from rosfpga_lab.tcpros import frame_prefix

log = logging.getLogger("rosfpga_lab.graph")

#: Bytes asked of each recv() on a TCPROS stream between frame bodies (handshake, length
#: prefixes, small frames). A body longer than what such a chunk holds is received straight
#: into its own buffer (``recv_into``), so this stays small: it bounds the part of a big frame
#: copied once, and the memory each recv() allocates.
RECV_CHUNK = 1 << 16


def send_frame(sock: socket.socket, body: bytes | bytearray | memoryview) -> int:
    """Send a 4-byte length prefix and ``body`` without joining them; return bytes sent."""
    view = memoryview(body).cast("B")
    return send_parts(sock, frame_prefix(len(view)), view)


def send_parts(sock: socket.socket, *pieces: bytes | memoryview) -> int:
    """Send ``pieces`` one after the other with vectored writes (no joining); return bytes sent."""
    parts = [memoryview(p).cast("B") for p in pieces if len(p)]
    total = sum(len(p) for p in parts)
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


def socket_ends(sock: socket.socket) -> dict[str, str]:
    """``{"local": "host:port", "remote": "host:port"}`` of a connected socket, for trace
    events (empty strings once the socket is gone)."""
    ends = {}
    for key, get in (("local", sock.getsockname), ("remote", sock.getpeername)):
        try:
            host, port = get()[:2]
            ends[key] = f"{host}:{port}"
        except OSError:
            ends[key] = ""
    return ends


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


def accept_loop(sock: socket.socket, running: Callable[[], bool],
                handle: Callable[[socket.socket, str], None], what: str) -> None:
    """Accept connections on ``sock`` and pass each to ``handle(conn, "host:port")`` while
    ``running()`` is true: the accept thread of every server (XML-RPC and TCPROS).

    A failing ``accept()`` (out of file descriptors: EMFILE/ENFILE; ECONNABORTED; out of
    buffers) does not end the loop: it is retried after a pause that doubles from
    ``ACCEPT_BACKOFF_FIRST`` up to ``ACCEPT_BACKOFF_MAX`` seconds, so the server serves again
    within that pause once descriptors are free. The first failure is logged (a warning), later
    ones at most every ``ACCEPT_LOG_INTERVAL`` seconds with a count, recovery once. The loop
    ends only when ``running()`` turns false (the owner closes ``sock`` after clearing it). A
    ``handle`` that raises (say, no thread can be started) loses that one connection only.
    """
    delay = ACCEPT_BACKOFF_FIRST
    failing = False          # the last accept() failed
    reported = False         # this run of failures was logged
    unlogged = 0             # failures since the last log line
    last_log = -ACCEPT_LOG_INTERVAL
    while running():
        try:
            conn, addr = sock.accept()
        except OSError as exc:
            if not running():
                return
            unlogged += 1
            now = time.monotonic()
            if now - last_log >= ACCEPT_LOG_INTERVAL:
                log.warning("%s: accept() failed (%s; %d failure(s) since the last report); "
                            "retrying with back-off up to %.1f s", what, exc, unlogged,
                            ACCEPT_BACKOFF_MAX)
                last_log, unlogged, reported = now, 0, True
            failing = True
            time.sleep(delay)
            delay = min(delay * 2, ACCEPT_BACKOFF_MAX)
            continue
        if failing:
            if reported:
                log.info("%s: accepting connections again", what)
            failing, reported, delay = False, False, ACCEPT_BACKOFF_FIRST
        if not running():
            hard_close(conn)
            return
        try:
            handle(conn, f"{addr[0]}:{addr[1]}")
        except Exception as exc:  # noqa: BLE001 - the loop must outlive one bad connection
            log.warning("%s: dropped a connection from %s:%s: %s: %s", what, addr[0], addr[1],
                        type(exc).__name__, exc)
            hard_close(conn)
