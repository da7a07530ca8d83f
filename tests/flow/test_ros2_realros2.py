"""The FPGA component as a ROS 2 node against REAL ROS 2: Jazzy's rclpy on Fast DDS
(rmw_fastrtps_cpp), from the ``[ros2]`` extra's PyPI wheels.

rclpy runs only in subprocesses of this Python (tests/ros_programs/rclpy_peer.py), each bounded
in time, in a DDS domain of this test process's own, on loopback: ROS_AUTOMATIC_DISCOVERY_RANGE
=LOCALHOST (Jazzy) keeps Fast DDS's discovery off the network; the lab's participant announces
itself to the discovery ports of indices 0..9 on 127.0.0.1, where Fast DDS listens, and Fast DDS
answers it. Every image that comes back is compared with OpenCV run on what rclpy sent (never
with the lab's own models). Skips without rclpy; fails under ROSFPGA_REQUIRE_ROS2=1 (CI).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.realros import ROS_PROGRAMS, require_ros2, stop_process
from tests.support.ros2tools import DOMAIN, wait
from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.component.sources import open_source
from rosfpga_lab.config import parse_config

pytestmark = pytest.mark.timeout(120)

PEER = ROS_PROGRAMS / "rclpy_peer.py"
#: This process's DDS domain for real ROS 2 (ros2tools' DOMAIN + 7 and + 21 are taken).
REAL_DOMAIN = (DOMAIN + 50) % 233
CONFIG = """\
node: {{name: {name}}}
subscriber: {{topic: {topic}, type: sensor_msgs/Image}}
publisher: {{topic: {topic}_out, type: sensor_msgs/Image}}
image: {{width: {w}, height: {h}, encoding: rgba8}}
application: {{op: dilate, ksize: 3}}
"""


def picture(k: int, h: int, w: int) -> np.ndarray:
    """What rclpy_peer.py publishes as frame k (the same numpy generator)."""
    return np.random.default_rng(k).integers(0, 256, (h, w, 4), dtype=np.uint8)


def cv2_dilate(img: np.ndarray) -> np.ndarray:
    return cv2.dilate(img, np.ones((3, 3), np.uint8)).reshape(img.shape)


def ros2_env(tmp: Path) -> dict[str, str]:
    """The environment of a real ROS 2 process: this domain, loopback discovery, Fast DDS,
    logs under ``tmp``; no ROS_/RMW_/Fast DDS setting of the caller's leaks in."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "RMW_", "FASTRTPS_", "FASTDDS_", "CYCLONEDDS_"))}
    env.update(ROS_DOMAIN_ID=str(REAL_DOMAIN), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_LOG_DIR=str(tmp / "ros_log"),
               ROS_HOME=str(tmp / "ros_home"))
    return env


def rclpy_peer(tmp: Path, mode: str, *args: object, timeout: float = 15.0,
               matched: Callable[[], bool] | None = None,
               options: tuple[str, ...] = ()) -> tuple[dict, Path]:
    """Run rclpy_peer.py MODE ARGS; its JSON report and the folder of the frames it received.
    ``matched``: the relay's go-ahead, once it says true (the lab has matched its writer)."""
    out = tmp / f"rclpy-{mode}"
    out.mkdir(exist_ok=True)
    proc = subprocess.Popen([sys.executable, str(PEER), mode, *map(str, args), "--out", str(out),
                             "--timeout", str(timeout), *options], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=ros2_env(tmp))
    try:
        if matched is not None:
            assert proc.stdout is not None and proc.stdin is not None
            first = proc.stdout.readline()      # within the peer's own timeout
            assert first.strip() == "matched" and wait(matched, 10), first
            proc.stdin.write("go\n")
            proc.stdin.flush()
        stdout, stderr = proc.communicate(timeout=timeout + 30)
    finally:
        stop_process(proc)
    assert proc.returncode == 0, stderr[-3000:]
    return json.loads(stdout.strip().splitlines()[-1]), out


class Labs:
    """The lab's components for the whole module (one DDS domain): a small one, 64x48, named
    /lab/fpga_ros2 (a namespace), and one for 640x480 frames (fragmented both ways)."""

    def __init__(self) -> None:
        self.small = Ros2Component(parse_config(CONFIG.format(
            name="/lab/fpga_ros2", topic="/cam", w=64, h=48)), domain=REAL_DOMAIN)
        self.big = Ros2Component(parse_config(CONFIG.format(
            name="/fpga_big", topic="/big", w=640, h=480)), domain=REAL_DOMAIN)


@pytest.fixture(scope="module")
def labs() -> Iterator[Labs]:
    require_ros2()
    labs = Labs()
    with labs.small, labs.big:
        yield labs


@pytest.mark.parametrize("which,topic,w,h,n", [("small", "/cam", 64, 48, 5),
                                               ("big", "/big", 640, 480, 1)])
def test_rclpy_images_through_the_component_exact(labs: Labs, tmp_path: Path, which: str,
                                                  topic: str, w: int, h: int, n: int) -> None:
    """rclpy publisher (RELIABLE KEEP_LAST 10) -> component -> rclpy subscriber (the same)."""
    comp = getattr(labs, which)
    before = dict(comp.counts)
    (reader_id,) = comp.node._subs

    def writers() -> set[bytes]:     # remote writers the lab's input reader is matched with
        with comp.node._lock:
            return set(comp.node.participant.matched(reader_id))

    earlier = writers()
    report, out = rclpy_peer(tmp_path, "relay", topic, f"{topic}_out", w, h, n,
                             matched=lambda: bool(writers() - earlier))
    assert report["matched"], comp.notes()
    got = report["got"]
    assert len(got) == n, (got, comp.counts, comp.notes())
    for k, s in enumerate(got):
        assert (s["width"], s["height"], s["encoding"], s["step"]) == (w, h, "rgba8", 4 * w)
        assert (s["sec"], s["nanosec"], s["frame_id"]) == (1700000000 + k, 500, "rclpy")
        data = np.frombuffer((out / f"{k}.bin").read_bytes(), np.uint8).reshape(h, w, 4)
        assert np.array_equal(data, cv2_dilate(picture(k, h, w))), f"sample {k}"
    assert {k: comp.counts[k] - before[k] for k in before} == \
        {"seen": n, "published": n, "refused": 0}


def test_rclpy_sees_the_component_in_the_ros2_graph(labs: Labs, tmp_path: Path) -> None:
    """What ``ros2 node list`` / ``ros2 node info`` / ``ros2 topic list -t`` read: the node
    from ros_discovery_info, its endpoints from SEDP, matched by GID."""
    report, _ = rclpy_peer(tmp_path, "graph", "fpga_ros2", "/lab", "/cam", "/cam_out", "/big",
                           timeout=10, options=("--node", "/fpga_big"))
    nodes = {tuple(x) for x in report["nodes"]}
    assert {("fpga_ros2", "/lab"), ("fpga_big", "/")} <= nodes, nodes
    image = ["sensor_msgs/msg/Image"]
    assert report["publishers"] == [["/cam_out", image]]
    assert report["subscribers"] == [["/cam", image]]
    topics = dict((name, types) for name, types in report["topics"])
    assert topics["/cam"] == topics["/cam_out"] == topics["/big"] == topics["/big_out"] == image
    (sub,) = report["infos"]["/cam"]
    (pub,) = report["infos"]["/cam_out"]
    for info, kind in ((sub, "SUBSCRIPTION"), (pub, "PUBLISHER")):
        assert (info["node"], info["ns"], info["type"], info["kind"]) == \
            ("fpga_ros2", "/lab", "sensor_msgs/msg/Image", kind)
        assert (info["reliability"], info["durability"]) == ("RELIABLE", "VOLATILE")


def test_best_effort_rclpy_publisher_never_matches_the_reliable_input(labs: Labs,
                                                                      tmp_path: Path) -> None:
    comp = labs.small
    seen = comp.counts["seen"]
    report, _ = rclpy_peer(tmp_path, "best_effort", "/cam", timeout=8)
    assert report["subscribers_seen"] >= 1 and report["matched"] == 0, report
    # Fast DDS says why too: the RELIABILITY policy (rclpy's incompatible-QoS event)
    assert any("RELIABILITY" in e for e in report["incompatible"]), report
    why = "a BEST_EFFORT writer never matches a RELIABLE reader"
    assert any(why in note and "reader rt/cam " in note for note in comp.notes()), comp.notes()
    assert comp.counts["seen"] == seen


def test_camera_ros2_to_an_rclpy_subscriber(labs: Labs, tmp_path: Path) -> None:
    source = open_source("synthetic", 32, 16, "rgba8")
    frames = [source.frame(k) for k in range(source.period)]
    env = dict(ros2_env(tmp_path), PYTHONPATH=os.pathsep.join(sys.path))
    cam = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "camera", "--ros2", "--domain",
                            str(REAL_DOMAIN), "--topic", "/cam_r2", "--size", "32x16", "--rate",
                            "20", "--count", "400", "--name", "/camera_r2"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    try:
        report, out = rclpy_peer(tmp_path, "listen", "/cam_r2", 3, timeout=15)
    finally:
        stop_process(cam)
    got = report["got"]
    assert len(got) == 3, got
    for k, s in enumerate(got):
        assert (s["width"], s["height"], s["encoding"], s["step"], s["frame_id"]) == \
            (32, 16, "rgba8", 128, "camera")
        data = np.frombuffer((out / f"{k}.bin").read_bytes(), np.uint8).reshape(16, 32, 4)
        assert any(np.array_equal(data, f) for f in frames), f"frame {k} is none the camera has"


def test_rclpy_publisher_to_view_ros2(labs: Labs, tmp_path: Path) -> None:
    save = tmp_path / "view"
    env = dict(ros2_env(tmp_path), PYTHONPATH=os.pathsep.join(sys.path))
    view = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "view", "/view_r2", "--ros2",
                             "--domain", str(REAL_DOMAIN), "--count", "3", "--timeout", "20",
                             "--save", str(save), "--name", "/viewer_r2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        report, _ = rclpy_peer(tmp_path, "talk", "/view_r2", 32, 16, 3, timeout=15)
        out, err = view.communicate(timeout=20)
    finally:
        stop_process(view)
    assert report["matched"] and view.returncode == 0, out + err
    pngs = sorted(save.glob("frame_*.png"))
    assert len(pngs) == 3, out
    for k, png in enumerate(pngs):
        rgb = cv2.cvtColor(cv2.imread(str(png), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
        assert np.array_equal(rgb, picture(k, 16, 32)[..., :3]), png.name
