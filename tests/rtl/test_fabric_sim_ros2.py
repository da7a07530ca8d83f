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
API (the hash against rosidl's, copied in tests/msg/test_typehash_realros2.py), and its
LaserScans come back exact against numpy (Fast DDS sends each DATA_FRAG twice). A 64x48 Image
goes through the dilation in ten DATA_FRAGs each way, exact against OpenCV; with ``--tap`` the
same scans cross a Linux TAP interface, whose capture tshark reads without a malformed packet.
The samples go out 0.3-0.5 s apart (a scanner's rate): three scans back to back at line rate
overflowed the circuit's 2 KB receive buffer once (rx_overflow counts it; the circuit's reader
asks for nothing again, so that sample is lost). Domains 230 and 231 for the model's ports (a
build per domain, address and sample bound; each cached after the first, some 15-50 s).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest

from rosfpga_lab.component.fabricsim import (
    TAP_NAME, TAP_NODE_ADDRESS, fabric_tap_peer_uri, fastdds_peer_profile,
)
from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.rtl.discrom import render_rom
from rosfpga_lab.rtl.fabricsim import build_fabric_sim
from tests.component.test_ros2_rtl import SCAN_CDR, SPECIALS, _assert_exact, _scans
from tests.support.generictools import window_oracle
from tests.msg.test_typehash_realros2 import GOLDEN
from tests.support.realros import ROS_PROGRAMS, require_ros2
from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.fabricpeer import CyclonePeer, fabric_cyclone
from tests.support.ros2tools import image, wait
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


@dataclass
class _Cli:
    """``rosfpga-lab fabric sim`` running, its stderr going to a file."""

    proc: subprocess.Popen
    stderr: Path

    def stop(self) -> str:
        """Ctrl-C: its stdout (the counters) once it ended."""
        stdout, _ = stop_with(self.proc, signal.SIGINT)
        return stdout

    def log(self) -> str:
        """What it wrote on stderr so far."""
        return self.stderr.read_text(errors="replace")

    def ready(self) -> bool:
        return any(x.startswith("ready:") for x in self.log().splitlines())


@contextlib.contextmanager
def _running_cli(tmp_path: Path, config: Path = SCAN_CDR, *extra: str, domain: int = DOMAIN,
                 mode: str = "--shim") -> Iterator[_Cli]:
    """The command started and ready (the model built, the bridge bound), killed if the test
    ends before it did."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    stderr = tmp_path / "fabric_sim.stderr"
    with stderr.open("w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "rosfpga_lab", "fabric", "sim", str(config), mode,
             "--domain", str(domain), "--seconds", "60", *extra],
            stdout=subprocess.PIPE, stderr=err, text=True, env=env, cwd=tmp_path,
            preexec_fn=interruptible)
    cli = _Cli(proc, stderr)
    try:
        assert wait(lambda: cli.ready() or proc.poll() is not None, 60) \
            and proc.poll() is None, cli.log()
        yield cli
    finally:
        kill_if_running(proc)


def _build(config: NodeConfig, domain: int = DOMAIN, *, address: str = "127.0.0.1",
           max_bytes: int | None = None) -> None:
    """The model the command will take from the cache (built here first: its time printed)."""
    start = time.monotonic()
    build = build_fabric_sim(config, render_rom(config, domain=domain, address=address),
                             max_bytes=max_bytes)
    print(f"build {build.seconds:.1f} s (0: cached), {time.monotonic() - start:.1f} s")


def test_cyclone_talks_to_the_simulated_fabric_and_gets_exact_scans(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    require_fabric_sim()
    dds = fabric_cyclone(monkeypatch)
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    _build(config)
    sent = _scans(T, SCANS)
    with _running_cli(tmp_path) as cli:
        t0 = time.monotonic()
        peer = CyclonePeer(dds, DOMAIN, "rt/scan", "rt/scan_min", T.LaserScan_, cli.log)
        matched = time.monotonic() - t0
        peer.send(sent, 0.3)
        got = peer.take(SCANS, 15)
        print(f"matched after {matched:.2f} s, {SCANS} scans back after "
              f"{time.monotonic() - t0:.2f} s")
        peer.close()
        stdout = cli.stop()
    assert cli.proc.returncode == 0, cli.log()
    print(stdout)
    pipe = CdrPipeline(config)
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    counters = _counters(stdout)
    assert (counters["samples"], counters["judged"], counters["refused"], counters["rx_error"],
            counters["rx_overflow"], counters["tx_overflow"]) == \
        (str(SCANS), str(SCANS), "0", "0", "0", "0"), stdout
    assert counters["peer_learned"] == "1", stdout        # the circuit learned its peer itself
    assert "bridge: peers seen: 1;" in stdout and "send_sedp pulses: 0" in stdout, stdout


def _read_counters(host: str, domain: int) -> dict[str, int]:
    """``rosfpga-lab fabric counters --json`` against the running command (the shim's or the
    TAP's node address)."""
    from rosfpga_lab.rtl.discrom import counters_port

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    done = subprocess.run([sys.executable, "-m", "rosfpga_lab", "fabric", "counters", "--host",
                           host, "--port", str(counters_port(domain)), "--json"],
                          capture_output=True, text=True, timeout=60, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_fabric_counters_reads_the_circuit_after_a_cyclone_exchange(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``rosfpga-lab fabric counters`` (one UDP request to the circuit's counter readout, through
    the shim) after a Cyclone DDS peer sent three scans and got them back: every counter by name,
    equal to what the command prints at its end for those that did not move since (the user data
    path's, the RTPS stages'); the readout's own say one request answered. With nothing running
    on the port: a clear error, exit 1, within the timeout."""
    require_fabric_sim()
    dds = fabric_cyclone(monkeypatch)
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    _build(config)
    sent = _scans(T, SCANS)
    with _running_cli(tmp_path) as cli:
        peer = CyclonePeer(dds, DOMAIN, "rt/scan", "rt/scan_min", T.LaserScan_, cli.log)
        peer.send(sent, 0.3)
        peer.take(SCANS, 15)
        read = _read_counters("127.0.0.1", DOMAIN)
        peer.close()
        stdout = cli.stop()
    assert cli.proc.returncode == 0, cli.log()
    print(json.dumps(read), stdout)
    printed = _counters(stdout)
    assert (read["samples"], read["rtps_samples"], read["seam_samples"], read["peer_learned"],
            read["rx_error"], read["rx_overflow"]) == (SCANS, SCANS, SCANS, 1, 0, 0), read
    for key in ("samples", "rx_error", "rx_length", "rx_overflow", "tx_overflow",
                "peer_learned"):
        assert str(read[key]) == printed[key], (key, read[key], stdout)
    assert int(printed["rx_packets"]) > read["rx_packets"] > SCANS   # the request among them
    assert (read["counters_answered"], read["counters_malformed"],
            read["counters_limited"]) == (1, 0, 0)
    # the command gone: no answer, said so
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    done = subprocess.run([sys.executable, "-m", "rosfpga_lab", "fabric", "counters", "--host",
                           "127.0.0.1", "--domain", str(DOMAIN)], capture_output=True,
                          text=True, timeout=60, env=env)
    assert done.returncode == 1 and "no answer from 127.0.0.1:" in done.stderr, done.stderr
    assert "is the board up / fabric sim running?" in done.stderr


def test_rclpy_sees_the_fabric_node_in_the_ros2_graph(tmp_path: Path) -> None:
    """What ``ros2 node list`` / ``ros2 node info`` / ``ros2 topic list -t`` read, of the node
    whose discovery is the circuit's ROMs: the node from its ros_discovery_info sample, its
    endpoints from its SEDP data."""
    require_fabric_sim()
    require_ros2()
    _build(load_config(SCAN_CDR))
    with _running_cli(tmp_path) as cli:
        peer = subprocess.run([sys.executable, str(ROS_PROGRAMS / "rclpy_peer.py"), "graph",
                               "fpga_scan_min", "/", "/scan", "/scan_min", "--timeout", "15",
                               "--out", str(tmp_path)], capture_output=True, text=True,
                              env=_rclpy_env(tmp_path, DOMAIN), timeout=60)
        stdout = cli.stop()
    assert peer.returncode == 0, (peer.stderr[-2000:], cli.log())
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


def _rclpy_fabric_env(tmp_path: Path, domain: int) -> dict[str, str]:
    """:func:`_rclpy_env` with the Fast DDS profile that keeps datagrams to one frame."""
    profile = tmp_path / "fastdds.xml"
    profile.write_text(fastdds_peer_profile())
    return dict(_rclpy_env(tmp_path, domain), FASTRTPS_DEFAULT_PROFILES_FILE=str(profile))


def _scan_descriptions(n: int) -> list[dict]:
    """``n`` LaserScans for tests/ros_programs/rclpy_peer.py's ``scans`` mode: 360 beams (the
    configuration's stream), every other one of special values (signed zeros, infinities,
    NaN), float32 fields as little-endian hex."""
    rng = np.random.default_rng(31)
    out = []
    for k in range(n):
        ranges = rng.choice(SPECIALS, 360) if k % 2 else rng.uniform(0.1, 30, 360)
        f32 = {name: np.array([v], "<f4").tobytes().hex() for name, v in (
            ("angle_min", -1.5), ("angle_max", 1.5), ("angle_increment", 0.01),
            ("time_increment", 1e-5 * k), ("scan_time", 0.1), ("range_min", 0.05),
            ("range_max", 30.0))}
        out.append({"sec": 200 + k, "nanosec": 1000 * k, "frame_id": "l" * 64 if k % 2 else "laser",
                    **f32, "ranges": np.asarray(ranges, "<f4").tobytes().hex(),
                    "intensities": np.arange(k * 7 % 12, dtype="<f4").tobytes().hex()})
    return out


def test_rclpy_laserscans_through_the_simulated_fabric_exact(tmp_path: Path) -> None:
    """rclpy (Fast DDS, datagrams of one frame: each scan in two DATA_FRAGs, each sent twice)
    publishes LaserScans with ROS 2's default QoS to the fabric node of
    data/fpga_laserscan_min_cdr.yaml and subscribes to its output: each exact against numpy's
    5-beam minimum of what it sent (every other field as sent), bit for bit."""
    require_fabric_sim()
    require_ros2()
    _build(load_config(SCAN_CDR))
    env = _rclpy_fabric_env(tmp_path, DOMAIN)
    sent = _scan_descriptions(SCANS)
    (tmp_path / "scans.json").write_text(json.dumps(sent))
    with _running_cli(tmp_path) as cli:
        peer = subprocess.run([sys.executable, str(ROS_PROGRAMS / "rclpy_peer.py"), "scans",
                               "/scan", "/scan_min", str(tmp_path / "scans.json"),
                               "--timeout", "15"], input="go\n", capture_output=True,
                              text=True, env=env, timeout=60)
        stdout = cli.stop()
    assert peer.returncode == 0, (peer.stderr[-2000:], cli.log())
    report = json.loads(peer.stdout.strip().splitlines()[-1])
    print(stdout)
    assert report["matched"] and len(report["got"]) == SCANS, (report.get("matched"), stdout)
    for k, (want, got) in enumerate(zip(sent, report["got"], strict=True)):
        ranges = window_oracle(bytes.fromhex(want["ranges"]), "<f4", 5, "erode")
        assert bytes.fromhex(got["ranges"]) == ranges, k
        assert {n: v for n, v in got.items() if n != "ranges"} == \
            {n: v for n, v in want.items() if n != "ranges"}, k
    counters = _counters(stdout)
    assert (counters["samples"], counters["judged"], counters["refused"]) == \
        (str(SCANS), str(SCANS), "0"), stdout


def test_rclpy_images_64x48_through_the_simulated_fabric_exact(tmp_path: Path) -> None:
    """rclpy (Fast DDS, a profile that keeps datagrams to one frame: DATA_FRAGs) publishes two
    64x48 rgba8 images with ROS 2's default QoS and subscribes to the output: each exact
    against OpenCV's dilation of what it sent (tests/ros_programs/rclpy_peer.py's pictures)."""
    from tests.flow.test_ros2_realros2 import cv2_dilate, picture

    require_fabric_sim()
    require_ros2()
    path = tmp_path / "fpga_dilate_64x48_cdr.yaml"
    path.write_text(IMAGE_CONFIG)
    _build(load_config(path), max_bytes=IMAGE_MAX_BYTES)
    env = _rclpy_fabric_env(tmp_path, DOMAIN)
    out = tmp_path / "got"
    out.mkdir()
    with _running_cli(tmp_path, path, "--max-bytes", str(IMAGE_MAX_BYTES)) as cli:
        peer = subprocess.run([sys.executable, str(ROS_PROGRAMS / "rclpy_peer.py"), "relay",
                               "/image_raw", "/image_dilated", "64", "48", str(IMAGES),
                               "--out", str(out), "--timeout", "15"], input="go\n",
                              capture_output=True, text=True, env=env, timeout=60)
        stdout = cli.stop()
    assert peer.returncode == 0, (peer.stderr[-2000:], cli.log())
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
    dds = fabric_cyclone(monkeypatch)
    path = tmp_path / "fpga_dilate_64x48_cdr.yaml"
    path.write_text(IMAGE_CONFIG)
    _build(load_config(path), max_bytes=IMAGE_MAX_BYTES)
    rng = np.random.default_rng(31)
    pictures = [rng.integers(0, 256, (48, 64, 4), dtype=np.uint8) for _ in range(IMAGES)]
    with _running_cli(tmp_path, path, "--max-bytes", str(IMAGE_MAX_BYTES)) as cli:
        peer = CyclonePeer(dds, DOMAIN, "rt/image_raw", "rt/image_dilated", dds.Image_,
                            cli.log)
        t0 = time.monotonic()
        peer.send((image(dds, pic, "rgba8", sec=k, frame_id="cam")
                   for k, pic in enumerate(pictures)), 0.5)
        got = peer.take(IMAGES, 15)
        print(f"{IMAGES} images back after {time.monotonic() - t0:.2f} s")
        peer.close()
        stdout = cli.stop()
    assert cli.proc.returncode == 0, cli.log()
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
    interface with no malformed packet; ``rosfpga-lab fabric counters`` reads the circuit's
    counters over the interface; the interface is gone after the command."""
    from rosfpga_lab.graph.tap import tap_missing_reason

    require_fabric_sim()
    reason = tap_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)
    tshark = require_tshark()
    dds = fabric_cyclone(monkeypatch, fabric_tap_peer_uri())
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    _build(config, TAP_DOMAIN, address=TAP_NODE_ADDRESS)
    capture = tmp_path / "tap.pcapng"
    dump = None
    sent = _scans(T, SCANS)
    try:
        with _running_cli(tmp_path, SCAN_CDR, domain=TAP_DOMAIN, mode="--tap") as cli:
            dump = subprocess.Popen([tshark, "-i", TAP_NAME, "-w", str(capture), "-q"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                    preexec_fn=interruptible)
            assert wait(capture.exists, 10), "tshark did not start"
            peer = CyclonePeer(dds, TAP_DOMAIN, "rt/scan", "rt/scan_min", T.LaserScan_,
                                cli.log)
            peer.send(sent, 0.3)
            got = peer.take(SCANS, 15)
            read = _read_counters(TAP_NODE_ADDRESS, TAP_DOMAIN)    # over the TAP interface
            time.sleep(0.5)
            peer.close()                       # gone before the interface is
            stop_with(dump, signal.SIGINT)
            stdout = cli.stop()
    finally:
        if dump is not None:
            kill_if_running(dump)
    assert cli.proc.returncode == 0, cli.log()
    print(stdout)
    pipe = CdrPipeline(config)
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    assert _counters(stdout)["samples"] == str(SCANS), stdout
    assert (read["samples"], read["rtps_samples"], read["counters_answered"]) == \
        (SCANS, SCANS, 1), read

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
    dds = fabric_cyclone(monkeypatch)
    _build(load_config(BIG_CONFIG), BIG_DOMAIN, max_bytes=BIG_MAX_BYTES)
    pic = np.random.default_rng(5).integers(0, 256, (480, 640, 4), dtype=np.uint8)
    with _running_cli(tmp_path, BIG_CONFIG, "--max-bytes", str(BIG_MAX_BYTES), "--rate", "0",
                      domain=BIG_DOMAIN) as cli:
        peer = CyclonePeer(dds, BIG_DOMAIN, "rt/image_raw", "rt/image_dilated", dds.Image_,
                            cli.log)
        t0 = time.monotonic()
        peer.writer.write(image(dds, pic, "rgba8", sec=1, frame_id="cam"))
        got = peer.take(1, 60)
        print(f"640x480 back after {time.monotonic() - t0:.2f} s")
        peer.close()
        stdout = cli.stop()
    assert cli.proc.returncode == 0, cli.log()
    print(stdout)
    (out,) = got
    want = cv2.dilate(pic, np.ones((3, 3), np.uint8)).reshape(pic.shape)
    assert (out.height, out.width, out.encoding, out.step) == (480, 640, "rgba8", 2560)
    assert bytes(out.data) == want.tobytes()
    # datagrams that came while the 2 KB receive buffer was full are counted (rx_overflow: 6 in
    # a run here), none of the sample's fragments (it is exact)
    assert _counters(stdout)["samples"] == "1", stdout
