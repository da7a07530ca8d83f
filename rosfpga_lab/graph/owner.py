"""Who owns a listening TCP port: so a node never silently joins another Unix user's master.

How this works: on a server shared by many users (a course on JupyterHub) they all share the
loopback interface, so "a master answering on 127.0.0.1:11311" may be another user's notebook.
Linux lists every socket with its owner's uid in ``/proc/net/tcp`` and ``/proc/net/tcp6``
(columns ``local_address`` as ``HEXADDR:HEXPORT``, ``st`` where ``0A`` is LISTEN, and
``uid``); :func:`listener_uids` reads them. Elsewhere (macOS, Windows) nothing is known and
callers keep their old behaviour.
"""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.graph.limits import OWNER_MAX_TABLE_BYTES

#: The kernel's socket tables (IPv4, IPv6).
PROC_NET_TCP = (Path("/proc/net/tcp"), Path("/proc/net/tcp6"))
#: ``st`` of a listening socket in those tables.
TCP_LISTEN = "0A"


def parse_tcp_table(text: str, port: int) -> set[int]:
    """The uids of the LISTEN sockets on ``port`` in one ``/proc/net/tcp`` table's text."""
    uids = set()
    for line in text.splitlines()[1:]:
        cols = line.split()
        if len(cols) < 8 or cols[3] != TCP_LISTEN:
            continue
        _, _, hexport = cols[1].rpartition(":")
        try:
            if int(hexport, 16) == port:
                uids.add(int(cols[7]))
        except ValueError:
            continue
    return uids


def listener_uids(port: int, tables: tuple[Path, ...] = PROC_NET_TCP) -> set[int] | None:
    """The uids that listen on TCP ``port`` on any local address.

    Returns:
        A set of uids (empty: nobody listens), or None when the tables cannot be read (not
        Linux), so the owner is unknown.
    """
    found: set[int] = set()
    readable = False
    for table in tables:
        try:
            with open(table, encoding="ascii", errors="replace") as f:
                text = f.read(OWNER_MAX_TABLE_BYTES)
        except OSError:
            continue
        readable = True
        found |= parse_tcp_table(text, port)
    return found if readable else None
