"""ROS 1 services on real sockets: a node's service port (server) and one call (client).

How it works: a :class:`ServiceServer` listens on its own TCP port (its ``rosrpc://host:port``
URI is what the master's ``lookupService`` gives clients) and serves every service its node
advertises. Each connection gets a thread running
:class:`~rosfpga_lab.tcpros.service.ServiceServerConnection` (bytes in, events out): the client's
header must be complete within ``HANDSHAKE_TIMEOUT``; a persistent connection may then sit idle
for at most :data:`SERVICE_IDLE_TIMEOUT` between calls; at most :data:`MAX_SERVICE_CONNECTIONS`
connections are served at once (a new one beyond that evicts the one idle longest, or is closed
when every one is inside a call). A request
is decoded with the service's request type, the handler's dict is encoded with the response
type; a handler that raises answers ``ok=0`` with its text, as rospy does ("error processing
request: ..."). :func:`call_service` is one call from a client: lookupService, connect, header,
request, response, all within ``timeout``. Each exchange is recorded in the node's trace.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from typing import Any

from rosfpga_lab.graph.errors import GraphError, ServiceError
from rosfpga_lab.graph.limits import (
    JOIN_TIMEOUT,
    LISTEN_BACKLOG,
    MAX_SERVICE_CONNECTIONS,
    SERVICE_CALL_TIMEOUT,
    SERVICE_IDLE_TIMEOUT,
)
from rosfpga_lab.graph.trace import Trace
from rosfpga_lab.graph.wire import RECV_CHUNK, accept_loop, hard_close, socket_ends
from rosfpga_lab.msg.srv import SrvSpec
from rosfpga_lab.tcpros import HANDSHAKE_TIMEOUT, ProtocolError
from rosfpga_lab.tcpros.service import (
    ServiceAccepted,
    ServiceClientConnection,
    ServiceClosed,
    ServiceHeader,
    ServiceRejected,
    ServiceRequest,
    ServiceResponse,
    ServiceServerConnection,
    ServiceSpec,
    encode_response,
)

#: ``handler(request_dict) -> response_dict``
ServiceHandler = Callable[[dict], dict]


def split_rosrpc(uri: str) -> tuple[str, int]:
    """``rosrpc://host:port`` -> (host, port).

    Raises:
        ServiceError: not such a URI.
    """
    rest = uri[len("rosrpc://"):] if uri.startswith("rosrpc://") else ""
    host, _, port = rest.rstrip("/").rpartition(":")
    if not host or not port.isdigit():
        raise ServiceError(f"not a service URI (want rosrpc://host:port): {uri!r}")
    return host.strip("[]"), int(port)


class ServiceServer:
    """The service port of one node.

    Args:
        name: the node's name (callerid of every reply).
        bind: address to listen on; advertise_host: host written in :attr:`uri`.
        registry: message registry holding every served type's request and response.
    """

    def __init__(self, name: str, bind: str, advertise_host: str, registry: Any,
                 trace: Trace | None = None) -> None:
        self.name = name
        self.registry = registry
        self.trace = trace
        self.advertise_host = advertise_host
        self._services: dict[str, tuple[ServiceSpec, SrvSpec, ServiceHandler]] = {}
        self._conns: dict[socket.socket, float] = {}   # socket -> idle since (inf: in a call)
        self._threads: set[threading.Thread] = set()
        self._lock = threading.Lock()
        self._running = True
        family = socket.AF_INET6 if ":" in bind else socket.AF_INET
        self._sock = socket.socket(family, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._sock.bind((bind, 0))
        except OSError as exc:
            self._sock.close()
            raise GraphError(f"cannot bind the service port of {name} on {bind}: {exc}") from None
        self._sock.listen(LISTEN_BACKLOG)
        self.port = self._sock.getsockname()[1]
        #: calls answered, connections closed to make room for newer ones, and connections
        #: refused because every one was inside a call
        self.calls = 0
        self.evicted = 0
        self.refused = 0
        self._accept = threading.Thread(target=accept_loop, daemon=True,
                                        name=f"rosfpga-service-accept-{name}",
                                        args=(self._sock, lambda: self._running, self._admit,
                                              f"service port of {name}"))
        self._accept.start()

    @property
    def uri(self) -> str:
        """``rosrpc://host:port``."""
        host = f"[{self.advertise_host}]" if ":" in self.advertise_host else self.advertise_host
        return f"rosrpc://{host}:{self.port}"

    def add(self, service: str, srv: SrvSpec, handler: ServiceHandler) -> None:
        """Serve ``service`` (a global name) with ``handler``."""
        spec = ServiceSpec(service, srv.name, srv.md5sum, srv.request, srv.response)
        with self._lock:
            self._services[service] = (spec, srv, handler)

    def remove(self, service: str) -> None:
        with self._lock:
            self._services.pop(service, None)

    def names(self) -> list[str]:
        with self._lock:
            return list(self._services)

    def _lookup(self, service: str) -> ServiceSpec | None:
        with self._lock:
            entry = self._services.get(service)
        return entry[0] if entry else None

    def _admit(self, conn: socket.socket, peer: str) -> None:
        with self._lock:
            if len(self._conns) >= MAX_SERVICE_CONNECTIONS:
                idle = [c for c, since in self._conns.items() if since != float("inf")]
                if not idle:  # every connection is inside a call: this one waits for none
                    self.refused += 1
                    hard_close(conn)
                    return
                victim = min(idle, key=self._conns.__getitem__)
                del self._conns[victim]
                self.evicted += 1
                try:  # wakes its thread, which closes it
                    victim.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
            self._conns[conn] = time.monotonic()
            t = threading.Thread(target=self._serve, args=(conn, peer), daemon=True,
                                 name=f"rosfpga-service-conn-{self.name}")
            self._threads.add(t)
        t.start()

    def _serve(self, conn: socket.socket, peer: str) -> None:
        try:
            self._run(conn, peer)
        except (OSError, ProtocolError):
            pass
        finally:
            with self._lock:
                self._conns.pop(conn, None)
                self._threads.discard(threading.current_thread())
            hard_close(conn)

    def _run(self, conn: socket.socket, peer: str) -> None:
        machine = ServiceServerConnection(self.name, self._lookup)
        ends = socket_ends(conn)
        deadline = time.monotonic() + HANDSHAKE_TIMEOUT
        persistent = False
        caller = peer
        while self._running:
            if machine.spec is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                conn.settimeout(left)
            else:
                conn.settimeout(SERVICE_IDLE_TIMEOUT)
            try:
                data = conn.recv(RECV_CHUNK)
            except TimeoutError:
                return
            events = machine.receive_data(data) if data else machine.receive_eof()
            for ev in events:
                if isinstance(ev, ServiceHeader):
                    caller = ev.fields.get("callerid", peer)
                    self._record("service_call", role="in", src=caller, dst=self.name,
                                 method=ev.fields.get("service", ""), args=dict(ev.fields),
                                 result="connection header", size=len(ev.raw), **ends)
                elif isinstance(ev, ServiceRejected):
                    conn.settimeout(1.0)
                    conn.sendall(ev.reply)
                    return
                elif isinstance(ev, ServiceAccepted):
                    conn.settimeout(HANDSHAKE_TIMEOUT)
                    conn.sendall(ev.reply)
                    if ev.probe:
                        return
                    persistent = ev.persistent
                elif isinstance(ev, ServiceRequest):
                    if not self._set_busy(conn, True):
                        return
                    assert machine.spec is not None
                    reply = self._answer(machine.spec, ev.body, caller)
                    conn.settimeout(SERVICE_CALL_TIMEOUT)
                    conn.sendall(reply)
                    self.calls += 1
                    if not persistent or not self._set_busy(conn, False):
                        return
                elif isinstance(ev, ServiceClosed):
                    return

    def _set_busy(self, conn: socket.socket, busy: bool) -> bool:
        with self._lock:
            if conn not in self._conns:
                return False
            self._conns[conn] = float("inf") if busy else time.monotonic()
            return True

    def _answer(self, spec: ServiceSpec, body: bytes, caller: str) -> bytes:
        from rosfpga_lab.msg import deserialize, serialize

        with self._lock:
            entry = self._services.get(spec.service)
        t0 = time.time()
        ok, out = False, b""
        try:
            if entry is None or entry[0] != spec:
                raise GraphError(f"service [{spec.service}] is no longer provided by {self.name}")
            _spec, srv, handler = entry
            response = handler(deserialize(self.registry, srv.request, body))
            out = serialize(self.registry, srv.response, response or {})
            ok = True
        except Exception as exc:  # rospy's wording; the server keeps serving
            out = f"error processing request: {exc}".encode()
        self._record("service_call", role="server", src=caller, dst=self.name, method=spec.service,
                     result="ok" if ok else out.decode(errors="replace"), size=len(body) + len(out) + 5,
                     t0=t0)
        return encode_response(ok, out)

    def _record(self, kind: str, **fields: Any) -> None:
        if self.trace is not None:
            self.trace.record(kind, self.name, **fields)

    def stop(self) -> None:
        """Stop accepting, close every connection, join every thread."""
        self._running = False
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        with self._lock:
            for c in self._conns:
                try:
                    c.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
            threads = list(self._threads)
        for t in threads:
            if t is not threading.current_thread():
                t.join(JOIN_TIMEOUT)
        if self._accept is not threading.current_thread():
            self._accept.join(JOIN_TIMEOUT)
        self._sock.close()


def call_service(uri: str, service: str, srv: SrvSpec, request: dict | None, *, callerid: str,
                 registry: Any, timeout: float = SERVICE_CALL_TIMEOUT,
                 trace: Trace | None = None) -> dict:
    """Call ``service`` at ``uri`` (``rosrpc://host:port``) once; return the response dict.

    Raises:
        ServiceError: refused header, ``ok=0`` answer (its text), closed early or time-out.
        MsgError: the request does not fit the request type.
    """
    from rosfpga_lab.msg import deserialize, serialize

    host, port = split_rosrpc(uri)
    body = serialize(registry, srv.request, request or {})
    client = ServiceClientConnection(callerid, service, srv.md5sum, type_name=srv.name)
    deadline = time.monotonic() + timeout
    t0 = time.time()
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            sock.sendall(client.request_header)  # the request after the server's header, as
            #                                      rospy's client does (rospy's server reads no further)
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError
                sock.settimeout(left)
                data = sock.recv(RECV_CHUNK)
                events = client.receive_data(data) if data else client.receive_eof()
                for ev in events:
                    if isinstance(ev, ServiceHeader) and "error" not in ev.fields:
                        sock.sendall(client.request(body))
                    if isinstance(ev, ServiceRejected):
                        raise ServiceError(f"service [{service}] at {uri} refused the call: {ev.error}")
                    if isinstance(ev, ServiceResponse):
                        if trace is not None:
                            trace.record("service_call", callerid, role="client", src=callerid,
                                         dst=service, method=service, t0=t0,
                                         result="ok" if ev.ok else ev.body.decode(errors="replace"),
                                         size=len(body) + len(ev.body) + 5)
                        if not ev.ok:
                            raise ServiceError(f"service [{service}] responded with an error: "
                                               f"{ev.body.decode(errors='replace')}")
                        return deserialize(registry, srv.response, ev.body)
                    if isinstance(ev, ServiceClosed):
                        raise ServiceError(f"service [{service}] at {uri}: "
                                           f"{ev.error or 'closed without a response'}")
    except TimeoutError:
        raise ServiceError(f"service [{service}] at {uri} did not answer within {timeout} s") from None
    except OSError as exc:
        raise ServiceError(f"cannot reach service [{service}] at {uri}: {exc}") from None
    except ProtocolError as exc:
        raise ServiceError(f"service [{service}] at {uri}: {exc}") from None
