"""Errors of the graph layer (XML-RPC master/slave, node runtime).

The parameter server refuses values nested deeper than :data:`MAX_XMLRPC_DEPTH`, integers
outside XML-RPC's 32-bit range and ``<nil/>`` (see ``master``).
"""

from __future__ import annotations

from rosfpga_lab.errors import LabError
# The limits live in limits.py; re-exported here for code written before the move.
from rosfpga_lab.graph.limits import (  # noqa: F401
    MAX_XMLRPC_BODY,
    MAX_XMLRPC_REPLY,
    MAX_HTTP_HEAD,
    XMLRPC_TIMEOUT,
    XMLRPC_IDLE_TIMEOUT,
    XMLRPC_REQUEST_TIMEOUT,
    MAX_XMLRPC_CONNECTIONS,
    MAX_XMLRPC_DEPTH,
    MAX_PENDING_HANDSHAKES,
    ACCEPT_BACKOFF_FIRST,
    ACCEPT_BACKOFF_MAX,
    ACCEPT_LOG_INTERVAL,
    MAX_PUBLISHERS_PER_TOPIC,
    CONNECT_TIMEOUT,
    RECONNECT_FIRST,
    RECONNECT_FACTOR,
    RECONNECT_MAX,
    JOIN_TIMEOUT,
    NOTIFY_TIMEOUT,
    NOTIFY_WORKERS,
    MAX_NOTIFY_PENDING,
    MAX_ERRORS_KEPT,
    TRACE_MAX_EVENTS,
    TRACE_MAX_BYTES,
    TRACE_EXCERPT_BYTES,
    MAX_CLOSED_LINKS_KEPT,
)


class GraphError(LabError):
    """Base of errors in the graph layer."""


class XmlRpcError(GraphError):
    """An XML-RPC call failed: network, HTTP, XML or an XML-RPC fault."""


class XmlRpcTooLargeError(XmlRpcError):
    """An HTTP body (request or reply) is over the size limit; the message gives both sizes."""


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
