"""``rosfpga-lab fabric sim data/fpga_laserscan_min_cdr.yaml`` (issue 31 item 3) against a real
DDS peer: the whole network-attached top (LiteEth GMII, RTPS, the generated CDR circuit) in
Verilator, bridged by the shim to UDP ports on 127.0.0.1, and a PyPI Cyclone DDS participant
configured as rmw_cyclonedds_cpp is for a loopback graph (the lab's ``cyclone_loopback_uri``,
with MaxMessageSize one frame's payload: the circuit reassembles no IP fragments) that
publishes sensor_msgs/LaserScan on rt/scan and subscribes to rt/scan_min, both with ROS 2's
default QoS (RELIABLE, KEEP_LAST 10, VOLATILE).

Discovery is the circuit's own (its SPDP, SEDP and answers from its ROMs; its one peer learned
from the peer's SPDP by the circuit itself, rfl_spdp_peer: the bridge sets no register and
pulses no send_sedp). Every output is compared with
numpy (a 5-beam minimum over ``ranges``) and with the lab's CDR model, never with the circuit's
own output. rclpy (the ``[ros2]`` extra: Fast DDS, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST)
sees the fabric's node, its publisher and subscriber, their types and type hashes in its graph
API (the hash against rosidl's, copied in tests/msg/test_typehash_realros2.py). A 64x48 Image
goes through the dilation in ten DATA_FRAGs each way, exact against OpenCV; with ``--tap`` the
same scans cross a Linux TAP interface, whose capture tshark reads without a malformed packet.
The samples go out 0.3-0.5 s apart (a scanner's rate): three scans back to back at line rate
overflowed the circuit's 2 KB receive buffer once (rx_overflow counts it; the circuit's reader
asks for nothing again, so that sample is lost). Domains 230 and 231 for the model's ports (a
build per domain, address and sample bound; each cached after the first, some 15-50 s).
"""

from __future__ import annotations

import gc
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from rosfpga_lab.component.fabricsim import (
    TAP_NAME, TAP_NODE_ADDRESS, fabric_peer_uri, fabric_tap_peer_uri, fastdds_peer_profile,
)
from rosfpga_lab.config import load_config
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.rtl.discrom import render_rom
from rosfpga_lab.rtl.fabricsim import build_fabric_sim
from tests.component.test_ros2_rtl import SCAN_CDR, _assert_exact, _scans
from tests.msg.test_typehash_realros2 import GOLDEN
from tests.support.realros import ROS_PROGRAMS, require_ros2
from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.ros2tools import cyclone, image, qos, wait
from tests.support.realros import skip_or_fail
from tests.support.rtltools import REQUIRE, require_fabric_sim
from tests.support.wiretools import require_tshark

pytestmark = [pytest.mark.rtl, pytest.mark.timeout(300)]

DOMAIN = 230
SCANS = 3
#: data/fpga_dilate_rgba8_cdr.yaml at 64x48 (its 640x480 samples are 1.2 MB: a store-and-forward
#: buffer that large is not simulated here).
IMAGE_CONFIG = """\
node: {name: /fpga_dilate}
subscriber: {topic: /image_raw, type: sensor_msgs/Image}
publisher: {topic: /image_dilated, type: sensor_msgs/Image}
image: {width: 64, height: 48, encoding: rgba8}
application: {op: dilate, ksize: 3}
wire: cdr
"""
IMAGE_MAX_BYTES = 16384
#: The shipped 640x480 configuration, its sample bound (1.2 MB and the header) and its domain.
BIG_CONFIG = SCAN_CDR.parent / "fpga_dilate_rgba8_cdr.yaml"
BIG_MAX_BYTES = 1310720
BIG_DOMAIN = 229
#: The TAP test's domain (a Cyclone domain of its own in this process: another configuration).
TAP_DOMAIN = 231
IMAGES = 2


def _start_cli(tmp_path: Path, config: Path = SCAN_CDR, *extra: str,
               domain: int = DOMAIN, mode: str = "--shim") -> tuple[subprocess.Popen, list[str]]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.Popen(
        [sys.executable, "-m", "rosfpga_lab", "fabric", "sim", str(config), mode,
         "--domain", str(domain), "--seconds", "60", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
        preexec_fn=interruptible)
    lines: list[str] = []

    def pump() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line)

    threading.Thread(target=pump, daemon=True).start()
    return proc, lines


def test_cyclone_talks_to_the_simulated_fabric_and_gets_exact_scans(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    require_fabric_sim()
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", fabric_peer_uri())
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    start = time.monotonic()
    build = build_fabric_sim(config, render_rom(config, domain=DOMAIN))   # the CLI's, cached
    print(f"build {build.seconds:.1f} s (0: cached), {time.monotonic() - start:.1f} s")
    proc, lines = _start_cli(tmp_path)
    got: list = []
    sent = _scans(T, SCANS)
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        t0 = time.monotonic()
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/scan", T.LaserScan_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/scan_min", T.LaserScan_), qos=qos(dds))
        assert wait(lambda: writer.get_matched_subscriptions()
                    and reader.get_matched_publications(), 15), "".join(lines)
        matched = time.monotonic() - t0
        for msg in sent:
            writer.write(msg)
            time.sleep(0.3)
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= SCANS, 15), \
            (len(got), "".join(lines))
        print(f"matched after {matched:.2f} s, {SCANS} scans back after "
              f"{time.monotonic() - t0:.2f} s")
        del writer, reader, dp                 # its goodbye: the next test's peer is its own
        gc.collect()
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, "".join(lines)
    print(stdout)
    pipe = CdrPipeline(config)
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    counters = dict(kv.rsplit(" ", 1) for kv in
                    next(x for x in stdout.splitlines() if x.startswith("circuit: "))
                    [len("circuit: "):].split(", "))
    assert (counters["samples"], counters["judged"], counters["refused"], counters["rx_error"],
            counters["rx_overflow"], counters["tx_overflow"]) == \
        (str(SCANS), str(SCANS), "0", "0", "0", "0"), stdout
    assert counters["peer_learned"] == "1", stdout        # the circuit learned its peer itself
    assert "bridge: peers seen: 1;" in stdout and "send_sedp pulses: 0" in stdout, stdout


def test_rclpy_sees_the_fabric_node_in_the_ros2_graph(tmp_path: Path) -> None:
    """What ``ros2 node list`` / ``ros2 node info`` / ``ros2 topic list -t`` read, of the node
    whose discovery is the circuit's ROMs: the node from its ros_discovery_info sample, its
    endpoints from its SEDP data."""
    require_fabric_sim()
    require_ros2()
    config = load_config(SCAN_CDR)
    build_fabric_sim(config, render_rom(config, domain=DOMAIN))   # the CLI's, cached
    proc, lines = _start_cli(tmp_path)
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "RMW_", "FASTRTPS_", "FASTDDS_", "CYCLONEDDS_"))}
    env.update(ROS_DOMAIN_ID=str(DOMAIN), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_LOG_DIR=str(tmp_path / "ros_log"),
               ROS_HOME=str(tmp_path / "ros_home"))
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        peer = subprocess.run([sys.executable, str(ROS_PROGRAMS / "rclpy_peer.py"), "graph",
                               "fpga_scan_min", "/", "/scan", "/scan_min", "--timeout", "15",
                               "--out", str(tmp_path)], capture_output=True, text=True,
                              env=env, timeout=60)
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert peer.returncode == 0, (peer.stderr[-2000:], "".join(lines))
    report = json.loads(peer.stdout.strip().splitlines()[-1])
    print(stdout)
    assert ["fpga_scan_min", "/"] in report["nodes"], report["nodes"]
    scan = ["sensor_msgs/msg/LaserScan"]
    assert report["publishers"] == [["/scan_min", scan]]
    assert report["subscribers"] == [["/scan", scan]]
    topics = dict((name, types) for name, types in report["topics"])
    assert topics["/scan"] == topics["/scan_min"] == scan
    (sub,) = report["infos"]["/scan"]
    (pub,) = report["infos"]["/scan_min"]
    for info, kind in ((sub, "SUBSCRIPTION"), (pub, "PUBLISHER")):
        assert (info["node"], info["ns"], info["type"], info["kind"]) == \
            ("fpga_scan_min", "/", "sensor_msgs/msg/LaserScan", kind)
        assert (info["reliability"], info["durability"]) == ("RELIABLE", "VOLATILE")
        assert info["type_hash"] == GOLDEN["sensor_msgs/LaserScan"]


def _rclpy_env(tmp_path: Path, domain: int) -> dict[str, str]:
    """A real ROS 2 process on Fast DDS, loopback discovery, ``domain``; nothing of the
    caller's ROS, RMW or DDS settings."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "RMW_", "FASTRTPS_", "FASTDDS_", "CYCLONEDDS_"))}
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_LOG_DIR=str(tmp_path / "ros_log"),
               ROS_HOME=str(tmp_path / "ros_home"))
    return env


def test_rclpy_images_64x48_through_the_simulated_fabric_exact(tmp_path: Path) -> None:
    """rclpy (Fast DDS, a profile that keeps datagrams to one frame: DATA_FRAGs) publishes two
    64x48 rgba8 images with ROS 2's default QoS and subscribes to the output: each exact
    against OpenCV's dilation of what it sent (tests/ros_programs/rclpy_peer.py's pictures)."""
    from tests.flow.test_ros2_realros2 import cv2_dilate, picture

    require_fabric_sim()
    require_ros2()
    path = tmp_path / "fpga_dilate_64x48_cdr.yaml"
    path.write_text(IMAGE_CONFIG)
    config = load_config(path)
    build_fabric_sim(config, render_rom(config, domain=DOMAIN), max_bytes=IMAGE_MAX_BYTES)
    profile = tmp_path / "fastdds.xml"
    profile.write_text(fastdds_peer_profile())
    env = dict(_rclpy_env(tmp_path, DOMAIN), FASTRTPS_DEFAULT_PROFILES_FILE=str(profile))
    proc, lines = _start_cli(tmp_path, path, "--max-bytes", str(IMAGE_MAX_BYTES))
    out = tmp_path / "got"
    out.mkdir()
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        peer = subprocess.run([sys.executable, str(ROS_PROGRAMS / "rclpy_peer.py"), "relay",
                               "/image_raw", "/image_dilated", "64", "48", str(IMAGES),
                               "--out", str(out), "--timeout", "15"], input="go\n",
                              capture_output=True, text=True, env=env, timeout=60)
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert peer.returncode == 0, (peer.stderr[-2000:], "".join(lines))
    report = json.loads(peer.stdout.strip().splitlines()[-1])
    print(stdout)
    assert report["matched"] and len(report["got"]) == IMAGES, (report, stdout)
    for k in range(IMAGES):
        assert (out / f"{k}.bin").read_bytes() == cv2_dilate(picture(k, 48, 64)).tobytes(), k
    counters = _counters(stdout)
    assert (counters["samples"], counters["refused"]) == (str(IMAGES), "0"), stdout


def _counters(stdout: str) -> dict[str, str]:
    line = next(x for x in stdout.splitlines() if x.startswith("circuit: "))
    return dict(kv.rsplit(" ", 1) for kv in line[len("circuit: "):].split(", "))


def test_cyclone_images_64x48_through_the_simulated_fabric_exact(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """sensor_msgs/Image 64x48 rgba8 (12 kB: ten DATA_FRAG datagrams each way) through the
    fabric's dilation, exact against OpenCV's 3x3 dilation of what was sent."""
    require_fabric_sim()
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", fabric_peer_uri())
    path = tmp_path / "fpga_dilate_64x48_cdr.yaml"
    path.write_text(IMAGE_CONFIG)
    config = load_config(path)
    start = time.monotonic()
    build = build_fabric_sim(config, render_rom(config, domain=DOMAIN), max_bytes=IMAGE_MAX_BYTES)
    print(f"build {build.seconds:.1f} s (0: cached), {time.monotonic() - start:.1f} s")
    proc, lines = _start_cli(tmp_path, path, "--max-bytes", str(IMAGE_MAX_BYTES))
    rng = np.random.default_rng(31)
    pictures = [rng.integers(0, 256, (48, 64, 4), dtype=np.uint8) for _ in range(IMAGES)]
    got: list = []
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/image_raw", dds.Image_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/image_dilated", dds.Image_), qos=qos(dds))
        assert wait(lambda: writer.get_matched_subscriptions()
                    and reader.get_matched_publications(), 15), "".join(lines)
        t0 = time.monotonic()
        for k, pic in enumerate(pictures):
            writer.write(image(dds, pic, "rgba8", sec=k, frame_id="cam"))
            time.sleep(0.5)
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= IMAGES, 15), \
            (len(got), "".join(lines))
        print(f"{IMAGES} images back after {time.monotonic() - t0:.2f} s")
        del writer, reader, dp                 # its goodbye: the next test's peer is its own
        gc.collect()
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, "".join(lines)
    print(stdout)
    for k, (pic, out) in enumerate(zip(pictures, got, strict=True)):
        want = cv2.dilate(pic, np.ones((3, 3), np.uint8)).reshape(pic.shape)
        assert (out.height, out.width, out.encoding, out.step) == (48, 64, "rgba8", 256)
        assert (out.header.stamp.sec, out.header.frame_id) == (k, "cam")
        assert bytes(out.data) == want.tobytes(), f"image {k}"
    counters = _counters(stdout)
    assert (counters["samples"], counters["judged"], counters["refused"],
            counters["rx_overflow"]) == (str(IMAGES), str(IMAGES), "0", "0"), stdout


def test_cyclone_over_a_tap_interface_and_tshark_finds_nothing_malformed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--tap``: the circuit's frames on a Linux TAP interface (the host 10.31.0.1/24, the node
    10.31.0.2): the host's own network stack answers ARP and routes, Cyclone DDS binds that
    interface (multicast SPDP, as on a LAN); three scans exact; tshark reads a capture of the
    interface with no malformed packet; the interface is gone after the command."""
    from rosfpga_lab.graph.tap import tap_missing_reason

    require_fabric_sim()
    reason = tap_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)
    tshark = require_tshark()
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", fabric_tap_peer_uri())
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    build_fabric_sim(config, render_rom(config, domain=TAP_DOMAIN, address=TAP_NODE_ADDRESS))
    proc, lines = _start_cli(tmp_path, SCAN_CDR, domain=TAP_DOMAIN, mode="--tap")
    capture = tmp_path / "tap.pcapng"
    dump = None
    got: list = []
    sent = _scans(T, SCANS)
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        dump = subprocess.Popen([tshark, "-i", TAP_NAME, "-w", str(capture), "-q"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                preexec_fn=interruptible)
        assert wait(capture.exists, 10), "tshark did not start"
        dp = dds.DomainParticipant(TAP_DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/scan", T.LaserScan_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/scan_min", T.LaserScan_), qos=qos(dds))
        assert wait(lambda: writer.get_matched_subscriptions()
                    and reader.get_matched_publications(), 15), "".join(lines)
        for msg in sent:
            writer.write(msg)
            time.sleep(0.3)
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= SCANS, 15), \
            (len(got), "".join(lines))
        time.sleep(0.5)
        del writer, reader, dp                 # gone before the interface is
        gc.collect()
        stop_with(dump, signal.SIGINT)
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
        if dump is not None:
            kill_if_running(dump)
    assert proc.returncode == 0, "".join(lines)
    print(stdout)
    pipe = CdrPipeline(config)
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    assert _counters(stdout)["samples"] == str(SCANS), stdout

    def rows(display: str) -> list[str]:
        out = subprocess.run([tshark, "-r", str(capture), "-Y", display, "-T", "fields",
                              "-e", "frame.number"], capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        return out.stdout.split()

    assert rows("_ws.malformed || _ws.expert.severity >= error") == []
    assert len(rows(f"ip.src == {TAP_NODE_ADDRESS} && rtps.sm.id == 0x16")) >= 2 * SCANS
    assert rows(f"ip.src == {TAP_NODE_ADDRESS} && rtps.sm.id == 0x15")     # SPDP, SEDP...
    assert not Path(f"/sys/class/net/{TAP_NAME}").exists(), "the TAP interface outlived the command"


def test_one_640x480_image_fragments_through_the_simulated_fabric_exact(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """data/fpga_dilate_rgba8_cdr.yaml as shipped: one 640x480 rgba8 sample (1.2 MB: some 900
    DATA_FRAGs each way, stored whole in the circuit's buffer, --max-bytes) exact against
    OpenCV; the clock unthrottled (--rate 0). Some 10 s here, a first build some 45 s."""
    require_fabric_sim()
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", fabric_peer_uri())
    config = load_config(BIG_CONFIG)
    build_fabric_sim(config, render_rom(config, domain=BIG_DOMAIN), max_bytes=BIG_MAX_BYTES)
    proc, lines = _start_cli(tmp_path, BIG_CONFIG, "--max-bytes", str(BIG_MAX_BYTES),
                             "--rate", "0", domain=BIG_DOMAIN)
    pic = np.random.default_rng(5).integers(0, 256, (480, 640, 4), dtype=np.uint8)
    got: list = []
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        dp = dds.DomainParticipant(BIG_DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/image_raw", dds.Image_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/image_dilated", dds.Image_), qos=qos(dds))
        assert wait(lambda: writer.get_matched_subscriptions()
                    and reader.get_matched_publications(), 15), "".join(lines)
        t0 = time.monotonic()
        writer.write(image(dds, pic, "rgba8", sec=1, frame_id="cam"))
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= 1, 60), "".join(lines)
        print(f"640x480 back after {time.monotonic() - t0:.2f} s")
        del writer, reader, dp                 # its goodbye: the next test's peer is its own
        gc.collect()
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, "".join(lines)
    print(stdout)
    (out,) = got
    want = cv2.dilate(pic, np.ones((3, 3), np.uint8)).reshape(pic.shape)
    assert (out.height, out.width, out.encoding, out.step) == (480, 640, "rgba8", 2560)
    assert bytes(out.data) == want.tobytes()
    # datagrams that came while the 2 KB receive buffer was full are counted (rx_overflow: 6 in
    # a run here), none of the sample's fragments (it is exact)
    assert _counters(stdout)["samples"] == "1", stdout
