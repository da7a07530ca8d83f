"""The FPGA component in a real ROS 1 graph (Debian's rosmaster, rospy, rostopic).

A real rospy publisher feeds the component, a real rospy or roscpp subscriber receives its output; every
frame received must be OpenCV's dilation of a frame sent (compared byte for byte, found by
stamp), with the header carried. ``rostopic`` must see the component like any node.
These tests skip without ROS and fail under CI when ROS is missing (tests/support/realros.py).
"""

from __future__ import annotations

import signal
import struct
import subprocess
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.proctools import interruptible
from tests.support.realros import (
    ROS_PROGRAMS, ROS_PYTHON, build_roscpp_program, finish, free_port, require_ros, ros_env,
    stop_process, wait_for_master, wait_line,
)
from rosfpga_lab.component import Camera, FpgaComponent
from rosfpga_lab.config import load_config

pytestmark = pytest.mark.ros

CONFIG = Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml"


def records(path: Path) -> list[bytes]:
    """Complete ``uint32 length + bytes`` records (a killed writer may leave a partial last one)."""
    data = path.read_bytes()
    out, pos = [], 0
    while pos + 4 <= len(data):
        (n,) = struct.unpack_from("<I", data, pos)
        if pos + 4 + n > len(data):
            break
        out.append(data[pos + 4:pos + 4 + n])
        pos += 4 + n
    return out


def parse_image(body: bytes) -> dict:
    """A sensor_msgs/Image body, decoded by hand (independent of the lab's decoders)."""
    seq, secs, nsecs, n = struct.unpack_from("<IIII", body, 0)
    pos = 16
    frame_id = body[pos:pos + n].decode()
    pos += n
    height, width, n = struct.unpack_from("<III", body, pos)
    pos += 12
    encoding = body[pos:pos + n].decode()
    pos += n
    bigendian, step, n = struct.unpack_from("<BII", body, pos)
    pos += 9
    return {"seq": seq, "stamp": (secs, nsecs), "frame_id": frame_id, "height": height,
            "width": width, "encoding": encoding, "is_bigendian": bigendian, "step": step,
            "data": body[pos:pos + n], "end": pos + n}


def start(cmd: list[str], uri: str, tmp_path: Path) -> subprocess.Popen:
    proc = subprocess.Popen(cmd, env=ros_env(uri, tmp_path), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    wait_line(proc, b"READY", 30)
    return proc


@pytest.mark.parametrize("subscriber", ["rospy", "roscpp"])
def test_rospy_publisher_component_real_subscriber_every_frame_bit_exact(
        rosmaster_uri, tmp_path, subscriber) -> None:
    count = 20
    if subscriber == "roscpp":
        sub_cmd = [str(build_roscpp_program(ROS_PROGRAMS / "component_roscpp_sub.cpp"))]
    else:
        sub_cmd = [ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "sub"]
    # Queues as deep as the run: this test is about every frame coming out bit-exact; the
    # drop-oldest policy under a slow subscriber is tested in test_node.py.
    comp = FpgaComponent.from_config(CONFIG, master_uri=rosmaster_uri, input_queue=count,
                                     output_queue=count).start()
    procs = []
    try:
        sent_file, got_file = tmp_path / "sent.bin", tmp_path / "got.bin"
        sub = start(sub_cmd + ["/image_dilated", str(count), str(got_file), "60"], rosmaster_uri,
                    tmp_path)
        procs.append(sub)
        assert comp.wait_for_subscribers(1, 20), "the rospy subscriber never connected"
        pub = start([ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "pub", "/image_raw",
                     str(count), "640", "480", "rgba8", str(sent_file), "10", "60"],
                    rosmaster_uri, tmp_path)
        procs.append(pub)
        finish(pub)
        finish(sub)
        stats = comp.stats
    finally:
        for p in procs:
            stop_process(p)
        comp.stop()
    sent = {parse_image(b)["stamp"]: parse_image(b) for b in records(sent_file)}
    got = [parse_image(b) for b in records(got_file)]
    assert len(sent) == count
    assert len(got) == count, stats.report()
    for out in got:
        src = sent[out["stamp"]]
        image = np.frombuffer(src["data"], np.uint8).reshape(480, 640, 4)
        want = cv2.dilate(image, np.ones((3, 3), np.uint8))
        assert out["data"] == want.tobytes(), f"frame with stamp {out['stamp']}"
        for key in ("frame_id", "height", "width", "encoding", "is_bigendian", "step"):
            assert out[key] == src[key], key
    assert sorted(o["seq"] for o in got) == list(range(1, count + 1))  # the generator counts
    assert stats.refused == 0 and stats.dropped == 0 and stats.published == count


def _tool(args: list[str], env: dict, timeout: float = 30.0) -> str:
    proc = subprocess.run(args, env=env, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, f"{args}: {proc.stdout}\n{proc.stderr}"
    return proc.stdout


def test_rostopic_sees_the_component_like_any_node(rosmaster_uri, tmp_path) -> None:
    cfg = load_config(CONFIG)
    comp = FpgaComponent.from_config(cfg, master_uri=rosmaster_uri).start()
    cam = Camera("/image_raw", rate=20, source="synthetic", master_uri=rosmaster_uri,
                 name="/lab_camera")
    env = ros_env(rosmaster_uri, tmp_path)
    hz = None
    try:
        cam.start(duration=25)
        info = _tool(["rostopic", "info", "/image_dilated"], env)
        assert "Type: sensor_msgs/Image" in info
        pubs = info.split("Publishers:")[1].split("Subscribers:")[0]
        assert f"* /fpga_dilate ({comp.node.uri})" in pubs
        info_in = _tool(["rostopic", "info", "/image_raw"], env)
        assert "/fpga_dilate" in info_in.split("Subscribers:")[1]
        assert "/image_dilated" in _tool(["rostopic", "list"], env).split()
        assert _tool(["rostopic", "type", "/image_dilated"], env).strip() == "sensor_msgs/Image"
        # rostopic hz: a real subscriber measuring the component's output rate
        hz = subprocess.Popen(["rostopic", "hz", "/image_dilated"], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, preexec_fn=interruptible)
        time.sleep(6)
        hz.send_signal(signal.SIGINT)
        out, err = hz.communicate(timeout=15)
        rates = [float(line.split(":")[1]) for line in out.splitlines()
                 if line.strip().startswith("average rate:")]
        assert rates, out + err
        assert 12.0 < rates[-1] < 28.0, out  # the camera publishes at 20/s
        assert comp.stats.published > 50 and comp.stats.refused == 0
    finally:
        if hz is not None and hz.poll() is None:
            stop_process(hz)
        cam.stop()
        comp.stop()


def test_component_survives_a_real_rosmaster_restart(tmp_path) -> None:
    require_ros()
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    log = open(tmp_path / "rosmaster.log", "wb")

    def rosmaster() -> subprocess.Popen:
        proc = subprocess.Popen(["rosmaster", "--core", "-p", str(port), "-w", "2"],
                                env=ros_env(uri, tmp_path), stdout=log, stderr=subprocess.STDOUT)
        wait_for_master(uri)
        return proc

    master = rosmaster()
    comp = FpgaComponent.from_config(CONFIG, master_uri=uri).start()
    procs = []
    try:
        stop_process(master)                       # the master dies ...
        time.sleep(1.5)
        assert not comp.stats.master_ok
        master = rosmaster()                       # ... and comes back with an empty registry
        deadline = time.monotonic() + 10
        while comp.stats.master_reregistrations == 0 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert comp.stats.master_reregistrations == 1
        got_file, sent_file = tmp_path / "got.bin", tmp_path / "sent.bin"
        sub = start([ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "sub",
                     "/image_dilated", "5", str(got_file), "40"], uri, tmp_path)
        procs.append(sub)
        assert comp.wait_for_subscribers(1, 20)
        pub = start([ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "pub", "/image_raw",
                     "5", "640", "480", "rgba8", str(sent_file), "10", "40"], uri, tmp_path)
        procs.append(pub)
        finish(pub)
        finish(sub)
        got = [parse_image(b) for b in records(got_file)]
        sent = {parse_image(b)["stamp"]: parse_image(b) for b in records(sent_file)}
        assert len(got) == 5
        for out in got:
            image = np.frombuffer(sent[out["stamp"]]["data"], np.uint8).reshape(480, 640, 4)
            assert out["data"] == cv2.dilate(image, np.ones((3, 3), np.uint8)).tobytes()
    finally:
        for p in procs:
            stop_process(p)
        comp.stop()
        stop_process(master)
        log.close()


def test_parse_image_reads_what_the_lab_writes() -> None:
    """The hand decoder above, checked on a frame with known fields (so it cannot pass vacuously)."""
    from rosfpga_lab.hw import image_frame

    img = np.arange(2 * 3 * 4, dtype=np.uint8).reshape(2, 3, 4)
    body = image_frame(img, "rgba8", seq=5, stamp=(6, 7), frame_id="abc")[4:]
    m = parse_image(body)
    assert (m["seq"], m["stamp"], m["frame_id"], m["height"], m["width"], m["encoding"],
            m["step"], m["data"], m["end"]) == (5, (6, 7), "abc", 2, 3, "rgba8", 12, img.tobytes(),
                                                len(body))



def test_real_publisher_killed_and_restarted_component_keeps_serving(rosmaster_uri,
                                                                      tmp_path) -> None:
    from rosfpga_lab.graph import Node

    comp = FpgaComponent.from_config(CONFIG, master_uri=rosmaster_uri).start()
    got: list[bytes] = []
    lab = Node("/collector", master_uri=rosmaster_uri)
    lab.subscribe("/image_dilated", "sensor_msgs/Image", lambda b, _i: got.append(bytes(b)),
                  raw=True, queue_size=0)
    procs = []
    pub_cmd = [ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "pub", "/image_raw"]
    try:
        assert comp.wait_for_subscribers(1, 20)
        first = start(pub_cmd + ["0", "640", "480", "rgba8", str(tmp_path / "a.bin"), "10", "60"],
                      rosmaster_uri, tmp_path)
        procs.append(first)
        deadline = time.monotonic() + 20
        while len(got) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(got) >= 3
        first.kill()                                   # dies without unregistering
        first.wait(10)
        deadline = time.monotonic() + 10
        while comp.stats.publishers and time.monotonic() < deadline:
            time.sleep(0.05)
        assert comp.stats.publishers == 0 and comp.running
        before = len(got)
        second = start(pub_cmd + ["5", "640", "480", "rgba8", str(tmp_path / "b.bin"), "10", "60"],
                       rosmaster_uri, tmp_path)        # same node name, new URI
        procs.append(second)
        finish(second)
        after = [parse_image(b) for b in got[before:]]
        sent = {parse_image(b)["stamp"]: parse_image(b) for b in records(tmp_path / "b.bin")}
        assert len(after) == 5, comp.stats.report()
        for out in after:
            image = np.frombuffer(sent[out["stamp"]]["data"], np.uint8).reshape(480, 640, 4)
            assert out["data"] == cv2.dilate(image, np.ones((3, 3), np.uint8)).tobytes()
        assert comp.stats.refused == 0
    finally:
        for p in procs:
            stop_process(p)
        lab.shutdown()
        comp.stop()
