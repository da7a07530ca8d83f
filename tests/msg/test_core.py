"""Core of the message model: golden md5 sums, full texts, and the wire format of known types.

Every md5 pinned here was read from Debian's genpy classes (``sensor_msgs.msg.Image._md5sum``
...) on a machine with ROS Noetic; tests/msg/test_realros.py re-checks all of them live in CI.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.errors import LabError
from rosfpga_lab.msg import (
    DEFINITIONS_DIR, DeserializeError, Duration, MsgError, MsgRegistry, SerializeError, Time,
    default_registry, deserialize, field_layout, new_message, serialize,
)

GOLDEN_MD5 = {
    "std_msgs/String": "992ce8a1687cec8c8bd883ec73ca41d1",
    "geometry_msgs/Pose": "e45d45a5a1ce597b249e23fb30fc871f",
    "geometry_msgs/PoseStamped": "d3812c3cbc69362b77dc0b19b345f8f5",
    "sensor_msgs/PointCloud2": "1158d486dd51d683ce2f1be655c3c181",
    "sensor_msgs/Image": "060021388200f6f0f447d0fcd9c64743",
    "std_msgs/Header": "2176decaecbce78abc3b96ef049fabed",
    "sensor_msgs/CameraInfo": "c9a58c1b0b154e0e6da7578cb991d214",
    "sensor_msgs/NavSatStatus": "331cdbddfa4bc96ffc3b9ad98900a54c",
    "std_msgs/Empty": "d41d8cd98f00b204e9800998ecf8427e",
    "geometry_msgs/Twist": "9f195f881246fdfa2798d1d3eebca84a",
    "sensor_msgs/Imu": "6a62c6daae103f4ff57a132d6f95cec2",
    "sensor_msgs/JointState": "3066dcd76a6cfaef579bd0f34173e9fd",
    "std_msgs/Float64MultiArray": "4b7d974086d4060e7db4613a7e6c3ba4",
    "sensor_msgs/BatteryState": "4ddae7f048e32fda22cac764685e3974",
    "std_msgs/Time": "cd7166c74c552c311fbcc2fe5a7bc289",
    "std_msgs/Duration": "3e286caf4241d664e55f3ad380e2ae46",
    "sensor_msgs/CompressedImage": "8f7a12909da2c9d3332d540a0977563f",
    "geometry_msgs/TransformStamped": "b5764a33bfeb3588febc2682852579b0",
    "sensor_msgs/LaserScan": "90c7ef2dc6895d81024acba2ac42f369",
}

# genpy's sensor_msgs/Image._full_text (Debian's Noetic), comments included: what roscpp and
# rospy send as message_definition (2016 bytes); pinned from genpy.
IMAGE_FULL_TEXT = (Path(__file__).resolve().parents[1] / "golden" / "sensor_msgs_Image.full_text").read_text()


@pytest.fixture(scope="module")
def reg() -> MsgRegistry:
    return default_registry()


@pytest.mark.parametrize("type_name,md5", sorted(GOLDEN_MD5.items()))
def test_golden_md5(reg: MsgRegistry, type_name: str, md5: str) -> None:
    assert reg.md5(type_name) == md5


def test_bare_header_resolves(reg: MsgRegistry) -> None:
    assert reg.get("Header").full_name == "std_msgs/Header"
    assert reg.md5("Header") == "2176decaecbce78abc3b96ef049fabed"
    assert reg.get("Image").full_name == "sensor_msgs/Image"  # unique short name
    assert reg.get("Point", package="geometry_msgs").full_name == "geometry_msgs/Point"
    assert reg.get("sensor_msgs/msg/Image").full_name == "sensor_msgs/Image"


def test_shipped_packages_complete(reg: MsgRegistry) -> None:
    # Noetic: std_msgs 32, sensor_msgs 27, geometry_msgs 29 message types.
    assert len(reg.types("std_msgs")) == 32
    assert len(reg.types("sensor_msgs")) == 27
    assert len(reg.types("geometry_msgs")) == 29
    assert (DEFINITIONS_DIR / "sensor_msgs" / "msg" / "Image.msg").is_file()


def test_image_full_text(reg: MsgRegistry) -> None:
    assert len(IMAGE_FULL_TEXT.encode()) == 2016
    assert reg.full_text("sensor_msgs/Image") == IMAGE_FULL_TEXT


def test_full_text_dependency_order(reg: MsgRegistry) -> None:
    # genmsg: depth first, first occurrence kept.
    assert reg.dependencies("geometry_msgs/PoseWithCovarianceStamped") == [
        "std_msgs/Header", "geometry_msgs/PoseWithCovariance", "geometry_msgs/Pose",
        "geometry_msgs/Point", "geometry_msgs/Quaternion"]


def test_default_registry_is_read_only(reg: MsgRegistry) -> None:
    with pytest.raises(MsgError, match="with_defaults"):
        reg.add("my_msgs/X", "int32 a\n")
    own = MsgRegistry.with_defaults()
    own.add("my_msgs/X", "int32 a\n")
    assert "my_msgs/X" in own and "my_msgs/X" not in reg


def test_string_bytes_known(reg: MsgRegistry) -> None:
    assert serialize(reg, "std_msgs/String", {"data": "hi"}) == b"\x02\x00\x00\x00hi"
    assert deserialize(reg, "std_msgs/String", b"\x02\x00\x00\x00hi") == {"data": "hi"}


def test_header_bytes_known(reg: MsgRegistry) -> None:
    body = serialize(reg, "std_msgs/Header",
                     {"seq": 7, "stamp": Time(1, 2), "frame_id": "map"})
    assert body == struct.pack("<IIII", 7, 1, 2, 3) + b"map"
    value = deserialize(reg, "std_msgs/Header", body)
    assert value == {"seq": 7, "stamp": Time(1, 2), "frame_id": "map"}
    assert isinstance(value["stamp"], Time)


def test_time_inputs_accepted(reg: MsgRegistry) -> None:
    expected = serialize(reg, "std_msgs/Time", {"data": Time(5, 6)})
    for form in ((5, 6), {"secs": 5, "nsecs": 6}, [5, 6]):
        assert serialize(reg, "std_msgs/Time", {"data": form}) == expected
    assert deserialize(reg, "std_msgs/Duration",
                       serialize(reg, "std_msgs/Duration", {"data": Duration(-1, 5)})) \
        == {"data": Duration(-1, 5)}


def _image(height: int = 480, width: int = 640) -> tuple[dict, np.ndarray]:
    reg = default_registry()
    pixels = np.random.default_rng(1).integers(0, 256, height * width * 4, dtype=np.uint8)
    msg = new_message(reg, "sensor_msgs/Image", header={"seq": 1, "frame_id": "camera"},
                      height=height, width=width, encoding="rgba8", step=width * 4,
                      data=pixels)
    return msg, pixels


def test_image_640x480_rgba8_roundtrip_zero_copy(reg: MsgRegistry) -> None:
    msg, pixels = _image()
    body = serialize(reg, "sensor_msgs/Image", msg)
    head = struct.pack("<IIII", 1, 0, 0, 6) + b"camera" + struct.pack("<II", 480, 640) \
        + struct.pack("<I", 5) + b"rgba8" + struct.pack("<BII", 0, 2560, 1228800)
    assert body[:len(head)] == head
    assert body[len(head):] == pixels.tobytes()
    out = deserialize(reg, "sensor_msgs/Image", body)
    assert out["data"].dtype == np.uint8 and not out["data"].flags.writeable
    assert np.shares_memory(out["data"], np.frombuffer(body, np.uint8))  # zero copy
    assert np.array_equal(out["data"], pixels)
    assert out["encoding"] == "rgba8" and out["height"] == 480


def test_image_bytes_like_inputs(reg: MsgRegistry) -> None:
    msg, pixels = _image(2, 3)
    expected = serialize(reg, "sensor_msgs/Image", msg)
    for data in (pixels.tobytes(), bytearray(pixels.tobytes()), memoryview(pixels.tobytes()),
                 pixels.tolist()):
        assert serialize(reg, "sensor_msgs/Image", dict(msg, data=data)) == expected


def test_numeric_arrays_are_numpy(reg: MsgRegistry) -> None:
    body = serialize(reg, "std_msgs/Float32MultiArray",
                     new_message(reg, "std_msgs/Float32MultiArray", data=[1.5, -2.0]))
    out = deserialize(reg, "std_msgs/Float32MultiArray", body)
    assert out["data"].dtype == np.dtype("<f4")
    assert out["data"].tolist() == [1.5, -2.0]
    assert out["layout"] == {"dim": [], "data_offset": 0}


def test_trailing_bytes_refused_unless_allowed(reg: MsgRegistry) -> None:
    body = serialize(reg, "std_msgs/String", {"data": "hi"})
    with pytest.raises(DeserializeError, match="2 byte.s. left over .* offset 6"):
        deserialize(reg, "std_msgs/String", body + b"zz")
    assert deserialize(reg, "std_msgs/String", body + b"zz", allow_trailing=True) == {"data": "hi"}


def test_errors_are_lab_errors(reg: MsgRegistry) -> None:
    with pytest.raises(LabError):
        serialize(reg, "std_msgs/Int8", {"data": 200})
    with pytest.raises(SerializeError, match=r"field data: expected int8"):
        serialize(reg, "std_msgs/Int8", {"data": 200})


def test_layout_covers_every_byte(reg: MsgRegistry) -> None:
    msg, _ = _image(4, 4)
    body = serialize(reg, "sensor_msgs/Image", msg)
    spans = field_layout(reg, "sensor_msgs/Image", body)
    pos = 0
    for span in spans:
        assert span.offset == pos and span.size > 0
        pos = span.end
    assert pos == len(body)
    paths = [(s.path, s.role) for s in spans]
    assert paths[:5] == [("header.seq", "value"), ("header.stamp.secs", "value"),
                         ("header.stamp.nsecs", "value"), ("header.frame_id", "length"),
                         ("header.frame_id", "value")]
    assert ("data", "length") in paths
