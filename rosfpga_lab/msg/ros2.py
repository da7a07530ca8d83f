"""ROS 2 forms of the shipped ROS 1 types: the one place the ROS 1 -> ROS 2 mapping is written.

How this works: ROS 2 kept the ``.msg`` language and the shipped packages almost unchanged; the
differences that reach the wire are few and all listed here. ``time``/``duration`` became the
messages ``builtin_interfaces/Time``/``Duration`` (``int32 sec, uint32 nanosec``);
``std_msgs/Header`` lost its ``seq``; ``CameraInfo``'s ``D K R P`` became lower case;
``std_msgs/Time`` and ``std_msgs/Duration`` are gone.
:func:`ros2_registry` applies these rules to a ROS 1 registry and returns a registry of ROS 2
forms (same type names) that the CDR codec (:mod:`rosfpga_lab.msg.cdr`) reads, and
:func:`to_ros2_value` turns a ROS 1 value (what ``deserialize`` returns) into its ROS 2 form, so
the same image can be put on both wires.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

from rosfpga_lab.msg.builtins import DURATION, HEADER_FULL_NAME, TIME
from rosfpga_lab.msg.encode import time_parts
from rosfpga_lab.msg.errors import UnknownTypeError
from rosfpga_lab.msg.parser import Field
from rosfpga_lab.msg.registry import MsgRegistry, default_registry

#: ROS 1 builtin -> the ROS 2 message that replaced it.
TIME_MESSAGES: dict[str, str] = {
    TIME: "builtin_interfaces/Time",
    DURATION: "builtin_interfaces/Duration",
}
#: Definitions of those ROS 2 messages (rcl_interfaces' builtin_interfaces package).
BUILTIN_INTERFACES: dict[str, str] = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n",
}
#: Fields ROS 2 removed from a shipped type.
DROPPED_FIELDS: dict[str, tuple[str, ...]] = {HEADER_FULL_NAME: ("seq",)}
#: Fields ROS 2 renamed (its field names are lower case).
RENAMED_FIELDS: dict[str, dict[str, str]] = {
    "sensor_msgs/CameraInfo": {"D": "d", "K": "k", "R": "r", "P": "p"},
}
#: Shipped ROS 1 types that have no ROS 2 form.
NOT_IN_ROS2: tuple[str, ...] = ("std_msgs/Time", "std_msgs/Duration")
#: The member rosidl gives a message without fields (its type and name): CDR sends it as one
#: zero byte and the type description lists it.
PLACEHOLDER_TYPE, PLACEHOLDER_MEMBER = "uint8", "structure_needs_at_least_one_member"
#: ROS 1 time value fields -> ROS 2 Time/Duration fields.
TIME_FIELDS = ("sec", "nanosec")


def _ros2_type(f: Field) -> str:
    base = TIME_MESSAGES.get(f.base_type, f.base_type)
    return base + f.type[len(f.base_type):]


def ros2_registry(reg: MsgRegistry | None = None) -> MsgRegistry:
    """A registry of the ROS 2 forms of every type of ``reg`` (default: the shipped types).

    Types listed in :data:`NOT_IN_ROS2` are left out; ``builtin_interfaces`` is added.
    The default registry's ROS 2 form is built once and shared (read-only).
    """
    if reg is None:
        return _default_ros2()
    out = MsgRegistry()
    for name, text in BUILTIN_INTERFACES.items():
        out.add(name, text, source="<rosfpga_lab.msg.ros2>")
    for name in reg.types():
        if name in NOT_IN_ROS2:
            continue
        spec = reg.get(name)
        dropped = DROPPED_FIELDS.get(name, ())
        renamed = RENAMED_FIELDS.get(name, {})
        lines = [f"{c.type} {c.name}={c.value_text}" for c in spec.constants]
        lines += [f"{_ros2_type(f)} {renamed.get(f.name, f.name)}" for f in spec.fields
                  if f.name not in dropped]
        out.add(name, "\n".join(lines) + "\n", source=f"ROS 2 form of {spec.source or name}")
    return out


@functools.cache
def _default_ros2() -> MsgRegistry:
    return ros2_registry(default_registry()).freeze()


def to_ros2_value(reg: MsgRegistry, type_name: str, value: Any) -> dict:
    """The ROS 2 form of a ROS 1 message value of ``type_name`` (a dict, as ``deserialize`` gives).

    Times become ``{"sec", "nanosec"}`` dicts, dropped fields are removed, renamed fields
    renamed; arrays are passed on
    as they are (no copy).

    Raises:
        UnknownTypeError: the type has no ROS 2 form.
    """
    spec = reg.check(type_name)
    if spec.full_name in NOT_IN_ROS2:
        raise UnknownTypeError(f"{spec.full_name} has no ROS 2 form (ROS 2 removed it)",
                               spec.full_name)
    dropped = DROPPED_FIELDS.get(spec.full_name, ())
    renamed = RENAMED_FIELDS.get(spec.full_name, {})
    get = value.__getitem__ if isinstance(value, Mapping) else functools.partial(getattr, value)
    out = {}
    for f in spec.fields:
        if f.name in dropped:
            continue
        v = get(f.name)
        if f.base_type in TIME_MESSAGES:
            v = ([_time(x, f.base_type) for x in v] if f.is_array else _time(v, f.base_type))
        elif not f.is_builtin:
            v = ([to_ros2_value(reg, f.base_type, x) for x in v] if f.is_array
                 else to_ros2_value(reg, f.base_type, v))
        out[renamed.get(f.name, f.name)] = v
    return out


def _time(value: Any, kind: str) -> dict:
    secs, nsecs = time_parts(value, kind)
    return dict(zip(TIME_FIELDS, (secs, nsecs)))
