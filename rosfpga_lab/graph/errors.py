"""Errors and limits of the graph layer (XML-RPC master/slave, node runtime)."""

from __future__ import annotations

from rosfpga_lab.errors import LabError

#: Largest HTTP request/response body accepted (XML-RPC payloads are small; 8 MiB leaves room
#: for a big getSystemState or parameter tree).
MAX_XMLRPC_BODY = 8 << 20
#: Largest HTTP head (request line + headers).
MAX_HTTP_HEAD = 16 << 10
#: Seconds an XML-RPC call (connect + request + reply) may take.
XMLRPC_TIMEOUT = 10.0
#: Seconds an idle keep-alive XML-RPC connection stays open on our servers.
XMLRPC_IDLE_TIMEOUT = 30.0
#: Open XML-RPC connections a server accepts at once (more get "503" and are closed).
MAX_XMLRPC_CONNECTIONS = 128
#: TCPROS connections still in their handshake a node accepts at once (more are refused).
MAX_PENDING_HANDSHAKES = 64
#: Seconds to connect to a publisher's TCPROS port.
CONNECT_TIMEOUT = 5.0
#: Reconnect back-off after a publisher vanishes: first delay, factor, cap (roscpp: 0.1 s x2 up to 20 s).
RECONNECT_FIRST = 0.1
RECONNECT_FACTOR = 2.0
RECONNECT_MAX = 5.0
#: Seconds stop()/shutdown() waits for each worker thread.
JOIN_TIMEOUT = 5.0
#: Seconds the master waits on one publisherUpdate/paramUpdate/shutdown notification.
NOTIFY_TIMEOUT = 5.0
#: Error texts kept by a subscriber (``stats.errors``) and by the master (``notify_errors``):
#: the most recent ones.
MAX_ERRORS_KEPT = 50
#: Closed connections whose counters a publisher's ``stats.links`` still reports.
MAX_CLOSED_LINKS_KEPT = 64


class GraphError(LabError):
    """Base of errors in the graph layer."""


class XmlRpcError(GraphError):
    """An XML-RPC call failed: network, HTTP, XML or an XML-RPC fault."""


class MasterError(GraphError):
    """The master (or a node's slave API) answered with a status code other than 1."""

    def __init__(self, message: str, code: int = -1, status: str = "") -> None:
        super().__init__(message)
        self.code = code
        self.status = status


class ApiArgumentError(GraphError):
    """An XML-RPC API call had the wrong number or types of arguments."""


class ConfigError(GraphError):
    """Bad configuration: a malformed ROS_MASTER_URI, host or name."""
