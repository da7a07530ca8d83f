"""A topic publisher: one queue and one writer thread per connected subscriber.

How it works: the node's TCPROS server runs the publisher side of the handshake; a
successful one hands the socket and the handshake machine (now ``STREAMING``) to
:meth:`Publisher.attach`. Every frame goes out through that machine
(:meth:`~rosfpga_lab.tcpros.PublisherHandshake.send_parts`), and the subscriber hanging up or
the publisher closing runs its ``eof``/``close`` rows, so the table the notebooks draw is the
one a running node follows. Each link owns a bounded
queue (``queue_size``; when full the oldest frame is dropped and counted, as roscpp's
``TransportSubscriberLink`` does), a writer thread that sends frames, and a reader thread
whose only job is to notice the subscriber hanging up. ``publish()`` serializes once and
enqueues the same body on every link. A latching publisher keeps its last body and sends it
first to every new subscriber.
"""

from __future__ import annotations

import collections
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.limits import JOIN_TIMEOUT, MAX_CLOSED_LINKS_KEPT
from rosfpga_lab.graph.topic import TopicContext
from rosfpga_lab.graph.wire import hard_close, send_parts, set_nodelay, socket_ends
from rosfpga_lab.tcpros import PublisherHandshake, TopicSpec, publisher_reply_fields

if TYPE_CHECKING:
    import socket


@dataclass
class LinkStats:
    """Counters of one connection."""

    conn: int
    peer: str
    frames: int = 0
    bytes: int = 0
    drops: int = 0
    connected: bool = True


class _SubscriberLink:
    def __init__(self, pub: Publisher, sock: socket.socket, conn_id: int, peer: str,
                 handshake: PublisherHandshake, tcp_nodelay: bool, header: bytes) -> None:
        self.pub = pub
        self.handshake = handshake  # STREAMING: every frame, the eof and the close run through it
        self.header = header
        self.sock = sock
        self.stats = LinkStats(conn_id, peer)
        self.ends = socket_ends(sock)
        self.queue: collections.deque = collections.deque()
        self.cond = threading.Condition()
        self.closed = False
        if tcp_nodelay:
            set_nodelay(sock)
        sock.settimeout(None)
        self.writer = threading.Thread(target=self._write_loop, daemon=True,
                                       name=f"rosfpga-pub-write-{pub.topic}")
        self.reader = threading.Thread(target=self._read_loop, daemon=True,
                                       name=f"rosfpga-pub-watch-{pub.topic}")

    def start(self) -> None:
        self.writer.start()
        self.reader.start()

    def enqueue(self, body: bytes | bytearray | memoryview) -> None:
        with self.cond:
            if self.closed:
                return
            limit = self.pub.queue_size
            while limit > 0 and len(self.queue) >= limit:
                self.queue.popleft()
                self.stats.drops += 1
            self.queue.append(body)
            self.cond.notify()

    def _write_loop(self) -> None:
        ctx = self.pub.context
        t0 = time.time()
        try:
            self.sock.sendall(self.header)  # our connection header goes before any frame
        except OSError:
            self.close(by_peer=True)
            return
        ctx.trace.record("tcpros_header", ctx.name, role="out", src=ctx.name, dst=self.stats.peer,
                         method=self.pub.topic, args=self.pub.node_reply_fields(), raw=self.header,
                         size=len(self.header), conn=self.stats.conn, t0=t0, **self.ends)
        while True:
            with self.cond:
                while not self.queue and not self.closed:
                    self.cond.wait()
                if self.closed:
                    return
                body = self.queue.popleft()
                prefix, view = self.handshake.send_parts(body)  # the table's STREAMING --send-->
            t0 = time.time()
            try:
                size = send_parts(self.sock, prefix, view)
            except OSError:
                self.close(by_peer=True)
                return
            self.stats.frames += 1
            self.stats.bytes += size
            if ctx.trace.frames:
                ctx.trace.record(
                    "tcpros_frame", ctx.name, role="out", src=ctx.name, dst=self.stats.peer,
                    method=self.pub.topic, raw=ctx.trace.frame_raw(body), size=size,
                    conn=self.stats.conn, index=self.stats.frames - 1, t0=t0,
                    **self.ends)

    def _read_loop(self) -> None:
        try:
            while not self.closed:
                if not self.sock.recv(4096):
                    break
        except OSError:
            pass
        self.close(by_peer=True)

    def close(self, by_peer: bool = False) -> None:
        """End the link: the subscriber hung up (``by_peer``: the table's ``eof``) or we do
        (``close``)."""
        with self.cond:
            if self.closed:
                return
            self.closed = True
            self.stats.connected = False
            if by_peer:
                self.handshake.receive_eof()
            else:
                self.handshake.close()
            self.cond.notify_all()
        hard_close(self.sock)
        ctx = self.pub.context
        ctx.trace.record("tcp_close", ctx.name, role="out", src=ctx.name, dst=self.stats.peer,
                         method=self.pub.topic, conn=self.stats.conn, **self.ends)
        self.pub._remove_link(self)

    def join(self, timeout: float) -> None:
        for t in (self.writer, self.reader):
            if t.is_alive() and t is not threading.current_thread():
                t.join(timeout)


@dataclass
class PublisherStats:
    """What a publisher did: frames/bytes enqueued, drops over all links, links now open."""

    frames: int
    bytes: int
    drops: int
    connections: int
    links: list[LinkStats]


class Publisher:
    """Publishes one topic. Create with :meth:`Node.advertise`, not directly.

    Args:
        context: what the publisher may use of its node (:class:`TopicContext`).
    """

    def __init__(self, context: TopicContext, topic: str, type_name: str, md5sum: str,
                 message_definition: str, *, queue_size: int, latch: bool) -> None:
        self.context = context
        self.topic = topic
        self.type_name = type_name
        self.md5sum = md5sum
        self.message_definition = message_definition
        self.queue_size = int(queue_size or 0)
        self.latch = latch
        self.spec = TopicSpec(topic, type_name, md5sum, message_definition, latch)
        self._links: list[_SubscriberLink] = []
        self._all_links: list[_SubscriberLink] = []
        self._lock = threading.Lock()
        self._last: bytes | bytearray | memoryview | None = None
        self._frames = 0
        self._bytes = 0
        self.closed = False

    # ----------------------------------------------------------------- publishing
    def publish(self, value: dict[str, Any]) -> None:
        """Serialize ``value`` (a dict as ``rosfpga_lab.msg`` builds them) and publish it.

        Raises:
            MsgError: the value does not fit the type.
            GraphError: the publisher was closed.
        """
        from rosfpga_lab.msg import serialize

        self.publish_body(serialize(self.context.registry, self.type_name, value))

    def publish_body(self, body: bytes | bytearray | memoryview) -> None:
        """Publish an already serialized body (no frame length): the raw bytes path.

        The same object is queued on every link: do not modify it afterwards.
        """
        if self.closed:
            raise GraphError(f"publisher of {self.topic} is closed; advertise again")
        with self._lock:
            if self.latch:
                self._last = body
            links = list(self._links)
            self._frames += 1
            self._bytes += len(body)
        for link in links:
            link.enqueue(body)

    def node_reply_fields(self) -> dict[str, str]:
        """The header fields this publisher answers subscribers with."""
        return publisher_reply_fields(self.context.name, self.spec)

    # ----------------------------------------------------------------- links
    def attach(self, sock: socket.socket, conn_id: int, peer: str,
               handshake: PublisherHandshake, tcp_nodelay: bool, header: bytes) -> bool:
        """Take over a socket whose handshake succeeded (``handshake`` is ``STREAMING``);
        ``header`` is our reply, sent first. Returns False when the publisher is closed (the
        caller then closes the socket)."""
        link = _SubscriberLink(self, sock, conn_id, peer, handshake, tcp_nodelay, header)
        with self._lock:
            if self.closed:
                return False
            self._links.append(link)
            self._all_links.append(link)
            if len(self._all_links) > MAX_CLOSED_LINKS_KEPT:  # keep stats of recent links only
                closed = [l for l in self._all_links if l.closed]
                self._all_links = closed[-MAX_CLOSED_LINKS_KEPT // 2:] + \
                    [l for l in self._all_links if not l.closed]
            if self.latch and self._last is not None:
                link.enqueue(self._last)
        link.start()
        return True

    def _remove_link(self, link: _SubscriberLink) -> None:
        with self._lock:
            if link in self._links:
                self._links.remove(link)

    @property
    def stats(self) -> PublisherStats:
        """Counters (a snapshot)."""
        with self._lock:
            links = [l.stats for l in self._all_links]
            return PublisherStats(self._frames, self._bytes, sum(l.drops for l in links),
                                  len(self._links), [LinkStats(**vars(l)) for l in links])

    def get_num_connections(self) -> int:
        """Subscribers connected right now."""
        with self._lock:
            return len(self._links)

    def wait_for_subscribers(self, n: int = 1, timeout: float = 10.0) -> bool:
        """Wait until at least ``n`` subscribers are connected; False on time-out."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.get_num_connections() >= n:
                return True
            time.sleep(0.01)
        return self.get_num_connections() >= n

    def unregister(self) -> None:
        """Stop publishing: unregister from the master and close every link."""
        self.context.leave(self)
        self.close()

    def close(self) -> None:
        """Close every link (the node calls this on shutdown; :meth:`unregister` also tells
        the master)."""
        with self._lock:
            self.closed = True
            links = list(self._links)
        for link in links:
            link.close()
        for link in {*self._all_links, *links}:
            link.join(JOIN_TIMEOUT)

    def __repr__(self) -> str:
        return f"<Publisher {self.topic} [{self.type_name}] links={self.get_num_connections()}>"
