"""The TCPROS handshake as two state machines driven by one transition table.

How it works: a subscriber connects to the publisher's TCPROS port and speaks first, sending
its connection header (``callerid``, ``md5sum``, ``topic``, ``type``, ``tcp_nodelay`` and,
from rospy, ``message_definition``). The publisher checks it the way roscpp's
``Publication::validateHeader`` does and answers either with its own header (``callerid``,
``latching``, ``md5sum``, ``message_definition``, ``topic``, ``type``) followed by message
frames, or with a single ``error=...`` field and a hang-up. The subscriber checks the reply
(an ``error`` field, the required ``md5sum`` and ``type``, a matching md5 unless either side
says ``*``) and then reads frames.

:data:`TRANSITIONS` is the only copy of the rules: the machines look every move up in it (a
move it does not list raises :class:`StateError`), and notebooks draw it. Both machines are
sans-IO: bytes in, events out; the caller owns the socket and the clock (it calls
:meth:`timeout` when :data:`HANDSHAKE_TIMEOUT` passes without a complete header).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum

from rosfpga_lab.tcpros.errors import (
    HandshakeRejected,
    HandshakeTimeout,
    IncompleteError,
    ProtocolError,
    RemoteError,
    StateError,
)
from rosfpga_lab.tcpros.limits import (
    HISTORY_REPEATS,
    MAX_FIELD_BYTES,
    MAX_FRAME_BYTES,
    MAX_HEADER_BYTES,
)
from rosfpga_lab.tcpros.frame import FrameDecoder, encode_frame, frame_prefix
from rosfpga_lab.msg.span import Span
from rosfpga_lab.tcpros.header import HeaderDecoder, encode_header

#: md5sum (and type) wildcard: "any type" (used by rostopic echo and topic_tools).
ANY = "*"


class _Name(StrEnum):
    """A name from the handshake's vocabulary: compares equal to its text and prints as it
    (``State.STREAMING == "STREAMING"``; shown as ``STREAMING``), like h11's sentinels."""

    def __repr__(self) -> str:
        return self.value


class Role(_Name):
    """The two sides of a TCPROS connection."""

    SUBSCRIBER = "subscriber"
    PUBLISHER = "publisher"


class State(_Name):
    """Handshake states (both roles)."""

    IDLE = "IDLE"
    AWAIT_HEADER = "AWAIT_HEADER"
    STREAMING = "STREAMING"
    FAILED = "FAILED"
    REJECTED = "REJECTED"
    CLOSED = "CLOSED"


class Trigger(_Name):
    """What happened: the events that move a handshake machine."""

    CONNECT = "connect"
    HEADER_OK = "header_ok"
    HEADER_ERROR = "header_error"
    HEADER_BAD = "header_bad"
    HEADER_REJECTED = "header_rejected"
    EOF = "eof"
    TIMEOUT = "timeout"
    FRAME = "frame"
    FRAME_BAD = "frame_bad"
    SEND = "send"
    CLOSE = "close"


@dataclass(frozen=True)
class Transition:
    """One row of the handshake table."""

    role: Role
    source: State    # state before
    trigger: Trigger  # what happened
    target: State    # state after
    action: str      # what the machine does / emits, in words (drawn by the notebooks)


_T, S, T = Transition, State, Trigger
SUB, PUB = Role.SUBSCRIBER, Role.PUBLISHER
TRANSITIONS: tuple[Transition, ...] = (
    _T(SUB, S.IDLE, T.CONNECT, S.AWAIT_HEADER,
       "send our header: callerid, md5sum, [message_definition], tcp_nodelay, topic, type"),
    _T(SUB, S.AWAIT_HEADER, T.HEADER_OK, S.STREAMING,
       "publisher header has md5sum and type, md5 matches (or '*'): emit Connected"),
    _T(SUB, S.AWAIT_HEADER, T.HEADER_ERROR, S.FAILED,
       "publisher answered error=...: raise RemoteError"),
    _T(SUB, S.AWAIT_HEADER, T.HEADER_BAD, S.FAILED,
       "header malformed, field missing or md5 mismatch: raise HeaderFormatError/HandshakeRejected"),
    _T(SUB, S.AWAIT_HEADER, T.EOF, S.FAILED, "closed before the header: raise IncompleteError"),
    _T(SUB, S.AWAIT_HEADER, T.TIMEOUT, S.FAILED, "no header in time: raise HandshakeTimeout"),
    _T(SUB, S.STREAMING, T.FRAME, S.STREAMING, "emit Frame(body)"),
    _T(SUB, S.STREAMING, T.FRAME_BAD, S.FAILED, "length over the limit: raise FrameError"),
    _T(SUB, S.STREAMING, T.EOF, S.CLOSED, "emit Closed (IncompleteError if mid-frame)"),
    _T(SUB, S.STREAMING, T.CLOSE, S.CLOSED, "we hang up"),
    _T(SUB, S.AWAIT_HEADER, T.CLOSE, S.CLOSED, "we hang up"),
    _T(PUB, S.AWAIT_HEADER, T.HEADER_OK, S.STREAMING,
       "subscriber header valid: send our header (callerid, latching, md5sum, "
       "message_definition, topic, type), then the latched message if any"),
    _T(PUB, S.AWAIT_HEADER, T.HEADER_REJECTED, S.REJECTED,
       "field missing, unknown topic or md5 mismatch: send error=..., hang up"),
    _T(PUB, S.AWAIT_HEADER, T.HEADER_BAD, S.REJECTED,
       "malformed header (bad length, no '=', not UTF-8): send error=..., hang up"),
    _T(PUB, S.AWAIT_HEADER, T.EOF, S.CLOSED, "subscriber left before its header"),
    _T(PUB, S.AWAIT_HEADER, T.TIMEOUT, S.REJECTED,
       "no header in time: send error=..., hang up (keeps the port free for others)"),
    _T(PUB, S.STREAMING, T.SEND, S.STREAMING, "write Frame(body)"),
    _T(PUB, S.STREAMING, T.EOF, S.CLOSED, "subscriber hung up"),
    _T(PUB, S.STREAMING, T.CLOSE, S.CLOSED, "we hang up"),
)

STATES: dict[Role, tuple[State, ...]] = {
    role: tuple(dict.fromkeys(s for t in TRANSITIONS if t.role == role for s in (t.source, t.target)))
    for role in Role
}


# ---------------------------------------------------------------------------------- events
@dataclass(frozen=True)
class HeaderReceived:
    """A complete connection header arrived (before it is checked)."""

    fields: dict[str, str]
    raw: bytes
    layout: tuple[Span, ...]  # the header's fields as spans (parse_fields)


@dataclass(frozen=True)
class Connected:
    """The handshake succeeded.

    Attributes:
        peer: the peer's header fields.
        reply: bytes the publisher must send now (its header); empty for the subscriber.
        topic: the topic agreed on.
        latching: the publisher said ``latching=1``.
        tcp_nodelay: the subscriber asked for ``tcp_nodelay=1``.
    """

    peer: dict[str, str]
    reply: bytes
    topic: str
    latching: bool
    tcp_nodelay: bool


@dataclass(frozen=True)
class Rejected:
    """The publisher refused the subscriber; send ``reply`` (an ``error=`` header), then close."""

    error: ProtocolError
    reply: bytes


@dataclass(frozen=True)
class Frame:
    """One message body (zero-copy memoryview or bytes) and its index on this connection."""

    body: bytes | memoryview
    index: int
    offset: int  # stream offset of the frame's length prefix


@dataclass(frozen=True)
class Closed:
    """The peer closed the connection cleanly (between frames)."""

    frames: int


Event = HeaderReceived | Connected | Rejected | Frame | Closed


@dataclass(frozen=True)
class TopicSpec:
    """What a publisher serves on a topic (the answer of a publisher's topic lookup)."""

    topic: str
    type: str
    md5sum: str
    message_definition: str = ""
    latching: bool = False


# ------------------------------------------------------------------------- header builders
def subscriber_request_fields(*, callerid: str, topic: str, md5sum: str, type_name: str,
                              message_definition: str | None = None,
                              tcp_nodelay: bool = False) -> dict[str, str]:
    """The connection header a subscriber opens with (rospy's field set; roscpp leaves out
    ``message_definition``). The one definition used by :class:`SubscriberHandshake` and by the
    generated circuit's precomputed header.

    Args:
        callerid: the subscribing node's name.
        topic, md5sum, type_name: what it subscribes to (``*`` for md5sum and type: any).
        message_definition: the full text of the type; None leaves the field out.
        tcp_nodelay: ask the publisher for TCP_NODELAY.

    Returns:
        ``{key: value}`` in key order (as the wire has them).
    """
    fields = {"callerid": callerid, "md5sum": md5sum, "tcp_nodelay": "1" if tcp_nodelay else "0",
              "topic": topic, "type": type_name}
    if message_definition is not None:
        fields["message_definition"] = message_definition
    return dict(sorted(fields.items()))


def publisher_reply_fields(callerid: str, spec: TopicSpec) -> dict[str, str]:
    """The connection header a publisher answers an accepted subscriber with (roscpp's field
    set). The one definition used by :class:`PublisherHandshake`, the graph's publisher and the
    generated circuit's precomputed header.

    Args:
        callerid: the publishing node's name.
        spec: what it publishes on the topic.

    Returns:
        ``{key: value}`` in key order: callerid, latching, md5sum, message_definition, topic, type.
    """
    return {"callerid": callerid, "latching": "1" if spec.latching else "0",
            "md5sum": spec.md5sum, "message_definition": spec.message_definition,
            "topic": spec.topic, "type": spec.type}


# ---------------------------------------------------------------------------------- checks
def check_subscriber_header(fields: Mapping[str, str], spec: TopicSpec | None,
                            peer: str = "") -> str | None:
    """Check a subscriber's header as roscpp's publisher does; return the error text or None.

    Args:
        fields: the subscriber's header.
        spec: what we publish on ``fields['topic']`` (None: not a topic of ours).
        peer: transport description used in roscpp's "nonexistent topic" text.
    """
    if "topic" not in fields:
        return "Header from subscriber did not have the required element: topic"
    topic = fields["topic"]
    caller = fields.get("callerid", "")
    if spec is None:
        return f"received a connection for a nonexistent topic [{topic}] from [{peer}] [{caller}]."
    if "md5sum" not in fields or "callerid" not in fields:
        return "Header from subscriber did not have the required elements: md5sum, topic, callerid"
    md5 = fields["md5sum"]
    if md5 != spec.md5sum and md5 != ANY and spec.md5sum != ANY:
        return (f"Client [{caller}] wants topic {topic} to have datatype/md5sum "
                f"[{fields.get('type', '')}/{md5}], but our version has "
                f"[{spec.type}/{spec.md5sum}]. Dropping connection.")
    return None


def check_publisher_header(fields: Mapping[str, str], md5sum: str, type_name: str) -> None:
    """Check a publisher's reply header as rospy/roscpp subscribers do.

    Raises:
        RemoteError: the reply is an ``error=`` header.
        HandshakeRejected: ``md5sum`` or ``type`` missing, or an md5 mismatch.
    """
    if "error" in fields:
        raise RemoteError(f"publisher refused the connection: {fields['error']}")
    for required in ("md5sum", "type"):
        if required not in fields:
            raise HandshakeRejected(f"Publisher header did not have required element: {required}")
    theirs = fields["md5sum"]
    if theirs != md5sum and ANY not in (theirs, md5sum):
        raise HandshakeRejected(
            f"publisher's md5sum/type [{theirs}/{fields['type']}] does not match ours "
            f"[{md5sum}/{type_name}]: the two sides were built from different .msg files")


# ---------------------------------------------------------------------------------- machines
class _Machine:
    role: Role

    def __init__(self, initial: State) -> None:
        self.state = initial
        #: the transitions taken, in order; a self-loop (``frame``, ``send``) appears at most
        #: ``HISTORY_REPEATS`` times in a row, so the list stays short on a long stream
        self.history: list[Transition] = []
        #: self-loop transitions taken but not kept in ``history``, by trigger
        self.repeats: dict[Trigger, int] = {}

    def _fire(self, trigger: Trigger) -> Transition:
        for t in TRANSITIONS:
            if t.role == self.role and t.source == self.state and t.trigger == trigger:
                self.state = t.target
                h = self.history
                if t.source == t.target and len(h) >= HISTORY_REPEATS and \
                        all(x is t for x in h[-HISTORY_REPEATS:]):
                    self.repeats[trigger] = self.repeats.get(trigger, 0) + 1
                else:
                    h.append(t)
                return t
        raise StateError(f"{self.role} handshake: '{trigger}' is not allowed in state {self.state}")

    def close(self) -> None:
        """We hang up (allowed while waiting or streaming; a no-op once finished)."""
        if self.state in (State.AWAIT_HEADER, State.STREAMING):
            self._fire(Trigger.CLOSE)


class SubscriberHandshake(_Machine):
    """The connecting side. Call :meth:`initiate`, send its bytes, feed what comes back.

    Args:
        callerid: our node name.
        topic: topic we subscribe to.
        md5sum: md5 of our message type (or ``*``).
        type_name: our message type (or ``*``).
        message_definition: sent when given (rospy sends it, roscpp does not).
        tcp_nodelay: ask the publisher for TCP_NODELAY.
    """

    role = Role.SUBSCRIBER

    def __init__(self, *, callerid: str, topic: str, md5sum: str, type_name: str,
                 message_definition: str | None = None, tcp_nodelay: bool = False,
                 max_header: int = MAX_HEADER_BYTES, max_field: int = MAX_FIELD_BYTES,
                 max_frame: int = MAX_FRAME_BYTES) -> None:
        super().__init__(State.IDLE)
        self.fields: dict[str, str] = subscriber_request_fields(
            callerid=callerid, topic=topic, md5sum=md5sum, type_name=type_name,
            message_definition=message_definition, tcp_nodelay=tcp_nodelay)
        self._header = HeaderDecoder(max_header=max_header, max_field=max_field)
        self._max_frame = max_frame
        self._frames: FrameDecoder | None = None
        self.peer: dict[str, str] | None = None

    def initiate(self) -> bytes:
        """Return our connection header (to send right after connecting)."""
        self._fire(Trigger.CONNECT)
        return encode_header(self.fields)

    def receive_data(self, data: bytes | memoryview) -> list[Event]:
        """Feed bytes from the publisher; return the events they complete.

        Raises:
            RemoteError, HandshakeRejected, HeaderFormatError, FrameError: see the table. A
                FrameError's ``partial`` holds the events decoded before the bad length.
        """
        if self.state is State.AWAIT_HEADER:
            try:
                fields = self._header.feed(data)
            except ProtocolError:
                self._fire(Trigger.HEADER_BAD)
                raise
            if fields is None:
                return []
            events: list[Event] = [HeaderReceived(fields, self._header.raw, tuple(self._header.layout))]
            try:
                check_publisher_header(fields, self.fields["md5sum"], self.fields["type"])
            except RemoteError:
                self._fire(Trigger.HEADER_ERROR)
                raise
            except ProtocolError:
                self._fire(Trigger.HEADER_BAD)
                raise
            self._fire(Trigger.HEADER_OK)
            self.peer = fields
            events.append(Connected(fields, b"", self.fields["topic"],
                                    fields.get("latching", "0") == "1",
                                    self.fields["tcp_nodelay"] == "1"))
            self._frames = FrameDecoder(max_frame=self._max_frame, stream_offset=self._header.consumed)
            if self._header.remainder:
                try:
                    events += self._frames_from(self._header.remainder)
                except ProtocolError as exc:
                    exc.partial = events + exc.partial
                    raise
            return events
        if self.state is State.STREAMING:
            return self._frames_from(data)
        raise StateError(f"subscriber handshake: data received in state {self.state}")

    def _frames_from(self, data: bytes | memoryview) -> list[Event]:
        assert self._frames is not None
        dec = self._frames
        start = dec.frames
        try:
            bodies = dec.feed(data)
        except ProtocolError as exc:
            exc.partial = self._frame_events(exc.partial, start)
            self._fire(Trigger.FRAME_BAD)
            raise
        return self._frame_events(bodies, start)

    def _frame_events(self, bodies: list, start: int) -> list[Event]:
        assert self._frames is not None
        out: list[Event] = []
        for i, (body, at) in enumerate(zip(bodies, self._frames.starts)):
            self._fire(Trigger.FRAME)
            out.append(Frame(body, start + i, at))
        return out

    def body_buffer(self) -> memoryview | None:
        """While streaming inside a frame body: the writable rest of that body, else None.

        A reader receives big frames straight into it (``n = sock.recv_into(view)``, then
        :meth:`receive_into`) instead of copying from a chunk; when this is None it feeds
        :meth:`receive_data`. See :meth:`FrameDecoder.pending_body`.
        """
        if self.state is not State.STREAMING or self._frames is None:
            return None
        return self._frames.pending_body()

    def receive_into(self, n: int) -> list[Event]:
        """``n`` (> 0) bytes were written into the view of :meth:`body_buffer`: the events.

        Raises:
            StateError: not streaming, no body pending, or ``n`` larger than what it misses.
        """
        if self.state is not State.STREAMING or self._frames is None:
            raise StateError(f"subscriber handshake: receive_into in state {self.state}")
        start = self._frames.frames
        return self._frame_events(self._frames.filled(n), start)

    def receive_eof(self) -> list[Event]:
        """The publisher closed the connection.

        Raises:
            IncompleteError: closed before the header completed, or mid-frame.
        """
        if self.state is State.AWAIT_HEADER:
            self._fire(Trigger.EOF)
            self._header.eof()
        if self.state is State.STREAMING:
            self._fire(Trigger.EOF)
            assert self._frames is not None
            self._frames.eof()
            return [Closed(self._frames.frames)]
        return []

    def timeout(self) -> None:
        """The handshake time-out expired.

        Raises:
            HandshakeTimeout: always (when still waiting for the header).
        """
        if self.state is State.AWAIT_HEADER:
            self._fire(Trigger.TIMEOUT)
            raise HandshakeTimeout(
                f"publisher sent no complete connection header for {self.fields['topic']} in time")


class PublisherHandshake(_Machine):
    """The accepting side: feed the subscriber's bytes; send what the events say.

    Args:
        callerid: our node name.
        lookup: ``topic -> TopicSpec`` for topics we publish, None for others.
        peer: description of the remote end, used in error texts.
    """

    role = Role.PUBLISHER

    def __init__(self, *, callerid: str, lookup: Callable[[str], TopicSpec | None],
                 peer: str = "", max_header: int = MAX_HEADER_BYTES,
                 max_field: int = MAX_FIELD_BYTES) -> None:
        super().__init__(State.AWAIT_HEADER)
        self.callerid = callerid
        self.lookup = lookup
        self.peer_desc = peer
        self._header = HeaderDecoder(max_header=max_header, max_field=max_field)
        self.spec: TopicSpec | None = None
        self.peer: dict[str, str] | None = None
        self.frames_sent = 0

    def reply_fields(self, spec: TopicSpec) -> dict[str, str]:
        """Our answer header for ``spec`` (:func:`publisher_reply_fields`)."""
        return publisher_reply_fields(self.callerid, spec)

    def _reject(self, trigger: Trigger, error: ProtocolError) -> list[Event]:
        self._fire(trigger)
        return [Rejected(error, encode_header({"error": str(error)}))]

    def receive_data(self, data: bytes | memoryview) -> list[Event]:
        """Feed bytes from the subscriber; return the events (Connected or Rejected)."""
        if self.state is not State.AWAIT_HEADER:
            return []  # subscribers send nothing after their header; ignore stray bytes
        try:
            fields = self._header.feed(data)
        except ProtocolError as exc:
            return self._reject(Trigger.HEADER_BAD, exc)
        if fields is None:
            return []
        events: list[Event] = [HeaderReceived(fields, self._header.raw, tuple(self._header.layout))]
        spec = self.lookup(fields["topic"]) if "topic" in fields else None
        problem = check_subscriber_header(fields, spec, self.peer_desc)
        if problem is not None:
            return events + self._reject(Trigger.HEADER_REJECTED, HandshakeRejected(problem))
        assert spec is not None
        self._fire(Trigger.HEADER_OK)
        self.spec, self.peer = spec, fields
        events.append(Connected(fields, encode_header(self.reply_fields(spec)), spec.topic,
                                spec.latching, fields.get("tcp_nodelay", "0").strip() == "1"))
        return events

    def receive_eof(self) -> list[Event]:
        """The subscriber closed the connection."""
        if self.state in (State.AWAIT_HEADER, State.STREAMING):
            self._fire(Trigger.EOF)
            return [Closed(self.frames_sent)]
        return []

    def timeout(self) -> list[Event]:
        """The handshake time-out expired: returns Rejected (send its reply, close)."""
        if self.state is not State.AWAIT_HEADER:
            return []
        return self._reject(Trigger.TIMEOUT, HandshakeTimeout(
            "no complete connection header received in time; closing"))

    def send(self, body: bytes | memoryview) -> bytes:
        """Frame ``body`` for sending (only once streaming).

        Raises:
            StateError: not streaming (before the handshake, or after eof/close).
        """
        self._fire(Trigger.SEND)
        self.frames_sent += 1
        return encode_frame(body)

    def send_parts(self, body: bytes | bytearray | memoryview) -> tuple[bytes, memoryview]:
        """:meth:`send` without joining: ``(length prefix, body)`` for a vectored write, so a
        big image is not copied. This is what a node's publisher streams through.

        Raises:
            StateError: not streaming (before the handshake, or after eof/close).
        """
        view = memoryview(body).cast("B")
        self._fire(Trigger.SEND)
        self.frames_sent += 1
        return frame_prefix(len(view)), view


__all__ = [
    "ANY", "Closed", "Connected", "Event", "Frame", "HeaderReceived", "IncompleteError",
    "PublisherHandshake", "Rejected", "STATES", "SubscriberHandshake", "TRANSITIONS",
    "TopicSpec", "Transition", "check_publisher_header", "check_subscriber_header",
]
