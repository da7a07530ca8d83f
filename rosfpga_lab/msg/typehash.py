"""The ROS 2 type hash (REP-2011, ``RIHS01_<64 hex>``) of any message type the lab can load.

How this works: since Iron, ROS 2 names a message type's structure by a hash that every
endpoint announces (rmw puts ``typehash=RIHS01_...;`` in its USER_DATA QoS). rosidl computes
it (``rosidl_generator_type_description``) from the *type description* of the ROS 2 form of the
type (:mod:`rosfpga_lab.msg.ros2`: ``builtin_interfaces/Time``, no ``Header.seq``):

* an individual description per type: ``{"type_name": "pkg/msg/Name", "fields": [...]}``, the
  fields in declaration order, each ``{"name", "type": {"type_id", "capacity",
  "string_capacity", "nested_type_name"}}``; constants are not part of it, and a message
  without fields has rosidl's ``uint8 structure_needs_at_least_one_member``;
* ``type_id`` is type_description_interfaces/FieldType's id: the element type's id
  (:data:`FIELD_TYPE_IDS`, 1 for a nested message), plus :data:`ARRAY_OFFSET` for ``T[N]``
  (``capacity`` N) or :data:`UNBOUNDED_SEQUENCE_OFFSET` for ``T[]``;
* the full description: the type's own, then every type it references (transitively) sorted
  by name; the hash is the SHA-256 of its JSON text with ``", "`` and ``": "`` separators and
  the keys in the order above. Field default values are left out of the hash (ROS 1 has none).

:func:`type_description` gives the description (as the ``type_description_msg`` of the JSON
files rosidl installs), :func:`hashed_text` the exact text hashed, :func:`type_hash` the hash.
"""

from __future__ import annotations

import hashlib
import json
import re
from typing import Any

from rosfpga_lab.msg.builtins import BUILTIN_TYPES
from rosfpga_lab.msg.errors import UnknownTypeError
from rosfpga_lab.msg.parser import SEP, Field, MsgSpec
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.ros2 import PLACEHOLDER_MEMBER, PLACEHOLDER_TYPE, ros2_registry

#: Version prefix of the hashes this module computes (REP-2011 hashing standard 01).
RIHS01_PREFIX = "RIHS01_"
#: A type hash string of any RIHS version (two hex digits) and its 32-byte value.
RIHS_PATTERN = re.compile(r"RIHS([0-9a-f]{2})_([0-9a-f]{64})")
#: The interface kind between package and name in a ROS 2 type name (``pkg/msg/Name``).
MSG_NAMESPACE = "msg"

#: type_description_interfaces/FieldType ids of the element types a ``.msg`` names. rosidl reads
#: ``char`` as ``uint8`` and ``byte`` as ``octet`` (FIELD_TYPE_BYTE); ``time``/``duration`` have no
#: id: their ROS 2 forms are the nested messages builtin_interfaces/Time and Duration.
FIELD_TYPE_IDS: dict[str, int] = {
    "int8": 2, "uint8": 3, "char": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7,
    "int64": 8, "uint64": 9, "float32": 10, "float64": 11, "bool": 15, "byte": 16, "string": 17,
}
#: FieldType id of a nested message (FIELD_TYPE_NESTED_TYPE).
NESTED_TYPE_ID = 1
#: Added to the element's id for a fixed-size array ``T[N]`` (FIELD_TYPE_*_ARRAY).
ARRAY_OFFSET = 48
#: Added for a bounded sequence ``T[<=N]`` (FIELD_TYPE_*_BOUNDED_SEQUENCE; no ROS 1 form).
BOUNDED_SEQUENCE_OFFSET = 96
#: Added for a sequence ``T[]`` (FIELD_TYPE_*_UNBOUNDED_SEQUENCE).
UNBOUNDED_SEQUENCE_OFFSET = 144
#: json.dumps separators of rosidl's hashed text (libyaml's, which C cannot change).
JSON_SEPARATORS = (", ", ": ")


def ros2_type_name(type_name: str) -> str:
    """``sensor_msgs/Image`` (or ``sensor_msgs/msg/Image``) -> ``sensor_msgs/msg/Image``."""
    parts = type_name.split(SEP)
    if len(parts) == 3 and parts[1] == MSG_NAMESPACE:
        return type_name
    if len(parts) != 2:
        raise UnknownTypeError(f"{type_name!r} is not a message type name (use pkg/Name or "
                               f"pkg/msg/Name)", type_name)
    return f"{parts[0]}{SEP}{MSG_NAMESPACE}{SEP}{parts[1]}"


def lab_type_name(type_name: str) -> str:
    """``sensor_msgs/msg/Image`` -> ``sensor_msgs/Image`` (the registry's name)."""
    parts = type_name.split(SEP)
    return f"{parts[0]}{SEP}{parts[2]}" if len(parts) == 3 and parts[1] == MSG_NAMESPACE \
        else type_name


def field_type(f: Field) -> dict[str, Any]:
    """The FieldType of one field of a ROS 2 form (as rosidl serializes it)."""
    if f.base_type in FIELD_TYPE_IDS:
        element, nested = FIELD_TYPE_IDS[f.base_type], ""
    elif f.base_type in BUILTIN_TYPES:
        raise UnknownTypeError(f"field {f.name}: ROS 1 {f.base_type} has no ROS 2 type id; hash "
                               f"the ROS 2 form (ros2_registry(): builtin_interfaces/Time)",
                               f.base_type)
    else:
        element, nested = NESTED_TYPE_ID, ros2_type_name(f.base_type)
    if not f.is_array:
        type_id, capacity = element, 0
    elif f.array_length is not None:
        type_id, capacity = element + ARRAY_OFFSET, f.array_length
    else:
        type_id, capacity = element + UNBOUNDED_SEQUENCE_OFFSET, 0
    return {"type_id": type_id, "capacity": capacity, "string_capacity": 0,
            "nested_type_name": nested}


def individual_description(spec: MsgSpec) -> dict[str, Any]:
    """The IndividualTypeDescription of one ROS 2 form (default values empty, as ROS 1 has none)."""
    fields = [{"name": f.name, "type": field_type(f), "default_value": ""} for f in spec.fields]
    if not fields:
        placeholder = Field(PLACEHOLDER_MEMBER, PLACEHOLDER_TYPE, PLACEHOLDER_TYPE)
        fields = [{"name": placeholder.name, "type": field_type(placeholder), "default_value": ""}]
    return {"type_name": ros2_type_name(spec.full_name), "fields": fields}


def _ros2(reg: MsgRegistry | None) -> MsgRegistry:
    if reg is None:
        return ros2_registry()
    return reg.cached("ros2-form", "", lambda: ros2_registry(reg))


def type_description(type_name: str, reg: MsgRegistry | None = None) -> dict[str, Any]:
    """The full TypeDescription of ``type_name``'s ROS 2 form: ``{"type_description": ...,
    "referenced_type_descriptions": [...]}`` (the references sorted by name).

    Args:
        type_name: ``pkg/Name`` or ``pkg/msg/Name``.
        reg: a registry of ROS 1 definitions (default: the shipped types); its ROS 2 forms are
            used (:func:`rosfpga_lab.msg.ros2.ros2_registry`).

    Raises:
        UnknownTypeError: the type or one it uses is not in ``reg`` or has no ROS 2 form.
    """
    return _description(_ros2(reg), type_name)


def _description(r2: MsgRegistry, type_name: str) -> dict[str, Any]:
    spec = r2.check(lab_type_name(type_name))
    refs = {dep: individual_description(r2.get(dep)) for dep in r2.dependencies(spec.full_name)}
    return {"type_description": individual_description(spec),
            "referenced_type_descriptions": [refs[d] for d in sorted(refs, key=ros2_type_name)]}


def hashed_text(type_name: str, reg: MsgRegistry | None = None) -> str:
    """The exact JSON text whose SHA-256 is the type hash (default values removed)."""
    return _hashed_text(_ros2(reg), type_name)


def _hashed_text(r2: MsgRegistry, type_name: str) -> str:
    desc = _description(r2, type_name)
    for td in [desc["type_description"], *desc["referenced_type_descriptions"]]:
        for f in td["fields"]:
            del f["default_value"]
    return json.dumps(desc, ensure_ascii=True, allow_nan=False, indent=None,
                      separators=JSON_SEPARATORS, sort_keys=False)


def type_hash(type_name: str, reg: MsgRegistry | None = None) -> str:
    """The RIHS01 type hash of ``type_name``'s ROS 2 form, e.g. ``RIHS01_f49fb3ae...``.

    Cached in ``reg`` (or in the shared ROS 2 registry) until a definition changes.

    Raises:
        UnknownTypeError: the type or one it uses is not in ``reg`` or has no ROS 2 form.
    """
    r2 = _ros2(reg)
    name = r2.check(lab_type_name(type_name)).full_name
    return r2.cached(
        "rihs01", name, lambda: RIHS01_PREFIX + hashlib.sha256(
            _hashed_text(r2, name).encode("utf-8")).hexdigest())
