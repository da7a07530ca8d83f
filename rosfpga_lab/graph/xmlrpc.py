"""XML-RPC over HTTP/1.1, small and safe, recording the exact bytes: the sockets.

How it works: the server accepts connections on a loopback socket (unless told otherwise),
gives each connection a thread, feeds its bytes to a sans-IO decoder
(:class:`~rosfpga_lab.graph.http.HttpDecoder`: the HTTP head capped at :data:`MAX_HTTP_HEAD`, a
``Content-Length`` body capped at :data:`MAX_XMLRPC_BODY`), parses the body
(:func:`~rosfpga_lab.graph.xmlrpccodec.parse_xmlrpc`: defusedxml, nesting capped at
``graph.limits.MAX_XMLRPC_DEPTH``), calls the handler and writes the reply; keep-alive is honoured as
rospy's and roscpp's clients expect. A request must be complete within
:data:`XMLRPC_REQUEST_TIMEOUT` of its first byte (a deadline for the whole request, not per
``recv``); at :data:`MAX_XMLRPC_CONNECTIONS` a new connection evicts the one that has waited
longest for request bytes, so peers holding sockets open cannot lock others out. The client
opens one connection per call, and its ``timeout`` bounds the whole call. Both sides record
request and response bytes in a :class:`~rosfpga_lab.graph.trace.Trace`. The XML documents are
:mod:`rosfpga_lab.graph.xmlrpccodec`'s, the HTTP messages :mod:`rosfpga_lab.graph.http`'s.
"""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass
import urllib.parse
from collections.abc import Callable
from typing import Any

from rosfpga_lab.graph.errors import ConfigError, XmlRpcError, XmlRpcTooLargeError
from rosfpga_lab.graph.http import (
    Body, EndOfStream, Head, HttpDecoder, keeps_alive, request_message, response_message,
)
from rosfpga_lab.graph.limits import (
    JOIN_TIMEOUT,
    LISTEN_BACKLOG,
    MAX_HTTP_HEAD,
    MAX_XMLRPC_BODIES_IN_FLIGHT,
    MAX_XMLRPC_BODY,
    MAX_XMLRPC_CONNECTIONS,
    MAX_XMLRPC_MULTICALL,
    MAX_XMLRPC_REPLY,
    XMLRPC_IDLE_TIMEOUT,
    XMLRPC_REQUEST_TIMEOUT,
    XMLRPC_TIMEOUT,
)
from rosfpga_lab.graph.names import address_family, uri_host
from rosfpga_lab.graph.trace import Trace
from rosfpga_lab.graph.wire import RECV_CHUNK, accept_loop, hard_close, socket_ends
from rosfpga_lab.graph.xmlrpccodec import (
    Fault, check_int_range, dump_fault, dump_request, dump_response, parse_xmlrpc,
)

Handler = Callable[[str, tuple], Any]


def split_uri(uri: str) -> tuple[str, int, str]:
    """``http://host:port/path`` -> (host, port, path).

    Raises:
        ConfigError: not an http URI with a host and port (also when ``uri`` is no str,
            e.g. a whole ``[code, statusMessage, value]`` reply instead of its value).
    """
    if not isinstance(uri, str):
        reply = (isinstance(uri, (list, tuple)) and len(uri) == 3
                 and isinstance(uri[0], int) and isinstance(uri[2], str))
        hint = (": that is a whole [code, statusMessage, value] XML-RPC reply (of lookupNode, "
                "say); its value, reply[2], is the URI" if reply else "")
        raise ConfigError(f"an XML-RPC URI is a str like 'http://host:port/', not "
                          f"{type(uri).__name__} {uri!r:.120}{hint}")
    parts = urllib.parse.urlsplit(uri)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "http" or not parts.hostname or port is None:
        raise ConfigError(f"not an XML-RPC URI (want http://host:port/): {uri!r}")
    return parts.hostname, port, parts.path or "/"


class _Deadline:
    """When the bytes of one request (or of one call) must have arrived.

    Args:
        first: seconds to wait for the first byte.
        whole: seconds for everything once the first byte is in (None: ``first`` bounds all).
    """

    def __init__(self, first: float, whole: float | None = None) -> None:
        now = time.monotonic()
        self.at = now + first
        self.whole = whole
        self.what = "reply" if whole is None else "request"

    def started(self) -> None:
        """The first byte arrived: from now on the whole-request limit applies."""
        if self.whole is not None:
            self.at = time.monotonic() + self.whole
            self.whole = None

    def recv(self, sock: socket.socket, n: int) -> bytes:
        """``sock.recv(n)`` within the deadline.

        Raises:
            TimeoutError: the deadline passed (before or during this recv).
        """
        left = self.at - time.monotonic()
        if left <= 0:
            raise TimeoutError(f"{self.what} not complete in time")
        sock.settimeout(left)
        chunk = sock.recv(n)
        if chunk:
            self.started()
        return chunk


def _next_event(sock: socket.socket, http: HttpDecoder, deadline: _Deadline) -> Head | Body | None:
    """Feed ``sock``'s bytes to ``http`` until it has an event; None when the stream ended
    cleanly between messages.

    Raises:
        XmlRpcError: what the decoder refuses (sizes, format, a stream cut inside a message).
        TimeoutError: ``deadline`` passed.
    """
    while True:
        event = http.next_event()
        if isinstance(event, (Head, Body)):
            return event
        if isinstance(event, EndOfStream):
            return None
        want = min(max(RECV_CHUNK, http.missing), 1 << 20)   # a big body in big pieces
        http.receive(deadline.recv(sock, want))


def _discard(sock: socket.socket, n: int, deadline: _Deadline) -> None:
    """Receive and drop up to ``n`` bytes (a refused body) within ``deadline``; keeps nothing."""
    sock.shutdown(socket.SHUT_WR)
    scratch = bytearray(65536)
    try:
        while n > 0:
            left = deadline.at - time.monotonic()
            if left <= 0:
                return
            sock.settimeout(left)
            got = sock.recv_into(scratch, min(n, len(scratch)))
            if not got:
                return
            n -= got
    except OSError:
        return


_context = threading.local()


def request_peer() -> str:
    """``host:port`` of the peer whose request this server thread is handling ("" elsewhere)."""
    return getattr(_context, "peer", "")


@dataclass
class _Conn:
    """A served connection: since when it waits for request bytes, and whether a handler runs."""

    since: float
    busy: bool = False


class XmlRpcServer:
    """A threaded XML-RPC server on one TCP port.

    Args:
        handler: ``handler(method, params) -> value``; raise :class:`Fault` for a fault reply.
            :func:`request_peer` tells it who is calling.
        host: address to bind (127.0.0.1 by default; "0.0.0.0" binds every interface).
        port: port, 0 for any free one.
        trace: where to record each exchange (role ``server``).
        name: recorder name (node name or ``master``).
        advertise_host: host written in :attr:`uri` (defaults to ``host``).
        request_timeout: seconds for a whole request once its first byte arrived.
        max_connections: connections kept open at once (see the module docstring).
        body_budget: bytes of request bodies held at once, all connections together; a request
            whose declared length would pass it is answered "503" before its body is read.
    """

    def __init__(self, handler: Handler, *, host: str = "127.0.0.1", port: int = 0,
                 trace: Trace | None = None, name: str = "", advertise_host: str | None = None,
                 request_timeout: float = XMLRPC_REQUEST_TIMEOUT,
                 max_connections: int = MAX_XMLRPC_CONNECTIONS,
                 body_budget: int = MAX_XMLRPC_BODIES_IN_FLIGHT) -> None:
        self.handler = handler
        self.body_budget = body_budget
        #: bytes of request bodies reserved now, and requests refused for the budget
        self.bodies_in_flight = 0
        self.over_budget = 0
        self.host = host
        self.port = port
        self.trace = trace
        self.name = name
        self.advertise_host = advertise_host or host
        self.request_timeout = request_timeout
        self.max_connections = max_connections
        self._sock: socket.socket | None = None
        self._threads: set[threading.Thread] = set()
        self._conns: dict[socket.socket, _Conn] = {}
        self._lock = threading.Lock()
        self._running = False
        self.requests = 0
        #: connections answered "503" (every kept connection was busy in a handler)
        self.refused = 0
        #: connections closed to make room for a new one (the longest-waiting first)
        self.evicted = 0

    @property
    def uri(self) -> str:
        """``http://host:port/`` of this server."""
        host = self.advertise_host
        if host in ("0.0.0.0", "", "::"):
            host = socket.gethostname()
        return f"http://{uri_host(host)}:{self.port}/"

    def start(self) -> None:
        """Bind, listen and start the accept thread."""
        sock = socket.socket(address_family(self.host), socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((self.host.strip("[]"), self.port))
        except (OSError, OverflowError) as exc:  # OverflowError: a port outside 0..65535
            sock.close()
            raise XmlRpcError(f"cannot bind XML-RPC server to {self.host}:{self.port}: {exc}") from None
        sock.listen(LISTEN_BACKLOG)
        self._sock = sock
        self.port = sock.getsockname()[1]
        self._running = True
        self._spawn(self._accept_loop, "xmlrpc-accept")

    def _spawn(self, target: Callable, name: str, *args: Any) -> None:
        t = threading.Thread(target=self._run_thread, args=(target, *args),
                             name=f"rosfpga-{name}-{self.name}", daemon=True)
        with self._lock:
            self._threads.add(t)
            t.start()

    def _run_thread(self, target: Callable, *args: Any) -> None:
        try:
            target(*args)
        finally:
            with self._lock:
                self._threads.discard(threading.current_thread())

    def _accept_loop(self) -> None:
        assert self._sock is not None
        accept_loop(self._sock, lambda: self._running, self._admit,
                    f"XML-RPC server {self.name or self.uri}")

    def _admit(self, conn: socket.socket, peer: str) -> None:
        with self._lock:
            full = len(self._conns) >= self.max_connections
            if full:
                waiting = [(st.since, c) for c, st in self._conns.items() if not st.busy]
                if waiting:  # the longest-waiting connection makes room (a legit call is quick)
                    victim = min(waiting, key=lambda x: x[0])[1]
                    del self._conns[victim]
                    self.evicted += 1
                    full = False
                    try:  # wakes its thread, which closes it (closing here could race its recv)
                        victim.shutdown(socket.SHUT_RDWR)
                    except OSError:
                        pass
            if not full:
                self._conns[conn] = _Conn(time.monotonic())
        if full:  # every connection is inside a handler: refuse without costing a thread
            self.refused += 1
            try:
                conn.settimeout(1.0)
                conn.sendall(response_message("503 Service Unavailable", b"too many connections", False))
            except OSError:
                pass
            hard_close(conn)
            return
        self._spawn(self._serve_connection, "xmlrpc-conn", conn, peer)

    def _reserve(self, headers: dict[str, str]) -> int:
        """Reserve the declared body length in the budget: the bytes reserved, or -1 when it
        would pass the budget (bad or oversized lengths reserve 0: they are refused anyway)."""
        try:
            length = int(headers.get("content-length", "0"))
        except ValueError:
            return 0
        if length <= 0 or length > MAX_XMLRPC_BODY:
            return 0
        with self._lock:
            if self.bodies_in_flight + length > self.body_budget:
                self.over_budget += 1
                return -1
            self.bodies_in_flight += length
        return length

    def _release(self, reserved: int) -> None:
        if reserved:
            with self._lock:
                self.bodies_in_flight -= reserved

    def _set_busy(self, conn: socket.socket, busy: bool) -> bool:
        """Mark ``conn`` busy (in a handler) or waiting again; False when it was evicted."""
        with self._lock:
            st = self._conns.get(conn)
            if st is None:
                return False
            st.busy = busy
            if not busy:
                st.since = time.monotonic()
            return True

    def _serve_connection(self, conn: socket.socket, peer: str) -> None:
        http = HttpDecoder(max_head=MAX_HTTP_HEAD, max_body=MAX_XMLRPC_BODY)
        _context.peer = peer
        ends = socket_ends(conn)
        try:
            while self._running and self._serve_request(conn, peer, http, ends):
                pass
        except OSError:
            return
        finally:
            _context.peer = ""
            with self._lock:
                self._conns.pop(conn, None)
            hard_close(conn)

    def _serve_request(self, conn: socket.socket, peer: str, http: HttpDecoder,
                       ends: dict[str, str]) -> bool:
        """Read one request from ``conn``, answer it and record it; True when the connection
        stays open for the next (keep-alive), False once it is to be closed."""
        deadline = _Deadline(XMLRPC_IDLE_TIMEOUT, self.request_timeout)
        try:
            if http.in_message:
                deadline.started()
            head = _next_event(conn, http, deadline)
            if head is None:
                return False
            assert isinstance(head, Head)
        except XmlRpcError as exc:
            conn.sendall(response_message("400 Bad Request", str(exc).encode(), False))
            return False
        t0 = time.time()
        parts = head.start_line.split()
        if len(parts) != 3 or parts[0] != "POST":
            conn.sendall(response_message("405 Method Not Allowed", b"", False))
            return False
        reserved = self._reserve(head.headers)
        if reserved < 0:  # refuse, and read the body into nothing so the client
            conn.settimeout(1.0)  # finishes sending and reads the refusal
            conn.sendall(response_message("503 Service Unavailable", (
                f"request bodies in flight would pass this server's budget of "
                f"{self.body_budget} bytes (graph.limits.MAX_XMLRPC_BODIES_IN_FLIGHT); "
                "retry later").encode(), False))
            _discard(conn, http.missing, deadline)
            return False
        body = None
        try:
            body = self._request_body(conn, http, deadline)
        finally:
            if body is None:
                self._release(reserved)
        if body is None:
            return False
        if not self._set_busy(conn, True):
            self._release(reserved)
            return False
        try:
            reply_body, method, params, result = self._dispatch(body)
        finally:
            self._release(reserved)
        keep = keeps_alive(head)
        reply = response_message("200 OK", reply_body, keep)
        # The call ran: count and record it before its reply leaves, so a caller that has the
        # reply finds it in the trace even if the server is stopped at once (stop() would
        # otherwise win the race against the lines after sendall).
        self.requests += 1
        if self.trace is not None:
            caller = params[0] if params and isinstance(params[0], str) else peer
            self.trace.record("xmlrpc", self.name, role="server", src=caller,
                              dst=self.name, method=method, args=list(params),
                              result=result, raw=self.trace.excerpt(head.raw, body),
                              raw_reply=self.trace.excerpt(reply),
                              size=len(head.raw) + len(body) + len(reply), t0=t0, **ends)
        conn.settimeout(self.request_timeout)
        conn.sendall(reply)   # still "busy": stop() lets a reply go out (a "shutdown" call's)
        if not self._set_busy(conn, False):
            return False
        return keep

    def _request_body(self, conn: socket.socket, http: HttpDecoder,
                      deadline: _Deadline) -> bytes | None:
        """The body of the request whose head ``http`` gave; None after answering 400, 413 or
        408 (the caller then closes the connection)."""
        try:
            event = _next_event(conn, http, deadline)
            if not isinstance(event, Body):   # the decoder gives a body after a head
                raise XmlRpcError("connection closed before the request's body")
            return event.data
        except XmlRpcError as exc:
            status = ("413 Payload Too Large" if isinstance(exc, XmlRpcTooLargeError)
                      else "400 Bad Request")
            conn.sendall(response_message(status, str(exc).encode(), False))
        except TimeoutError:
            conn.settimeout(1.0)
            conn.sendall(response_message("408 Request Timeout", (
                f"request not complete within {self.request_timeout} s").encode(), False))
        return None

    def _dispatch(self, body: bytes) -> tuple[bytes, str, tuple, Any]:
        try:
            params, method = parse_xmlrpc(body)
        except XmlRpcError as exc:
            return dump_fault(-32700, f"parse error: {exc}"), "", (), f"fault: {exc}"
        if method is None:
            return dump_fault(-32600, "not an XML-RPC request (no methodName)"), "", params, "fault"
        try:
            if method == "system.multicall":
                value = multicall(self.handler, params)
            else:
                value = self.handler(method, params)
            return dump_response(value), method, params, value
        except Fault as fault:
            return dump_fault(fault.code, fault.message), method, params, f"fault: {fault.message}"
        except Exception as exc:  # a bug in a handler must not kill the server thread
            return dump_fault(1, f"internal error: {type(exc).__name__}: {exc}"), method, params, "fault"

    def stop(self) -> None:
        """Stop accepting, close every connection, join every thread."""
        self._running = False
        if self._sock is not None:  # wakes the accept thread; closed once it has left accept()
            try:                    # (a descriptor closed under a thread's syscall can be reused)
                self._sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        with self._lock:  # a connection's thread takes it out of _conns before closing it
            for c, st in self._conns.items():
                if st.busy:   # answering a call: its thread sends the reply, then sees the stop
                    continue
                try:
                    c.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
        deadline = time.monotonic() + JOIN_TIMEOUT
        while True:
            with self._lock:
                threads = [t for t in self._threads if t is not threading.current_thread()]
            if not threads or time.monotonic() > deadline:
                break
            threads[0].join(max(0.0, deadline - time.monotonic()))
        if self._sock is not None:
            self._sock.close()


def unsupported(method: str) -> Fault:
    """The fault Python's dispatcher (rosmaster's, rospy's) answers for an unknown method."""
    return Fault(1, f"<class 'Exception'>:method \"{method}\" is not supported")


def multicall(handler: Handler, params: tuple) -> list:
    """``system.multicall`` as Python's ``SimpleXMLRPCDispatcher`` answers it (rosmaster's and
    rospy's servers): a list of ``{methodName, params}`` structs in, a list of ``[result]`` or
    ``{faultCode, faultString}`` out, each call answered on its own; at most
    :data:`MAX_XMLRPC_MULTICALL` calls, and no multicall inside a multicall (Python runs it;
    here it is that call's fault).

    Raises:
        Fault: not one list of structs with ``methodName`` and ``params`` (Python's texts), or
            more than :data:`MAX_XMLRPC_MULTICALL` calls: nothing is run then.
    """
    try:
        (calls,) = params
        if len(calls) > MAX_XMLRPC_MULTICALL:
            raise Fault(1, f"system.multicall of {len(calls)} calls refused: at most "
                           f"{MAX_XMLRPC_MULTICALL} (graph.limits.MAX_XMLRPC_MULTICALL)")
        batch = [(one["methodName"], one["params"]) for one in calls]
    except (TypeError, KeyError, ValueError) as exc:
        raise Fault(1, f"{type(exc)}:{exc}") from None
    results: list = []
    for name, args in batch:
        try:
            if not isinstance(name, str):
                raise unsupported(str(name))
            if name == "system.multicall":
                raise Fault(1, "system.multicall inside system.multicall is refused")
            if not isinstance(args, list):
                raise TypeError(f"params must be an array, not {type(args).__name__}")
            results.append([handler(name, tuple(args))])
        except Fault as fault:
            results.append({"faultCode": fault.code, "faultString": fault.message})
        except Exception as exc:  # what Python's dispatcher answers: "<class 'X'>:text"
            results.append({"faultCode": 1, "faultString": f"{type(exc)}:{exc}"})
    return results


def call(uri: str, method: str, *params: Any, trace: Trace | None = None, caller: str = "",
         callee: str = "", timeout: float = XMLRPC_TIMEOUT) -> Any:
    """Call ``method(*params)`` at ``uri``; return the result.

    Args:
        uri: ``http://host:port/``.
        trace: where to record the exchange (role ``client``).
        caller: recorder/source name; callee: destination name for the trace (default: uri).
        timeout: seconds for connect, send and receive.

    Raises:
        XmlRpcError: connection, HTTP or XML problem, a fault, no complete reply within
            ``timeout``, or an integer parameter outside XML-RPC's 32-bit range.
        ConfigError: malformed uri.
    """
    host, port, path = split_uri(uri)
    check_int_range(params)
    request = request_message(uri_host(host), port, path, dump_request(method, params))
    t0 = time.time()
    http = HttpDecoder(max_head=MAX_HTTP_HEAD, max_body=MAX_XMLRPC_REPLY, eof_ends_body=True)
    deadline = _Deadline(timeout)
    ends: dict[str, str] = {}
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            ends = socket_ends(sock)
            sock.settimeout(max(0.001, deadline.at - time.monotonic()))
            sock.sendall(request)
            head_event = _next_event(sock, http, deadline)
            if not isinstance(head_event, Head):
                raise XmlRpcError("connection closed before any reply")
            body_event = _next_event(sock, http, deadline)
            assert isinstance(body_event, Body)   # or the decoder raised
            reply_head, status_line, reply_body = head_event.raw, head_event.start_line, body_event.data
    except (OSError, XmlRpcError) as exc:
        if trace is not None:
            trace.record("xmlrpc", caller, role="client", src=caller, dst=callee or uri,
                         method=method, args=list(params), result=f"error: {exc}", raw=request, t0=t0,
                         **ends)
        if isinstance(exc, XmlRpcTooLargeError):  # the server answered: say so, not "failed"
            raise XmlRpcTooLargeError(f"XML-RPC call {method} to {uri}: the reply's {exc} "
                                      "(graph.limits.MAX_XMLRPC_REPLY)") from None
        raise XmlRpcError(f"XML-RPC call {method} to {uri} failed: {exc}") from None
    if trace is not None:
        ev = trace.record("xmlrpc", caller, role="client", src=caller, dst=callee or trace.name_of(uri),
                          method=method, args=list(params), raw=trace.excerpt(request),
                          raw_reply=trace.excerpt(reply_head, reply_body),
                          size=len(request) + len(reply_head) + len(reply_body), t0=t0, **ends)
    else:
        ev = None
    parts = status_line.split(None, 2)
    if len(parts) < 2 or parts[1] != "200":
        raise XmlRpcError(f"XML-RPC call {method} to {uri}: HTTP status {status_line!r}")
    try:
        result, _ = parse_xmlrpc(reply_body)
    except XmlRpcError as exc:
        if trace is not None:
            trace.set_result(ev, f"error: {exc}")
        raise XmlRpcError(f"XML-RPC call {method} to {uri}: {exc}") from None
    value = result[0] if len(result) == 1 else list(result)
    if trace is not None:
        trace.set_result(ev, value)
    return value
