"""A topic subscriber: one connection thread per publisher, one dispatcher thread.

How it works: the master's ``registerSubscriber`` reply and later ``publisherUpdate`` calls
give the publishers' XML-RPC URIs. For each, a link thread asks ``requestTopic`` for a TCPROS
address, connects, runs the subscriber side of the handshake and reads frames into the
subscriber's bounded queue (a frame body is received straight into a buffer of its announced
length, so a big image is not copied on its way in) (``queue_size``: the oldest frame is dropped and counted when the
callback falls behind). At most ``max_publishers`` links exist at once (a publisher list
longer than that is cut, keeping the links already open, and logged). A dispatcher thread calls the callback, so a slow callback never
stalls the socket. When a connection drops, the link retries with exponential back-off
(0.1 s doubling up to ``RECONNECT_MAX``) for as long as the master still lists that
publisher; a refused handshake (md5 mismatch, ``error=`` reply) is not retried.

A publisher list without a connected publisher (its ``unregisterPublisher``, or a spoofed
``publisherUpdate`` with an empty list) does not close the link: like rospy, the subscriber keeps
it until the connection ends (a publisher that unregisters closes its connections), then does
not retry. Across a master restart (:meth:`Node.register_again`) established links are kept the
same way, as roscpp keeps them: the new master does not list their publishers until those register again (rospy and
roscpp never do), so such a link is *kept* rather than confirmed. Later publisher lists never
remove a kept link; one that lists its publisher confirms it; when its publisher closes the
connection, it ends without retrying.
"""

from __future__ import annotations

import collections
import logging
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosfpga_lab.graph.errors import GraphError, MasterError
from rosfpga_lab.graph.limits import (
    CONNECT_TIMEOUT,
    JOIN_TIMEOUT,
    MAX_ERRORS_KEPT,
    RECONNECT_FACTOR,
    RECONNECT_FIRST,
    RECONNECT_MAX,
)
from rosfpga_lab.graph.trace import new_connection_id
from rosfpga_lab.graph.wire import RECV_CHUNK, hard_close, set_nodelay, socket_ends
from rosfpga_lab.graph.xmlrpc import call
from rosfpga_lab.errors import LabError
from rosfpga_lab.tcpros import (
    HANDSHAKE_TIMEOUT,
    Closed,
    Connected,
    Frame,
    HandshakeRejected,
    HeaderReceived,
    ProtocolError,
    RemoteError,
    State,
    SubscriberHandshake,
)

if TYPE_CHECKING:
    from rosfpga_lab.graph.topic import TopicContext

log = logging.getLogger("rosfpga_lab.graph")


@dataclass(frozen=True)
class MessageInfo:
    """Where a message came from (second argument of a raw callback)."""

    topic: str
    publisher: str          # the publisher's callerid
    conn: int               # connection id (as in the trace)
    index: int              # frame number on that connection
    size: int               # body bytes
    received: float         # time.time() when the frame was complete
    header: dict[str, str] = field(repr=False, default_factory=dict)  # publisher's connection header


@dataclass
class SubscriberStats:
    """Frames/bytes received, drops in our queue, publishers connected, errors seen."""

    frames: int = 0
    bytes: int = 0
    drops: int = 0
    connections: int = 0
    callback_errors: int = 0
    errors: list[str] = field(default_factory=list)


class _PublisherLink:
    def __init__(self, sub: Subscriber, pub_uri: str) -> None:
        self.sub = sub
        self.pub_uri = pub_uri
        self.stop = threading.Event()
        self.sock: socket.socket | None = None
        self.connected = False
        self.kept = False   # kept across a master restart, not (yet) listed by the master
        self.permanent_error: str | None = None
        self.conn = 0              # connection id of the current (or last) TCPROS connection
        self.frames = 0            # frames and body bytes received on it (getBusStats)
        self.bytes = 0
        self.thread = threading.Thread(target=self._run, daemon=True,
                                       name=f"rosfpga-sub-link-{sub.topic}")

    def _run(self) -> None:
        delay = RECONNECT_FIRST
        while not self.stop.is_set():
            try:
                if self._connect_once():  # the handshake succeeded: back-off starts over (as roscpp)
                    delay = RECONNECT_FIRST
            except (RemoteError, HandshakeRejected) as exc:
                self.permanent_error = str(exc)
                self.sub._error(f"{self.pub_uri}: {exc} (not retrying)")
                return
            except (LabError, OSError) as exc:
                if not self.stop.is_set():
                    self.sub._error(f"{self.pub_uri}: {exc}")
            finally:
                self._drop_socket()
            if self.kept and self.sub._forget(self):
                return  # its publisher closed it and the master does not list it: no retry
            if self.stop.wait(delay):
                return
            delay = min(delay * RECONNECT_FACTOR, RECONNECT_MAX)

    def _drop_socket(self) -> None:
        if self.connected:
            self.connected = False
            self.sub._connections_changed(-1)
        if self.sock is not None:
            hard_close(self.sock)
            self.sock = None

    def _request_topic(self) -> tuple[str, int]:
        """Ask the publisher's slave API for a TCPROS address: (host, port)."""
        sub, node = self.sub, self.sub.context
        reply = call(self.pub_uri, "requestTopic", node.name, sub.topic, [["TCPROS"]],
                     trace=node.trace, caller=node.name, timeout=CONNECT_TIMEOUT)
        if not (isinstance(reply, list) and len(reply) == 3 and reply[0] == 1):
            raise MasterError(f"requestTopic refused: {reply!r}")
        proto = reply[2]
        if not (isinstance(proto, list) and len(proto) >= 3 and proto[0] == "TCPROS"
                and isinstance(proto[1], str) and isinstance(proto[2], int)):
            raise GraphError(f"requestTopic gave an unusable protocol description: {proto!r}")
        return proto[1], proto[2]

    def _send_header(self, sock: socket.socket, conn: int,
                     ends: dict[str, str]) -> SubscriberHandshake:
        """Start the handshake: send the subscriber's connection header, recorded in the trace."""
        sub, node = self.sub, self.sub.context
        hs = SubscriberHandshake(callerid=node.name, topic=sub.topic, md5sum=sub.md5sum,
                                 type_name=sub.type_name, message_definition=sub.message_definition,
                                 tcp_nodelay=sub.tcp_nodelay, max_frame=sub.max_frame)
        request = hs.initiate()
        t0 = time.time()
        sock.sendall(request)
        node.trace.record("tcpros_header", node.name, role="out", src=node.name,
                          dst=node.trace.name_of(self.pub_uri), method=sub.topic,
                          args=dict(hs.fields), raw=request, size=len(request), conn=conn, t0=t0,
                          **ends)
        return hs

    def _connect_once(self) -> bool:
        sub, node = self.sub, self.sub.context
        host, port = self._request_topic()
        if self.stop.is_set():
            return False
        sock = socket.create_connection((host, port), timeout=CONNECT_TIMEOUT)
        self.sock = sock
        if self.stop.is_set():
            return False
        if sub.tcp_nodelay:
            set_nodelay(sock)
        conn = new_connection_id()
        self.conn, self.frames, self.bytes = conn, 0, 0
        peer = f"{host}:{port}"
        ends = socket_ends(sock)
        node.trace.names[ends["local"]] = node.name
        node.trace.record("tcp_connect", node.name, role="out", src=node.name,
                          dst=node.trace.name_of(self.pub_uri), method=sub.topic, conn=conn, **ends)
        hs = self._send_header(sock, conn, ends)
        deadline = time.monotonic() + HANDSHAKE_TIMEOUT
        publisher, header = peer, dict[str, str]()
        got = False
        while not self.stop.is_set():
            if hs.state is State.AWAIT_HEADER:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    hs.timeout()
                sock.settimeout(remaining)
            # inside a frame body the bytes land straight in the frame's buffer (no copy);
            # otherwise a small chunk, whose whole frames come out as zero-copy views of it
            view = hs.body_buffer()
            try:
                if view is not None:
                    n = sock.recv_into(view)
                    view.release()
                else:
                    data = sock.recv(RECV_CHUNK)
                    n = len(data)
            except TimeoutError:
                hs.timeout()
                raise
            failure: ProtocolError | None = None
            try:
                if not n:
                    events = hs.receive_eof()
                else:
                    events = hs.receive_data(data) if view is None else hs.receive_into(n)
            except ProtocolError as exc:  # deliver what came before the bad bytes, then fail
                events, failure = exc.partial, exc
            for ev in events:
                if isinstance(ev, Frame):
                    self.frames += 1
                    self.bytes += len(ev.body)
                    sub._deliver(ev.body, MessageInfo(sub.topic, publisher, conn, ev.index,
                                                      len(ev.body), time.time(), header), ev.offset, ends)
                elif isinstance(ev, HeaderReceived):
                    publisher = ev.fields.get("callerid", peer)
                    header = ev.fields
                    node.trace.names[peer] = publisher
                    node.trace.record("tcpros_header", node.name, role="in", src=publisher,
                                      dst=node.name, method=sub.topic, args=dict(ev.fields),
                                      raw=ev.raw, size=len(ev.raw), conn=conn,
                                      result=ev.fields.get("error"), **ends)
                elif isinstance(ev, Connected):
                    got = True
                    sock.settimeout(None)
                    self.connected = True
                    sub._connections_changed(+1)
                elif isinstance(ev, Closed):
                    node.trace.record("tcp_close", node.name, role="in", src=publisher,
                                      dst=node.name, method=sub.topic, conn=conn, **ends)
                    return got
            if failure is not None:
                raise failure
            if not n:
                return got
        return got

    def close(self) -> None:
        self.stop.set()
        sock = self.sock
        if sock is not None:
            hard_close(sock)


class Subscriber:
    """Subscribes to one topic. Create with :meth:`Node.subscribe`, not directly.

    Args:
        context: what the subscriber may use of its node (:class:`TopicContext`).
    """

    def __init__(self, context: TopicContext, topic: str, type_name: str, md5sum: str,
                 callback: Callable[..., Any] | None, *, raw: bool, queue_size: int,
                 tcp_nodelay: bool, message_definition: str | None, max_frame: int,
                 max_publishers: int) -> None:
        self.context = context
        self.topic = topic
        self.type_name = type_name
        self.md5sum = md5sum
        self.callback = callback
        self.raw = raw
        self.queue_size = int(queue_size or 0)
        self.tcp_nodelay = tcp_nodelay
        self.message_definition = message_definition
        self.max_frame = max_frame
        self.max_publishers = max(1, int(max_publishers))
        self._stats = SubscriberStats()
        self._links: dict[str, _PublisherLink] = {}
        self._queue: collections.deque = collections.deque()
        self._cond = threading.Condition()
        self._lock = threading.Lock()
        self.closed = False
        self.last: tuple[Any, MessageInfo] | None = None
        self._dispatcher = threading.Thread(target=self._dispatch_loop, daemon=True,
                                            name=f"rosfpga-sub-dispatch-{topic}")
        self._dispatcher.start()

    # ----------------------------------------------------------------- publishers
    def update_publishers(self, uris: list[str], *, keep_live: bool = False) -> None:
        """Make the links follow the master's publisher list ``uris`` (``registerSubscriber``'s
        reply, ``publisherUpdate``): new ones are connected; an unlisted one still trying to
        connect is closed, a connected one is *kept* until its connection ends (a publisher that
        unregisters closes it), as rospy keeps it: a spoofed ``publisherUpdate`` with an empty
        list cannot cut a live link.

        ``keep_live`` (a restarted master's first list) is accepted for the callers; every list
        now keeps live links (see the module docstring).
        """
        with self._lock:
            if self.closed:
                return
            wanted = list(dict.fromkeys(uris))
            if len(wanted) > self.max_publishers:  # links already open stay, then list order
                old = [u for u in wanted if u in self._links]
                new = [u for u in wanted if u not in self._links]
                kept = (old + new)[:self.max_publishers]
                text = (f"{len(wanted)} publishers listed for {self.topic}; linking to "
                        f"{len(kept)} (max_publishers), ignoring {len(wanted) - len(kept)}")
                log.warning("%s: %s", self.context.name, text)
                self._error(text)
                keep = set(kept)
                wanted = [u for u in wanted if u in keep]
            for uri in [u for u in self._links if u not in wanted]:
                stale = self._links[uri]
                if stale.kept or stale.connected:  # live: kept until it fails (as rospy)
                    stale.kept = True
                    continue
                self._links.pop(uri).close()
            for uri in wanted:
                link = self._links.get(uri)
                if link is not None:
                    link.kept = False   # the master lists it again: an ordinary link
                if link is None or not link.thread.is_alive() and link.permanent_error is None:
                    fresh = _PublisherLink(self, uri)
                    self._links[uri] = fresh
                    fresh.thread.start()

    def _forget(self, link: _PublisherLink) -> bool:
        """Drop a kept link whose connection ended; False when the master listed it meanwhile."""
        with self._lock:
            if not link.kept:
                return False
            if self._links.get(link.pub_uri) is link:
                del self._links[link.pub_uri]
            return True

    def _connections_changed(self, delta: int) -> None:
        with self._cond:
            self._stats.connections += delta
            self._cond.notify_all()

    def _error(self, text: str) -> None:
        with self._cond:
            self._stats.errors.append(text)
            del self._stats.errors[:-MAX_ERRORS_KEPT]
        self.context.trace.record("error", self.context.name, src=self.context.name,
                                  method=self.topic, result=text)

    # ----------------------------------------------------------------- delivery
    def _deliver(self, body: bytes | memoryview, info: MessageInfo, offset: int,
                 ends: dict[str, str] | None = None) -> None:
        node = self.context
        if node.trace.frames:
            node.trace.record("tcpros_frame", node.name, role="in", src=info.publisher,
                              dst=node.name, method=self.topic,
                              raw=node.trace.frame_raw(body),
                              size=4 + len(body), conn=info.conn, index=info.index, offset=offset,
                              **(ends or {}))
        with self._cond:
            self._stats.frames += 1
            self._stats.bytes += len(body)
            limit = self.queue_size
            while limit > 0 and len(self._queue) >= limit:
                self._queue.popleft()
                self._stats.drops += 1
            self._queue.append((body, info))
            self._cond.notify_all()

    def _dispatch_loop(self) -> None:
        from rosfpga_lab.msg import deserialize

        while True:
            with self._cond:
                while not self._queue and not self.closed:
                    self._cond.wait()
                if self.closed:
                    return
                body, info = self._queue.popleft()
            try:
                value = body if self.raw else deserialize(self.context.registry, self.type_name, body)
            except LabError as exc:
                self._error(f"cannot deserialize frame #{info.index} from {info.publisher}: {exc}")
                continue
            with self._cond:
                self.last = (value, info)
                self._cond.notify_all()
            if self.callback is None:
                continue
            try:
                if self.raw:
                    self.callback(value, info)
                else:
                    self.callback(value)
            except Exception as exc:  # a user's callback must not kill the dispatcher
                with self._cond:
                    self._stats.callback_errors += 1
                self._error(f"callback raised {type(exc).__name__}: {exc}")

    # ----------------------------------------------------------------- user API
    @property
    def stats(self) -> SubscriberStats:
        """Counters (a snapshot)."""
        with self._cond:
            s = self._stats
            return SubscriberStats(s.frames, s.bytes, s.drops, s.connections, s.callback_errors,
                                   list(s.errors))

    def publisher_links(self) -> list[tuple[str, bool]]:
        """``(publisher XML-RPC URI, connected)`` of every publisher linked to now."""
        with self._lock:
            return [(uri, link.connected) for uri, link in self._links.items()]

    def link_stats(self) -> list[tuple[int, int, int, bool]]:
        """``(connection id, bytes, frames, connected)`` of every publisher link now (the
        current connection of each; getBusStats)."""
        with self._lock:
            return [(link.conn, link.bytes, link.frames, link.connected)
                    for link in self._links.values()]

    def get_num_connections(self) -> int:
        """Publishers connected right now."""
        return self.stats.connections

    def wait_for_connection(self, n: int = 1, timeout: float = 10.0) -> bool:
        """Wait until at least ``n`` publishers are connected; False on time-out."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._stats.connections < n:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def wait_for_message(self, timeout: float = 10.0) -> tuple[Any, MessageInfo]:
        """Wait for the next message handled by the dispatcher; return ``(value, info)``.

        Raises:
            GraphError: nothing arrived within ``timeout`` seconds.
        """
        deadline = time.monotonic() + timeout
        with self._cond:
            before = self.last
            while self.last is before or self.last is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise GraphError(f"no message on {self.topic} within {timeout} s "
                                     f"(connections: {self._stats.connections}, "
                                     f"errors: {self._stats.errors[-1:] or 'none'})")
                self._cond.wait(left)
            return self.last

    def unregister(self) -> None:
        """Stop: unregister from the master, close every connection."""
        self.context.leave(self)
        self.close()

    def close(self) -> None:
        """Close every connection and stop the dispatcher (the node calls this on shutdown;
        :meth:`unregister` also tells the master)."""
        with self._lock:
            self.closed = True
            links = list(self._links.values())
            self._links.clear()
        for link in links:
            link.close()
        with self._cond:
            self._cond.notify_all()
        for link in links:
            if link.thread.is_alive():
                link.thread.join(JOIN_TIMEOUT)
        if self._dispatcher is not threading.current_thread():
            self._dispatcher.join(JOIN_TIMEOUT)

    def __repr__(self) -> str:
        return f"<Subscriber {self.topic} [{self.type_name}] connections={self.get_num_connections()}>"
