"""Wire codecs: properties over every shipped type, decoders fed whole/truncated/with trailing
bytes, the fast decoder against the plain reference model, field layouts, and error tables."""

from __future__ import annotations

import struct
import tracemalloc
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.msg import (
    DeserializeError, MsgLimits, MsgRegistry, SerializeError, Time, default_registry,
    deserialize, deserialize_partial, deserialize_reference, field_layout, min_size,
    new_message, serialize,
)
from rosfpga_lab.msg.strategies import message, normalize

REG = default_registry()
ALL_TYPES = REG.types()
PROPERTY = settings(max_examples=15, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def check_layout(type_name: str, body: bytes) -> None:
    spans = field_layout(REG, type_name, body, element_spans=4)
    pos = 0
    for span in spans:  # every byte in exactly one span, in order
        assert span.offset == pos and span.size > 0, span
        pos = span.end
    assert pos == len(body)


@pytest.mark.parametrize("type_name", ALL_TYPES)
@PROPERTY
@given(data=st.data())
def test_roundtrip_every_type(type_name: str, data: st.DataObject) -> None:
    value = data.draw(message(REG, type_name))
    body = serialize(REG, type_name, value)
    assert len(body) >= min_size(REG, type_name)
    out = deserialize(REG, type_name, body)
    assert normalize(REG, type_name, out) == normalize(REG, type_name, value)
    assert serialize(REG, type_name, out) == body
    # the plain reference model decodes to the same values
    ref = deserialize_reference(REG, type_name, body)
    assert normalize(REG, type_name, ref) == normalize(REG, type_name, out)
    check_layout(type_name, body)


TRUNCATION_TYPES = ["sensor_msgs/Image", "sensor_msgs/PointCloud2", "sensor_msgs/JointState",
                    "geometry_msgs/PolygonStamped", "std_msgs/Float64MultiArray",
                    "sensor_msgs/CameraInfo", "sensor_msgs/MultiDOFJointState"]


@pytest.mark.parametrize("type_name", TRUNCATION_TYPES)
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_every_truncation_and_trailing_byte_is_an_error(type_name: str, data: st.DataObject) -> None:
    body = serialize(REG, type_name, data.draw(message(REG, type_name)))
    for cut in range(len(body)):  # fed byte by byte: every strict prefix is refused
        with pytest.raises(DeserializeError) as info:
            deserialize(REG, type_name, body[:cut])
        assert info.value.offset <= cut
        with pytest.raises(DeserializeError):
            field_layout(REG, type_name, body[:cut])
        spans = field_layout(REG, type_name, body[:cut], partial=True)
        assert spans[-1].role == "error" and spans[-1].end == cut
        assert [s.offset for s in spans] == [0] + [s.end for s in spans[:-1]]
    with pytest.raises(DeserializeError, match="left over"):
        deserialize(REG, type_name, body + b"\x00")
    value, end = deserialize_partial(REG, type_name, body + body, offset=0)
    assert end == len(body)
    second, end2 = deserialize_partial(REG, type_name, body + body, offset=end)
    assert end2 == 2 * len(body)
    assert normalize(REG, type_name, second) == normalize(REG, type_name, value)


def test_partial_layout_marks_the_rest() -> None:
    body = serialize(REG, "std_msgs/String", {"data": "hello"})
    spans = field_layout(REG, "std_msgs/String", body[:6], partial=True)
    assert [(s.role, s.offset, s.size) for s in spans] == [("length", 0, 4), ("error", 4, 2)]
    assert "declares 5 byte(s)" in spans[-1].value
    spans = field_layout(REG, "std_msgs/String", body + b"xy", partial=True)
    s = spans[-1]
    assert (s.offset, s.size, s.type, s.value, s.role) == (9, 2, "uint8[]", b"xy", "trailing")


def test_layout_paths_of_message_arrays() -> None:
    value = new_message(REG, "geometry_msgs/Polygon",
                        points=[{"x": 1.0, "y": 2.0, "z": 3.0}, {"x": 4.0, "y": 5.0, "z": 6.0}])
    spans = field_layout(REG, "geometry_msgs/Polygon", serialize(REG, "geometry_msgs/Polygon", value))
    assert [(s.path, s.offset, s.size, s.type, s.value, s.role) for s in spans] == [
        ("points", 0, 4, "uint32", 2, "length"),
        ("points[0].x", 4, 4, "float32", 1.0, "value"),
        ("points[0].y", 8, 4, "float32", 2.0, "value"),
        ("points[0].z", 12, 4, "float32", 3.0, "value"),
        ("points[1].x", 16, 4, "float32", 4.0, "value"),
        ("points[1].y", 20, 4, "float32", 5.0, "value"),
        ("points[1].z", 24, 4, "float32", 6.0, "value"),
    ]


def test_layout_array_blocks() -> None:
    value = new_message(REG, "sensor_msgs/CameraInfo", D=[0.5] * 5)
    spans = field_layout(REG, "sensor_msgs/CameraInfo", serialize(REG, "sensor_msgs/CameraInfo", value),
                         element_spans=4)
    by_path = {s.path: s for s in spans if s.role != "length"}
    assert by_path["D"].role == "array" and by_path["D"].size == 40 and by_path["D"].type == "float64[]"
    assert by_path["K"].size == 72  # float64[9] has no length prefix
    assert not any(s.path == "K" and s.role == "length" for s in spans)
    spans = field_layout(REG, "sensor_msgs/CameraInfo", serialize(REG, "sensor_msgs/CameraInfo", value))
    assert [s.path for s in spans if s.path.startswith("K")] == [f"K[{i}]" for i in range(9)]


def test_uint8_array_is_zero_copy_view_of_input() -> None:
    raw = bytearray(serialize(REG, "std_msgs/UInt8MultiArray",
                              new_message(REG, "std_msgs/UInt8MultiArray", data=b"\x01\x02\x03")))
    out = deserialize(REG, "std_msgs/UInt8MultiArray", raw)
    assert not out["data"].flags.writeable
    raw[-1] = 9  # the view sees the buffer it came from
    assert out["data"].tolist() == [1, 2, 9]


def test_huge_length_refused_before_allocation() -> None:
    body = struct.pack("<I", 50_000_000) + b"x" * 8  # a string declaring 50 MB
    tracemalloc.start()
    try:
        with pytest.raises(DeserializeError) as info:
            deserialize(REG, "std_msgs/String", body)
        _current, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000
    assert info.value.path == "data" and info.value.offset == 0
    assert "declares 50000000" in str(info.value) and "only 8 byte(s) are left" in str(info.value)
    # an array of 8-byte elements: the count alone is checked against the bytes left
    body = struct.pack("<II", 0, 0) + struct.pack("<I", 2) + b"\0" * 12
    with pytest.raises(DeserializeError, match=r"field data: .* offset 8 declares 2 element\(s\) \(16 byte"):
        deserialize(REG, "std_msgs/Float64MultiArray", body)


def test_arrays_of_empty_messages_are_bounded() -> None:
    reg = MsgRegistry.with_defaults()
    reg.add("t/Empties", "std_msgs/Empty[] e\n")
    assert deserialize(reg, "t/Empties", struct.pack("<I", 3)) == {"e": [{}, {}, {}]}
    body = struct.pack("<I", 100_000_000)  # 4 bytes asking for 1e8 empty dicts
    with pytest.raises(DeserializeError, match="max_empty_elements=65536"):
        deserialize(reg, "t/Empties", body)
    with pytest.raises(DeserializeError, match="max_empty_elements=65536"):
        field_layout(reg, "t/Empties", body)


def test_limits_are_applied() -> None:
    body = serialize(REG, "std_msgs/String", {"data": "hello"})
    with pytest.raises(DeserializeError, match="max_string_bytes=3"):
        deserialize(REG, "std_msgs/String", body, limits=MsgLimits(max_string_bytes=3))
    body = serialize(REG, "std_msgs/Int32MultiArray", new_message(REG, "std_msgs/Int32MultiArray",
                                                                   data=[1, 2, 3]))
    with pytest.raises(DeserializeError, match="max_array_length=2"):
        deserialize(REG, "std_msgs/Int32MultiArray", body, limits=MsgLimits(max_array_length=2))


DESERIALIZE_ERRORS = [
    # type, body, path, offset, text
    ("std_msgs/Header", b"\x01\x00", "seq", 0, "ends early"),
    ("std_msgs/Header", struct.pack("<III", 1, 2, 3), "frame_id", 12, "length prefix"),
    ("std_msgs/Header", struct.pack("<IIII", 1, 2, 3, 5) + b"ab", "frame_id", 12, "declares 5"),
    ("geometry_msgs/PoseStamped", struct.pack("<IIII", 0, 0, 0, 0) + b"\0" * 30,
     "pose.orientation.x", 40, "ends early"),
    ("geometry_msgs/Polygon", struct.pack("<I", 1) + b"\0" * 8, "points", 0, "declares 1"),
    ("sensor_msgs/JointState", b"\0" * 16 + struct.pack("<I", 2) + struct.pack("<I", 1) + b"a"
     + struct.pack("<I", 9), "name[1]", 25, "declares 9"),
]


@pytest.mark.parametrize("type_name,body,path,offset,text", DESERIALIZE_ERRORS)
def test_deserialize_error_table(type_name: str, body: bytes, path: str, offset: int,
                                 text: str) -> None:
    with pytest.raises(DeserializeError) as info:
        deserialize(REG, type_name, body)
    assert info.value.path.startswith(path), (info.value.path, str(info.value))
    assert info.value.offset == offset, str(info.value)
    assert text in str(info.value) and path in str(info.value)


SERIALIZE_ERRORS = [
    # type, value, path, expected-type text
    ("std_msgs/UInt8", {"data": 256}, "data", "expected uint8"),
    ("std_msgs/Int32", {"data": 1.5}, "data", "expected int32"),
    ("std_msgs/Float64", {"data": "x"}, "data", "expected float64"),
    ("std_msgs/Bool", {"data": 2}, "data", "expected bool"),
    ("std_msgs/String", {"data": 5}, "data", "expected string"),
    ("std_msgs/String", {}, "data", "missing"),
    ("std_msgs/String", {"data": "a", "extra": 1}, "extra", "no such field"),
    ("std_msgs/Header", {"seq": 0, "stamp": 1.5, "frame_id": ""}, "stamp", "Time.from_sec"),
    ("std_msgs/Header", {"seq": 0, "stamp": (0, -1), "frame_id": ""}, "stamp.nsecs", "uint32"),
    ("geometry_msgs/PoseStamped", {"header": {"seq": 0, "stamp": (0, 0), "frame_id": ""},
                                   "pose": {"position": {"x": 0, "y": 0},
                                            "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}},
     "pose.position.z", "missing"),
    ("geometry_msgs/Polygon", {"points": [{"x": 0, "y": 0, "z": 0}, {"x": "a", "y": 0, "z": 0}]},
     "points[1].x", "expected float32"),
    ("std_msgs/UInt8MultiArray", {"layout": {"dim": [], "data_offset": 0}, "data": [1, 300]},
     "data", "out of range"),
    ("std_msgs/UInt8MultiArray", {"layout": {"dim": [], "data_offset": 0}, "data": "text"},
     "data", "encode the str"),
    ("std_msgs/Float32MultiArray", {"layout": {"dim": [], "data_offset": 0}, "data": ["a"]},
     "data", "not numbers"),
    ("std_msgs/Int16MultiArray", {"layout": {"dim": [], "data_offset": 0}, "data": [0.5]},
     "data", "not integers"),
    ("sensor_msgs/CameraInfo", new_message(REG, "sensor_msgs/CameraInfo", K=[0.0] * 8),
     "K", "exactly 9 elements"),
    ("sensor_msgs/JointState", new_message(REG, "sensor_msgs/JointState", name="abc"),
     "name", "a list"),
    ("std_msgs/String", 42, "", "mapping or object"),
]


@pytest.mark.parametrize("type_name,value,path,text", SERIALIZE_ERRORS)
def test_serialize_error_table(type_name: str, value: object, path: str, text: str) -> None:
    with pytest.raises(SerializeError) as info:
        serialize(REG, type_name, value)
    assert info.value.path == path, str(info.value)
    assert text in str(info.value)
    if path:
        assert f"field {path}" in str(info.value)


def test_objects_with_attributes_serialize_like_dicts() -> None:
    obj = SimpleNamespace(header=SimpleNamespace(seq=1, stamp=SimpleNamespace(secs=2, nsecs=3),
                                                 frame_id="f"),
                          point=SimpleNamespace(x=1.0, y=2.0, z=3.0))
    expected = serialize(REG, "geometry_msgs/PointStamped",
                         {"header": {"seq": 1, "stamp": Time(2, 3), "frame_id": "f"},
                          "point": {"x": 1.0, "y": 2.0, "z": 3.0}})
    assert serialize(REG, "geometry_msgs/PointStamped", obj) == expected


def test_new_message_defaults() -> None:
    msg = new_message(REG, "sensor_msgs/CameraInfo", header={"frame_id": "cam"})
    assert msg["header"] == {"seq": 0, "stamp": Time(0, 0), "frame_id": "cam"}
    assert msg["K"].dtype == np.dtype("<f8") and msg["K"].shape == (9,)
    assert msg["D"].shape == (0,) and msg["roi"]["do_rectify"] is False
    assert len(serialize(REG, "sensor_msgs/CameraInfo", msg)) == min_size(REG, "sensor_msgs/CameraInfo") + 3
    with pytest.raises(SerializeError, match="header.nope"):
        new_message(REG, "sensor_msgs/CameraInfo", header={"nope": 1})


def test_invalid_utf8_round_trips_byte_exact() -> None:
    body = struct.pack("<I", 3) + b"a\xffb"
    out = deserialize(REG, "std_msgs/String", body)
    assert serialize(REG, "std_msgs/String", out) == body


def test_registry_changes_invalidate_codecs() -> None:
    reg = MsgRegistry()
    reg.add("a/B", "int32 x\n")
    assert serialize(reg, "a/B", {"x": 1}) == struct.pack("<i", 1)
    reg.add("a/B", "int64 x\n")
    assert serialize(reg, "a/B", {"x": 1}) == struct.pack("<q", 1)


FUZZ_TYPES = ["std_msgs/String", "sensor_msgs/Image", "sensor_msgs/JointState",
              "geometry_msgs/PolygonStamped", "std_msgs/Float64MultiArray", "sensor_msgs/CameraInfo"]


def _outcome(decode, type_name: str, body: bytes):
    try:
        return normalize(REG, type_name, decode(REG, type_name, body))
    except DeserializeError as exc:
        assert 0 <= exc.offset <= len(body)
        # the offsets may differ inside a field: the fast decoder names the start of a short
        # time field, the reference the start of its missing secs/nsecs half
        return "error"


@pytest.mark.parametrize("type_name", FUZZ_TYPES)
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_fuzz_decoders_only_typed_errors_and_agree(type_name: str, data: st.DataObject) -> None:
    """Random bytes, or a valid body with a few bytes overwritten: the fast decoder, the plain
    reference decoder and field_layout raise nothing but DeserializeError, and the two decoders
    accept the same bodies with the same values."""
    if data.draw(st.booleans(), label="mutate a valid body"):
        body = bytearray(serialize(REG, type_name, data.draw(message(REG, type_name), label="value")))
        for _ in range(data.draw(st.integers(1, 3), label="edits")):
            if body:
                body[data.draw(st.integers(0, len(body) - 1))] = data.draw(st.integers(0, 255))
        body = bytes(body)
    else:
        body = data.draw(st.binary(max_size=200), label="bytes")
    fast = _outcome(deserialize, type_name, body)
    # repr: a float field overwritten into NaN is still "the same value"
    assert repr(_outcome(deserialize_reference, type_name, body)) == repr(fast)
    try:
        field_layout(REG, type_name, body)
    except DeserializeError:
        assert fast == "error"
    else:
        assert fast != "error"
    spans = field_layout(REG, type_name, body, partial=True)
    assert spans[-1].end == len(body) or spans[-1].role != "error"
