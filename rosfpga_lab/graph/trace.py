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
           response; for frames the 4-byte prefix plus the first ``frame_bytes`` body bytes.
           A payload longer than ``excerpt_bytes`` keeps only its first ``excerpt_bytes``
           bytes, and then ``args``/``result`` keep an excerpt too (long strings cut, long
           lists shortened, each marked with its full length)
raw_reply  see above (xmlrpc only)
size       total bytes on the wire (for frames: 4 + body length)
conn       connection id (same for the header and frames of one TCPROS link)
index      frame number on its connection; offset: stream offset of the frame's prefix
local,     ``host:port`` of the recorder's and of the peer's end of the TCP connection that
remote     carried the bytes (empty when unknown); with ``role`` they give the bytes'
           direction, and a ``tcp_connect`` (role ``out``: the recorder connected) or an xmlrpc
           event (the client connected) tells which end opened it (capture files use this)
========== ============================================================================

Bounds: a trace keeps at most ``max_events`` events and about ``max_bytes`` bytes (raw bytes
plus an estimate of the decoded values); the oldest events go first and ``dropped`` counts
them. :meth:`Trace.excerpt`, :meth:`Trace.frame_raw` and :func:`excerpt_value` are the one
place that decides what of a payload is kept.

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

from rosfpga_lab.graph.limits import TRACE_EXCERPT_BYTES, TRACE_MAX_BYTES, TRACE_MAX_EVENTS

#: (``service_call``: a TCPROS service header or call, by its service name; no bytes kept)
KINDS = ("xmlrpc", "tcp_connect", "tcpros_header", "tcpros_frame", "tcp_close", "error", "service_call")

_conn_ids = itertools.count(1)


def new_connection_id() -> int:
    """A process-wide unique id for a TCPROS connection."""
    return next(_conn_ids)


#: Bytes an event costs beyond its raw bytes (the dataclass, its small fields).
_EVENT_OVERHEAD = 512
#: What :func:`excerpt_value` keeps: characters of one string, items overall, nesting levels.
_TEXT_KEPT = 256
_ITEMS_KEPT = 64
_DEPTH_KEPT = 8


def excerpt_value(value: Any) -> Any:
    """A small copy of a decoded XML-RPC value or header dict, for a trace.

    Strings and bytes longer than 256 keep their start and say their length; lists and dicts
    keep their first items (64 over the whole value) and say how many there were; nesting
    deeper than 8 levels is replaced by a note.
    """
    budget = [_ITEMS_KEPT]

    def cut(v: Any, depth: int) -> Any:
        if isinstance(v, (str, bytes, bytearray)):
            if len(v) <= _TEXT_KEPT:
                return v
            if isinstance(v, str):
                return v[:_TEXT_KEPT] + f"... ({len(v)} chars)"
            return bytes(v[:_TEXT_KEPT]) + f"... ({len(v)} bytes)".encode()
        if not isinstance(v, (list, tuple, dict)):
            return v
        if depth >= _DEPTH_KEPT:
            return f"... (nested deeper than {_DEPTH_KEPT} levels)"
        items = list(v.items()) if isinstance(v, dict) else list(v)
        kept = items[:max(0, budget[0])]
        budget[0] -= len(kept)
        if isinstance(v, dict):
            out: Any = {k: cut(x, depth + 1) for k, x in kept}
            if len(kept) < len(items):
                out["..."] = f"{len(items)} keys"
            return out
        out = [cut(x, depth + 1) for x in kept]
        if len(kept) < len(items):
            out.append(f"... ({len(items)} items)")
        return out

    return cut(value, 0)


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
    local: str = ""
    remote: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The event as a plain dict."""
        return asdict(self)


class Trace:
    """A bounded, thread-safe list of :class:`TraceEvent`.

    Args:
        max_events: keep at most this many (oldest evicted, counted in ``dropped``).
        frame_bytes: body bytes of each frame to keep in ``raw`` (the rest is only counted).
        frames: record frame events at all (headers and XML-RPC are always recorded).
        max_bytes: keep about this many bytes at most (oldest evicted, counted in ``dropped``).
        excerpt_bytes: bytes of one payload (``raw``, ``raw_reply``) kept; a longer one keeps
            its start, and the event's ``args``/``result`` are cut with :func:`excerpt_value`.
    """

    def __init__(self, max_events: int = TRACE_MAX_EVENTS, frame_bytes: int = 64,
                 frames: bool = True, *, max_bytes: int = TRACE_MAX_BYTES,
                 excerpt_bytes: int = TRACE_EXCERPT_BYTES) -> None:
        self.max_events = max_events
        self.frame_bytes = frame_bytes
        self.frames = frames
        self.max_bytes = max_bytes
        self.excerpt_bytes = excerpt_bytes
        self.enabled = True
        self.dropped = 0
        self._events: deque[TraceEvent] = deque()
        self._costs: deque[int] = deque()
        self._held = 0
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
        # a caller that cut the payload already (Trace.excerpt) says so through a larger size
        cut = kind != "tcpros_frame" and fields.get("size", 0) > \
            len(fields.get("raw", b"")) + len(fields.get("raw_reply", b""))
        for key in ("raw", "raw_reply"):
            data = fields.get(key)
            if data is not None and len(data) > self.excerpt_bytes:
                fields[key] = self.excerpt(data)
                cut = True
        if cut:
            for key in ("args", "result"):
                if key in fields:
                    fields[key] = excerpt_value(fields[key])
        # the decoded args/result are about as big as the bytes they came from: count them twice
        cost = _EVENT_OVERHEAD + 2 * (len(fields.get("raw", b"")) + len(fields.get("raw_reply", b"")))
        with self._lock:
            ev = TraceEvent(seq=self._seq, t=now, kind=kind, recorder=recorder, **fields)
            self._seq += 1
            self._events.append(ev)
            self._costs.append(cost)
            self._held += cost
            while self._events and (len(self._events) > self.max_events or self._held > self.max_bytes):
                self._events.popleft()
                self._held -= self._costs.popleft()
                self.dropped += 1
        return ev

    def set_result(self, ev: TraceEvent | None, value: Any) -> None:
        """Fill in an event's ``result`` afterwards (an excerpt when its reply was cut)."""
        if ev is None:
            return
        if ev.kind != "tcpros_frame" and len(ev.raw) + len(ev.raw_reply) < ev.size:
            value = excerpt_value(value)
        ev.result = value

    def excerpt(self, *parts: bytes | bytearray | memoryview) -> bytes:
        """What an event keeps of a payload (given whole or as consecutive parts, e.g. an HTTP
        head and body): all of it up to :attr:`excerpt_bytes`, else its first that many bytes.
        Give the event the full length as ``size``."""
        out = bytearray()
        for part in parts:
            room = self.excerpt_bytes - len(out)
            if room <= 0:
                break
            out += part[:room]
        return bytes(out)

    @property
    def bytes_held(self) -> int:
        """About how many bytes the kept events hold (what ``max_bytes`` bounds)."""
        return self._held

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
            self._costs.clear()
            self._held = 0

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
