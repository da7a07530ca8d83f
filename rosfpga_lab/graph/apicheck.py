"""Argument checks for XML-RPC APIs, returning rosmaster's error triples.

Every ROS XML-RPC API takes ``caller_id`` first and answers ``[code, status, value]``.
:func:`checked` wraps an implementation with a per-argument spec and produces exactly the
error replies of rosmaster's ``apivalidate`` and validators (missing caller_id, bad arity,
caller_id not a string, each argument's check, same texts; tests compare them with a real
rosmaster), so a bad call never raises in the server and the server keeps serving.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rosfpga_lab.graph.names import resolve

Spec = tuple[tuple[str, str], ...]  # (argument name, kind)


class ArgError(Exception):
    """Internal: an argument failed its check (turned into a -1 reply)."""


def _check(kind: str, name: str, value: Any, caller_id: str) -> Any:
    """rosmaster's validators (rosmaster/validators.py), same texts."""
    if kind == "any":
        return value
    if kind == "key":  # non_empty_str
        if not value:
            raise ArgError(f"ERROR: parameter [{name}] must be specified and non-empty")
        if not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a string")
        return value
    if kind == "str":
        if not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a string")
        return value
    if kind in ("name", "topic"):  # valid_name / is_topic / is_service
        if not value or not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a non-empty string")
        if ":" in value or " " in value:
            raise ArgError(f"ERROR: parameter [{name}] contains illegal chars")
        if kind == "topic" and value == "/":
            raise ArgError(f"ERROR: parameter [{name}] cannot be the global namespace")
        return resolve(value, caller_id)
    if kind == "opt_name":  # empty_or_valid_name
        if not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a string")
        return resolve(value, caller_id) if value else ""
    if kind == "type":  # valid_type_name
        if value == "*":
            return value
        if not value or not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] must be a non-empty string")
        if len(value.split("/")) != 2:
            raise ArgError(f"ERROR: parameter [{name}] is not a valid package resource name")
        return value
    if kind == "api":  # is_api
        if not value or not isinstance(value, str):
            raise ArgError(f"ERROR: parameter [{name}] is not an XMLRPC URI")
        if not value.startswith(("http://", "rosrpc://")):
            raise ArgError(f"ERROR: parameter [{name}] is not an RPC URI")
        return value
    if kind == "list":
        if not isinstance(value, list):
            raise ArgError(f"ERROR: parameter [{name}] must be a list")
        return value
    raise AssertionError(f"unknown argument kind {kind}")


def checked(spec: Spec, error_value: Any) -> Callable[[Callable], Callable]:
    """Decorate ``f(self, caller_id, *args)`` so bad calls get rosmaster's error replies."""

    def wrap(f: Callable) -> Callable:
        def api(self: Any, *params: Any) -> list:
            if len(params) == 0:
                return [-1, "missing required caller_id parameter", error_value]
            if len(params) != len(spec) + 1:
                return [-1, "Error: bad call arity", error_value]
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
        api.ros_params = ("caller_id", *(name for name, _kind in spec))  # type: ignore[attr-defined]
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
