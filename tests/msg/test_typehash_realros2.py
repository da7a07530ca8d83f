"""The ROS 2 type hash (REP-2011 RIHS01) against real ROS 2 Jazzy.

The golden hashes are copied from the JSON files the ros-jazzy-* wheels install
(``share/PKG/msg/Type.json``, key ``type_hashes``): they hold on any machine. With the wheels
installed (``require_ros2_python``), every installed message type the lab can load is compared
with its file, and the lab's own types (which no file holds) with what rosidl's generator
(``rosidl_adapter`` .msg -> .idl, then ``rosidl_generator_type_description``) writes for a
hand-written ROS 2 form of them.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import io
import json
from pathlib import Path
from typing import Any

import pytest

from rosfpga_lab.msg import MsgRegistry, UnknownTypeError, registry_with
from rosfpga_lab.msg.builtins import PRIMITIVE_TYPES
from rosfpga_lab.msg.ros2 import ros2_registry
from rosfpga_lab.msg.typehash import (
    ARRAY_OFFSET, FIELD_TYPE_IDS, NESTED_TYPE_ID, RIHS_PATTERN, UNBOUNDED_SEQUENCE_OFFSET,
    hashed_text, lab_type_name, ros2_type_name, type_description, type_hash,
)
from tests.support.realros import require_ros2_python, ros2_share

LAB_MSGS = Path(__file__).resolve().parents[2] / "data" / "msg"

#: Copied from share/<pkg>/msg/<Type>.json of the ros-jazzy-* wheels (type_hashes[0]).
GOLDEN = {
    "std_msgs/Header": "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01",
    "builtin_interfaces/Time":
        "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
    "builtin_interfaces/Duration":
        "RIHS01_e8d009f659816f758b75334ee1a9ca5b5c0b859843261f14c7f937349599d93b",
    "sensor_msgs/Image": "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47",
    "sensor_msgs/LaserScan":
        "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
    "std_msgs/String": "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
    # no fields: rosidl's uint8 structure_needs_at_least_one_member is hashed
    "std_msgs/Empty": "RIHS01_20b625256f32d5dbc0d04fee44f43c41e51c70d3502f84b4a08e7a9c26a96312",
    # fixed arrays (float64[9] k, ...) beside a sequence (float64[] d), lower-cased names
    "sensor_msgs/CameraInfo":
        "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275",
    # a sequence of nested messages (PointField[] fields)
    "sensor_msgs/PointCloud2":
        "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5",
    # float64[36] covariance; Jazzy's Quaternion has default values, which the hash leaves out
    "geometry_msgs/PoseWithCovariance":
        "RIHS01_9a7c0fd234b7f45c6098745ecccd773ca1085670e64107135397aee31c02e1bb",
}
#: What rosidl's generator writes for the hand-written ROS 2 forms of data/msg/lab_msgs (no
#: installed file holds them; test_lab_msgs_hash_as_rosidl_generates_it derives them again).
LAB_GOLDEN = {
    "lab_msgs/Samples": "RIHS01_66141d0aaf67694542693aa6499d50ee641b99b3d30b3453e8037dbc06becffa",
    "lab_msgs/Calibration":
        "RIHS01_e57fb46cb30dd9375c3c31095f8a36fb1cf601f7d89ef3df55b1778a5e4f0a08",
}
#: Installed types whose Jazzy definition is not the lab's ROS 2 form, and why. The lab's forms
#: follow Humble's (tests/msg/test_cdr.py checks them against rosbags' Humble store).
JAZZY_CHANGED = {
    "sensor_msgs/Range": "Jazzy added 'float32 variance' at the end (Humble has none)",
}


@pytest.mark.parametrize("type_name", sorted(GOLDEN))
def test_type_hash_equals_jazzy(type_name: str) -> None:
    assert type_hash(type_name) == GOLDEN[type_name]
    assert type_hash(ros2_type_name(type_name)) == GOLDEN[type_name]


def test_hashed_text_of_time_is_rosidls_json() -> None:
    # Written out by hand from rosidl_generator_type_description: keys in this order, ", " and
    # ": " separators, FieldType ids INT32=6, UINT32=7, no default_value.
    field = '{{"name": "{}", "type": {{"type_id": {}, "capacity": 0, "string_capacity": 0, ' \
            '"nested_type_name": ""}}}}'
    text = ('{"type_description": {"type_name": "builtin_interfaces/msg/Time", "fields": ['
            + field.format("sec", 6) + ", " + field.format("nanosec", 7)
            + ']}, "referenced_type_descriptions": []}')
    assert hashed_text("builtin_interfaces/Time") == text
    assert "RIHS01_" + hashlib.sha256(text.encode()).hexdigest() == GOLDEN["builtin_interfaces/Time"]


def test_references_are_sorted_by_name_and_transitive() -> None:
    desc = type_description("sensor_msgs/Image")
    assert [d["type_name"] for d in desc["referenced_type_descriptions"]] == \
        ["builtin_interfaces/msg/Time", "std_msgs/msg/Header"]
    header = desc["referenced_type_descriptions"][1]
    assert [f["name"] for f in header["fields"]] == ["stamp", "frame_id"]   # no seq in ROS 2
    assert header["fields"][0]["type"] == {"type_id": NESTED_TYPE_ID, "capacity": 0,
                                           "string_capacity": 0,
                                           "nested_type_name": "builtin_interfaces/msg/Time"}
    data = desc["type_description"]["fields"][-1]
    assert data["name"] == "data" and data["type"]["type_id"] == 3 + UNBOUNDED_SEQUENCE_OFFSET


def test_fixed_array_has_capacity() -> None:
    fields = {f["name"]: f["type"] for f in
              type_description("sensor_msgs/CameraInfo")["type_description"]["fields"]}
    assert fields["k"] == {"type_id": FIELD_TYPE_IDS["float64"] + ARRAY_OFFSET, "capacity": 9,
                           "string_capacity": 0, "nested_type_name": ""}
    assert fields["d"]["type_id"] == 11 + UNBOUNDED_SEQUENCE_OFFSET and fields["d"]["capacity"] == 0


def test_every_ros1_primitive_has_a_field_type_id() -> None:
    assert set(FIELD_TYPE_IDS) == set(PRIMITIVE_TYPES)


def test_hash_follows_a_changed_definition_and_ignores_constants() -> None:
    reg = MsgRegistry.with_defaults()
    reg.add("hash_msgs/T", "int32 a\n")
    first = type_hash("hash_msgs/T", reg)
    reg.add("hash_msgs/T", "int32 A_CONSTANT=3\nint32 a\n")     # constants are not hashed
    assert type_hash("hash_msgs/T", reg) == first
    reg.add("hash_msgs/T", "int32 b\n")                          # a renamed field is
    renamed = type_hash("hash_msgs/T", reg)
    reg.add("hash_msgs/T", "uint32 b\n")                         # and a retyped one
    assert len({first, renamed, type_hash("hash_msgs/T", reg)}) == 3


def test_unknown_types_are_refused() -> None:
    with pytest.raises(UnknownTypeError):
        type_hash("no_msgs/Nothing")
    with pytest.raises(UnknownTypeError, match="pkg/Name"):
        ros2_type_name("a/b/c/d")
    with pytest.raises(UnknownTypeError):
        type_hash("std_msgs/Time")         # ROS 2 has no std_msgs/Time
    assert lab_type_name("sensor_msgs/msg/Image") == "sensor_msgs/Image"
    assert RIHS_PATTERN.fullmatch(type_hash("std_msgs/Header"))


# ---- against the real files and the real generator ------------------------------------------

def _without_defaults(desc: dict[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(desc)
    for td in [out["type_description"], *out["referenced_type_descriptions"]]:
        for f in td["fields"]:
            f.pop("default_value", None)
    return out


def test_every_installed_message_the_lab_loads() -> None:
    require_ros2_python()
    from rosidl_generator_type_description import calculate_type_hash

    r2 = ros2_registry()
    checked, changed = [], []
    for path in sorted(ros2_share().glob("*/msg/*.json")):
        real = json.loads(path.read_text())
        name = real["type_description_msg"]["type_description"]["type_name"]
        hashes = {h["type_name"]: h["hash_string"] for h in real["type_hashes"]}
        if lab_type_name(name) not in r2:
            continue
        ours = type_hash(name)
        if lab_type_name(name) in JAZZY_CHANGED:
            # the only difference is the added trailing field: without it, rosidl's own hash
            # of Jazzy's description is ours
            desc = copy.deepcopy(real["type_description_msg"])
            added = desc["type_description"]["fields"].pop()
            assert added["name"] == "variance", JAZZY_CHANGED[lab_type_name(name)]
            assert ours != hashes[name] and calculate_type_hash(desc) == ours
            changed.append(name)
            continue
        assert _without_defaults(type_description(name)) == \
            _without_defaults(real["type_description_msg"]), path
        assert ours == hashes[name], path
        for ref, value in hashes.items():        # the referenced types' hashes too
            assert type_hash(ref) == value, (path, ref)
        checked.append(name)
    assert len(checked) >= 80, checked          # std/sensor/geometry/builtin_interfaces/...
    assert {"sensor_msgs/msg/Image", "std_msgs/msg/Header"} <= set(checked)
    assert changed == ["sensor_msgs/msg/Range"]


def _rosidl_hashes(tmp: Path, package: str, msgs: dict[str, str]) -> dict[str, dict[str, Any]]:
    """What rosidl's generator writes for ``package``'s ROS 2 ``.msg`` texts: its .msg -> .idl
    adapter, then ``generate_type_hash`` with the installed packages' JSON as includes."""
    from rosidl_adapter.msg import convert_msg_to_idl
    from rosidl_generator_type_description import generate_type_hash

    src, idl = tmp / "src" / package, tmp / "idl"
    (src / "msg").mkdir(parents=True)
    (idl / "msg").mkdir(parents=True)
    for name, text in msgs.items():
        (src / "msg" / f"{name}.msg").write_text(text)
        with contextlib.redirect_stdout(io.StringIO()):   # it prints what it reads and writes
            convert_msg_to_idl(src, package, Path("msg") / f"{name}.msg", idl / "msg")
    share = ros2_share()
    args = {"package_name": package, "output_dir": str(tmp / "gen"),
            "idl_tuples": [f"{idl}:msg/{name}.idl" for name in msgs],
            "include_paths": [f"{p.name}:{p}" for p in share.iterdir() if (p / "msg").is_dir()]}
    (tmp / "args.json").write_text(json.dumps(args))
    return {f.stem: json.loads(f.read_text()) for f in map(Path, generate_type_hash(
        str(tmp / "args.json")))}


def test_lab_msgs_hash_as_rosidl_generates_it(tmp_path: Path) -> None:
    require_ros2_python()
    # The ROS 2 forms of data/msg/lab_msgs, written by hand as a ROS 2 user would (Header and
    # duration in their ROS 2 types), comments dropped.
    theirs = _rosidl_hashes(tmp_path, "lab_msgs", {
        "Calibration": "string sensor_name\nfloat64[3] offset\nuint8 mode\n",
        "Samples": "std_msgs/Header header\nCalibration calibration\nstring label\n"
                   "int16[4] thresholds\nint32[] samples\nbuiltin_interfaces/Duration period\n"
                   "Calibration[] history\nbool valid\n",
    })
    reg = registry_with([LAB_MSGS])
    for name in ("Calibration", "Samples"):
        real = theirs[name]
        assert real["type_hashes"][0]["hash_string"] == LAB_GOLDEN[f"lab_msgs/{name}"]
        assert type_hash(f"lab_msgs/{name}", reg) == LAB_GOLDEN[f"lab_msgs/{name}"]
        assert type_description(f"lab_msgs/{name}", reg) == real["type_description_msg"]


def test_every_builtin_kind_hashes_as_rosidl_generates_it(tmp_path: Path) -> None:
    """char (rosidl: uint8), byte (octet), bool, string arrays, time and duration, an empty nested
    message, a constant: the lab's ROS 1 definition against the ROS 2 one written by hand."""
    require_ros2_python()
    ros1 = ("int8 K=3\nchar c\nbyte b\nchar[] cs\nbyte[4] bs\nbool[] flags\nstring[2] names\n"
            "time t\nduration[] ds\nstd_msgs/Empty e\nint64 i\nuint64[] u\nfloat32 f\n")
    ros2 = ros1.replace("time t", "builtin_interfaces/Time t").replace(
        "duration[] ds", "builtin_interfaces/Duration[] ds")
    theirs = _rosidl_hashes(tmp_path, "hash_msgs", {"Kinds": ros2})["Kinds"]
    reg = MsgRegistry.with_defaults()
    reg.add("hash_msgs/Kinds", ros1)
    assert type_description("hash_msgs/Kinds", reg) == theirs["type_description_msg"]
    assert type_hash("hash_msgs/Kinds", reg) == theirs["type_hashes"][0]["hash_string"]


def test_field_type_ids_are_rosidls() -> None:
    require_ros2_python()
    import rosidl_generator_type_description as g

    ids = g.FIELD_TYPE_NAME_TO_ID
    idl = {"char": "uint8", "byte": "octet", "bool": "boolean", "float32": "float",
           "float64": "double"}
    for kind, value in FIELD_TYPE_IDS.items():
        if kind == "string":
            assert value == ids["FIELD_TYPE_STRING"]
            continue
        name = g.FIELD_VALUE_TYPE_NAMES[idl.get(kind, kind)]
        assert value == ids[name], kind
        assert value + ARRAY_OFFSET == ids[name + "_ARRAY"]
        assert value + UNBOUNDED_SEQUENCE_OFFSET == ids[name + "_UNBOUNDED_SEQUENCE"]
    assert NESTED_TYPE_ID == ids["FIELD_TYPE_NESTED_TYPE"]


def test_component_announces_the_hash_of_its_configured_type() -> None:
    """A lab_msgs component (its msg_path types) sends rosidl's hash of them in SEDP."""
    from tests.support.ros2tools import DOMAIN
    from rosfpga_lab.component.ros2 import Ros2Component
    from rosfpga_lab.rtps.build import PID_TOPIC_NAME, PID_USER_DATA, cdr_string_value
    from rosfpga_lab.rtps.discovery import parse_parameters, user_data_type_hash
    from rosfpga_lab.rtps.participant import PUB_WRITER, SUB_WRITER

    comp = Ros2Component(LAB_MSGS.parent / "fpga_samples_dilate.yaml", domain=DOMAIN).start()
    try:
        assert comp.node is not None
        with comp.node._lock:                      # the SEDP samples it sends
            p = comp.node.participant
            sedp = [params for eid in (PUB_WRITER, SUB_WRITER)
                    for params in map(parse_parameters, p.local[eid].history.values())]
    finally:
        comp.stop()
    announced = {cdr_string_value(params[PID_TOPIC_NAME][0]):
                 user_data_type_hash(params[PID_USER_DATA][0]) for params in sedp
                 if PID_USER_DATA in params}
    assert announced == {"rt/samples": LAB_GOLDEN["lab_msgs/Samples"],
                         "rt/samples_dilated": LAB_GOLDEN["lab_msgs/Samples"]}


# ---- real rmw (rclpy on Fast DDS) and the lab's node, both ways ---------------------------------

FASTDDS_LOOPBACK = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors><transport_descriptor><transport_id>loopback</transport_id>
    <type>UDPv4</type><interfaceWhiteList><address>127.0.0.1</address></interfaceWhiteList>
  </transport_descriptor></transport_descriptors>
  <participant profile_name="loopback_only" is_default_profile="true"><rtps>
    <userTransports><transport_id>loopback</transport_id></userTransports>
    <useBuiltinTransports>false</useBuiltinTransports>
  </rtps></participant>
</profiles>
"""
#: rclpy subscribes to the lab's /hash_cam and publishes /hash_back; prints the type hash its rmw
#: read from the lab's publisher, then stays a while so the lab sees its endpoints.
RCLPY_PROBE = """
import json, sys, time
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import Image
rclpy.init()
node = Node("hash_probe")
node.create_subscription(Image, "/hash_cam", lambda m: None, 10)
node.create_publisher(Image, "/hash_back", 10)
end, seen = time.time() + 20, []
while time.time() < end and not seen:
    rclpy.spin_once(node, timeout_sec=0.1)
    seen = [str(i.topic_type_hash) for i in node.get_publishers_info_by_topic("/hash_cam")]
print(json.dumps(seen), flush=True)
end = time.time() + 20
while time.time() < end and not sys.stdin.readline():
    pass
node.destroy_node()
rclpy.shutdown()
"""


def test_real_rmw_reads_the_labs_hash_and_the_lab_reads_rmws(tmp_path: Path) -> None:
    require_ros2_python()
    import importlib.util
    import os
    import subprocess
    import sys
    import time

    from tests.support.realros import skip_or_fail
    from tests.support.ros2tools import DOMAIN
    from rosfpga_lab.graph.ros2 import Ros2Node

    if importlib.util.find_spec("rclpy") is None:
        skip_or_fail("rclpy not installed (ros-jazzy-rclpy[fastrtps] wheels)", "ROSFPGA_REQUIRE_ROS2")
    (tmp_path / "fastdds.xml").write_text(FASTDDS_LOOPBACK)
    env = {**os.environ, "ROS_DOMAIN_ID": str(DOMAIN),
           "FASTRTPS_DEFAULT_PROFILES_FILE": str(tmp_path / "fastdds.xml")}
    image = GOLDEN["sensor_msgs/Image"]
    with Ros2Node("hash_lab", DOMAIN) as node:
        node.create_publisher("/hash_cam", "sensor_msgs/Image")
        probe = subprocess.Popen([sys.executable, "-c", RCLPY_PROBE], env=env, text=True,
                                 stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE)
        try:
            assert probe.stdout is not None and probe.stdin is not None
            line = probe.stdout.readline()
            seen: dict[tuple[str, str], str] = {}
            deadline = time.monotonic() + 10
            while len(seen) < 2 and time.monotonic() < deadline:
                with node._lock:
                    seen = {(r.kind, r.topic): r.type_hash for r in node.participant.remote.values()
                            if r.topic in ("rt/hash_cam", "rt/hash_back")}
                time.sleep(0.05)
            probe.stdin.write("done\n")
            probe.stdin.flush()
        finally:
            try:
                _, err = probe.communicate(timeout=20)
            except subprocess.TimeoutExpired:
                probe.kill()
                _, err = probe.communicate()
    # rmw_fastrtps parsed the lab's USER_DATA: the hash it reports is Jazzy's own for Image
    assert json.loads(line or "null") == [image], (line, err[-2000:])
    # and the lab read what Jazzy's rmw announces for its reader and writer
    assert seen == {("reader", "rt/hash_cam"): image, ("writer", "rt/hash_back"): image}, seen
