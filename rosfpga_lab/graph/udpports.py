"""A set of UDP ports bound on one address, waited on together: the host side of a simulated
network port (``rosfpga-lab fabric sim --shim`` binds the node's metatraffic and user-data
ports on 127.0.0.1 and sends what the circuit sends from them).
"""

from __future__ import annotations

import errno
import socket

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.limits import ROS2_SOCKET_BUFFER_BYTES

__all__ = ["UdpPorts"]

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
