"""Benchmark: 640x480 rgba8 sensor_msgs/Image over TCPROS on loopback.

Prints, in one run, frames/s (back-to-back burst) and latency (frames paced at 10 Hz,
publish-to-callback, measured with the wall-clock stamp in header.stamp) for:

* the lab's publisher -> the lab's subscriber, in two processes and in one process;
* with real ROS 1 installed: rospy -> rospy, roscpp -> roscpp, lab -> roscpp, roscpp -> lab.

Every pair registers with one lab EmbeddedMaster (the master is not on the data path).
"sub CPU" is the CPU time the lab's subscribing process spent per frame during the burst (all
its threads; in the one-process rows the publisher's work is included), "-" for real ROS.
The lab's subscribers use the raw path (``raw=True``: the callback gets the body bytes and
reads only the header stamp), except the "typed" row, which deserializes every frame into a
dict as rospy and roscpp deserialize into message objects.
Run:  .venv/bin/python tests/benchmarks/bench_transport.py [--frames 100] [--lat-frames 30] [--no-ros]
Figures depend on the machine and its load; compare the rows of one run, not across runs.
"""

from __future__ import annotations

import argparse
import json
import statistics
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))   # tests.support

from rosfpga_lab.graph import EmbeddedMaster, Node  # noqa: E402
from rosfpga_lab.msg import Time, default_registry, serialize  # noqa: E402

FRAME_BYTES = 640 * 480 * 4
TOPIC = "/bench/image"


# ------------------------------------------------------------------------ the lab's two roles
def _image_body(reg, phase: str, data) -> bytes:
    now = time.time()
    return serialize(reg, "sensor_msgs/Image", {
        "header": {"seq": 0, "stamp": Time(int(now), int((now % 1) * 1e9)), "frame_id": phase},
        "height": 480, "width": 640, "encoding": "rgba8", "is_bigendian": 0, "step": 2560, "data": data})


def _stamp_and_phase(body) -> tuple[float, str]:
    _seq, secs, nsecs, n = struct.unpack_from("<IIII", body, 0)
    return secs + nsecs * 1e-9, bytes(body[16:16 + n]).decode()


class LabSink:
    """Collects latency and burst arrival times from raw frames."""

    def __init__(self, nlat: int, nthr: int) -> None:
        self.nlat, self.nthr = nlat, nthr
        self.lat_ms: list[float] = []
        self.arrivals: list[float] = []
        self.cpu: list[float] = []  # process CPU seconds at the first and the last burst frame
        self.done = threading.Event()

    def typed(self, msg: dict) -> None:
        """Callback for a typed (deserialized) subscription."""
        stamp = msg["header"]["stamp"]
        self._arrived(time.time(), stamp.secs + stamp.nsecs * 1e-9, msg["header"]["frame_id"])

    def __call__(self, body, info) -> None:
        now = time.time()
        stamp, phase = _stamp_and_phase(body)
        self._arrived(now, stamp, phase)

    def _arrived(self, now: float, stamp: float, phase: str) -> None:
        if phase == "lat":
            self.lat_ms.append((now - stamp) * 1000.0)
        else:
            self.arrivals.append(now)
            if len(self.arrivals) in (1, self.nthr):
                self.cpu.append(time.process_time())
        if len(self.lat_ms) >= self.nlat and len(self.arrivals) >= self.nthr:
            self.done.set()

    def result(self) -> dict:
        span = self.arrivals[-1] - self.arrivals[0] if len(self.arrivals) > 1 else float("nan")
        cpu_ms = ((self.cpu[-1] - self.cpu[0]) * 1000.0 / (len(self.arrivals) - 1)
                  if len(self.cpu) == 2 else None)
        return {"lat_ms": self.lat_ms, "thr_frames": len(self.arrivals), "thr_seconds": span,
                "cpu_ms": cpu_ms}


def lab_publish(pub, nlat: int, nthr: int) -> None:
    import numpy as np

    reg = default_registry()
    data = np.tile(np.arange(256, dtype=np.uint8), FRAME_BYTES // 256)
    for phase, n, gap in (("lat", nlat, 0.1), ("thr", nthr, 0.0)):
        for _ in range(n):
            pub.publish_body(_image_body(reg, phase, data))
            if gap:
                time.sleep(gap)


def role_main(role: str, master_uri: str, nlat: int, nthr: int) -> None:
    node = Node(f"/bench_lab_{role}", master_uri=master_uri)
    try:
        if role == "sub":
            sink = LabSink(nlat, nthr)
            node.subscribe(TOPIC, "sensor_msgs/Image", sink, raw=True, queue_size=0)
            print("READY", flush=True)
            sink.done.wait(120)
            print(json.dumps(sink.result()), flush=True)
        else:
            pub = node.advertise(TOPIC, "sensor_msgs/Image", queue_size=0)
            print("READY", flush=True)
            pub.wait_for_subscribers(1, 60)
            time.sleep(0.5)
            lab_publish(pub, nlat, nthr)
            time.sleep(5.0)
    finally:
        node.shutdown()


# ------------------------------------------------------------------------ running pairs
def command(impl: str, role: str, master_uri: str, nlat: int, nthr: int) -> list[str]:
    if impl == "lab":
        return [sys.executable, __file__, "--role", role, "--master", master_uri,
                "--lat-frames", str(nlat), "--frames", str(nthr)]
    from tests.support.realros import ROS_PROGRAMS, ROS_PYTHON, build_roscpp_program

    if impl == "rospy":
        return [ROS_PYTHON, str(ROS_PROGRAMS / "wire_bench_rospy.py"), role, TOPIC, str(nlat), str(nthr)]
    return [str(build_roscpp_program(ROS_PROGRAMS / "wire_bench_roscpp.cpp")), role, TOPIC,
            str(nlat), str(nthr)]


def _wait_ready(proc: subprocess.Popen) -> None:
    for line in proc.stdout:  # type: ignore[union-attr]
        if line.strip() == "READY":
            return
    raise RuntimeError(f"{proc.args[0]} exited before READY")


def run_pair(pub_impl: str, sub_impl: str, master_uri: str, nlat: int, nthr: int) -> dict:
    from tests.support.realros import ros_env, stop_process

    env = ros_env(master_uri)  # loopback only; the lab's roles run from the installed package
    procs = []
    try:
        sub = subprocess.Popen(command(sub_impl, "sub", master_uri, nlat, nthr), stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True, env=env)
        procs.append(sub)
        _wait_ready(sub)
        pub = subprocess.Popen(command(pub_impl, "pub", master_uri, nlat, nthr), stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True, env=env)
        procs.append(pub)
        _wait_ready(pub)
        for line in sub.stdout:  # type: ignore[union-attr]
            if line.startswith("{"):
                return json.loads(line)
        raise RuntimeError("subscriber exited without results")
    finally:
        for p in procs:
            stop_process(p)


def run_in_process(master_uri: str, nlat: int, nthr: int, typed: bool = False) -> dict:
    a, b = Node("/bench_inproc_pub", master_uri=master_uri), Node("/bench_inproc_sub", master_uri=master_uri)
    try:
        sink = LabSink(nlat, nthr)
        if typed:
            b.subscribe(TOPIC + "_inproc", "sensor_msgs/Image", sink.typed, queue_size=0)
        else:
            b.subscribe(TOPIC + "_inproc", "sensor_msgs/Image", sink, raw=True, queue_size=0)
        pub = a.advertise(TOPIC + "_inproc", "sensor_msgs/Image", queue_size=0)
        pub.wait_for_subscribers(1, 10)
        lab_publish(pub, nlat, nthr)
        sink.done.wait(120)
        return sink.result()
    finally:
        a.shutdown()
        b.shutdown()


def row(name: str, r: dict) -> str:
    fps = (r["thr_frames"] - 1) / r["thr_seconds"] if r["thr_seconds"] and r["thr_seconds"] > 0 else float("nan")
    lat = sorted(r["lat_ms"]) or [float("nan")]
    p95 = lat[min(len(lat) - 1, int(round(0.95 * (len(lat) - 1))))]
    cpu = f"{r['cpu_ms']:9.2f}" if r.get("cpu_ms") is not None else f"{'-':>9}"
    return (f"{name:<34} {fps:9.1f} {fps * FRAME_BYTES / 1e6:9.1f} {statistics.median(lat):9.2f} "
            f"{p95:9.2f} {cpu} {len(r['lat_ms']):>4}/{r['thr_frames']:<4}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=100, help="frames in the back-to-back burst")
    ap.add_argument("--lat-frames", type=int, default=30, help="frames paced at 10 Hz for latency")
    ap.add_argument("--no-ros", action="store_true", help="skip the real ROS rows")
    ap.add_argument("--role", choices=["pub", "sub"], help=argparse.SUPPRESS)
    ap.add_argument("--master", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.role:
        role_main(args.role, args.master, args.lat_frames, args.frames)
        return 0
    from tests.support.realros import ros_missing_reason

    pairs = [("lab", "lab")]
    reason = None if not args.no_ros else "--no-ros"
    reason = reason or ros_missing_reason()
    if reason is None:
        pairs += [("rospy", "rospy"), ("roscpp", "roscpp"), ("lab", "roscpp"), ("roscpp", "lab")]
    with EmbeddedMaster(port=0) as master:
        print(f"640x480 rgba8 sensor_msgs/Image ({FRAME_BYTES:,} data bytes), loopback, "
              f"{args.frames} frames back to back, {args.lat_frames} paced at 10 Hz\n")
        print(f"{'publisher -> subscriber':<34} {'frames/s':>9} {'MB/s':>9} {'lat p50':>9} "
              f"{'lat p95':>9} {'sub CPU':>9} lat/thr")
        print(f"{'':<34} {'':>9} {'':>9} {'ms':>9} {'ms':>9} {'ms/frame':>9} frames")
        print(row("lab -> lab (one process)", run_in_process(master.uri, args.lat_frames, args.frames)), flush=True)
        print(row("lab -> lab typed (one process)",
                  run_in_process(master.uri, args.lat_frames, args.frames, typed=True)), flush=True)
        for pub_impl, sub_impl in pairs:
            name = f"{pub_impl} -> {sub_impl} (two processes)"
            try:
                print(row(name, run_pair(pub_impl, sub_impl, master.uri, args.lat_frames, args.frames)), flush=True)
            except Exception as exc:  # one failing pair should not hide the others
                print(f"{name:<34} failed: {exc}")
        if reason:
            print(f"\nreal ROS rows skipped: {reason}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
