"""Argument checks for XML-RPC APIs, returning rosmaster's error triples.

Every ROS XML-RPC API takes ``caller_id`` first and answers ``[code, status, value]``.
:func:`checked` wraps an implementation with a per-argument spec and produces exactly the
error replies rosmaster's ``apivalidate`` does (missing caller_id, bad arity, caller_id not a
string) plus a clear one for each wrongly typed argument, so a bad call never raises in the
server and the server keeps serving.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rosfpga_lab.graph.names import is_legal_name, resolve

Spec = tuple[tuple[str, str], ...]  # (argument name, kind)


class ArgError(Exception):
    """Internal: an argument failed its check (turned into a -1 reply)."""


def _check(kind: str, name: str, value: Any, caller_id: str) -> Any:
    if kind == "any":
        return value
    if kind in ("str", "name", "topic", "type", "api", "opt_name"):
        if not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a string, got {type(value).__name__}")
    if kind in ("name", "topic"):
        if not value or not is_legal_name(value):
            raise ArgError(f"ERROR: parameter [{name}] is not a valid name: {value!r}")
        return resolve(value, caller_id)
    if kind == "opt_name":
        if value and not is_legal_name(value):
            raise ArgError(f"ERROR: parameter [{name}] is not a valid name: {value!r}")
        return resolve(value, caller_id) if value else ""
    if kind == "type":
        if value != "*" and (value.count("/") != 1 or not all(value.split("/"))):
            raise ArgError(f"ERROR: parameter [{name}] is not a valid package resource name: {value!r}")
        return value
    if kind == "api":
        if not value.startswith(("http://", "rosrpc://")):
            raise ArgError(f"ERROR: parameter [{name}] is not an XML-RPC URI: {value!r}")
        return value
    if kind == "list":
        if not isinstance(value, list):
            raise ArgError(f"ERROR: parameter [{name}] must be a list, got {type(value).__name__}")
        return value
    return value


def checked(spec: Spec, error_value: Any) -> Callable[[Callable], Callable]:
    """Decorate ``f(self, caller_id, *args)`` so bad calls get rosmaster's error replies."""

    def wrap(f: Callable) -> Callable:
        def api(self: Any, *params: Any) -> list:
            if len(params) == 0:
                return [-1, "missing required caller_id parameter", error_value]
            if len(params) != len(spec) + 1:
                return [-1, f"Error: bad call arity (expected {len(spec) + 1} arguments: caller_id, "
                        f"{', '.join(n for n, _ in spec) or 'nothing else'}; got {len(params)})",
                        error_value]
            caller_id = params[0]
            if not isinstance(caller_id, str):
                return [-1, "caller_id must be a string", error_value]
            try:
                args = [_check(kind, name, v, caller_id) for (name, kind), v in zip(spec, params[1:])]
            except ArgError as exc:
                return [-1, str(exc), error_value]
            code, status, value = f(self, caller_id, *args)
            return [code, status, value]

        api.__name__ = f.__name__
        api.__doc__ = f.__doc__
        api.ros_api = True  # type: ignore[attr-defined]
        return api

    return wrap


def api_methods(obj: Any) -> dict[str, Callable]:
    """Every method of ``obj`` decorated with :func:`checked`, by name."""
    out = {}
    for name in dir(type(obj)):
        attr = getattr(type(obj), name, None)
        if callable(attr) and getattr(attr, "ros_api", False):
            out[getattr(attr, "ros_name", name)] = getattr(obj, name)
    return out
