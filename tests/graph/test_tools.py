"""``topic echo``/``pub`` as rostopic's, without ROS (issue 23, items 11, 12, 13, 20).

The real-ROS comparisons are in test_tools_realros.py; here: a golden text from genpy's
``strify_message``, rostopic's pub argument forms, decoding a type from a connection header,
``--msg-path``, and the drop count under a burst.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

from rosfpga_lab.graph import EmbeddedMaster, GraphError, Node
from rosfpga_lab.graph.tools import format_message, parse_message_value, registry_from_header
from rosfpga_lab.msg import MsgRegistry, Time, default_registry, deserialize, serialize

pytestmark = pytest.mark.timeout(60)
REG = default_registry()

# genpy.message.strify_message of this PoseArray (Debian's genpy 0.6, as rostopic echo prints it)
POSE_ARRAY_TEXT = (
    'header: \n  seq: 3\n  stamp: \n    secs: 12\n    nsecs:       345\n  frame_id: "map"\n'
    "poses: \n  - \n    position: \n      x: 1.5\n      y: 0.0\n      z: 0.0\n    orientation: \n"
    "      x: 0.0\n      y: 0.0\n      z: 0.0\n      w: 0.0\n  - \n    position: \n      x: 0.0\n"
    "      y: 0.0\n      z: 0.0\n    orientation: \n      x: 0.0\n      y: 0.0\n      z: 0.0\n"
    "      w: -0.25")


def test_echo_text_of_an_array_of_messages_is_rostopics_and_valid_yaml() -> None:
    """The old text put `- position:` and `orientation:` at one indent: yaml.safe_load failed."""
    v = parse_message_value(REG, "geometry_msgs/PoseArray", [
        "{header: {seq: 3, stamp: {secs: 12, nsecs: 345}, frame_id: map}, "
        "poses: [{position: {x: 1.5}}, {orientation: {w: -0.25}}]}"])
    text = format_message(deserialize(REG, "geometry_msgs/PoseArray",
                                      serialize(REG, "geometry_msgs/PoseArray", v)))
    assert text == POSE_ARRAY_TEXT
    assert yaml.safe_load(text)["poses"][1]["orientation"]["w"] == -0.25
    multi = parse_message_value(REG, "std_msgs/Int8MultiArray", [
        "{layout: {dim: [{label: rows, size: 2, stride: 2}]}, data: [1, -2]}"])
    assert yaml.safe_load(format_message(multi)) == {
        "layout": {"dim": [{"label": "rows", "size": 2, "stride": 2}], "data_offset": 0},
        "data": [1, -2]}


def test_pub_forms_of_rostopic() -> None:
    twist = parse_message_value(REG, "geometry_msgs/Twist", ["[0.1, 0, 0]", "[0, 0, 1]"])
    assert twist == {"linear": {"x": 0.1, "y": 0, "z": 0}, "angular": {"x": 0, "y": 0, "z": 1}}
    poses = parse_message_value(REG, "geometry_msgs/PoseArray", ["{poses: [{position: {x: 1}}]}"])
    assert poses["poses"][0]["position"] == {"x": 1, "y": 0.0, "z": 0.0}
    assert poses["poses"][0]["orientation"]["w"] == 0.0
    before = time.time()
    stamped = parse_message_value(REG, "geometry_msgs/PoseStamped", ["{header: auto}"])
    header = parse_message_value(REG, "std_msgs/Header", ["{stamp: now, frame_id: f}"])
    for stamp in (stamped["header"]["stamp"], header["stamp"]):
        assert isinstance(stamp, Time) and before - 1 < stamp.to_sec() < time.time() + 1
    assert parse_message_value(REG, "std_msgs/Header", ["{stamp: 1500000000}"])["stamp"] == Time(1, 500000000)
    assert parse_message_value(REG, "std_msgs/String", ["hello"]) == {"data": "hello"}
    for args, error in ((["{poses: [{nope: 1}]}"], r"PoseArray\.poses\[0\] has no field 'nope'"),
                        (["{header: {stamp: later}}"], "give now, integer nanoseconds"),
                        (["{pose: now}"], "no key"),
                        (["{poses: 3}"], "is an array: give a list")):
        with pytest.raises(GraphError, match=error):
            parse_message_value(REG, "geometry_msgs/PoseArray" if "poses" in args[0] else
                                "geometry_msgs/PoseStamped", args)


CUSTOM = {"lab_test_msgs/Reading": "Header header\nlab_test_msgs/Sample[] samples\nstring note\n",
          "lab_test_msgs/Sample": "# a comment, as genmsg keeps it\nfloat32 value\nuint8 CHANNEL=3\n"
                                  "geometry_msgs/Point where\n"}


def custom_registry(tmp_path: Path | None = None) -> MsgRegistry:
    reg = MsgRegistry.with_defaults()
    for name, text in CUSTOM.items():
        reg.add(name, text)
        if tmp_path is not None:
            pkg, short = name.split("/")
            (tmp_path / pkg / "msg").mkdir(parents=True, exist_ok=True)
            (tmp_path / pkg / "msg" / f"{short}.msg").write_text(text)
    return reg


def test_a_type_from_a_connection_header_is_checked_against_its_md5() -> None:
    full = custom_registry()
    header = {"type": "lab_test_msgs/Reading", "md5sum": full.md5("lab_test_msgs/Reading"),
              "message_definition": full.full_text("lab_test_msgs/Reading"), "callerid": "/pub"}
    reg = registry_from_header("lab_test_msgs/Reading", header)
    assert reg.md5("lab_test_msgs/Reading") == header["md5sum"]
    with pytest.raises(GraphError, match="has md5 .* but its header says 0123"):
        registry_from_header("lab_test_msgs/Reading", {**header, "md5sum": "0123"})
    with pytest.raises(GraphError, match="/pub sent no message_definition; add its package with --msg-path"):
        registry_from_header("lab_test_msgs/Reading", {**header, "message_definition": ""})


def lab_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}


def topic_cli(uri: str, *args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "topic", "--master-uri", uri, *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=lab_env(), **kw)


@pytest.mark.parametrize("with_path", [False, True])
def test_echo_decodes_an_unshipped_type(tmp_path, with_path: bool) -> None:
    """The lab said "not in the lab's registry; use --hex"; rostopic decodes it from the
    publisher's message_definition. --msg-path DIR loads the package instead."""
    reg = custom_registry(tmp_path)
    value = {"header": {"seq": 1, "stamp": Time(2, 3), "frame_id": "f"}, "note": "n",
             "samples": [{"value": 0.5, "where": {"x": 1.0, "y": 2.0, "z": 3.0}}]}
    with EmbeddedMaster(port=0) as m:
        talker = Node("/talker", master=m, registry=reg)
        pub = talker.advertise("/reading", "lab_test_msgs/Reading", latch=True)
        pub.publish(value)
        try:
            extra = ["--msg-path", str(tmp_path)] if with_path else []
            proc = topic_cli(m.uri, *extra, "echo", "-n", "1", "--timeout", "20", "/reading")
            out, err = proc.communicate(timeout=40)
        finally:
            talker.shutdown()
    assert proc.returncode == 0, err
    assert yaml.safe_load(out.split("\n---")[0]) == {
        "header": {"seq": 1, "stamp": {"secs": 2, "nsecs": 3}, "frame_id": "f"},
        "samples": [{"value": 0.5, "where": {"x": 1.0, "y": 2.0, "z": 3.0}}], "note": "n"}


def test_echo_counts_and_reports_dropped_messages() -> None:
    """Item 20: a burst printed a fraction of the messages without a word about the rest."""
    total = 3000
    with EmbeddedMaster(port=0) as m:
        talker = Node("/talker", master=m)
        pub = talker.advertise("/burst", "std_msgs/String", queue_size=0)
        proc = topic_cli(m.uri, "echo", "--queue-size", "5", "--timeout", "6", "/burst")
        try:
            deadline = time.monotonic() + 20
            while pub.get_num_connections() < 1 and time.monotonic() < deadline:
                time.sleep(0.05)
            for i in range(total):   # ~120 KB of text: the unread pipe stops the printing
                pub.publish({"data": f"message {i:05d} " + "x" * 20})
            out, err = proc.communicate(timeout=40)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            talker.shutdown()
    printed = out.count("\n---")
    found = re.search(r"topic echo: (\d+) of (\d+) messages dropped in all: printing fell behind "
                      r"and the queue of 5 was full \(a larger --queue-size", err)
    assert found, err
    dropped, received = int(found[1]), int(found[2])
    # every message received is printed or counted as dropped, but for at most the queue (5)
    # and one in hand still waiting when --timeout ends on a loaded machine
    assert dropped > 0 and received - 6 <= printed + dropped <= received
    assert total // 2 < received <= total


def test_new_message_completes_messages_inside_arrays() -> None:
    """The library's new_message completed nested dicts only outside arrays; serialize then
    failed with "missing ... y" for `poses=[{"position": {"x": 1}}]`."""
    from rosfpga_lab.msg import SerializeError, new_message

    v = new_message(REG, "geometry_msgs/PoseArray", poses=[{"position": {"x": 1.0}}])
    back = deserialize(REG, "geometry_msgs/PoseArray", serialize(REG, "geometry_msgs/PoseArray", v))
    assert back["poses"][0]["position"] == {"x": 1.0, "y": 0.0, "z": 0.0}
    with pytest.raises(SerializeError, match=r"field poses\[0\]\.position\.q: geometry_msgs/Point has no such field"):
        new_message(REG, "geometry_msgs/PoseArray", poses=[{"position": {"q": 1}}])


def test_pub_with_msg_path_publishes_an_unshipped_type(tmp_path) -> None:
    reg = custom_registry(tmp_path)
    with EmbeddedMaster(port=0) as m:
        listener = Node("/listener", master=m, registry=reg)
        sub = listener.subscribe("/reading", "lab_test_msgs/Reading")
        proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "topic", "--master-uri", m.uri,
                                 "--msg-path", str(tmp_path), "pub", "/reading", "lab_test_msgs/Reading",
                                 "{samples: [{value: 2}, {where: [1, 2, 3]}], note: hi}"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=lab_env())
        try:
            value, _info = sub.wait_for_message(20)
        finally:
            proc.terminate()
            proc.wait(10)
            listener.shutdown()
    assert value["note"] == "hi" and [s["value"] for s in value["samples"]] == [2.0, 0.0]
    assert value["samples"][1]["where"] == {"x": 1.0, "y": 2.0, "z": 3.0}
