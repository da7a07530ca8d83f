"""The CDR codec (ROS 2 wire format) against rosbags' own CDR serializer, byte for byte.

rosbags (in the [test] extra) carries ROS 2 Humble's type store and a CDR serializer written
independently of this lab: the ROS 2 forms the lab derives from its ROS 1 types must be the
types rosbags knows, and every shipped type's bytes must equal rosbags' on hypothesis values.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.msg import DeserializeError, SerializeError, default_registry, new_message
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.cdr import (
    CDR_LE, ROLE_ENCAPSULATION, ROLE_PADDING, cdr_layout, deserialize_cdr, serialize_cdr,
)
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.ros2 import NOT_IN_ROS2, ros2_registry, to_ros2_value
from rosfpga_lab.msg.strategies import message, normalize

rosbags_typesys = pytest.importorskip("rosbags.typesys")
STORE = rosbags_typesys.get_typestore(rosbags_typesys.Stores.ROS2_HUMBLE)
REG1 = default_registry()
REG2 = ros2_registry()
PACKAGES = ("std_msgs", "sensor_msgs", "geometry_msgs", "builtin_interfaces")
SHIPPED = [t for t in REG2.types() if t.split("/")[0] in PACKAGES]


def rb_name(type_name: str) -> str:
    pkg, name = type_name.split("/")
    return f"{pkg}/msg/{name}"


def to_rosbags(type_name: str, value: Any) -> Any:
    """A lab ROS 2 value as a rosbags message object."""
    spec = REG2.get(type_name)
    fields = {}
    for f in spec.fields:
        v = value[f.name]
        if f.is_array and f.base_type in SCALARS:
            if isinstance(v, (bytes, bytearray, memoryview)):
                v = np.frombuffer(bytes(v), np.uint8)
            v = np.asarray(v, dtype=SCALARS[f.base_type].dtype)
        elif f.is_array and f.base_type != "string":
            v = [to_rosbags(f.base_type, x) for x in v]
        elif not f.is_array and not f.is_builtin:
            v = to_rosbags(f.base_type, v)
        fields[f.name] = v
    return STORE.types[rb_name(type_name)](**fields)


def test_ros2_forms_are_the_types_rosbags_knows() -> None:
    theirs = sorted(t.replace("/msg/", "/") for t in STORE.types if t.split("/")[0] in PACKAGES)
    assert theirs == SHIPPED
    for name in NOT_IN_ROS2:
        assert name in REG1 and name not in REG2


@pytest.mark.parametrize("type_name", SHIPPED)
def test_field_names_match_rosbags(type_name: str) -> None:
    # rosidl gives a message without fields a placeholder byte: the lab sends the same byte.
    theirs = [name for name, _ in STORE.fielddefs[rb_name(type_name)][1]
              if name != "structure_needs_at_least_one_member"]
    assert [f.name for f in REG2.get(type_name).fields] == theirs


@pytest.mark.parametrize("type_name", SHIPPED)
@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_cdr_bytes_match_rosbags(type_name: str, data: st.DataObject) -> None:
    value = data.draw(message(REG2, type_name))
    ours = serialize_cdr(REG2, type_name, value)
    theirs = bytes(STORE.serialize_cdr(to_rosbags(type_name, value), rb_name(type_name)))
    assert ours == theirs
    assert normalize(REG2, type_name, deserialize_cdr(REG2, type_name, ours)) == \
        normalize(REG2, type_name, value)
    spans = cdr_layout(REG2, type_name, ours, element_spans=2)
    assert [s.offset for s in spans] == sorted(s.offset for s in spans)
    assert sum(s.size for s in spans) == len(ours)
    assert all(a.end == b.offset for a, b in zip(spans, spans[1:]))
    for s in spans:
        if s.role == ROLE_PADDING and s.type == "padding":
            assert s.value == bytes(s.size) and 0 < s.size < 8


def test_header_golden_bytes_with_padding() -> None:
    # Encapsulation 00 01 00 00; sec=1 (int32), nanosec=2 (uint32); frame_id "ab": length 3
    # counts the NUL. No padding: every field falls on its alignment.
    value = {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "ab"}
    assert serialize_cdr(REG2, "std_msgs/Header", value).hex(" ") == \
        "00 01 00 00 01 00 00 00 02 00 00 00 03 00 00 00 61 62 00"


def test_image_padding_before_step_and_data_count() -> None:
    img = new_message(REG1, "sensor_msgs/Image", header={"seq": 5, "stamp": (1, 2), "frame_id": "cam"},
                      height=2, width=2, encoding="mono8", is_bigendian=0, step=2,
                      data=bytes([1, 2, 3, 4]))
    payload = serialize_cdr(None, "sensor_msgs/Image", to_ros2_value(REG1, "sensor_msgs/Image", img))
    theirs = bytes(STORE.serialize_cdr(to_rosbags("sensor_msgs/Image", to_ros2_value(
        REG1, "sensor_msgs/Image", img)), "sensor_msgs/msg/Image"))
    assert payload == theirs
    spans = cdr_layout(None, "sensor_msgs/Image", payload, element_spans=2)
    assert spans[0].role == ROLE_ENCAPSULATION and payload[:4] == CDR_LE
    pads = [(s.path, s.offset, s.size) for s in spans if s.role == ROLE_PADDING]
    # Body offsets (after the 4-byte header): stamp 0-7, frame_id 8-15 ("cam\0"), height,
    # width 16-23, encoding 24-33 ("mono8\0"), is_bigendian 34, so step (uint32) needs one
    # padding byte at 35: payload offset 39.
    assert pads == [("step", 39, 1)]
    data = next(s for s in spans if s.path == "data" and s.role != "length")
    assert bytes(payload[data.offset:data.end]) == bytes([1, 2, 3, 4])


def test_empty_message_is_one_byte() -> None:
    assert serialize_cdr(None, "std_msgs/Empty", {}) == CDR_LE + b"\x00"
    assert deserialize_cdr(None, "std_msgs/Empty", CDR_LE + b"\x00") == {}


def test_a_message_of_zero_length_arrays_is_zero_bytes_and_reads_back() -> None:
    """A message whose only field is a zero-length fixed array is no bytes in CDR (it has a
    field, so no placeholder byte); an array of such messages has a count and nothing else.
    The reader held each element to 1 byte at least and refused what the writer wrote (found
    by hypothesis)."""
    reg = MsgRegistry.with_defaults()
    reg.add("h_msgs/T1", "time[0] f0\n")
    reg.add("h_msgs/T0", "uint8[] data\nh_msgs/T1[] f3\n")
    value = {"data": b"", "f3": [{"f0": []}]}
    wire = serialize_cdr(reg, "h_msgs/T0", value)
    assert wire == CDR_LE + b"\x00" * 4 + b"\x01\x00\x00\x00"
    back = deserialize_cdr(reg, "h_msgs/T0", wire)
    assert len(back["f3"]) == 1 and list(back["f3"][0]["f0"]) == []
    with pytest.raises(DeserializeError):   # a count of 2 with one element's bytes missing
        deserialize_cdr(reg, "h_msgs/T0", CDR_LE + b"\x00" * 4 + b"\x02\x00\x00")


def test_truncated_payloads_raise_typed_errors() -> None:
    value = {"layout": {"dim": [{"label": "x", "size": 3, "stride": 3}], "data_offset": 0},
             "data": [1.5, 2.5, 3.5]}
    payload = serialize_cdr(None, "std_msgs/Float64MultiArray", value)
    for n in range(len(payload)):
        with pytest.raises(DeserializeError):
            deserialize_cdr(None, "std_msgs/Float64MultiArray", payload[:n])
        spans = cdr_layout(None, "std_msgs/Float64MultiArray", payload[:n], partial=True)
        assert spans[-1].role == "error" and spans[-1].end == n
    with pytest.raises(DeserializeError, match="left over"):
        deserialize_cdr(None, "std_msgs/Float64MultiArray", payload + b"\x00")
    back = deserialize_cdr(None, "std_msgs/Float64MultiArray", payload + b"\x07", allow_trailing=True)
    assert back["data"].tolist() == [1.5, 2.5, 3.5]


def test_bad_encapsulation_and_lengths() -> None:
    with pytest.raises(DeserializeError, match="big-endian"):
        deserialize_cdr(None, "std_msgs/String", b"\x00\x00\x00\x00\x00\x00\x00\x01a")
    with pytest.raises(DeserializeError, match="NUL"):
        deserialize_cdr(None, "std_msgs/String", CDR_LE + b"\x01\x00\x00\x00a")
    with pytest.raises(DeserializeError, match="least is 1"):
        deserialize_cdr(None, "std_msgs/String", CDR_LE + b"\x00\x00\x00\x00")
    with pytest.raises(DeserializeError):
        deserialize_cdr(None, "std_msgs/String", CDR_LE + b"\xff\xff\xff\x7f")
    with pytest.raises(SerializeError, match="int32"):
        serialize_cdr(None, "builtin_interfaces/Time", {"sec": 2**31, "nanosec": 0})
    with pytest.raises(SerializeError, match="ROS 1 time"):
        serialize_cdr(REG1, "std_msgs/Header", {"seq": 1, "stamp": (0, 0), "frame_id": ""})


def test_to_ros2_value_drops_seq_and_maps_time() -> None:
    value = to_ros2_value(REG1, "std_msgs/Header", {"seq": 3, "stamp": (7, 8), "frame_id": "f"})
    assert value == {"stamp": {"sec": 7, "nanosec": 8}, "frame_id": "f"}
    with pytest.raises(Exception, match="no ROS 2 form"):
        to_ros2_value(REG1, "std_msgs/Time", {"data": (0, 0)})


def test_image_640x480_rgba8_matches_rosbags() -> None:
    pixels = np.random.default_rng(7).integers(0, 256, 640 * 480 * 4, dtype=np.uint8)
    ros1 = new_message(REG1, "sensor_msgs/Image", header={"seq": 9, "stamp": (1, 2), "frame_id": "cam"},
                       height=480, width=640, encoding="rgba8", step=2560, data=pixels)
    value = to_ros2_value(REG1, "sensor_msgs/Image", ros1)
    ours = serialize_cdr(None, "sensor_msgs/Image", value)
    assert ours == bytes(STORE.serialize_cdr(to_rosbags("sensor_msgs/Image", value), "sensor_msgs/msg/Image"))
    assert np.array_equal(deserialize_cdr(None, "sensor_msgs/Image", ours)["data"], pixels)
