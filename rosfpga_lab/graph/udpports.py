"""A set of UDP ports bound on one address, waited on together: the host side of a simulated
network port (``rosfpga-lab fabric sim --shim`` binds the node's metatraffic and user-data
ports on 127.0.0.1 and sends what the circuit sends from them); and :func:`ask`, one datagram
out and the first one back (``rosfpga-lab fabric counters``).
"""

from __future__ import annotations

import errno
import select
import socket
import time

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.limits import ROS2_SOCKET_BUFFER_BYTES

__all__ = ["UdpPorts", "ask"]

#: The largest UDP payload read at once.
_READ_BYTES = 65535


class UdpPorts:
    """UDP sockets bound to ``ports`` on ``address``."""

    def __init__(self, address: str, ports: list[int]) -> None:
        self.address = address
        self.sockets: dict[int, socket.socket] = {}
        try:
            for port in ports:
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                for opt in (socket.SO_RCVBUF, socket.SO_SNDBUF):
                    s.setsockopt(socket.SOL_SOCKET, opt, ROS2_SOCKET_BUFFER_BYTES)
                self.sockets[port] = s
                s.bind((address, port))
                s.setblocking(False)
        except OSError as exc:
            self.close()
            what = ("in use (another DDS participant, or another fabric sim, has it: stop it "
                    "or pick another --domain)" if exc.errno == errno.EADDRINUSE else str(exc))
            raise GraphError(f"cannot bind UDP port {port} on {address}: {what}") from None

    def filenos(self) -> list[int]:
        return [s.fileno() for s in self.sockets.values()]

    def receive(self, fileno: int) -> list[tuple[int, tuple[str, int], bytes]]:
        """The datagrams waiting on the socket ``fileno``: (our port, sender, payload) each."""
        for port, s in self.sockets.items():
            if s.fileno() == fileno:
                out: list[tuple[int, tuple[str, int], bytes]] = []
                while True:
                    try:
                        data, source = s.recvfrom(_READ_BYTES)
                    except (BlockingIOError, InterruptedError):
                        return out
                    except ConnectionRefusedError:   # an ICMP error of an earlier send
                        continue
                    out.append((port, source, data))
        return []

    def send(self, from_port: int, address: str, port: int, payload: bytes) -> bool:
        """Send from our ``from_port`` (the first port when we do not have it); False when the
        host refused it (no one there: an ICMP error, or a full buffer)."""
        s = self.sockets.get(from_port) or next(iter(self.sockets.values()))
        try:
            s.sendto(payload, (address, port))
        except OSError:
            return False
        return True

    def close(self) -> None:
        for s in self.sockets.values():
            s.close()
        self.sockets.clear()


def ask(host: str, port: int, payload: bytes, timeout: float) -> bytes | None:
    """Send ``payload`` to ``host``:``port`` from a fresh UDP port and return the first datagram
    that comes back from that address and port within ``timeout`` seconds (None: none came).

    Raises:
        GraphError: the datagram could not be sent (no route, a bad address).
    """
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect((host, port))     # only its answers come in
            s.send(payload)
        except OSError as exc:
            raise GraphError(f"cannot send to {host}:{port}: {exc}") from None
        end = time.monotonic() + timeout
        while (left := end - time.monotonic()) > 0:
            if not select.select([s], [], [], left)[0]:
                break
            try:
                return s.recv(_READ_BYTES)
            except ConnectionRefusedError:     # an ICMP port unreachable: nobody there yet
                return None
    return None
