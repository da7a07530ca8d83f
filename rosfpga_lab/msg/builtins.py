"""ROS 1 builtin field types: names, wire formats, numpy dtypes, and the Time/Duration values.

Every builtin is little-endian on the wire (TCPROS). ``byte`` and ``char`` are the deprecated
aliases genmsg keeps: ``byte`` is a signed 8-bit integer, ``char`` an unsigned one.
``time`` is two ``uint32`` (secs, nsecs) and ``duration`` two ``int32``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

HEADER = "Header"
HEADER_FULL_NAME = "std_msgs/Header"
TIME = "time"
DURATION = "duration"

#: Types allowed in constants (genmsg's PRIMITIVE_TYPES), in genmsg's order.
PRIMITIVE_TYPES: tuple[str, ...] = (
    "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
    "float32", "float64", "string", "bool", "char", "byte",
)
#: Every builtin field type (genmsg's BUILTIN_TYPES).
BUILTIN_TYPES: tuple[str, ...] = PRIMITIVE_TYPES + (TIME, DURATION)


class Scalar(NamedTuple):
    """Wire format of one fixed-size scalar builtin."""

    struct_char: str   # for struct, without byte order
    dtype: np.dtype    # little-endian numpy dtype
    size: int


_S = {
    "bool": ("?", "u1"), "int8": ("b", "i1"), "byte": ("b", "i1"),
    "uint8": ("B", "u1"), "char": ("B", "u1"),
    "int16": ("h", "<i2"), "uint16": ("H", "<u2"),
    "int32": ("i", "<i4"), "uint32": ("I", "<u4"),
    "int64": ("q", "<i8"), "uint64": ("Q", "<u8"),
    "float32": ("f", "<f4"), "float64": ("d", "<f8"),
}
#: Scalar numeric builtins (and bool): struct char, dtype, size.
SCALARS: dict[str, Scalar] = {
    name: Scalar(ch, np.dtype(dt), np.dtype(dt).itemsize) for name, (ch, dt) in _S.items()
}
#: Builtins whose arrays are carried as raw bytes (numpy uint8 views).
BYTE_ARRAY_TYPES = frozenset({"uint8", "char"})
FLOAT_TYPES = frozenset({"float32", "float64"})


def is_builtin(type_name: str) -> bool:
    """True if ``type_name`` (without array suffix) is a builtin type."""
    return type_name in BUILTIN_TYPES


def integer_bounds(type_name: str) -> tuple[int, int]:
    """Inclusive (low, high) range of an integer builtin, as genmsg checks constants."""
    info = np.iinfo(SCALARS[type_name].dtype)
    return int(info.min), int(info.max)


class Time(NamedTuple):
    """A ROS ``time``: unsigned seconds and nanoseconds since the epoch."""

    secs: int = 0
    nsecs: int = 0

    @classmethod
    def from_sec(cls, seconds: float) -> "Time":
        """Build from floating-point seconds (nanoseconds rounded)."""
        total = int(round(seconds * 1e9))
        return cls(total // 1_000_000_000, total % 1_000_000_000)

    def to_sec(self) -> float:
        """Floating-point seconds."""
        return self.secs + self.nsecs * 1e-9

    def to_nsec(self) -> int:
        """Integer nanoseconds."""
        return self.secs * 1_000_000_000 + self.nsecs


class Duration(NamedTuple):
    """A ROS ``duration``: signed seconds and nanoseconds."""

    secs: int = 0
    nsecs: int = 0

    @classmethod
    def from_sec(cls, seconds: float) -> "Duration":
        """Build from floating-point seconds (nanoseconds rounded, nsecs kept in [0, 1e9))."""
        total = int(round(seconds * 1e9))
        return cls(total // 1_000_000_000, total % 1_000_000_000)

    def to_sec(self) -> float:
        """Floating-point seconds."""
        return self.secs + self.nsecs * 1e-9

    def to_nsec(self) -> int:
        """Integer nanoseconds."""
        return self.secs * 1_000_000_000 + self.nsecs


#: struct chars of (secs, nsecs) for time and duration.
TIME_STRUCT = {TIME: "II", DURATION: "ii"}
TIME_CLASS = {TIME: Time, DURATION: Duration}
