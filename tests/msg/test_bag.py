"""Bags without ROS (issue 23, item 15): read and write ROS 1 bags with ``rosbags``.

``camera --source x.bag`` said "not an image OpenCV can read"; now it replays the bag's images
with their recorded timing, and ``topic echo --bag`` records what it receives. Debian's
``rosbag info/play`` read those bags (the real-ROS part skips with a reason without ROS).
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import require_ros, ros_env, skip_or_fail
from rosfpga_lab.component import Camera
from rosfpga_lab.component.errors import SourceError
from rosfpga_lab.component.sources import open_source
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.realros import ros_missing
from rosfpga_lab.hw import image_frame
from rosfpga_lab.msg import default_registry, deserialize, serialize
from rosfpga_lab.msg.bag import BagWriter, bag_topics, read_bag

pytestmark = pytest.mark.timeout(60)
REG = default_registry()
IMAGE = "sensor_msgs/Image"
# recorded gaps that a fixed-rate camera would not reproduce: 0, 0.1, 0.4, 0.45, 0.75 s
OFFSETS = [0.0, 0.1, 0.4, 0.45, 0.75]
T0 = 1_700_000_000_000_000_000


def frames(n: int = len(OFFSETS)) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    return [rng.integers(0, 256, (6, 8, 3), dtype=np.uint8) for _ in range(n)]


def write_camera_bag(path: Path, images: list[np.ndarray], topic: str = "/cam/image") -> None:
    with BagWriter(path) as bag:
        bag.write("/chatter", "std_msgs/String", REG.md5("std_msgs/String"),
                  REG.full_text("std_msgs/String"), T0, serialize(REG, "std_msgs/String", {"data": "x"}))
        for i, (img, off) in enumerate(zip(images, OFFSETS)):
            body = image_frame(img, "rgb8", seq=i, stamp=(1, i), frame_id="cam")[4:]
            bag.write(topic, IMAGE, REG.md5(IMAGE), REG.full_text(IMAGE), T0 + int(off * 1e9), body)


def test_bag_round_trip_keeps_bodies_types_and_times(tmp_path) -> None:
    images = frames()
    write_camera_bag(tmp_path / "x.bag", images)
    assert bag_topics(tmp_path / "x.bag") == {"/chatter": "std_msgs/String", "/cam/image": IMAGE}
    got = list(read_bag(tmp_path / "x.bag", ["/cam/image"]))
    assert [m.time_ns - T0 for m in got] == [int(o * 1e9) for o in OFFSETS]
    assert {(m.type_name, m.md5sum, m.definition) for m in got} == {(IMAGE, REG.md5(IMAGE), REG.full_text(IMAGE))}
    msg = deserialize(REG, IMAGE, got[2].body)
    assert (msg["width"], msg["height"], msg["encoding"], msg["header"]["seq"]) == (8, 6, "rgb8", 2)
    assert bytes(msg["data"]) == images[2].tobytes()
    with pytest.raises(Exception, match="exists already"):
        BagWriter(tmp_path / "x.bag")


def test_bag_source_gives_the_recorded_frames_and_times(tmp_path) -> None:
    images = frames()
    write_camera_bag(tmp_path / "x.bag", images)
    src = open_source(str(tmp_path / "x.bag"), 8, 6, "rgb8")
    assert src.bag_topic == "/cam/image" and src.period == len(images)
    assert src.times == pytest.approx(OFFSETS)
    assert all(np.array_equal(src.frame(k), images[k]) for k in range(len(images)))
    grey = open_source(str(tmp_path / "x.bag"), 4, 3, "mono8")  # converted when asked to
    assert grey.frame(0).shape == (3, 4, 1)
    with pytest.raises(SourceError, match="no topic /nope of sensor_msgs/Image.*: /cam/image"):
        open_source(str(tmp_path / "x.bag"), 8, 6, "rgb8", topic="/nope")


def test_camera_replays_a_bag_on_its_recorded_timing(tmp_path) -> None:
    images = frames()
    write_camera_bag(tmp_path / "x.bag", images)
    with EmbeddedMaster(port=0) as m:
        viewer = Node("/v", master=m)
        arrivals: list[tuple[float, bytes]] = []
        sub = viewer.subscribe("/cam/image", IMAGE, lambda v: arrivals.append(
            (time.monotonic(), bytes(v["data"]))), queue_size=0)
        sent: list[float] = []
        cam = Camera("/cam/image", width=8, height=6, encoding="rgb8", rate=1000.0,
                     source=open_source(str(tmp_path / "x.bag"), 8, 6, "rgb8"), master=m,
                     on_sent=lambda f: sent.append(f.sent))
        try:
            assert sub.wait_for_connection(1, 10)
            cam.run(count=len(images))
            deadline = time.monotonic() + 5
            while len(arrivals) < len(images) and time.monotonic() < deadline:
                time.sleep(0.02)
        finally:
            cam.stop()
            viewer.shutdown()
    assert [a[1] for a in arrivals] == [img.tobytes() for img in images]
    # on the recorded schedule (at the --rate of 1000 fps they would be 1 ms apart): never
    # early, and late by no more than a loaded machine's scheduling delay
    for got, want in zip([t - sent[0] for t in sent], OFFSETS):
        assert want - 0.005 <= got <= want + 0.2, (sent, OFFSETS)


def lab_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}


def test_camera_cli_replays_a_bag(tmp_path) -> None:
    """The defect: `camera --source x.bag` -> "not an image OpenCV can read"."""
    images = frames()
    write_camera_bag(tmp_path / "x.bag", images)
    with EmbeddedMaster(port=0) as m:
        node = Node("/v", master=m)
        got: list[bytes] = []
        node.subscribe("/cam/image", IMAGE, lambda v: got.append(bytes(v["data"])), queue_size=0)
        try:
            # publish the bag's frames on their topic, after the subscriber can connect
            out = subprocess.run([sys.executable, "-m", "rosfpga_lab", "camera", "--master-uri", m.uri,
                                  "--source", str(tmp_path / "x.bag"), "--size", "8x6",
                                  "--encoding", "rgb8"], capture_output=True, text=True,
                                 timeout=40, env=lab_env())
            assert out.returncode == 0, out.stderr
            deadline = time.monotonic() + 5
            while len(got) < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
        finally:
            node.shutdown()
    assert f"sent {len(images)} frames" in out.stdout
    assert got and set(got) <= {img.tobytes() for img in images}


@pytest.mark.ros
def test_topic_echo_records_a_bag_that_rosbag_reads(tmp_path) -> None:
    require_ros()
    reason = ros_missing(("rosbag",), modules=("rosbag",))
    if reason:
        skip_or_fail(f"Debian's rosbag is missing: {reason}", "ROSFPGA_REQUIRE_ROS")
    bag = tmp_path / "rec.bag"
    with EmbeddedMaster(port=0) as m:
        talker = Node("/talker", master=m)
        pub = talker.advertise("/chatter", "std_msgs/String")
        stop = threading.Event()

        def loop() -> None:
            i = 0
            while not stop.wait(0.02):
                pub.publish({"data": f"m{i}"})
                i += 1

        threading.Thread(target=loop, daemon=True).start()
        try:
            out = subprocess.run([sys.executable, "-m", "rosfpga_lab", "topic", "--master-uri", m.uri,
                                  "echo", "-n", "5", "--timeout", "30", "--bag", str(bag), "/chatter"],
                                 capture_output=True, text=True, timeout=40, env=lab_env())
        finally:
            stop.set()
        assert out.returncode == 0, out.stderr
        assert f"recorded 5 messages to {bag}" in out.stderr
        env = ros_env(m.uri, tmp_path)
        info = subprocess.run(["rosbag", "info", "--yaml", str(bag)], capture_output=True, text=True,
                              timeout=30, env=env)
        assert info.returncode == 0, info.stderr
        assert "messages: 5" in info.stdout and "topic: /chatter" in info.stdout
        assert f"md5: {REG.md5('std_msgs/String')}" in info.stdout
        # rosbag play into the lab's master: a lab subscriber gets the recorded messages
        listener = Node("/listener", master=m)
        got: list[str] = []
        listener.subscribe("/chatter", "std_msgs/String", lambda v: got.append(v["data"]))
        talker.shutdown()
        play = subprocess.run(["rosbag", "play", "-q", "-d", "1", str(bag)], capture_output=True,
                              text=True, timeout=40, env=env)
        listener.shutdown()
    assert play.returncode == 0, play.stderr
    assert len(got) == 5 and all(g.startswith("m") for g in got)
    printed = [line for line in out.stdout.splitlines() if line.startswith("data: ")]
    assert [f'data: "{g}"' for g in got] == printed
