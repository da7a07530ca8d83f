"""A Linux TAP interface: the host's end of a simulated Ethernet link (``rosfpga-lab fabric sim
--tap``): whole frames (no preamble, no FCS) written to it arrive at the host's network stack as
from a wire, and what the host sends on that interface is read back.

How this works: ``/dev/net/tun`` with ``TUNSETIFF`` (``IFF_TAP | IFF_NO_PI``) creates the
interface, which lives as long as its file descriptor; ``ip`` gives it the host's address and
brings it up, and IPv6 is turned off on it (the host's router solicitations and MLD reports are
not the circuit's business). Closing it removes the interface. Root (CAP_NET_ADMIN) is needed.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import struct
import subprocess
from pathlib import Path

from rosfpga_lab.graph.errors import GraphError

__all__ = ["TapDevice", "tap_missing_reason"]

TUN_DEVICE = "/dev/net/tun"
TUNSETIFF = 0x400454CA
IFF_TAP, IFF_NO_PI = 0x0002, 0x1000
_IP_TIMEOUT = 10.0
_READ_BYTES = 65536


def _ip_tool() -> str | None:
    return shutil.which("ip") or next((p for p in ("/usr/sbin/ip", "/sbin/ip")
                                       if Path(p).exists()), None)


def tap_missing_reason() -> str | None:
    """Why a TAP interface cannot be made here, or None."""
    if not Path(TUN_DEVICE).exists():
        return f"no {TUN_DEVICE} (a container without the TUN device?)"
    if os.geteuid() != 0:
        return "a TAP interface needs root (CAP_NET_ADMIN): run as root, or use --shim"
    if _ip_tool() is None:
        return "no 'ip' command (apt-get install iproute2)"
    return None


class TapDevice:
    """The TAP interface ``name`` with the host's address ``host_cidr`` (``10.31.0.1/24``)."""

    def __init__(self, name: str, host_cidr: str) -> None:
        reason = tap_missing_reason()
        if reason:
            raise GraphError(f"cannot make TAP interface {name}: {reason}")
        if not 0 < len(name.encode()) < 16:
            raise GraphError(f"TAP interface name {name!r}: 1..15 bytes")
        self.name = name
        self.fd = os.open(TUN_DEVICE, os.O_RDWR | os.O_NONBLOCK)
        try:
            fcntl.ioctl(self.fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TAP | IFF_NO_PI))
            v6 = Path(f"/proc/sys/net/ipv6/conf/{name}/disable_ipv6")
            if v6.exists():
                v6.write_text("1\n")
            self._ip("addr", "add", host_cidr, "dev", name)
            self._ip("link", "set", name, "up")
        except (OSError, GraphError) as exc:
            os.close(self.fd)
            raise GraphError(f"cannot set up TAP interface {name}: {exc}") from None

    def _ip(self, *args: str) -> None:
        proc = subprocess.run([_ip_tool() or "ip", *args], capture_output=True, text=True,
                              timeout=_IP_TIMEOUT)
        if proc.returncode != 0:
            raise GraphError(f"ip {' '.join(args)}: {proc.stderr.strip()}")

    def fileno(self) -> int:
        return self.fd

    def read(self) -> list[bytes]:
        """The frames the host has sent on the interface since the last call."""
        out = []
        while True:
            try:
                out.append(os.read(self.fd, _READ_BYTES))
            except (BlockingIOError, InterruptedError):
                return out

    def write(self, frame: bytes) -> None:
        """Give the host one frame (no FCS) as from the wire."""
        os.write(self.fd, frame)

    def close(self) -> None:
        """Remove the interface."""
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1
