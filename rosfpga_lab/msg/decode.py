"""Deserialize ROS 1 message bodies (little-endian, as TCPROS carries them).

How this works: for each message type a codec is compiled once per registry (and cached there):
a list of field operations. Runs of fixed-size scalars (numbers, bool, time, duration) become
one ``struct.Struct``, so a ``Header``'s ``seq`` and ``stamp`` are one ``unpack_from``. Arrays of
numbers never loop in Python: ``uint8[]``/``char[]`` decode to a read-only numpy view of the
input buffer (zero copy) and other numeric arrays to read-only numpy views of the little-endian
dtype (``bool[]`` is the one copy). ``encode.py`` is the mirror image.

Every length prefix is checked against the bytes left (and the limits) before anything is
allocated. Errors name the field path (``points[3].x``) and, when decoding, the byte offset.
Values: nested message -> dict; time/duration -> :class:`Time`/:class:`Duration`; string -> str
(UTF-8; undecodable bytes kept as surrogates so a round trip is byte-exact).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

import numpy as np

from rosfpga_lab.msg.builtins import (
    DURATION, SCALARS, TIME, TIME_CLASS, TIME_STRUCT,
)
from rosfpga_lab.msg.errors import DeserializeError
from rosfpga_lab.msg.limits import DEFAULT_LIMITS, MsgLimits
from rosfpga_lab.msg.parser import Field, MsgSpec
from rosfpga_lab.msg.registry import MsgRegistry

_U32 = struct.Struct("<I")
_STR_ERRORS = "surrogateescape"

Decoder = Callable[[memoryview, int, MsgLimits], tuple[Any, int]]


# --------------------------------------------------------------------------- helpers
def _join(prefix: str, path: str) -> str:
    if not path:
        return prefix
    return f"{prefix}{path}" if path.startswith("[") else f"{prefix}.{path}"


def min_size(reg: MsgRegistry, type_name: str) -> int:
    """Smallest possible serialized size of ``type_name`` (empty strings and arrays)."""
    spec = reg.check(type_name)

    def build() -> int:
        total = 0
        for f in spec.fields:
            if f.is_array and f.array_length is None:
                total += 4
                continue
            count = f.array_length if f.array_length is not None else 1
            if f.base_type in SCALARS:
                total += count * SCALARS[f.base_type].size
            elif f.base_type in (TIME, DURATION):
                total += count * 8
            elif f.base_type == "string":
                total += count * 4
            else:
                total += count * min_size(reg, f.base_type)
        return total
    return reg.cached("min_size", spec.full_name, build)


def flat_fields(reg: MsgRegistry, type_name: str) -> tuple[list[str], list[str]] | None:
    """(names, types) if every field of the type is a non-array integer or float, else None.

    Arrays of such "flat" messages (Point32, Vector3, ColorRGBA ...) take a vectorized path.
    """
    spec = reg.check(type_name)

    def build() -> tuple[list[str], list[str]] | None:
        if not spec.fields or any(f.is_array or f.base_type not in SCALARS or f.base_type == "bool"
                                  for f in spec.fields):
            return None
        return spec.field_names, [f.base_type for f in spec.fields]
    return reg.cached("flat", spec.full_name, build)


# --------------------------------------------------------------------------- decoding
def _need(buf: memoryview, pos: int, size: int, path: str, what: str) -> None:
    if pos + size > len(buf):
        raise DeserializeError(
            f"message ends early: {what} at byte offset {pos} needs {size} byte(s), "
            f"only {len(buf) - pos} left (field {path})", path, pos)


def too_long(path: str, offset: int, n: int, elem_min: int, left: int,
             limit_name: str) -> DeserializeError:
    """The error for a length prefix declaring more than the bytes left."""
    if limit_name == "max_string_bytes":
        what = f"{n} byte(s)"
    else:
        what = f"{n} element(s) ({n * elem_min} byte(s) at least)"
    return DeserializeError(f"field {path}: length prefix at byte offset {offset} declares "
                            f"{what} but only {left} byte(s) are left", path, offset)


def _read_count(buf: memoryview, pos: int, path: str, elem_min: int, limit: int,
                limit_name: str) -> tuple[int, int]:
    """Read a uint32 length prefix and check it fits the bytes left and the limit."""
    _need(buf, pos, 4, path, "the uint32 length prefix")
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    if n > limit:
        raise DeserializeError(
            f"field {path}: length prefix at byte offset {pos - 4} declares {n}, more than "
            f"{limit_name}={limit} (raise it with deserialize(..., limits=MsgLimits(...)))",
            path, pos - 4)
    if n * elem_min > len(buf) - pos:
        raise too_long(path, pos - 4, n, elem_min, len(buf) - pos, limit_name)
    return n, pos


def _group_decoder(names: list[str], kinds: list[str]) -> Callable:
    fmt = "<" + "".join(TIME_STRUCT[k] if k in TIME_STRUCT else SCALARS[k].struct_char
                        for k in kinds)
    st = struct.Struct(fmt)
    simple = all(k not in TIME_STRUCT for k in kinds)

    def op(buf: memoryview, pos: int, out: dict, limits: MsgLimits) -> int:
        if pos + st.size > len(buf):
            off = pos
            for name, kind in zip(names, kinds):
                size = 8 if kind in TIME_STRUCT else SCALARS[kind].size
                _need(buf, off, size, name, kind)
                off += size
        vals = st.unpack_from(buf, pos)
        if simple:
            out.update(zip(names, vals))
        else:
            i = 0
            for name, kind in zip(names, kinds):
                if kind in TIME_CLASS:
                    out[name] = TIME_CLASS[kind](vals[i], vals[i + 1])
                    i += 2
                else:
                    out[name] = vals[i]
                    i += 1
        return pos + st.size
    return op


def _decode_string(buf: memoryview, pos: int, path: str, limits: MsgLimits) -> tuple[str, int]:
    n, pos = _read_count(buf, pos, path, 1, limits.max_string_bytes, "max_string_bytes")
    return str(buf[pos:pos + n], "utf-8", _STR_ERRORS), pos + n


# long: one branch per kind of field, each returning the closure the
# compiled decoder calls per message (the fast path: the kind is decided once, here); encode.py's
# _field_encoder is its mirror, branch for branch, so the two read side by side.
def _field_decoder(reg: MsgRegistry, f: Field) -> Callable:
    name, base, fixed = f.name, f.base_type, f.array_length
    if not f.is_array:
        if base == "string":
            def op(buf, pos, out, limits):
                out[name], pos = _decode_string(buf, pos, name, limits)
                return pos
            return op
        sub = compiled_decoder(reg, base)

        def op(buf, pos, out, limits):
            try:
                out[name], pos = sub(buf, pos, limits)
            except DeserializeError as exc:
                raise _prefixed(exc, name) from None
            return pos
        return op

    def count(buf, pos, limits, elem_min):
        if fixed is not None:
            _need(buf, pos, fixed * elem_min, name, f"{f.type} ({fixed} elements)")
            return fixed, pos
        return _read_count(buf, pos, name, elem_min, limits.max_array_length, "max_array_length")

    if base in SCALARS:
        dtype = SCALARS[base].dtype
        size = dtype.itemsize
        is_bool = base == "bool"

        def op(buf, pos, out, limits):
            n, pos = count(buf, pos, limits, size)
            arr = np.frombuffer(buf, dtype=dtype, count=n, offset=pos) if n else np.empty(0, dtype)
            if is_bool:
                arr = arr.astype(bool)
            arr.flags.writeable = False
            out[name] = arr
            return pos + n * size
        return op
    if base in TIME_STRUCT:
        cls, dt = TIME_CLASS[base], np.dtype("<u4" if base == TIME else "<i4")

        def op(buf, pos, out, limits):
            n, pos = count(buf, pos, limits, 8)
            pairs = np.frombuffer(buf, dtype=dt, count=2 * n, offset=pos).reshape(n, 2).tolist() \
                if n else []
            out[name] = [cls(s, ns) for s, ns in pairs]
            return pos + 8 * n
        return op
    if base == "string":
        def op(buf, pos, out, limits):
            n, pos = count(buf, pos, limits, 4)
            items = []
            for i in range(n):
                s, pos = _decode_string(buf, pos, f"{name}[{i}]", limits)
                items.append(s)
            out[name] = items
            return pos
        return op
    flat = flat_fields(reg, base)
    if flat is not None:
        names = flat[0]
        row = np.dtype([(n, SCALARS[k].dtype) for n, k in zip(*flat)])

        def op(buf, pos, out, limits):
            n, pos = count(buf, pos, limits, row.itemsize)
            rows = np.frombuffer(buf, dtype=row, count=n, offset=pos).tolist() if n else []
            out[name] = [dict(zip(names, r)) for r in rows]
            return pos + n * row.itemsize
        return op
    sub = compiled_decoder(reg, base)
    elem_min = min_size(reg, base)

    def op_elements(buf, pos, out, limits):
        n, pos = count(buf, pos, limits, elem_min)
        if elem_min == 0 and n > limits.max_empty_elements:
            # elements of zero bytes (e.g. std_msgs/Empty): the bytes left cannot bound n
            raise DeserializeError(
                f"field {name}: length prefix at byte offset {pos - 4} declares {n} elements of "
                f"{base} (0 bytes each), more than max_empty_elements={limits.max_empty_elements}",
                name, pos - 4)
        items = []
        try:
            for i in range(n):
                item, pos = sub(buf, pos, limits)
                items.append(item)
        except DeserializeError as exc:
            raise _prefixed(exc, f"{name}[{len(items)}]") from None
        out[name] = items
        return pos
    return op_elements


def _prefixed(exc: DeserializeError, prefix: str) -> DeserializeError:
    path = _join(prefix, exc.path)
    msg = str(exc).replace(f"(field {exc.path})", f"(field {path})") \
        .replace(f"field {exc.path}:", f"field {path}:")
    return DeserializeError(msg, path, exc.offset)


def _scalar_kind(f: Field) -> str | None:
    if f.is_array:
        return None
    if f.base_type in SCALARS or f.base_type in TIME_STRUCT:
        return f.base_type
    return None


def _build_ops(reg: MsgRegistry, spec: MsgSpec, group: Callable, single: Callable) -> list:
    ops: list = []
    run: list[Field] = []
    for f in spec.fields + (None,):
        if f is not None and _scalar_kind(f):
            run.append(f)
            continue
        if run:
            ops.append(group([r.name for r in run], [r.base_type for r in run]))
            run = []
        if f is not None:
            ops.append(single(reg, f))
    return ops


def compiled_decoder(reg: MsgRegistry, type_name: str) -> Decoder:
    """The cached decoder ``(buf, pos, limits) -> (dict, new_pos)`` of a type."""
    spec = reg.check(type_name)

    def build() -> Decoder:
        ops = _build_ops(reg, spec, _group_decoder, _field_decoder)

        def decode(buf: memoryview, pos: int, limits: MsgLimits) -> tuple[dict, int]:
            out: dict = {}
            for op in ops:
                pos = op(buf, pos, out, limits)
            return out, pos
        return decode
    return reg.cached("decoder", spec.full_name, build)


def _as_buffer(data: Any) -> memoryview:
    try:
        mv = memoryview(data)
    except TypeError:
        raise DeserializeError(f"expected bytes, bytearray or memoryview, got {type(data).__name__}") \
            from None
    if mv.ndim != 1 or mv.itemsize != 1:
        mv = mv.cast("B")
    return mv


def deserialize_partial(reg: MsgRegistry, type_name: str, data: Any, offset: int = 0,
                        limits: MsgLimits = DEFAULT_LIMITS) -> tuple[dict, int]:
    """Decode one message starting at ``offset``; return it and the offset just after it.

    Raises:
        DeserializeError: the bytes end early or declare more than is left or allowed.
        UnknownTypeError: the type (or a nested one) is not registered.
    """
    buf = _as_buffer(data)
    return compiled_decoder(reg, type_name)(buf, offset, limits)


def deserialize(reg: MsgRegistry, type_name: str, data: Any, *, allow_trailing: bool = False,
                limits: MsgLimits = DEFAULT_LIMITS) -> dict:
    """Decode a message body (without the 4-byte TCPROS frame length).

    Args:
        reg: the registry holding the type.
        type_name: e.g. ``sensor_msgs/Image``.
        data: bytes-like; ``uint8[]`` fields in the result are read-only views into it.
        allow_trailing: accept bytes after the message (they are ignored).
        limits: limits on declared lengths.

    Returns:
        The message as a dict (see the module docstring for value types).

    Raises:
        DeserializeError: truncated body, trailing bytes, or a length over the bytes left/limits.
        UnknownTypeError: the type (or a nested one) is not registered.
    """
    buf = _as_buffer(data)
    value, end = compiled_decoder(reg, type_name)(buf, 0, limits)
    if end != len(buf) and not allow_trailing:
        raise DeserializeError(
            f"{len(buf) - end} byte(s) left over after a complete {reg.resolve(type_name)} at "
            f"byte offset {end} (body is {len(buf)} bytes; pass allow_trailing=True to ignore)",
            "", end)
    return value


__all__ = ["compiled_decoder", "deserialize", "deserialize_partial", "min_size"]
