"""Default values and message construction (:func:`new_message`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rosfpga_lab.msg.builtins import FLOAT_TYPES, SCALARS, TIME_CLASS
from rosfpga_lab.msg.errors import SerializeError
from rosfpga_lab.msg.parser import Field
from rosfpga_lab.msg.registry import MsgRegistry


def default_value(reg: MsgRegistry, f: Field) -> Any:
    """The value a new message has in field ``f`` (zeros, empty strings and arrays)."""
    base = f.base_type
    if f.is_array:
        n = f.array_length or 0
        if base in SCALARS:
            return np.zeros(n, dtype=SCALARS[base].dtype)
        return [_default_element(reg, base) for _ in range(n)]
    return _default_element(reg, base)


def _default_element(reg: MsgRegistry, base: str) -> Any:
    if base in SCALARS:
        if base == "bool":
            return False
        return 0.0 if base in FLOAT_TYPES else 0
    if base in TIME_CLASS:
        return TIME_CLASS[base](0, 0)
    if base == "string":
        return ""
    return new_message(reg, base)


def new_message(reg: MsgRegistry, type_name: str, **fields: Any) -> dict:
    """A message value with every field set: given ``fields`` plus defaults for the rest.

    A dict given for a nested message field, or inside an array of messages, is completed
    with defaults too.

    Args:
        reg: the registry holding the type.
        type_name: e.g. ``sensor_msgs/Image``.
        **fields: field values.

    Returns:
        A dict ready for :func:`serialize`.

    Raises:
        SerializeError: a keyword is not a field of the type.
        UnknownTypeError: the type (or a nested one) is not registered.
    """
    spec = reg.check(type_name)
    unknown = sorted(set(fields) - set(spec.field_names))
    if unknown:
        raise SerializeError(f"field {unknown[0]}: {spec.full_name} has no such field (fields: "
                             f"{', '.join(spec.field_names) or 'none'})", unknown[0], spec.full_name)
    out: dict = {}
    for f in spec.fields:
        if f.name not in fields:
            out[f.name] = default_value(reg, f)
            continue
        value = fields[f.name]
        if not f.is_array and not f.is_builtin and isinstance(value, Mapping):
            value = _completed(reg, f.base_type, value, f.name)
        elif f.is_array and not f.is_builtin and isinstance(value, (list, tuple)):
            value = [_completed(reg, f.base_type, v, f"{f.name}[{i}]") if isinstance(v, Mapping)
                     else v for i, v in enumerate(value)]  # messages in arrays too, as genpy
        out[f.name] = value
    return out


def _completed(reg: MsgRegistry, type_name: str, value: Mapping, where: str) -> dict:
    try:
        return new_message(reg, type_name, **value)
    except SerializeError as exc:
        raise SerializeError(str(exc).replace("field ", f"field {where}.", 1),
                             f"{where}.{exc.path}", exc.expected) from None
