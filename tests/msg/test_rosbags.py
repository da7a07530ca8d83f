"""Second, independent reference that runs without ROS: the ``rosbags`` library.

rosbags (a pure-Python rosbag reader/writer with its own ROS 1 type store and codecs) was written
independently of genmsg/genpy and of this lab. Here it checks the md5 sum of every shipped type,
and the serialized bytes of hypothesis-generated values of every shipped type, both ways.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.msg import default_registry, deserialize, new_message, serialize
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.strategies import message, normalize

rosbags_typesys = pytest.importorskip("rosbags.typesys")
STORE = rosbags_typesys.get_typestore(rosbags_typesys.Stores.ROS1_NOETIC)
REG = default_registry()
SHIPPED = [t for t in REG.types() if t.split("/")[0] in ("std_msgs", "sensor_msgs", "geometry_msgs")]


def rb_name(type_name: str) -> str:
    pkg, name = type_name.split("/")
    return f"{pkg}/msg/{name}"


def to_rosbags(type_name: str, value: Any) -> Any:
    """A lab message value as a rosbags message object."""
    spec = REG.get(type_name)
    fields = {}
    for f in spec.fields:
        v = value[f.name]
        if f.is_array:
            if f.base_type in SCALARS:
                if isinstance(v, (bytes, bytearray, memoryview)):
                    v = np.frombuffer(bytes(v), np.uint8)
                v = np.asarray(v, dtype=SCALARS[f.base_type].dtype)
            else:
                v = [_element(f.base_type, x) for x in v]
        else:
            v = _element(f.base_type, v)
        fields[f.name] = v
    return STORE.types[rb_name(type_name)](**fields)


def _element(base: str, v: Any) -> Any:
    if base in ("time", "duration"):
        cls = STORE.types["builtin_interfaces/msg/Time" if base == "time"
                          else "builtin_interfaces/msg/Duration"]
        # rosbags packs (sec, nanosec) as (int32, uint32), ROS 2's builtin_interfaces, for both
        # ROS 1 time (uint32, uint32) and duration (int32, int32): hand it the same 32 bits.
        sec, nsec = int(v[0]) % 2**32, int(v[1]) % 2**32
        return cls(sec=sec - 2**32 if sec >= 2**31 else sec, nanosec=nsec)
    if base in SCALARS or base == "string":
        return v
    return to_rosbags(base, v)


def test_rosbags_knows_the_same_types() -> None:
    theirs = sorted(t.replace("/msg/", "/") for t in STORE.types
                    if t.split("/")[0] in ("std_msgs", "sensor_msgs", "geometry_msgs"))
    assert theirs == SHIPPED


@pytest.mark.parametrize("type_name", SHIPPED)
def test_md5_matches_rosbags(type_name: str) -> None:
    _text, md5 = STORE.generate_msgdef(rb_name(type_name), ros_version=1)
    assert REG.md5(type_name) == md5


@pytest.mark.parametrize("type_name", SHIPPED)
@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_bytes_match_rosbags(type_name: str, data: st.DataObject) -> None:
    value = data.draw(message(REG, type_name))
    ours = serialize(REG, type_name, value)
    theirs = bytes(STORE.serialize_ros1(to_rosbags(type_name, value), rb_name(type_name)))
    assert ours == theirs
    back = STORE.deserialize_ros1(ours, rb_name(type_name))  # rosbags reads our bytes
    assert bytes(STORE.serialize_ros1(back, rb_name(type_name))) == ours


def test_image_640x480_rgba8_matches_rosbags() -> None:
    pixels = np.random.default_rng(7).integers(0, 256, 640 * 480 * 4, dtype=np.uint8)
    value = new_message(REG, "sensor_msgs/Image", header={"seq": 9, "stamp": (1, 2), "frame_id": "cam"},
                        height=480, width=640, encoding="rgba8", step=2560, data=pixels)
    ours = serialize(REG, "sensor_msgs/Image", value)
    theirs = bytes(STORE.serialize_ros1(to_rosbags("sensor_msgs/Image", value), "sensor_msgs/msg/Image"))
    assert ours == theirs
    out = deserialize(REG, "sensor_msgs/Image", theirs)
    assert normalize(REG, "std_msgs/Header", out["header"]) == {
        "seq": 9, "stamp": (1, 2), "frame_id": "cam"}
    assert np.array_equal(out["data"], pixels)
