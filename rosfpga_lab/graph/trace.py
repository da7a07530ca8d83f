"""The recorded conversation: every XML-RPC exchange and every TCPROS header and frame.

How it works: masters and nodes append :class:`TraceEvent` records to a :class:`Trace` (one
per node by default; pass the same Trace to several nodes and the master to get one timeline).
Everything is plain data (a dataclass of str/int/float/bytes/dict/list), so a notebook can turn
it into a table or draw the paper's Figure 2 sequence diagram.

Format of one event (``TraceEvent``; ``to_dicts()`` gives the same as dicts):

========== ============================================================================
field      meaning
========== ============================================================================
seq        position in this trace (0, 1, ...; ``Trace.dropped`` counts events evicted)
t          wall-clock time (``time.time()``) the event finished; ``t0`` when it started
kind       ``xmlrpc`` | ``tcp_connect`` | ``tcpros_header`` | ``tcpros_frame`` | ``tcp_close``
           | ``error``
recorder   name of the node (or ``master``) that wrote the event
role       ``client``/``server`` for xmlrpc; ``out``/``in`` for bytes we sent/received
src, dst   who sent / who received (node names when known, else URIs or host:port); for
           xmlrpc ``src`` is the caller and ``dst`` the callee
method     XML-RPC method name; for TCPROS the topic
args       XML-RPC parameters (list) or TCPROS header fields (dict)
result     XML-RPC result (``[code, status, value]`` for ROS APIs), or an error text
raw        exact bytes on the wire: xmlrpc ``raw`` is the HTTP request, ``raw_reply`` the HTTP
           response; for frames the 4-byte prefix plus the first ``frame_bytes`` body bytes
raw_reply  see above (xmlrpc only)
size       total bytes on the wire (for frames: 4 + body length)
conn       connection id (same for the header and frames of one TCPROS link)
index      frame number on its connection; offset: stream offset of the frame's prefix
========== ============================================================================

A sequence diagram draws one arrow per xmlrpc event (``src -> dst`` at ``t0`` labelled
``method``, and back at ``t`` labelled ``result[1]``) and one per TCPROS event.
:meth:`Trace.conversation` removes the duplicates that appear when both ends record into the
same trace (it keeps the client side of an XML-RPC call and the sending side of TCPROS bytes).
"""

from __future__ import annotations

import itertools
import threading
import time
from collections import deque
from dataclasses import asdict, dataclass, replace
from typing import Any

KINDS = ("xmlrpc", "tcp_connect", "tcpros_header", "tcpros_frame", "tcp_close", "error")

_conn_ids = itertools.count(1)


def new_connection_id() -> int:
    """A process-wide unique id for a TCPROS connection."""
    return next(_conn_ids)


@dataclass
class TraceEvent:
    """One recorded step of the conversation (see the module docstring for every field)."""

    seq: int
    t: float
    kind: str
    recorder: str
    role: str = ""
    src: str = ""
    dst: str = ""
    method: str = ""
    args: Any = None
    result: Any = None
    raw: bytes = b""
    raw_reply: bytes = b""
    size: int = 0
    conn: int = 0
    index: int = -1
    offset: int = -1
    t0: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """The event as a plain dict."""
        return asdict(self)


class Trace:
    """A bounded, thread-safe list of :class:`TraceEvent`.

    Args:
        max_events: keep at most this many (oldest evicted, counted in ``dropped``).
        frame_bytes: body bytes of each frame to keep in ``raw`` (the rest is only counted).
        frames: record frame events at all (headers and XML-RPC are always recorded).
    """

    def __init__(self, max_events: int = 20_000, frame_bytes: int = 64, frames: bool = True) -> None:
        self.max_events = max_events
        self.frame_bytes = frame_bytes
        self.frames = frames
        self.enabled = True
        self.dropped = 0
        self._events: deque[TraceEvent] = deque()
        self._seq = 0
        self._lock = threading.Lock()
        #: URI or host:port -> node name, filled in by nodes and masters as they learn them
        self.names: dict[str, str] = {}

    def record(self, kind: str, recorder: str, **fields: Any) -> TraceEvent | None:
        """Append an event; returns it (None when recording is disabled)."""
        if not self.enabled:
            return None
        now = time.time()
        fields.setdefault("t0", now)
        with self._lock:
            ev = TraceEvent(seq=self._seq, t=now, kind=kind, recorder=recorder, **fields)
            self._seq += 1
            self._events.append(ev)
            while len(self._events) > self.max_events:
                self._events.popleft()
                self.dropped += 1
        return ev

    def frame_raw(self, body: bytes | bytearray | memoryview) -> bytes:
        """What a ``tcpros_frame`` event keeps of a frame: its 4-byte length prefix and the
        first :attr:`frame_bytes` body bytes."""
        return len(body).to_bytes(4, "little") + bytes(body[:self.frame_bytes])

    def name_of(self, endpoint: str) -> str:
        """The node name for a URI or host:port when known, else the endpoint itself."""
        return self.names.get(endpoint, endpoint)

    @property
    def events(self) -> list[TraceEvent]:
        """A snapshot of the events, oldest first."""
        with self._lock:
            return list(self._events)

    def __len__(self) -> int:
        return len(self._events)

    def clear(self) -> None:
        """Forget every event (``seq`` keeps counting)."""
        with self._lock:
            self._events.clear()

    def to_dicts(self) -> list[dict[str, Any]]:
        """The events as plain dicts (for pandas, JSON after encoding bytes, widgets)."""
        return [e.to_dict() for e in self.events]

    def conversation(self) -> list[TraceEvent]:
        """Events with both-ends duplicates removed, names resolved, in time order.

        An event recorded by the receiving side (XML-RPC ``server``, TCPROS ``in``) is dropped
        when its sender also records into this trace, because the sender's own record (client
        / ``out``) describes the same bytes. ``src``/``dst`` given as URIs or host:port are
        replaced by node names where :attr:`names` knows them.
        """
        evs = self.events
        recorders = {e.recorder for e in evs}
        out = []
        for e in evs:
            src, dst = self.name_of(e.src), self.name_of(e.dst)
            if e.role in ("server", "in") and src in recorders and e.kind != "error":
                continue
            if (src, dst) != (e.src, e.dst):
                e = replace(e, src=src, dst=dst)
            out.append(e)
        return sorted(out, key=lambda e: (e.t0, e.seq))

    def summary(self) -> list[str]:
        """One line per conversation step: ``time src -> dst: what``."""
        lines = []
        evs = self.conversation()
        start = evs[0].t0 if evs else 0.0
        for e in evs:
            what = e.method if e.kind == "xmlrpc" else f"{e.kind} {e.method}".strip()
            if e.kind == "tcpros_frame":
                what += f" #{e.index} ({e.size} B)"
            lines.append(f"{e.t0 - start:8.4f}s {e.src} -> {e.dst}: {what}")
        return lines
