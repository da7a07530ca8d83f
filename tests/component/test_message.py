"""The FPGA component for any message type (issue 19, items 5 and 6): LaserScan and lab_msgs/Samples.

Outputs are compared with numpy written out here (a sliding min/max over the in-array window)
and with the msg layer's deserializer; frames of the shipped examples also come from real
genpy's dynamic classes (built from the .msg texts) under the system Python, and a real roscpp
program (Debian's sensor_msgs/LaserScan.h) publishes scans to the LaserScan component and
receives its output on a real rosmaster.
"""

from __future__ import annotations

import json
import struct
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.component import FpgaComponent, MessageChecker
from rosfpga_lab.config import load_config
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.hw.errors import FrameFieldError
from rosfpga_lab.hw.msgpipeline import MessagePipeline
from rosfpga_lab.msg import deserialize, new_message, serialize

from tests.support.realros import require_ros, run_ros_python

DATA = Path(__file__).resolve().parents[2] / "data"
SCAN_CONFIG = DATA / "fpga_laserscan_min.yaml"
SAMPLES_CONFIG = DATA / "fpga_samples_dilate.yaml"


def sliding(values: np.ndarray, k: int, pick) -> np.ndarray:
    r = k // 2
    return np.array([pick(values[max(0, i - r):i + r + 1]) for i in range(len(values))],
                    values.dtype)


def scan(k: int, n: int = 360) -> dict:
    rng = np.random.default_rng(k)
    reg = load_config(SCAN_CONFIG).registry()
    return {**new_message(reg, "sensor_msgs/LaserScan"),
            "header": {"seq": k, "stamp": (100 + k, k), "frame_id": "laser"},
            "angle_min": -1.5, "angle_increment": 0.01, "range_max": 30.0,
            "ranges": rng.uniform(0.1, 30, n).astype(np.float32),
            "intensities": rng.uniform(0, 1, 4).astype(np.float32)}


class Collector:
    def __init__(self, master: EmbeddedMaster, topic: str, type_name: str, registry) -> None:
        self.bodies: list[bytes] = []
        self.cond = threading.Condition()
        self.node = Node("/collector", master=master, registry=registry)
        self.sub = self.node.subscribe(topic, type_name, self._cb, raw=True, queue_size=0)

    def _cb(self, body, info) -> None:
        with self.cond:
            self.bodies.append(bytes(body))
            self.cond.notify_all()

    def wait(self, n: int, timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        with self.cond:
            while len(self.bodies) < n:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self.cond.wait(left)
        return True


@pytest.fixture
def master():
    with EmbeddedMaster(port=0) as m:
        yield m


def test_a_laserscan_component_publishes_the_minimum_filter_and_counts_refusals(master) -> None:
    config = load_config(SCAN_CONFIG)
    reg = config.registry()
    comp = FpgaComponent.from_config(config, master=master, output_queue=64).start()
    src = Node("/scanner", master=master, registry=reg)
    pub = src.advertise("/scan", "sensor_msgs/LaserScan", queue_size=0)
    out = Collector(master, "/scan_min", "sensor_msgs/LaserScan", reg)
    checker = MessageChecker(config, master=master)
    try:
        assert pub.wait_for_subscribers(2, 10) and comp.wait_for_subscribers(2, 10)
        sent = [scan(k) for k in range(4)]
        pub.publish(sent[0])
        assert comp.wait_for(1, 10)
        pub.publish(scan(9, n=359))                               # 359 beams: refused
        assert comp.wait_for(2, 10)
        pub.publish(dict(scan(8), range_max=5000.0))              # over the checked bound
        assert comp.wait_for(3, 10)
        for k, msg in enumerate(sent[1:], 1):
            pub.publish(msg)
            assert comp.wait_for(3 + k, 10)
        assert out.wait(4), comp.stats.report()
        for msg, body in zip(sent, out.bodies):
            got = deserialize(reg, "sensor_msgs/LaserScan", body)
            want = sliding(msg["ranges"], 5, np.min)
            assert np.asarray(got["ranges"]).tobytes() == want.tobytes()
            assert np.array_equal(got["intensities"], msg["intensities"])
            assert got["header"]["frame_id"] == "laser"
            assert tuple(got["header"]["stamp"]) == tuple(msg["header"]["stamp"])
            assert got["header"]["seq"] == msg["header"]["seq"]
            assert got["angle_increment"] == np.float32(0.01)
        st = comp.stats
        assert (st.published, st.refused) == (4, 2)
        assert st.refused_reasons == {"ranges length: not what the circuit was built for": 1,
                                      "range_max: over the limit": 1}
        assert st.cycles["subscriber"] == 4 + len(serialize(reg, "sensor_msgs/LaserScan", sent[-1]))
        assert checker.wait_for(4, 10), checker.mismatches
        assert (checker.inputs, checker.outputs, checker.bit_exact) == (6, 4, 4)
        # and the checker does catch a wrong output
        pub2 = src.advertise("/scan_min", "sensor_msgs/LaserScan", queue_size=0)
        assert pub2.wait_for_subscribers(2, 10)
        pub2.publish(sent[0])  # the input itself, not its minimum filter
        assert checker.wait_for(5, 10) and checker.bit_exact == 4
        assert "expected output of no input" in checker.mismatches[-1]
    finally:
        checker.stop()
        out.node.shutdown()
        src.shutdown()
        comp.stop()


def test_the_custom_message_component_dilates_samples_and_carries_the_rest(master) -> None:
    config = load_config(SAMPLES_CONFIG)
    reg = config.registry()
    comp = FpgaComponent.from_config(config, master=master, model="reference", input_queue=8,
                                     output_queue=8).start()
    src = Node("/sampler", master=master, registry=reg)
    pub = src.advertise("/samples", "lab_msgs/Samples", queue_size=0)
    out = Collector(master, "/samples_dilated", "lab_msgs/Samples", reg)
    cal = {"sensor_name": "front", "offset": [0.5, -1.0, 2.0], "mode": 2}
    samples = np.random.default_rng(1).integers(-2**31, 2**31, 64).astype(np.int32)
    msg = {"header": {"seq": 3, "stamp": (1, 2), "frame_id": "array"}, "calibration": cal,
           "label": "burst", "thresholds": [-5, 0, 5, 100], "samples": samples,
           "period": (0, 1000), "history": [cal, dict(cal, mode=7, sensor_name="")],
           "valid": True}
    try:
        assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
        pub.publish(dict(msg, calibration=dict(cal, mode=1)))     # checked mode: refused
        assert comp.wait_for(1, 10)
        pub.publish(msg)
        assert comp.wait_for(2, 10) and out.wait(1), comp.stats.report()
        got = deserialize(reg, "lab_msgs/Samples", out.bodies[0])
        expected = deserialize(reg, "lab_msgs/Samples", serialize(
            reg, "lab_msgs/Samples", dict(msg, samples=sliding(samples, 3, np.max))))
        assert serialize(reg, "lab_msgs/Samples", got) == serialize(reg, "lab_msgs/Samples", expected)
        assert comp.stats.refused_reasons == {
            "calibration.mode: not what the circuit was built for": 1}
    finally:
        out.node.shutdown()
        src.shutdown()
        comp.stop()


# -- frames from real genpy -------------------------------------------------------------------

GENPY = r"""
import json, sys, struct, io
import genpy.dynamic
spec = json.loads(sys.stdin.read())
out = {}
for name, full_text in spec["types"].items():
    classes = genpy.dynamic.generate_dynamic(name, full_text)
    cls = classes[name]
    msg = cls()
    for path, value in spec["values"][name]:
        obj = msg
        parts = path.split(".")
        for p in parts[:-1]:
            obj = getattr(obj, p)
        setattr(obj, parts[-1], value)
    if name == "lab_msgs/Samples":
        cal = classes["lab_msgs/Calibration"]
        msg.history = [cal(sensor_name="h%d" % i, offset=[i, 0.5, -i], mode=i) for i in range(3)]
    buf = io.BytesIO()
    msg.serialize(buf)
    out[name] = {"md5": cls._md5sum, "body": buf.getvalue().hex()}
print(json.dumps(out))
"""


def test_frames_from_real_genpy_through_the_shipped_examples() -> None:
    require_ros()
    scan_cfg, samples_cfg = load_config(SCAN_CONFIG), load_config(SAMPLES_CONFIG)
    ranges = [float(x) for x in np.linspace(0.5, 20, 360, dtype=np.float32)]
    ranges[100] = 0.25
    samples = [(-1) ** i * i * 1000 for i in range(64)]
    spec = {
        "types": {"sensor_msgs/LaserScan": scan_cfg.registry().full_text("sensor_msgs/LaserScan"),
                  "lab_msgs/Samples": samples_cfg.registry().full_text("lab_msgs/Samples")},
        "values": {
            "sensor_msgs/LaserScan": [["header.frame_id", "laser"], ["header.seq", 4],
                                      ["angle_min", -1.0], ["range_max", 25.0],
                                      ["ranges", ranges], ["intensities", [1.0, 2.0]]],
            "lab_msgs/Samples": [["header.frame_id", "arr"], ["calibration.mode", 2],
                                 ["calibration.sensor_name", "front"],
                                 ["calibration.offset", [1.0, 2.0, 3.0]], ["label", "genpy"],
                                 ["thresholds", [1, -2, 3, -4]], ["samples", samples],
                                 ["valid", True]]},
    }
    proc = run_ros_python(GENPY, input=json.dumps(spec).encode())
    got = json.loads(proc.stdout)
    for cfg, type_name, stream, k, pick in (
            (scan_cfg, "sensor_msgs/LaserScan", "ranges", 5, np.min),
            (samples_cfg, "lab_msgs/Samples", "samples", 3, np.max)):
        reg = cfg.registry()
        assert got[type_name]["md5"] == reg.md5(type_name)
        body = bytes.fromhex(got[type_name]["body"])
        frame = struct.pack("<I", len(body)) + body
        want_in = deserialize(reg, type_name, body)
        for model in ("fast", "reference"):
            res = MessagePipeline.from_config(cfg, model=model, reg=reg).process(frame)
            src = np.asarray(want_in[stream])
            assert res.input_stream.tobytes() == src.tobytes()
            out = deserialize(reg, type_name, res.output_frame[4:])
            assert np.asarray(out[stream]).tobytes() == sliding(src, k, pick).tobytes()
            # everything else is carried: the output with the input's stream is genpy's body
            restored = serialize(reg, type_name, dict(out, **{stream: src}))
            assert restored == body
    bad = bytearray(bytes.fromhex(got["lab_msgs/Samples"]["body"]))
    with pytest.raises(FrameFieldError, match="calibration.mode"):
        pipe = MessagePipeline.from_config(samples_cfg, reg=samples_cfg.registry())
        mode_at = 12 + 4 + 3 + 4 + 5 + 24  # header (seq, stamp, "arr"), sensor_name, offset
        bad[mode_at] = 9
        pipe.process(struct.pack("<I", len(bad)) + bytes(bad))


def test_the_node_and_topic_pub_commands_run_a_custom_type_end_to_end(master) -> None:
    """``rosfpga-lab node CONFIG`` for lab_msgs/Samples, fed by ``rosfpga-lab topic pub
    --msg-path`` (both real command lines, as subprocesses)."""
    import os
    import subprocess
    import sys

    reg = load_config(SAMPLES_CONFIG).registry()
    out = Collector(master, "/samples_dilated", "lab_msgs/Samples", reg)
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    cmd = [sys.executable, "-m", "rosfpga_lab"]
    node = subprocess.Popen(cmd + ["node", str(SAMPLES_CONFIG), "--master-uri", master.uri,
                                   "--duration", "8", "-q"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    samples = [(i * 37) % 101 - 50 for i in range(64)]
    value = json.dumps({"calibration": {"mode": 2}, "label": "cli", "samples": samples})
    try:
        assert out.sub.wait_for_connection(1, 15), node.stderr.read() if node.poll() else "no node"
        pub = subprocess.run(cmd + ["topic", "--master-uri", master.uri, "--msg-path",
                                    str(DATA / "msg"), "pub", "-1", "/samples",
                                    "lab_msgs/Samples", value],
                             env=env, capture_output=True, text=True, timeout=30)
        assert pub.returncode == 0, pub.stderr
        assert out.wait(1, 10)
    finally:
        node.terminate()
        node.communicate(timeout=15)
        out.node.shutdown()
    got = deserialize(reg, "lab_msgs/Samples", out.bodies[0])
    want = sliding(np.array(samples, np.int32), 3, np.max)
    assert np.asarray(got["samples"]).tolist() == want.tolist()
    assert got["label"] == "cli" and got["calibration"]["mode"] == 2


RAW_ROSPY = r"""
import json, sys, threading
import genpy.dynamic, rospy
spec = json.loads(sys.stdin.read())
classes = genpy.dynamic.generate_dynamic("lab_msgs/Samples", spec["full_text"])
Samples, Calibration = classes["lab_msgs/Samples"], classes["lab_msgs/Calibration"]
rospy.init_node("rospy_samples", disable_signals=True)
got, done = [], threading.Event()
def cb(msg):
    got.append({"samples": list(msg.samples), "label": msg.label, "seq": msg.header.seq,
                "history": [h.sensor_name for h in msg.history], "mode": msg.calibration.mode})
    if len(got) >= len(spec["bursts"]):
        done.set()
sub = rospy.Subscriber("/samples_dilated", Samples, cb)
pub = rospy.Publisher("/samples", Samples, queue_size=10)
deadline = rospy.get_time() + 20
while (pub.get_num_connections() < 1 or sub.get_num_connections() < 1) and rospy.get_time() < deadline:
    rospy.sleep(0.05)
for k, burst in enumerate(spec["bursts"]):
    m = Samples()
    m.header.seq, m.header.frame_id = k, "rospy"
    m.calibration = Calibration(sensor_name="c", offset=[0.0, 1.0, 2.0], mode=2)
    m.label, m.samples = "burst %d" % k, burst
    m.history = [Calibration(sensor_name="h%d" % i, offset=[0.0] * 3, mode=1) for i in range(k)]
    pub.publish(m)
done.wait(20)
print(json.dumps(got), flush=True)
rospy.signal_shutdown("done")
"""


#: The component's data path in the real-ROS tests: the Python model, and the generated circuit's
#: Verilog in the fast harness (``--model rtl``, issue 28 item 3).
MODELS = ["fast", pytest.param("rtl", marks=pytest.mark.rtl)]


@pytest.mark.ros
@pytest.mark.parametrize("model", MODELS)
def test_real_rospy_with_genpys_dynamic_classes_talks_to_the_custom_component(
        model, rosmaster_uri, tmp_path) -> None:
    import subprocess

    from tests.support.realros import ROS_PYTHON, require_rtl, ros_env

    if model == "rtl":
        require_rtl("verilator")
    config = load_config(SAMPLES_CONFIG)
    # queues as deep as the run: this test is about every message coming out right
    comp = FpgaComponent.from_config(config, master_uri=rosmaster_uri, input_queue=16,
                                     output_queue=16, model=model).start()
    rng = np.random.default_rng(5)
    bursts = [rng.integers(-1000, 1000, 64).tolist() for _ in range(3)]
    spec = {"full_text": config.registry().full_text("lab_msgs/Samples"), "bursts": bursts}
    try:
        proc = subprocess.run([ROS_PYTHON, "-c", RAW_ROSPY], input=json.dumps(spec).encode(),
                              env=ros_env(rosmaster_uri, tmp_path), capture_output=True,
                              timeout=60)
        assert proc.returncode == 0, proc.stderr.decode(errors="replace")[-2000:]
    finally:
        comp.stop()
    got = sorted(json.loads(proc.stdout.decode().strip().splitlines()[-1]), key=lambda g: g["label"])
    # rospy numbers header.seq itself (1, 2, 3); the circuit carries it
    assert [g["seq"] for g in got] == [1, 2, 3], comp.stats.report()
    for k, g in enumerate(got):
        assert g["samples"] == sliding(np.array(bursts[k], np.int32), 3, np.max).tolist()
        assert (g["label"], g["mode"], g["history"]) == (f"burst {k}", 2, [f"h{i}" for i in range(k)])


def _laserscan_by_hand(body: bytes) -> dict:
    """A sensor_msgs/LaserScan body decoded with struct (independent of the lab's decoders)."""
    seq, secs, nsecs, n = struct.unpack_from("<IIII", body, 0)
    pos = 16
    frame_id = body[pos:pos + n].decode()
    pos += n
    floats = struct.unpack_from("<7f", body, pos)
    pos += 28
    (n,) = struct.unpack_from("<I", body, pos)
    ranges = body[pos + 4:pos + 4 + 4 * n]
    pos += 4 + 4 * n
    (n,) = struct.unpack_from("<I", body, pos)
    intensities = struct.unpack_from(f"<{n}f", body, pos + 4)
    assert pos + 4 + 4 * n == len(body)
    return {"seq": seq, "stamp": (secs, nsecs), "frame_id": frame_id, "floats": floats,
            "ranges": ranges, "intensities": intensities}


@pytest.mark.ros
@pytest.mark.parametrize("model", MODELS)
def test_real_roscpp_laserscans_through_the_component_come_out_min_filtered_exactly(
        model, rosmaster_uri, tmp_path) -> None:
    """Issue 19 item 5: a real roscpp program (Debian's sensor_msgs/LaserScan.h) publishes to
    the LaserScan component on a real rosmaster and receives its output: a 359-beam scan is
    refused by name, every good one comes out as numpy's sliding minimum, the rest carried."""
    import subprocess

    from tests.support.realros import (
        ROS_PROGRAMS, build_roscpp_program, finish, require_rtl, ros_env, stop_process,
    )

    require_ros()
    if model == "rtl":
        require_rtl("verilator")
    binary = build_roscpp_program(ROS_PROGRAMS / "scan_roscpp_pubsub.cpp")
    rng = np.random.default_rng(19)
    scans = [rng.uniform(0.1, 30, 359).astype(np.float32)]            # refused: 359 beams
    scans += [rng.uniform(0.1, 30, 360).astype(np.float32) for _ in range(3)]
    scans[2][[0, 100, 359]] = [-np.inf, 0.0, np.inf]                   # the extremes too
    infile, outfile = tmp_path / "scans.bin", tmp_path / "out.bin"
    infile.write_bytes(b"".join(struct.pack("<I", len(s)) + s.tobytes() for s in scans))
    good = len(scans) - 1
    comp = FpgaComponent.from_config(SCAN_CONFIG, master_uri=rosmaster_uri, input_queue=8,
                                     output_queue=8, model=model).start()
    proc = subprocess.Popen([str(binary), "/scan", "/scan_min", str(infile), str(good),
                             str(outfile), "20"], env=ros_env(rosmaster_uri, tmp_path),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        finish(proc, 40)
        stats = comp.stats
    finally:
        stop_process(proc)
        comp.stop()
    data = outfile.read_bytes()
    bodies, pos = [], 0
    while pos < len(data):
        (n,) = struct.unpack_from("<I", data, pos)
        bodies.append(data[pos + 4:pos + 4 + n])
        pos += 4 + n
    assert len(bodies) == good, stats.report()
    assert (stats.published, stats.refused) == (good, 1)
    assert stats.refused_reasons == {
        "fast": {"ranges length: not what the circuit was built for": 1},
        "rtl": {"circuit status 4: SUB_BAD_RANGES_LENGTH": 1}}[model]
    for body in bodies:
        got = _laserscan_by_hand(body)
        k = got["stamp"][1]                       # the program stamps scan k with (100 + k, k)
        assert got["stamp"] == (100 + k, k) and 1 <= k <= good
        want = sliding(scans[k], 5, np.min)
        assert got["ranges"] == want.tobytes(), f"scan {k}"
        assert got["frame_id"] == "laser" and got["intensities"] == (float(k), 0.5)
        assert got["floats"] == struct.unpack("<7f", struct.pack(
            "<7f", -1.5, 1.5, 0.01, 0.0, 0.0, 0.05, 30.0))
        assert got["seq"] == k      # roscpp numbers from 0 (the refused scan); the circuit carries it
    assert sorted(_laserscan_by_hand(b)["stamp"][1] for b in bodies) == list(range(1, good + 1))
