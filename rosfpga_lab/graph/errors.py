"""Errors of the graph layer (XML-RPC master/slave, node runtime).

The parameter server refuses values nested deeper than :data:`~rosfpga_lab.graph.limits.MAX_XMLRPC_DEPTH`, integers
outside XML-RPC's 32-bit range and ``<nil/>`` (see ``master``).
"""

from __future__ import annotations

from rosfpga_lab.errors import LabError


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


class ServiceError(GraphError):
    """A service call failed: no provider, refused header, ``ok=0`` answer, or time-out."""


class ConfigError(GraphError):
    """Bad configuration: a malformed ROS_MASTER_URI, host or name."""
