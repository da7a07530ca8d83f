"""A ROS 1 node on real sockets: Slave API over XML-RPC, TCPROS server, publishers, subscribers.

How it works: a :class:`Node` starts two servers on its host (127.0.0.1 by default): the
XML-RPC Slave API (``requestTopic``, ``publisherUpdate``, ``getBusInfo`` ...) and a TCPROS
port. :meth:`Node.advertise` registers a publisher with the master; a subscriber that calls
``requestTopic`` learns the TCPROS port, connects, and a handshake thread runs
:class:`~rosfpga_lab.tcpros.PublisherHandshake` (with a time-out, so a silent client cannot
hold anything) before handing the socket to the publisher; at ``MAX_PENDING_HANDSHAKES`` a new
connection evicts the oldest one still in its handshake (an honest subscriber sends its header
at once, so only idle peers are evicted). :meth:`Node.subscribe` registers a
subscriber and connects to every publisher the master lists (see ``subscriber``). Everything
runs in daemon threads, so a node works inside a running Jupyter kernel; :meth:`shutdown`
unregisters, closes every socket and joins every thread.

Master selection (``master_uri``): an explicit URI; else ``ROS_MASTER_URI``; else a master
already answering on 127.0.0.1:11311 that runs as the same Unix user (see ``owner``); else the shared embedded master of this process
(:func:`shared_master`), started on first use on port 11311 (or a free port if 11311 is
taken). Pass ``master=`` an :class:`EmbeddedMaster` to use that one.
"""

from __future__ import annotations

import os
import socket
import threading
import time
import warnings
from collections.abc import Callable
from typing import Any

from rosfpga_lab.config import limits as config_limits
from rosfpga_lab.config.master import master_uri_from_env
from rosfpga_lab.graph.apicheck import api_methods, checked
from rosfpga_lab.graph.errors import GraphError, MasterError, XmlRpcError
from rosfpga_lab.graph.limits import (
    JOIN_TIMEOUT,
    LISTEN_BACKLOG,
    MAX_PENDING_HANDSHAKES,
    MAX_PUBLISHERS_PER_TOPIC,
)
from rosfpga_lab.graph.master import MASTER_ID, EmbeddedMaster
from rosfpga_lab.graph.names import (
    ALL_INTERFACES,
    address_family,
    bind_address,
    check_node_name,
    check_topic_name,
    default_host,
)
from rosfpga_lab.graph.owner import listener_uids
from rosfpga_lab.graph.publisher import Publisher
from rosfpga_lab.graph.rosout import log as rosout_log
from rosfpga_lab.graph.rosout import start_node_logging, stop_node_logging
from rosfpga_lab.graph.service import ServiceServer
from rosfpga_lab.graph.subscriber import Subscriber
from rosfpga_lab.graph.topic import TopicContext
from rosfpga_lab.graph.trace import Trace, new_connection_id
from rosfpga_lab.graph.watchdog import MasterWatch
from rosfpga_lab.graph.wire import RECV_CHUNK, accept_loop, hard_close, socket_ends
from rosfpga_lab.graph.xmlrpc import XmlRpcServer, call, split_uri, unsupported
from rosfpga_lab.tcpros import (
    HANDSHAKE_TIMEOUT,
    MAX_FRAME_BYTES,
    Closed,
    Connected,
    HeaderReceived,
    PublisherHandshake,
    Rejected,
    State,
    TopicSpec,
)

_shared_lock = threading.Lock()
_shared: EmbeddedMaster | None = None
#: Port of roscore's master, probed and (if free) used by the shared embedded master.
DEFAULT_MASTER_PORT = config_limits.DEFAULT_MASTER_PORT


def shared_master(port: int | None = None) -> EmbeddedMaster:
    """The process-wide embedded master, started on first call on ``port`` (default 11311,
    or any free port if that one is taken, with a warning: other processes will not find
    it). Stop it with :func:`stop_shared_master`."""
    global _shared
    with _shared_lock:
        if _shared is None or not _shared.running:
            wanted = DEFAULT_MASTER_PORT if port is None else port
            try:
                _shared = EmbeddedMaster(port=wanted).start()
            except XmlRpcError as exc:
                _shared = EmbeddedMaster(port=0).start()
                warnings.warn(
                    f"started a private ROS master at {_shared.uri} because port {wanted} is "
                    f"taken ({exc}); nodes of other processes will not find this one. Set "
                    "ROS_MASTER_URI (or pass master_uri=) to join an existing master.",
                    RuntimeWarning, stacklevel=2)
        return _shared


def stop_shared_master() -> None:
    """Stop the shared embedded master, if one runs."""
    global _shared
    with _shared_lock:
        if _shared is not None:
            _shared.stop()
            _shared = None


def default_master_uri() -> str:
    """The master a node uses when none is given.

    ``ROS_MASTER_URI`` if set; else a master already answering on 127.0.0.1:11311 (a roscore
    or ``rosfpga-lab master``) if it runs as this process's user (on Linux, where the owner of
    a port is known: on a shared server another user's master is never joined unasked, with a
    RuntimeWarning); else the shared embedded master of this process.
    """
    env = master_uri_from_env()  # steps 1-2 of rosfpga_lab.config.master's rule (no explicit URI here)
    if env:
        return env
    with _shared_lock:
        if _shared is not None and _shared.running:
            return _shared.uri
    probe = f"http://127.0.0.1:{DEFAULT_MASTER_PORT}/"
    owners = listener_uids(DEFAULT_MASTER_PORT)
    others = sorted((owners or set()) - {os.geteuid()})
    if others:
        # A shared server (a course on JupyterHub): never join another user's graph unasked.
        warnings.warn(
            f"the ROS master on {probe} belongs to another user (uid {others[0]}); this "
            "process uses a master of its own. Set ROS_MASTER_URI (or pass master_uri=) to "
            "join that one on purpose.", RuntimeWarning, stacklevel=3)
        return shared_master(port=0).uri   # 11311 is taken: no second warning about it
    try:
        reply = call(probe, "getUri", "/rosfpga_lab_probe", timeout=0.5)
        if isinstance(reply, list) and reply and reply[0] == 1:
            return probe
    except GraphError:
        pass
    return shared_master().uri


class Node:
    """A ROS node.

    Args:
        name: node name (global, e.g. ``/fpga_node``; a relative name is made global).
        master_uri: the master to use; None: see :func:`default_master_uri` (ROS_MASTER_URI,
            else a master on 127.0.0.1:11311, else the shared embedded master).
        host: address to bind and advertise; None: ``ROS_IP``, ``ROS_HOSTNAME``, else
            127.0.0.1. "0.0.0.0" binds every interface (with a warning) and advertises the
            machine's hostname.
        master: an :class:`EmbeddedMaster` to use (overrides ``master_uri``).
        trace: where to record the conversation (a new :class:`Trace` by default;
            share one between nodes and the master for a single timeline).
        registry: message registry for md5 sums and (de)serialization (default: shipped types).
        tcpros_port, xmlrpc_port: fixed ports (0: any free one).

    Raises:
        ConfigError: bad name or master URI.
        XmlRpcError: a port cannot be bound.
    """

    def __init__(self, name: str, master_uri: str | None = None, host: str | None = None, *,
                 master: EmbeddedMaster | None = None, trace: Trace | None = None,
                 registry: Any = None, tcpros_port: int = 0, xmlrpc_port: int = 0) -> None:
        self.name = check_node_name(name)
        if master is not None:
            master_uri = master.uri
        elif master_uri is None:
            master_uri = default_master_uri()
        split_uri(master_uri)
        self.master_uri = master_uri
        self.host = host or default_host()
        self.trace = trace if trace is not None else Trace()
        if registry is None:
            from rosfpga_lab.msg import default_registry

            registry = default_registry()
        self.registry = registry
        self._lock = threading.RLock()
        self.publishers: dict[str, Publisher] = {}
        self.subscribers: dict[str, Subscriber] = {}
        self._handshakes: set[threading.Thread] = set()
        self._pending: dict[socket.socket, float] = {}  # socket -> when it was accepted
        #: TCPROS connections closed in their handshake to make room for a newer one
        self.refused_connections = 0
        self.is_shutdown = False
        self.shutdown_reason = ""   # why it shut down (e.g. a remote slave-API shutdown's message)
        self._down = threading.Event()
        self._shutting_down_in: threading.Thread | None = None  # the thread that runs _shutdown
        self._service_port: ServiceServer | None = None   # started with the first service
        self._logging: Any = None   # /rosout and logger services, from the first registration
        self.ros_logging = True     # False: this node offers neither (before its first registration)
        self.watch_master = True    # register again after a master restart (see ``watchdog``)
        self._watch: MasterWatch | None = None
        self._updates: dict[str, int] = {}   # topic -> publisherUpdate calls received
        #: set once /rosout and the logger services are registered (or failed)
        self.logging_ready = threading.Event()
        bind = bind_address(self.host)
        self._bind = bind   # (warned once, here, when it opens every interface)
        if self.host in ALL_INTERFACES:  # peers need a reachable name, not 0.0.0.0
            self.host = socket.gethostname()
        self._xmlrpc = XmlRpcServer(self._handle_xmlrpc, host=bind, port=xmlrpc_port,
                                    trace=self.trace, name=self.name, advertise_host=self.host)
        self._xmlrpc.start()
        self._methods = api_methods(self)
        self._tcp = socket.socket(address_family(bind), socket.SOCK_STREAM)
        self._tcp.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._tcp.bind((bind, tcpros_port))
        except (OSError, OverflowError) as exc:  # OverflowError: a port outside 0..65535
            self._tcp.close()
            self._xmlrpc.stop()
            raise XmlRpcError(f"cannot bind TCPROS port {bind}:{tcpros_port}: {exc}") from None
        self._tcp.listen(LISTEN_BACKLOG)
        self.tcpros_port = self._tcp.getsockname()[1]
        self._accept = threading.Thread(target=self._accept_loop, daemon=True,
                                        name=f"rosfpga-tcpros-accept-{self.name}")
        self._accept.start()
        self.trace.names[self.uri] = self.name
        self.trace.names[f"{self.host}:{self.tcpros_port}"] = self.name
        self.trace.names.setdefault(self.master_uri, MASTER_ID)

    # ------------------------------------------------------------------ basics
    @property
    def uri(self) -> str:
        """This node's XML-RPC (Slave API) URI."""
        return self._xmlrpc.uri

    def __enter__(self) -> Node:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    def __repr__(self) -> str:
        return f"<Node {self.name} {self.uri} master={self.master_uri}>"

    def _master(self, method: str, *args: Any) -> Any:
        reply = call(self.master_uri, method, self.name, *args, trace=self.trace, caller=self.name,
                     callee=MASTER_ID)
        if not (isinstance(reply, list) and len(reply) == 3):
            raise MasterError(f"master's {method} reply is not [code, status, value]: {reply!r}")
        code, status, value = reply
        if code != 1:
            raise MasterError(f"master refused {method}{args}: {status}", code, status)
        return value

    def _type_info(self, type_name: str, md5sum: str | None,
                   message_definition: str | None) -> tuple[str, str]:
        if md5sum is not None:
            return md5sum, message_definition or ""
        if type_name == "*":
            return "*", ""
        return self.registry.md5(type_name), (
            message_definition if message_definition is not None else self.registry.full_text(type_name))

    # ------------------------------------------------------------------ publishing
    def advertise(self, topic: str, type_name: str, queue_size: int = 10, latch: bool = False, *,
                  md5sum: str | None = None, message_definition: str | None = None) -> Publisher:
        """Register as publisher of ``topic`` and return the :class:`Publisher`.

        Args:
            topic: topic name (relative names resolve in the node's namespace).
            type_name: ``pkg/Type`` known to the registry (or give ``md5sum``).
            queue_size: frames queued per subscriber before the oldest is dropped (<= 0: no limit).
            latch: send the last message to every new subscriber.
            md5sum, message_definition: override the registry (for types it does not know).

        Raises:
            GraphError: the topic is already advertised by this node.
            MasterError, XmlRpcError: the master refused or cannot be reached.
            MsgError: unknown type.
        """
        topic = check_topic_name(topic, self.name)
        md5, definition = self._type_info(type_name, md5sum, message_definition)
        with self._lock:
            if self.is_shutdown:
                raise GraphError(f"node {self.name} is shut down")
            if topic in self.publishers:
                raise GraphError(f"{self.name} already publishes {topic}; use the existing publisher")
            pub = Publisher(self._context(), topic, type_name, md5, definition,
                            queue_size=queue_size, latch=latch)
            self.publishers[topic] = pub
        try:
            self._master("registerPublisher", topic, type_name, self.uri)
        except Exception:
            with self._lock:
                self.publishers.pop(topic, None)
            raise
        self._undo_if_shut_down("unregisterPublisher", topic, self.uri)
        self._start_logging()
        return pub

    def _context(self) -> TopicContext:
        """What this node's publishers and subscribers may use of it."""
        return TopicContext(self.name, self.trace, self.registry, self._leave)

    def _leave(self, topic_object: Publisher | Subscriber) -> None:
        """Forget a publisher or subscriber and tell the master (it closes itself)."""
        table: dict[str, Any] = (self.publishers if isinstance(topic_object, Publisher)
                                 else self.subscribers)
        method = "unregisterPublisher" if isinstance(topic_object, Publisher) else "unregisterSubscriber"
        with self._lock:
            if table.get(topic_object.topic) is topic_object:
                del table[topic_object.topic]
        try:
            self._master(method, topic_object.topic, self.uri)
        except GraphError:
            pass

    def _lookup_spec(self, topic: str) -> TopicSpec | None:
        pub = self.publishers.get(topic)
        return pub.spec if pub is not None and not pub.closed else None

    # ------------------------------------------------------------------ subscribing
    def subscribe(self, topic: str, type_name: str, callback: Callable[..., Any] | None = None, *,
                  raw: bool = False, queue_size: int = 10, tcp_nodelay: bool = False,
                  md5sum: str | None = None, send_definition: bool = False,
                  max_frame: int = MAX_FRAME_BYTES,
                  max_publishers: int = MAX_PUBLISHERS_PER_TOPIC) -> Subscriber:
        """Subscribe to ``topic``; return the :class:`Subscriber`.

        Args:
            callback: ``callback(value_dict)``; with ``raw=True`` ``callback(body, info)``
                where body is the serialized message (bytes or memoryview, no frame length) and
                info a :class:`MessageInfo`. None: only ``wait_for_message``/``last``.
            queue_size: frames queued for the callback before the oldest is dropped (<= 0: no limit).
            tcp_nodelay: ask publishers for TCP_NODELAY.
            md5sum: override the registry (``"*"`` with type ``"*"`` accepts any type, raw only).
            send_definition: also send ``message_definition`` (as rospy does; roscpp does not).
            max_frame: largest frame body accepted from a publisher.
            max_publishers: publishers linked at once (a thread and a socket each); further
                URIs in the master's list are ignored with a logged warning.

        Raises:
            GraphError: already subscribed to this topic in this node.
            MasterError, XmlRpcError: the master refused or cannot be reached.
        """
        topic = check_topic_name(topic, self.name)
        md5, definition = self._type_info(type_name, md5sum, None)
        if type_name == "*" and not raw:
            raise GraphError("subscribing with type '*' needs raw=True (nothing to deserialize with)")
        with self._lock:
            if self.is_shutdown:
                raise GraphError(f"node {self.name} is shut down")
            if topic in self.subscribers:
                raise GraphError(f"{self.name} already subscribes to {topic}")
            sub = Subscriber(self._context(), topic, type_name, md5, callback, raw=raw,
                             queue_size=queue_size,
                             tcp_nodelay=tcp_nodelay,
                             message_definition=definition if send_definition else None,
                             max_frame=max_frame, max_publishers=max_publishers)
            self.subscribers[topic] = sub
        updates = self._updates.get(topic, 0)
        try:
            pubs = self._master("registerSubscriber", topic, type_name, self.uri)
        except Exception:
            with self._lock:
                self.subscribers.pop(topic, None)
            sub.close()
            raise
        self._undo_if_shut_down("unregisterSubscriber", topic, self.uri)
        self._start_logging()   # before connecting: a latched message comes after subscribe()
        if self._updates.get(topic, 0) == updates:  # else a newer list came meanwhile: kept
            sub.update_publishers([u for u in pubs if isinstance(u, str)])
        return sub

    # ------------------------------------------------------------------ services
    def _start_logging(self) -> None:
        """After the first registration: the master watchdog, ``/rosout`` and the logger
        services (see ``rosout``); a master that refuses those costs a warning, not the topic."""
        with self._lock:
            if self._watch is None and not self.is_shutdown:
                self._watch = MasterWatch(self)
            if self._logging is not None or not self.ros_logging or self.is_shutdown:
                return
            self._logging = True   # taken: the calls below come back here
        try:
            self._logging = start_node_logging(self)
        except GraphError as exc:
            self._logging = None
            if not self.is_shutdown:
                rosout_log.warning("%s: no /rosout or logger services: %s", self.name, exc)
        finally:
            self.logging_ready.set()

    def advertise_service(self, service: str, srv_type: str, handler: Callable[[dict], dict]) -> str:
        """Serve ``service`` (``~name`` is private to this node) of the shipped type
        ``srv_type`` with ``handler(request) -> response`` (dicts); register it with the
        master; return its global name. A handler that raises answers the caller ``ok=0``
        with its text.

        Raises:
            UnknownTypeError: ``srv_type`` is not a shipped service type.
            MasterError, XmlRpcError: the master refused or cannot be reached.
        """
        from rosfpga_lab.msg.srv import service_registry, srv_spec

        name = check_topic_name(service, self.name)
        srv = srv_spec(srv_type)
        with self._lock:
            if self.is_shutdown:
                raise GraphError(f"node {self.name} is shut down")
            if self._service_port is None:
                self._service_port = ServiceServer(self.name, self._bind,
                                                   self.host, service_registry()[0], self.trace)
            port = self._service_port
        port.add(name, srv, handler)
        self._master("registerService", name, port.uri, self.uri)
        self._undo_if_shut_down("unregisterService", name, port.uri)
        return name

    def _undo_if_shut_down(self, method: str, *args: object) -> None:
        """After a registration: if the node shut down meanwhile (a slave-API ``shutdown``
        while it registered), its unregistration may have reached the master before this
        registration did, so take it back with ``method`` (the caller finds the node shut
        down, as after any shutdown)."""
        if not self.is_shutdown:
            return
        try:
            self._master(method, *args)
        except (GraphError, OSError):
            pass

    def call_service(self, service: str, srv_type: str, request: dict | None = None, *,
                     timeout: float | None = None) -> dict:
        """Call ``service`` (looked up at the master) with ``request``; return the response.

        Raises:
            ServiceError: no provider, refused, ``ok=0`` (the provider's text) or time-out.
            UnknownTypeError: ``srv_type`` is not a shipped service type.
        """
        from rosfpga_lab.graph.limits import SERVICE_CALL_TIMEOUT
        from rosfpga_lab.graph.service import ServiceError, call_service
        from rosfpga_lab.msg.srv import service_registry, srv_spec

        name = check_topic_name(service, self.name)
        srv = srv_spec(srv_type)
        try:
            uri = self._master("lookupService", name)
        except MasterError as exc:
            raise ServiceError(f"no provider of service [{name}]: {exc.status or exc}") from None
        return call_service(uri, name, srv, request, callerid=self.name, registry=service_registry()[0],
                            timeout=SERVICE_CALL_TIMEOUT if timeout is None else timeout, trace=self.trace)

    def register_again(self) -> None:
        """Register every publisher and subscriber of this node again, after the master
        restarted and forgot the graph.

        Established input connections stay up, as roscpp's do across a master restart: the new
        master does not list their publishers until those register again (many never do), so
        its lists cannot tell a vanished publisher from a forgotten one. Such a link ends when
        its publisher closes it (see :mod:`rosfpga_lab.graph.subscriber`).

        Raises:
            MasterError, XmlRpcError: the master refused or cannot be reached.
        """
        with self._lock:
            pubs = list(self.publishers.values())
            subs = list(self.subscribers.values())
        port = self._service_port
        if port is not None:
            for name in port.names():
                self._master("registerService", name, port.uri, self.uri)
        for pub in pubs:
            self._master("registerPublisher", pub.topic, pub.type_name, self.uri)
        for sub in subs:
            uris = self._master("registerSubscriber", sub.topic, sub.type_name, self.uri)
            sub.update_publishers([u for u in uris if isinstance(u, str)], keep_live=True)
        if self._logging is None:   # its setup failed while the master was away: again
            self._start_logging()

    # ------------------------------------------------------------------ TCPROS server
    def _accept_loop(self) -> None:
        accept_loop(self._tcp, lambda: not self.is_shutdown, self._admit,
                    f"TCPROS server of {self.name}")

    def _admit(self, conn: socket.socket, peer: str) -> None:
        t = threading.Thread(target=self._handshake, args=(conn, peer),
                             daemon=True, name=f"rosfpga-tcpros-handshake-{self.name}")
        with self._lock:
            if len(self._pending) >= MAX_PENDING_HANDSHAKES:
                oldest = min(self._pending, key=self._pending.__getitem__)
                del self._pending[oldest]
                self.refused_connections += 1
                try:  # wakes its handshake thread, which closes it
                    oldest.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
            self._handshakes.add(t)
            self._pending[conn] = time.monotonic()
            try:
                t.start()
            except RuntimeError:  # no thread to be had: this connection is lost, not the loop
                self._handshakes.discard(t)
                self._pending.pop(conn, None)
                raise

    def _handshake(self, conn: socket.socket, peer: str) -> None:
        handed_over = False
        try:
            handed_over = self._run_handshake(conn, peer)
        except OSError:
            pass
        finally:
            with self._lock:
                self._pending.pop(conn, None)
                self._handshakes.discard(threading.current_thread())
            if not handed_over:
                hard_close(conn)

    def _run_handshake(self, conn: socket.socket, peer: str) -> bool:
        conn_id = new_connection_id()
        tr = self.trace
        ends = socket_ends(conn)
        tr.record("tcp_connect", self.name, role="in", src=peer, dst=self.name, conn=conn_id,
                  **ends)
        hs = PublisherHandshake(callerid=self.name, lookup=self._lookup_spec, peer=peer)
        deadline = time.monotonic() + HANDSHAKE_TIMEOUT
        src = peer
        while hs.state is State.AWAIT_HEADER:
            left = deadline - time.monotonic()
            if left <= 0:
                events = hs.timeout()
            else:
                conn.settimeout(left)
                try:
                    data = conn.recv(RECV_CHUNK)
                except TimeoutError:
                    events = hs.timeout()
                else:
                    events = hs.receive_data(data) if data else hs.receive_eof()
            for ev in events:
                if isinstance(ev, HeaderReceived):
                    src = ev.fields.get("callerid", peer)
                    tr.record("tcpros_header", self.name, role="in", src=src, dst=self.name,
                              method=ev.fields.get("topic", ""), args=dict(ev.fields), raw=ev.raw,
                              size=len(ev.raw), conn=conn_id, **ends)
                elif isinstance(ev, Rejected):
                    tr.record("tcpros_header", self.name, role="out", src=self.name, dst=src,
                              args={"error": str(ev.error)}, raw=ev.reply, size=len(ev.reply),
                              conn=conn_id, result=str(ev.error), **ends)
                    conn.settimeout(1.0)
                    conn.sendall(ev.reply)
                    return False
                elif isinstance(ev, Connected):
                    pub = self.publishers.get(ev.topic)
                    if pub is None:
                        return False
                    # the link sends our header, then frames: nothing published from now on is lost
                    return pub.attach(conn, conn_id, src, hs, ev.tcp_nodelay, ev.reply)
                elif isinstance(ev, Closed):
                    return False
        return False

    # ------------------------------------------------------------------ Slave API
    def _handle_xmlrpc(self, method: str, params: tuple) -> Any:
        f = self._methods.get(method)
        if f is None:
            raise unsupported(method)
        return f(*params)

    @checked((), "")
    def getMasterUri(self, caller_id: str) -> tuple:
        return 1, "", self.master_uri

    @checked((), 0)
    def getPid(self, caller_id: str) -> tuple:
        return 1, "", os.getpid()

    @checked((("msg", "any"),), 0)
    def _api_shutdown(self, caller_id: str, msg: Any = "") -> tuple:
        threading.Thread(target=self._shutdown, args=(f"remote shutdown by {caller_id}: {msg}",),
                         daemon=True, name=f"rosfpga-shutdown-{self.name}").start()
        return 1, "shutdown", 0

    @checked((), [])
    def getSubscriptions(self, caller_id: str) -> tuple:
        return 1, "subscriptions", [[s.topic, s.type_name] for s in list(self.subscribers.values())]

    @checked((), [])
    def getPublications(self, caller_id: str) -> tuple:
        return 1, "publications", [[p.topic, p.type_name] for p in list(self.publishers.values())]

    @checked((("key", "str"), ("value", "any")), 0)
    def paramUpdate(self, caller_id: str, key: str, value: Any) -> tuple:
        return 1, "", 0

    @checked((("topic", "topic"), ("publishers", "list")), 0)
    def publisherUpdate(self, caller_id: str, topic: str, publishers: list) -> tuple:
        bad = [p for p in publishers if not (isinstance(p, str) and p.startswith("http://"))]
        if bad:
            return -1, f"publisherUpdate for {topic}: publishers must be http:// URIs, got {bad[:3]!r}", 0
        sub = self.subscribers.get(topic)
        if sub is None:
            return 1, f"not subscribed to {topic}", 0
        self._updates[topic] = self._updates.get(topic, 0) + 1   # (one key per subscription)
        sub.update_publishers(publishers)
        return 1, "", 0

    @checked((("topic", "topic"), ("protocols", "list")), [])
    def requestTopic(self, caller_id: str, topic: str, protocols: list) -> tuple:
        if self._lookup_spec(topic) is None:
            return -1, f"Not a publisher of [{topic}]", []
        for proto in protocols:
            if isinstance(proto, list) and proto and proto[0] == "TCPROS":
                return 1, f"ready on {self.host}:{self.tcpros_port}", ["TCPROS", self.host, self.tcpros_port]
        return 0, "no supported protocol implementations", []

    @checked((), [])
    def getBusInfo(self, caller_id: str) -> tuple:
        info = []
        for pub in list(self.publishers.values()):
            for link in pub.stats.links:
                if link.connected:
                    info.append([link.conn, link.peer, "o", "TCPROS", pub.topic, True,
                                 f"TCPROS connection on port {self.tcpros_port} to [{link.peer}]"])
        for sub in list(self.subscribers.values()):
            for uri, connected in sub.publisher_links():
                info.append([0, uri, "i", "TCPROS", sub.topic, connected,
                             f"TCPROS connection to [{uri}]"])
        return 1, "bus info", info

    @checked((), [[], [], []])
    def getBusStats(self, caller_id: str) -> tuple:
        # rospy's and roscpp's shapes: a publisher lists its open connections only
        # ([conn_id, bytes_sent, num_sent, connected]); a subscriber one entry per publisher
        # link ([conn_id, bytes_received, num_received, drop_estimate, connected]; the drop
        # estimate is -1 as rospy's: drops happen in the subscription's shared queue, counted
        # by Subscriber.stats, not per connection)
        pubs = []
        for pub in list(self.publishers.values()):
            st = pub.stats
            pubs.append([pub.topic, st.bytes, [[l.conn, l.bytes, l.frames, True]
                                               for l in st.links if l.connected]])
        subs = []
        for sub in list(self.subscribers.values()):
            subs.append([sub.topic, [[conn, nbytes, frames, -1, connected]
                                     for conn, nbytes, frames, connected in sub.link_stats()]])
        return 1, "", [pubs, subs, []]

    # ------------------------------------------------------------------ shutdown
    def shutdown(self, reason: str = "") -> None:
        """Unregister everything, close every socket, join every thread (idempotent)."""
        self._shutdown(reason)

    _api_shutdown.ros_name = "shutdown"  # type: ignore[attr-defined]

    def wait_for_shutdown(self, timeout: float | None = None) -> bool:
        """Block until the node has shut down (by :meth:`shutdown` or a remote slave-API
        ``shutdown``; :attr:`shutdown_reason` says which); False when ``timeout`` ran out."""
        return self._down.wait(timeout)

    def _shutdown(self, reason: str = "") -> None:
        with self._lock:
            first = self._shutting_down_in
            if first is None:
                self._shutting_down_in = threading.current_thread()
                self.shutdown_reason = reason or "shut down"
                self.is_shutdown = True
        if first is not None:
            if first is not threading.current_thread():  # another thread (a remote shutdown's) is
                self._down.wait(JOIN_TIMEOUT)  # at it: return once it is done, so a caller that
            return                             # then exits lets that call's reply out first
        with self._lock:
            pubs = list(self.publishers.values())
            subs = list(self.subscribers.values())
            self.publishers.clear()
            self.subscribers.clear()
        if self._watch is not None:
            self._watch.stop()
        stop_node_logging(self._logging if self._logging is not True else None)
        port = self._service_port
        if port is not None:
            for name in port.names():
                try:
                    self._master("unregisterService", name, port.uri)
                except GraphError:
                    pass
            port.stop()
        topic_objects: list[Publisher | Subscriber] = [*subs, *pubs]
        for topic_object in topic_objects:
            self._leave(topic_object)
            topic_object.close()
        try:  # wakes the accept thread; the socket is closed once that thread has left accept()
            self._tcp.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        with self._lock:  # a handshake thread takes its socket out of _pending before closing it
            handshakes = list(self._handshakes)
            for conn in self._pending:  # wakes its handshake thread, which closes it
                try:
                    conn.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
        for t in handshakes:
            if t is not threading.current_thread():
                t.join(JOIN_TIMEOUT)
        if self._accept is not threading.current_thread():
            self._accept.join(JOIN_TIMEOUT)
        self._tcp.close()
        self._xmlrpc.stop()
        self._down.set()
