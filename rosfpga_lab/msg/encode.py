"""Serialize Python values to ROS 1 message bodies (the mirror image of ``decode.py``).

How this works: a compiled encoder per type appends byte chunks to a list that is joined once.
Runs of fixed-size scalars are packed by one ``struct.Struct``; when packing fails, each field of
the run is packed alone to name the culprit. Numeric arrays go through numpy (range-checked, cast
to the little-endian dtype) and ``uint8[]`` accepts any bytes-like value or numpy array without
a copy until the final join. A message value may be a mapping or any object with the fields as
attributes (e.g. a genpy message); a mapping with unknown keys is refused.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rosfpga_lab.msg.builtins import (
    BYTE_ARRAY_TYPES, FLOAT_TYPES, SCALARS, TIME_CLASS, TIME_STRUCT, Duration, Time,
)
from rosfpga_lab.msg.decode import flat_fields
from rosfpga_lab.msg.errors import SerializeError
from rosfpga_lab.msg.parser import Field, MsgSpec
from rosfpga_lab.msg.registry import MsgRegistry

_U32 = struct.Struct("<I")
_STR_ERRORS = "surrogateescape"
_MISSING = object()

Encoder = Callable[[Any, list], None]


def _join(prefix: str, path: str) -> str:
    if not path:
        return prefix
    return f"{prefix}{path}" if path.startswith("[") else f"{prefix}.{path}"


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{type(value).__name__} {text}"


def _fail(path: str, expected: str, value: Any, why: str = "") -> SerializeError:
    why = f" ({why})" if why else ""
    return SerializeError(f"field {path or '<message>'}: expected {expected}, got "
                          f"{_describe(value)}{why}", path, expected)


def _prefixed(exc: SerializeError, prefix: str) -> SerializeError:
    path = _join(prefix, exc.path)
    msg = str(exc).replace(f"field {exc.path or '<message>'}:", f"field {path}:", 1)
    return SerializeError(msg, path, exc.expected)


def _getter(spec: MsgSpec) -> Callable[[Any, str], Any]:
    names = set(spec.field_names)

    def get(msg: Any, name: str) -> Any:
        if type(msg) is dict and name in msg:  # the common case, without the ABC check
            return msg[name]
        if isinstance(msg, Mapping):
            value = msg.get(name, _MISSING)
        else:
            value = getattr(msg, name, _MISSING)
        if value is _MISSING:
            if not isinstance(msg, Mapping) and not hasattr(msg, "__dict__") \
                    and not hasattr(msg, "__slots__"):
                raise _fail("", f"a {spec.full_name} (mapping or object with its fields)", msg)
            raise SerializeError(
                f"field {name}: missing from the {spec.full_name} value (fields: "
                f"{', '.join(spec.field_names) or 'none'}; new_message() fills defaults)",
                name, spec.full_name)
        return value

    count = len(names)

    def check_keys(msg: Any) -> None:
        if type(msg) is dict and len(msg) == count:
            return
        if isinstance(msg, Mapping) and len(msg) != count:
            extra = sorted(str(k) for k in msg if k not in names)
            if extra:
                raise SerializeError(
                    f"field {extra[0]}: {spec.full_name} has no such field (fields: "
                    f"{', '.join(spec.field_names) or 'none'})", extra[0], spec.full_name)

    get.check_keys = check_keys  # type: ignore[attr-defined]
    return get


def time_parts(value: Any, kind: str, path: str = "") -> tuple[int, int]:
    """(secs, nsecs) of a Time/Duration, tuple, dict or object with secs/nsecs."""
    if isinstance(value, (Time, Duration, tuple, list)) and len(value) == 2:
        return value[0], value[1]
    if isinstance(value, Mapping) and "secs" in value and "nsecs" in value:
        return value["secs"], value["nsecs"]
    if hasattr(value, "secs") and hasattr(value, "nsecs"):
        return value.secs, value.nsecs
    cls = TIME_CLASS[kind].__name__
    raise _fail(path, f"{kind} as {cls}(secs, nsecs), a (secs, nsecs) tuple or a dict",
                value, f"for seconds as a float use {cls}.from_sec()" if isinstance(value, float)
                else "")


def _check_scalar(kind: str, value: Any, path: str) -> None:
    """Raise a SerializeError saying why ``value`` does not pack as ``kind``."""
    if kind in TIME_STRUCT:
        secs, nsecs = time_parts(value, kind, path)
        for part, v in (("secs", secs), ("nsecs", nsecs)):
            _check_scalar("uint32" if kind == "time" else "int32", v, _join(path, part))
        return
    if kind == "bool":
        if not isinstance(value, (bool, np.bool_, int, np.integer)) or value not in (0, 1):
            raise _fail(path, "bool", value)
        return
    try:
        struct.pack("<" + SCALARS[kind].struct_char, value)
    except (struct.error, OverflowError, TypeError) as exc:
        raise _fail(path, kind, value, str(exc)) from None


def _group_encoder(names: list[str], kinds: list[str]) -> Callable:
    st = struct.Struct("<" + "".join(TIME_STRUCT.get(k) or SCALARS[k].struct_char for k in kinds))
    has_time = any(k in TIME_STRUCT for k in kinds)
    has_bool = "bool" in kinds

    def op(msg: Any, get: Callable, chunks: list) -> None:
        try:
            vals = [msg[n] for n in names] if type(msg) is dict else [get(msg, n) for n in names]
        except KeyError:
            vals = [get(msg, n) for n in names]  # raises the error naming the missing field
        try:
            if has_bool:
                for v, k, n in zip(vals, kinds, names):
                    if k == "bool":
                        _check_scalar(k, v, n)
            if has_time:
                flat: list = []
                for v, k, n in zip(vals, kinds, names):
                    if k in TIME_STRUCT:
                        flat.extend(time_parts(v, k, n))
                    else:
                        flat.append(v)
                vals = flat
            chunks.append(st.pack(*vals))
        except (struct.error, OverflowError, TypeError):
            for n, k in zip(names, kinds):
                _check_scalar(k, get(msg, n), n)
            raise  # pragma: no cover - a field above must have failed
    return op


def _encode_string(value: Any, path: str, chunks: list) -> None:
    if isinstance(value, str):
        data = value.encode("utf-8", _STR_ERRORS)
    elif isinstance(value, (bytes, bytearray)):
        data = bytes(value)
    else:
        raise _fail(path, "string (str or bytes)", value)
    chunks.append(_U32.pack(len(data)))
    chunks.append(data)


def _byte_array(value: Any, path: str, type_name: str) -> Any:
    """A contiguous buffer of uint8 for ``uint8[]``/``char[]``."""
    if isinstance(value, (bytes, bytearray)):
        return value
    if isinstance(value, memoryview):
        return value.cast("B") if value.c_contiguous else value.tobytes()
    if isinstance(value, str):
        raise _fail(path, f"{type_name} as bytes-like or numpy uint8 array", value,
                    "encode the str first, e.g. text.encode()")
    return _numeric_array(value, path, "uint8", type_name)


def _numeric_array(value: Any, path: str, base: str, type_name: str) -> np.ndarray:
    target = SCALARS[base].dtype
    if isinstance(value, (list, tuple)) and target.kind in "iu" and value:
        # Python ints may exceed int64 (uint64 values): check them as Python ints.
        if all(isinstance(x, (int, np.integer)) for x in value):
            info = np.iinfo(target)
            low, high = min(value), max(value)
            if low < info.min or high > info.max:
                bad = low if low < info.min else high
                raise _fail(path, type_name, value,
                            f"element {bad} is out of range {info.min}..{info.max}")
            return np.array(value, dtype=target)
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:
        raise _fail(path, type_name, value, str(exc)) from None
    if arr.ndim != 1:
        if arr.size == 0:
            arr = arr.reshape(0)
        elif arr.ndim == 0:
            raise _fail(path, f"{type_name} (a sequence)", value)
        else:
            arr = arr.reshape(-1)
    if arr.dtype == target:
        return np.ascontiguousarray(arr)
    kind = arr.dtype.kind
    if arr.size == 0:
        return np.empty(0, target)
    if base == "bool":
        if kind == "b" or (kind in "iu" and np.all((arr == 0) | (arr == 1))):
            return arr.astype(target)
        raise _fail(path, type_name, value, "bool elements must be True/False or 0/1")
    if base in FLOAT_TYPES:
        if kind not in "biuf":
            raise _fail(path, type_name, value, f"elements of dtype {arr.dtype} are not numbers")
        return arr.astype(target)
    if kind not in "biu":
        raise _fail(path, type_name, value,
                    f"elements of dtype {arr.dtype} are not integers")
    info = np.iinfo(target)
    low, high = int(arr.min()), int(arr.max())
    if low < info.min or high > info.max:
        bad = low if low < info.min else high
        raise _fail(path, type_name, value, f"element {bad} is out of range {info.min}..{info.max}")
    return arr.astype(target)


# long: one branch per kind of field, each returning the closure the
# compiled encoder calls per message (the fast path: the kind is decided once, here); decode.py's
# _field_decoder is its mirror, branch for branch, so the two read side by side.
def _field_encoder(reg: MsgRegistry, f: Field) -> Callable:
    name, base, fixed = f.name, f.base_type, f.array_length

    if not f.is_array:
        if base == "string":
            return lambda msg, get, chunks: _encode_string(get(msg, name), name, chunks)
        sub = compiled_encoder(reg, base)

        def op(msg, get, chunks):
            try:
                sub(get(msg, name), chunks)
            except SerializeError as exc:
                raise _prefixed(exc, name) from None
        return op

    def head(n: int, value: Any, chunks: list) -> None:
        if fixed is None:
            chunks.append(_U32.pack(n))
        elif n != fixed:
            raise _fail(name, f"{f.type} (exactly {fixed} elements)", value, f"it has {n}")

    if base in SCALARS:
        to_array = _byte_array if base in BYTE_ARRAY_TYPES else \
            (lambda v, p, t: _numeric_array(v, p, base, t))
        size = SCALARS[base].size

        def op(msg, get, chunks):
            value = get(msg, name)
            data = to_array(value, name, f.type)
            n = len(data) // size if isinstance(data, (bytes, bytearray, memoryview)) else len(data)
            head(n, value, chunks)
            chunks.append(data)
        return op

    def seq(value: Any) -> list:
        if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__"):
            raise _fail(name, f"{f.type} (a list)", value)
        return list(value)

    if base in TIME_STRUCT:
        st = struct.Struct("<" + TIME_STRUCT[base])

        def op(msg, get, chunks):
            items = seq(get(msg, name))
            head(len(items), items, chunks)
            for i, item in enumerate(items):
                parts = time_parts(item, base, f"{name}[{i}]")
                try:
                    chunks.append(st.pack(*parts))
                except (struct.error, OverflowError, TypeError):
                    _check_scalar(base, item, f"{name}[{i}]")
        return op
    if base == "string":
        def op(msg, get, chunks):
            items = seq(get(msg, name))
            head(len(items), items, chunks)
            for i, item in enumerate(items):
                _encode_string(item, f"{name}[{i}]", chunks)
        return op
    sub = compiled_encoder(reg, base)

    def generic(items: list, chunks: list) -> None:
        for i, item in enumerate(items):
            try:
                sub(item, chunks)
            except SerializeError as exc:
                raise _prefixed(exc, f"{name}[{i}]") from None

    flat = flat_fields(reg, base)
    if flat is None:
        def op(msg, get, chunks):
            items = seq(get(msg, name))
            head(len(items), items, chunks)
            generic(items, chunks)
        return op
    names = flat[0]
    row = struct.Struct("<" + "".join(SCALARS[k].struct_char for k in flat[1]))

    def op_flat(msg, get, chunks):
        items = seq(get(msg, name))
        head(len(items), items, chunks)
        try:  # flat messages as dicts: one struct per element, no per-field calls
            if all(type(it) is dict and len(it) == len(names) for it in items):
                chunks.append(b"".join([row.pack(*[it[n] for n in names]) for it in items]))
                return
        except (KeyError, struct.error, OverflowError, TypeError):
            pass
        generic(items, chunks)  # anything else, and every error, takes the general path
    return op_flat


def compiled_encoder(reg: MsgRegistry, type_name: str) -> Encoder:
    """The cached encoder ``(value, chunks) -> None`` of a type."""
    spec = reg.check(type_name)

    def build() -> Encoder:
        ops: list = []
        run: list[Field] = []
        for f in list(spec.fields) + [None]:
            if f is not None and not f.is_array and (f.base_type in SCALARS
                                                     or f.base_type in TIME_STRUCT):
                run.append(f)
                continue
            if run:
                ops.append(_group_encoder([r.name for r in run], [r.base_type for r in run]))
                run = []
            if f is not None:
                ops.append(_field_encoder(reg, f))
        get = _getter(spec)
        check_keys = get.check_keys  # type: ignore[attr-defined]

        def encode(msg: Any, chunks: list) -> None:
            check_keys(msg)
            for op in ops:
                op(msg, get, chunks)
        return encode
    return reg.cached("encoder", spec.full_name, build)


def serialize(reg: MsgRegistry, type_name: str, value: Any) -> bytes:
    """Encode a message body (without the 4-byte TCPROS frame length).

    Args:
        reg: the registry holding the type.
        type_name: e.g. ``sensor_msgs/Image``.
        value: a dict (or object with the fields as attributes); see the module docstring.

    Returns:
        The body bytes.

    Raises:
        SerializeError: a value is missing, unknown, of the wrong type or out of range
            (names the field path and the expected type).
        UnknownTypeError: the type (or a nested one) is not registered.
    """
    chunks: list = []
    compiled_encoder(reg, type_name)(value, chunks)
    return b"".join(chunks)


__all__ = ["compiled_encoder", "serialize", "time_parts"]
