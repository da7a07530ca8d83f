"""Limits and defaults of the TCPROS layer, in one place.

The limits are the lab's defaults; every codec takes its own limits as arguments. roscpp
refuses header or frame lengths over 1e9 bytes and header fields over 1e6 bytes; the lab is
stricter so that a garbage length cannot make a notebook allocate gigabytes.
"""

from __future__ import annotations

#: Largest connection header (the 4-byte total length's value) the lab accepts by default.
MAX_HEADER_BYTES = 1 << 20
#: Largest single ``key=value`` field of a connection header.
MAX_FIELD_BYTES = 1 << 20
#: Largest message body (the 4-byte frame length's value) the lab accepts by default: 64 MiB,
#: room for a 4K rgba8 image (33 MB).
MAX_FRAME_BYTES = 64 << 20
#: First buffer of a frame body being assembled (bytes); it at most doubles as bytes arrive, so
#: a declared length costs nothing until its bytes come.
FRAME_BUFFER_FIRST = 1 << 18
#: Transitions a handshake machine keeps in ``history``: a self-loop (``frame``, ``send``) is
#: kept this many times in a row, later repeats are only counted (``repeats``).
HISTORY_REPEATS = 3
#: Seconds a peer may take to complete its connection header before we give up on it.
HANDSHAKE_TIMEOUT = 5.0
