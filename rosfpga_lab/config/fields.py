"""Field paths of a node configuration: which field of the message a key names, and whether it may.

A configuration names fields of its message by dotted path without indices: ``ranges``,
``header.frame_id``, ``info.samples``. A path walks nested messages; only ``limits:`` may walk
into the elements of an array of messages (``points.name``: the ``name`` of every element).
The rules live here once; the configuration checker (:mod:`~rosfpga_lab.config.sections`) turns a
problem into ``file:line: key: problem`` and the circuit layout (:mod:`rosfpga_lab.hw.layout`)
into its own error.
"""

from __future__ import annotations

import math
from typing import Any

from rosfpga_lab.config.vocabulary import STREAM_ELEMENT_TYPES
from rosfpga_lab.msg import BUILTIN_TYPES, Field, MsgRegistry
from rosfpga_lab.msg.builtins import FLOAT_TYPES, integer_bounds


class FieldPathError(ValueError):
    """A path names no field, or a field the key cannot take (the message says which and why)."""


def resolve_field(reg: MsgRegistry, type_name: str, path: str, *,
                  through_arrays: bool = False) -> tuple[Field, ...]:
    """The fields a dotted ``path`` walks, outermost first.

    Args:
        reg: the registry holding ``type_name`` and its dependencies.
        type_name: the message type, e.g. ``sensor_msgs/LaserScan``.
        path: e.g. ``header.frame_id``.
        through_arrays: allow the walk to enter arrays of messages.

    Raises:
        FieldPathError: no such field (the known ones are listed), or an array on the way.
    """
    spec = reg.check(type_name)
    chain: list[Field] = []
    parts = path.split(".")
    for i, name in enumerate(parts):
        by_name = {f.name: f for f in spec.fields}
        if name not in by_name:
            where = ".".join(parts[:i]) or spec.full_name
            raise FieldPathError(f"{where} has no field {name!r} (fields: "
                                 f"{', '.join(by_name) or 'none'})")
        f = by_name[name]
        chain.append(f)
        if i == len(parts) - 1:
            break
        if f.base_type in BUILTIN_TYPES:
            raise FieldPathError(f"{'.'.join(parts[:i + 1])} is a {f.type}, not a message: "
                                 f"it has no field {parts[i + 1]!r}")
        if f.is_array and not through_arrays:
            raise FieldPathError(f"{'.'.join(parts[:i + 1])} is an array of messages ({f.type}); "
                                 "this key cannot name a field inside its elements")
        spec = reg.check(f.base_type)
    return tuple(chain)


def stream_field(reg: MsgRegistry, type_name: str, path: str) -> Field:
    """The field ``stream.field`` names, if it can stream to the application.

    Raises:
        FieldPathError: it is missing, not an array, or an array of strings, times, messages or
            of an element type the application cannot take (see ``STREAM_ELEMENT_TYPES``).
    """
    f = resolve_field(reg, type_name, path)[-1]
    if not f.is_array:
        raise FieldPathError(f"{path} is a {f.type}, not an array: the stream is the one array "
                             "the application processes")
    if f.base_type not in STREAM_ELEMENT_TYPES:
        what = ("strings" if f.base_type == "string" else
                "messages" if f.base_type not in BUILTIN_TYPES else f.base_type)
        raise FieldPathError(f"{path} is an array of {what} ({f.type}); the application takes "
                             f"arrays of {', '.join(STREAM_ELEMENT_TYPES)}")
    return f


def limit_field(reg: MsgRegistry, type_name: str, path: str) -> Field:
    """The field a ``limits:`` key names: a string or a variable-length array.

    Raises:
        FieldPathError: it is missing or has a fixed size.
    """
    f = resolve_field(reg, type_name, path, through_arrays=True)[-1]
    if not (f.base_type == "string" or (f.is_array and f.array_length is None)):
        raise FieldPathError(f"{path} is a {f.type}: only strings and variable-length arrays "
                             "have a maximum")
    return f


def check_field(reg: MsgRegistry, type_name: str, path: str) -> Field:
    """The field a ``checks:`` key names: a number, bool, char/byte or string, not in an array.

    Raises:
        FieldPathError: it is missing, inside an array, an array, a message, a time or duration
            (check its ``secs``/``nsecs`` instead: not available, they are one field).
    """
    f = resolve_field(reg, type_name, path)[-1]
    if f.is_array or f.base_type not in BUILTIN_TYPES or f.base_type in ("time", "duration"):
        raise FieldPathError(f"{path} is a {f.type}: a check compares one number, bool or "
                             "string")
    return f


def check_value_problem(type_: str, value: Any) -> str | None:
    """Why ``value`` cannot be compared with a field of builtin ``type_``, or None."""
    if type_ == "string":
        ok = isinstance(value, str)
    elif type_ == "bool":
        ok = isinstance(value, bool)
    elif type_ in FLOAT_TYPES:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if ok and math.isnan(value):
            return "NaN equals nothing and bounds nothing: the circuit would refuse every frame"
    else:
        ok = isinstance(value, int) and not isinstance(value, bool)
        if ok:
            lo, hi = integer_bounds(type_)
            if not lo <= value <= hi:
                return f"{value} does not fit a {type_} ({lo}..{hi})"
    return None if ok else f"{value!r} is not a {type_} value"
