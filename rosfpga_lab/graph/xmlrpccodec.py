"""XML-RPC documents, sans-IO: values to XML and back, safely, with ROS's limits.

How it works: :func:`parse_xmlrpc` reads a request or a reply with defusedxml's expat parser (no
entity expansion, no DTDs, no external references) into the stdlib's unmarshaller, and refuses
values nested deeper than :data:`MAX_XMLRPC_DEPTH`; :func:`dump_request`,
:func:`dump_response` and :func:`dump_fault` write documents with the stdlib's marshaller (used
only to build XML, never to parse). XML-RPC's ``<int>`` is 32 bits: a call's parameters
outside that range are refused (:func:`check_int_range`), a reply's are clamped, as ROS expects.
A handler raises :class:`Fault` for a fault reply. The HTTP around the documents is
:mod:`rosfpga_lab.graph.http`'s, the sockets :mod:`rosfpga_lab.graph.xmlrpc`'s.
"""

from __future__ import annotations

import xmlrpc.client
from typing import Any

from defusedxml.xmlrpc import DefusedExpatParser

from rosfpga_lab.graph.errors import XmlRpcError
from rosfpga_lab.graph.limits import MAX_XMLRPC_DEPTH

#: XML-RPC's <int>/<i4> range (ROS's XmlRpcValue and rospy's marshaller refuse anything else).
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


class Fault(Exception):
    """Raise from a handler to answer with an XML-RPC fault (not a LabError: it is a reply)."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


def parse_xmlrpc(data: bytes) -> tuple[tuple, str | None]:
    """Parse an XML-RPC request or response safely.

    Returns:
        ``(params, method_name)``; method_name is None for responses.

    Raises:
        XmlRpcError: malformed XML, forbidden XML constructs, not XML-RPC, nested deeper than
            :data:`MAX_XMLRPC_DEPTH`, or a fault reply.
    """
    unmarshaller = xmlrpc.client.Unmarshaller(use_builtin_types=True)
    parser = DefusedExpatParser(unmarshaller)
    try:
        parser.feed(data)
        parser.close()
        params = unmarshaller.close()
    except xmlrpc.client.Fault as fault:
        raise XmlRpcError(f"XML-RPC fault {fault.faultCode}: {fault.faultString}") from None
    except Exception as exc:  # expat, defusedxml, ResponseError, bad int/float/base64 text
        raise XmlRpcError(f"malformed XML-RPC document: {type(exc).__name__}: {exc}") from None
    depth = value_depth(params, MAX_XMLRPC_DEPTH + 1)
    if depth > MAX_XMLRPC_DEPTH:
        raise XmlRpcError(f"XML-RPC values nested deeper than {MAX_XMLRPC_DEPTH} levels are refused")
    return params, unmarshaller.getmethodname()


def value_depth(value: Any, stop: int | None = None) -> int:
    """Nesting depth of lists/tuples/dicts in ``value`` (a scalar is 0), without recursion.

    Args:
        stop: return as soon as the depth reaches this (enough to know a limit is passed).
    """
    deepest = 0
    stack = [(value, 0)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, (list, tuple, dict)):
            d += 1
            deepest = max(deepest, d)
            if stop is not None and deepest >= stop:
                return deepest
            stack.extend((x, d) for x in (v.values() if isinstance(v, dict) else v))
    return deepest


def check_int_range(value: Any) -> None:
    """Refuse ints XML-RPC cannot carry (outside int32), anywhere in ``value``, without recursion.

    Raises:
        XmlRpcError: naming the first such integer.
    """
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, bool):
            continue
        if isinstance(v, int):
            if not INT32_MIN <= v <= INT32_MAX:
                raise XmlRpcError(f"integer {v} is outside XML-RPC's 32-bit range "
                                  f"[{INT32_MIN}, {INT32_MAX}]")
        elif isinstance(v, (list, tuple)):
            stack.extend(v)
        elif isinstance(v, dict):
            stack.extend(v.values())


def dump_response(value: Any) -> bytes:
    """Marshal a handler's return value (ints clamped to int32 as ROS expects)."""
    return xmlrpc.client.dumps((_clamp(value),), methodresponse=True, allow_none=False).encode()


def _clamp(v: Any) -> Any:
    if isinstance(v, bool):
        return v
    if isinstance(v, int):
        return max(INT32_MIN, min(INT32_MAX, v))
    if isinstance(v, (list, tuple)):
        return [_clamp(x) for x in v]
    if isinstance(v, dict):
        return {k: _clamp(x) for k, x in v.items()}
    return v


def dump_fault(code: int, message: str) -> bytes:
    """A fault reply."""
    return xmlrpc.client.dumps(xmlrpc.client.Fault(code, message), methodresponse=True).encode()


def dump_request(method: str, params: tuple) -> bytes:
    """A ``methodCall`` of ``method(*params)`` (check the ints with :func:`check_int_range`)."""
    return xmlrpc.client.dumps(tuple(params), methodname=method, allow_none=False).encode()


__all__ = [
    "INT32_MAX", "INT32_MIN", "Fault", "check_int_range", "dump_fault", "dump_request",
    "dump_response", "parse_xmlrpc", "value_depth",
]
