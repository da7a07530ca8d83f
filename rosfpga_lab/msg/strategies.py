"""Hypothesis strategies for values of any message type, and a value normalizer for comparisons.

For property tests in any layer (needs ``hypothesis``, a test dependency; not imported by
``rosfpga_lab.msg`` itself)::

    from rosfpga_lab.msg.strategies import message, normalize
    @given(message(reg, "sensor_msgs/Imu"))
    def test_roundtrip(value): ...

Generated values mix the accepted input forms (lists, numpy arrays, bytes for ``uint8[]``);
:func:`normalize` turns any value (input or decoded) into plain comparable Python data.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import strategies as st

from rosfpga_lab.msg import Duration, MsgRegistry, Time
from rosfpga_lab.msg.parser import Field
from rosfpga_lab.msg.builtins import FLOAT_TYPES, SCALARS, TIME_CLASS, integer_bounds

MAX_LEN = 3


def _scalar(base: str) -> st.SearchStrategy:
    if base == "bool":
        return st.booleans()
    if base == "float32":
        return st.floats(width=32, allow_nan=False)
    if base == "float64":
        return st.floats(allow_nan=False)
    low, high = integer_bounds(base)
    return st.integers(low, high)


def element(reg: MsgRegistry, base: str, max_len: int,
            canonical_time: bool = False) -> st.SearchStrategy:
    """Strategy of one element of builtin or message type ``base``.

    ``canonical_time`` keeps time/duration nsecs in [0, 1e9) (genpy canonicalizes on decode).
    """
    if base in SCALARS:
        return _scalar(base)
    canon = st.integers(0, 999_999_999)
    if base == "time":
        return st.builds(Time, st.integers(0, 2**32 - 1),
                         canon if canonical_time else st.integers(0, 2**32 - 1))
    if base == "duration":
        return st.builds(Duration, st.integers(-2**31, 2**31 - 1),
                         canon if canonical_time else st.integers(-2**31, 2**31 - 1))
    if base == "string":
        return st.text(max_size=6)
    return message(reg, base, max_len, canonical_time)


def field(reg: MsgRegistry, f: Field, max_len: int,
          canonical_time: bool = False) -> st.SearchStrategy:
    """Strategy of the value of field ``f`` (arrays up to ``max_len`` elements)."""
    if not f.is_array:
        return element(reg, f.base_type, max_len, canonical_time)
    low, high = (f.array_length, f.array_length) if f.array_length is not None else (0, max_len)
    base = f.base_type
    if base in ("uint8", "char"):
        return st.binary(min_size=low, max_size=high if f.array_length is not None else 12) \
            .flatmap(lambda b: st.sampled_from([b, np.frombuffer(b, np.uint8), list(b)]))
    items = st.lists(element(reg, base, max_len, canonical_time), min_size=low, max_size=high)
    if base in SCALARS:
        dtype = SCALARS[base].dtype
        return items.flatmap(lambda xs: st.sampled_from([xs, np.array(xs, dtype=dtype)]))
    return items


def message(reg: MsgRegistry, type_name: str, max_len: int = MAX_LEN,
            canonical_time: bool = False) -> st.SearchStrategy:
    """Strategy of dict values of ``type_name`` (arrays up to ``max_len`` elements)."""
    spec = reg.get(type_name)
    return st.fixed_dictionaries({f.name: field(reg, f, max_len, canonical_time)
                                  for f in spec.fields})


def normalize(reg: MsgRegistry, type_name: str, value: Any) -> Any:
    """Plain nested dict/list/tuple form, float32 values rounded as the wire rounds them."""
    spec = reg.get(type_name)
    return {f.name: _norm_field(reg, f, value[f.name]) for f in spec.fields}


def _norm_elem(reg: MsgRegistry, base: str, v: Any) -> Any:
    if base in TIME_CLASS:
        return (int(v[0]), int(v[1]))
    if base == "float32":
        return float(np.float32(v))
    if base in FLOAT_TYPES:
        return float(v)
    if base == "bool":
        return bool(v)
    if base in SCALARS:
        return int(v)
    if base == "string":
        return v
    return normalize(reg, base, v)


def _norm_field(reg: MsgRegistry, f: Field, v: Any) -> Any:
    if not f.is_array:
        return _norm_elem(reg, f.base_type, v)
    if isinstance(v, (bytes, bytearray, memoryview)):
        v = list(bytes(v))
    return [_norm_elem(reg, f.base_type, x) for x in v]
