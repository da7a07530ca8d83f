"""A ROS 2 node on real UDP sockets: the sans-IO :class:`rosfpga_lab.rtps.participant.Participant`
driven by one thread.

How this works: :class:`Ros2Node` binds the unicast discovery and user ports of the first free
participant index of its domain on 127.0.0.1 (the RTPS port mapping), and one thread waits on
both sockets: each datagram goes to the participant, what it returns is sent, and every
``tick`` (SPDP announcements, HEARTBEATs, leases) runs at least every 10 ms. Received samples go
to the subscriber callbacks on that thread, outside the participant's lock. Samples are raw
CDR payloads (encapsulation header first): ``rosfpga_lab.msg.serialize_cdr`` makes them.
Each note the participant logs (matches, QoS mismatches, hostile input) goes once to the
``rosfpga_lab.graph.ros2`` logger. :meth:`Ros2Node.record` keeps what the node sends and
receives (a bounded :class:`Ros2Recording`: datagrams as ``udp_datagrams`` of a capture gives
them, and the notes with their times), which ``widgets.events_from_rtps`` draws.
"""

from __future__ import annotations

import logging
import select
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.limits import (
    ROS2_RECORD_BYTES, ROS2_RECORD_DATAGRAMS, ROS2_SOCKET_BUFFER_BYTES, ROS2_TICK_SECONDS,
)
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.rtps.limits import MAX_PARTICIPANT_INDEX
from rosfpga_lab.rtps.participant import Participant, Qos, Sample, discovery_port, user_port
from rosfpga_lab.rtps.rosnode import RosNodeEntities, node_type_hash

log = logging.getLogger(__name__)


@dataclass
class Ros2Recording:
    """What one node sent and received while recording, bounded.

    Attributes:
        datagrams: ``(time, "src:port", "dst:port", payload)`` in order, as
            ``rosfpga_lab.graph.capture_read.udp_datagrams`` gives a capture's (``time.time()``).
        notes: ``(time, text)`` of each participant note (matches, QoS mismatches) as logged.
        names: participant names by GUID prefix (this node's and those it discovered).
        prefix: this node's GUID prefix (what it sent carries it in the RTPS header).
        dropped: datagrams not kept (past ``max_datagrams`` or ``max_bytes``), counted only.
    """

    max_datagrams: int = ROS2_RECORD_DATAGRAMS
    max_bytes: int = ROS2_RECORD_BYTES
    datagrams: list[tuple[float, str, str, bytes]] = field(default_factory=list)
    notes: list[tuple[float, str]] = field(default_factory=list)
    names: dict[bytes, str] = field(default_factory=dict)
    prefix: bytes = b""
    dropped: int = 0
    kept_bytes: int = 0

    def add(self, src: tuple[str, int], dst: tuple[str, int], data: bytes) -> None:
        if len(self.datagrams) >= self.max_datagrams or \
                self.kept_bytes + len(data) > self.max_bytes:
            self.dropped += 1
            return
        self.kept_bytes += len(data)
        self.datagrams.append((time.time(), f"{src[0]}:{src[1]}", f"{dst[0]}:{dst[1]}",
                               bytes(data)))


class Ros2Publisher:
    """A DDS writer of one ROS 2 topic."""

    def __init__(self, node: Ros2Node, writer_id: int, topic: str) -> None:
        self.node, self.writer_id, self.topic = node, writer_id, topic

    def publish(self, payload: bytes) -> None:
        """Send one CDR payload (encapsulation header first)."""
        self.node._write(self.writer_id, payload)

    def matched(self) -> int:
        """How many remote readers are matched."""
        with self.node._lock:
            return len(self.node.participant.matched(self.writer_id))

    def wait_for_subscribers(self, count: int = 1, timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while self.matched() < count:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def unacknowledged(self) -> int:
        """Remote reliable readers that have not acknowledged every sample written."""
        with self.node._lock:
            ep = self.node.participant.local[self.writer_id]
            return sum(1 for p in ep.proxies.values()
                       if getattr(p, "reliable", False) and getattr(p, "acked", 0) <= ep.seq)


class Ros2Subscriber:
    """A DDS reader of one ROS 2 topic; ``callback(payload, sample)`` runs on the node's thread."""

    def __init__(self, node: Ros2Node, reader_id: int, topic: str,
                 callback: Callable[[bytes, Sample], None]) -> None:
        self.node, self.reader_id, self.topic, self.callback = node, reader_id, topic, callback

    def matched(self) -> int:
        with self.node._lock:
            return len(self.node.participant.matched(self.reader_id))


class Ros2Node:
    """A DDS participant on 127.0.0.1 with ROS 2 publishers and subscribers of raw CDR samples.

    Args:
        name: the node name (the participant's entity name).
        domain: the DDS domain (``ROS_DOMAIN_ID``).
        address: the address to bind and announce (loopback by default).
        lease, announce: SPDP lease and announcement period in seconds.
    """

    def __init__(self, name: str = "rosfpga_lab", domain: int = 0, address: str = "127.0.0.1",
                 lease: float | None = None, announce: float | None = None,
                 namespace: str = "/") -> None:
        self.name, self.domain, self.namespace = name, domain, namespace
        self._meta, self._user, index = self._bind(domain, address)
        kw = {k: v for k, v in (("lease", lease), ("announce", announce)) if v is not None}
        self.participant = Participant(domain, index, address, name, **kw)  # type: ignore[arg-type]
        self._lock = threading.RLock()
        self._subs: dict[int, Ros2Subscriber] = {}
        self._logged = 0
        #: Datagrams whose handling raised (a bug: logged the first time, counted after).
        self._failures = 0
        self._stop = threading.Event()
        self._recording: Ros2Recording | None = None
        # the ROS 2 graph learns the node's name and endpoints from ros_discovery_info
        self.entities = RosNodeEntities(self.participant, name, namespace)
        self._announce_graph()
        self._thread = threading.Thread(target=self._run, name=f"ros2-{name}", daemon=True)
        self._thread.start()

    @staticmethod
    def _bind(domain: int, address: str) -> tuple[socket.socket, socket.socket, int]:
        for index in range(MAX_PARTICIPANT_INDEX + 1):
            socks = []
            try:
                for port in (discovery_port(domain, index), user_port(domain, index)):
                    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                    socks.append(s)
                    for opt in (socket.SO_RCVBUF, socket.SO_SNDBUF):
                        s.setsockopt(socket.SOL_SOCKET, opt, ROS2_SOCKET_BUFFER_BYTES)
                    s.bind((address, port))
                return socks[0], socks[1], index
            except OSError:
                for s in socks:
                    s.close()
        raise GraphError(f"no free participant index 0..{MAX_PARTICIPANT_INDEX} in DDS domain "
                         f"{domain} on {address} (ports {discovery_port(domain, 0)}.."
                         f"{user_port(domain, MAX_PARTICIPANT_INDEX)} taken): stop other DDS "
                         f"participants or pick another --domain")

    @property
    def index(self) -> int:
        return self.participant.index

    def _announce_graph(self) -> None:
        """Publish this node's name and endpoints on ros_discovery_info (a ROS 2 node list sees it)."""
        with self._lock:
            out = self.participant.write(self.entities.graph_writer, self.entities.entities_info(),
                                         time.monotonic(), time.time())
        self._send(out)

    @staticmethod
    def type_hash(type_name: str, registry: MsgRegistry | None = None) -> str:
        """The ROS 2 type hash the node announces for ``type_name`` (its definition in
        ``registry``, default the shipped types); '' for a type it cannot load (no hash sent)."""
        return node_type_hash(type_name, registry)

    def create_publisher(self, topic: str, type_name: str, qos: Qos = Qos(),
                         registry: MsgRegistry | None = None) -> Ros2Publisher:
        """A writer of ROS 2 topic ``topic`` (``/image``) of ROS type ``type_name`` (defined in
        ``registry``, default the shipped types: its type hash goes out with it)."""
        with self._lock:
            wid = self.entities.add_publisher(topic, type_name, qos, registry)
        self._announce_graph()
        return Ros2Publisher(self, wid, topic)

    def create_subscriber(self, topic: str, type_name: str,
                          callback: Callable[[bytes, Sample], None], qos: Qos = Qos(),
                          registry: MsgRegistry | None = None) -> Ros2Subscriber:
        with self._lock:
            rid = self.entities.add_subscriber(topic, type_name, qos, registry)
            sub = self._subs[rid] = Ros2Subscriber(self, rid, topic, callback)
        self._announce_graph()
        return sub

    def notes(self) -> list[str]:
        with self._lock:
            return list(self.participant.notes)

    def record(self, max_datagrams: int = ROS2_RECORD_DATAGRAMS,
               max_bytes: int = ROS2_RECORD_BYTES) -> Ros2Recording:
        """Start keeping what this node sends and receives (at most ``max_datagrams``
        datagrams and ``max_bytes`` bytes; later ones are counted in ``dropped``). Call it
        before the peers start to get the whole discovery. Returns the recording, which fills
        while the node runs (read it under :meth:`recorded` for a consistent copy)."""
        with self._lock:
            self._recording = Ros2Recording(max(0, max_datagrams), max(0, max_bytes))
            self._recording.prefix = self.participant.guid_prefix
            self._recording.names[self.participant.guid_prefix] = self.name
            return self._recording

    def recorded(self) -> Ros2Recording:
        """A copy of the recording so far, with the names of the participants discovered.

        Raises:
            GraphError: :meth:`record` was not called.
        """
        with self._lock:
            rec = self._recording
            if rec is None:
                raise GraphError(f"ROS 2 node {self.name} is not recording: call record() first")
            for prefix, p in self.participant.participants.items():
                rec.names.setdefault(prefix, p.name or f"participant {prefix[:4].hex()}..")
            return Ros2Recording(rec.max_datagrams, rec.max_bytes, list(rec.datagrams),
                                 list(rec.notes), dict(rec.names), rec.prefix, rec.dropped,
                                 rec.kept_bytes)

    def _write(self, writer_id: int, payload: bytes) -> None:
        with self._lock:
            out = self.participant.write(writer_id, payload, time.monotonic(), time.time())
        self._send(out)

    def _send(self, out: list[tuple[str, int, bytes]]) -> None:
        rec = self._recording
        if rec is not None and out:
            with self._lock:
                for host, port, data in out:
                    rec.add(self.participant.user, (host, port), data)
        for host, port, data in out:
            try:
                self._user.sendto(data, (host, port))
            except OSError as exc:
                log.debug("send to %s:%d failed: %s", host, port, exc)

    def _flush_notes(self) -> None:
        notes = self.participant.notes
        while self._logged < len(notes):
            log.info("%s", notes[self._logged])
            if self._recording is not None and \
                    len(self._recording.notes) < self._recording.max_datagrams:
                self._recording.notes.append((time.time(), notes[self._logged]))
            self._logged += 1

    def _run(self) -> None:
        socks = [self._meta, self._user]
        next_tick = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= next_tick:
                with self._lock:
                    out = self.participant.tick(now)
                self._send(out)
                next_tick = now + ROS2_TICK_SECONDS
            try:
                ready, _, _ = select.select(socks, [], [], max(0.0, next_tick - time.monotonic()))
            except (OSError, ValueError):
                return
            for s in ready:
                for _ in range(256):
                    try:
                        data, src = s.recvfrom(65536, socket.MSG_DONTWAIT)
                    except (BlockingIOError, InterruptedError):
                        break
                    except OSError:
                        return
                    with self._lock:
                        if self._recording is not None:
                            self._recording.add(src, s.getsockname(), data)
                        try:
                            out = self.participant.receive(data, src, time.monotonic())
                        except Exception:     # never let one datagram stop the node's thread
                            self._failures += 1
                            if self._failures == 1:
                                log.exception("datagram from %s:%d dropped (further ones counted "
                                              "in failures)", src[0], src[1])
                            out = []
                        samples = self.participant.take() if self.participant.samples else []
                        self._flush_notes()
                    self._send(out)
                    for sample in samples:
                        sub = self._subs.get(sample.reader_id)
                        if sub is not None:
                            try:
                                sub.callback(sample.payload, sample)
                            except Exception:   # a callback's error must not stop the node
                                log.exception("subscriber callback of %s failed", sub.topic)

    def close(self) -> None:
        """Stop the thread, tell the peers goodbye (SPDP dispose), close the sockets."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        with self._lock:
            bye = self.participant.goodbye()
        self._send(bye)
        self._meta.close()
        self._user.close()

    shutdown = close

    @property
    def master_uri(self) -> str:
        """What stands for the master in ROS 2: the DDS domain (status lines print it)."""
        return f"none (DDS domain {self.domain})"

    def __enter__(self) -> Ros2Node:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
