"""Benchmark: the lab's ROS 2 component next to a Cyclone DDS relay, 640x480 rgba8 (issue 20).

In one process, a source writes 640x480 rgba8 ``sensor_msgs::msg::dds_::Image_`` samples
(RELIABLE KEEP_LAST 10, rmw's QoS) and a sink reads them after one hop; source and sink are
the lab's participants moving raw CDR (Cyclone's Python binding would turn every pixel into a
Python object at both ends and hide the hop):

* relay:     a Cyclone DDS participant that takes each sample and writes it again (no processing;
             through Cyclone's Python binding, the only Cyclone API installed, which converts
             each sample to Python objects and back);
* direct:    no hop (the sink reads the source's topic), the cost of the two ends;
* component: the lab's ROS 2 component (its RTPS participant in Python, the 3x3 dilation through
             the fast model of the CDR circuit, hw.CdrPipeline).

Figures: frames/s with the source writing as fast as the hop keeps up (KEEP_LAST 10, the
output counted at the sink), and latency (source write -> sink take, one frame at a time)
median and 90th percentile; "added" is component minus relay. Runs on 127.0.0.1, in DDS domain
``--domain`` (default 199), bounded in frames and seconds.
Run:  PYTHONPATH=. .venv/bin/python tests/benchmarks/bench_ros2.py [--frames 30]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the root: tests.support

from tests.support.ros2tools import cyclone, qos  # noqa: E402

CONFIG = """\
node: {name: /fpga_bench}
subscriber: {topic: /cam, type: sensor_msgs/Image}
publisher: {topic: /cam_out, type: sensor_msgs/Image}
image: {width: 640, height: 480, encoding: rgba8}
application: {op: dilate, ksize: 3}
"""


def relay(dds, domain: int, stop: threading.Event) -> threading.Thread:
    dp = dds.DomainParticipant(domain)
    reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
    writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds))

    def loop() -> None:
        while not stop.is_set():
            for s in reader.take(10):
                if isinstance(s, dds.Image_):     # not the "writer gone" notices
                    writer.write(s)
            time.sleep(0.0005)

    t = threading.Thread(target=loop, daemon=True)
    t.start()
    return t


def measure(domain: int, frames: int, out: str = "/cam_out") -> tuple[float, list[float]]:
    """Source and sink are the lab's own participants, moving raw CDR bytes (no Python objects
    per pixel), so what differs between the rows is the hop."""
    from rosfpga_lab.graph.ros2 import Ros2Node
    from rosfpga_lab.msg import serialize_cdr

    pixels = np.random.default_rng(0).integers(0, 256, (480, 640, 4), dtype=np.uint8)

    def sample(k: int) -> bytes:
        return serialize_cdr(None, "sensor_msgs/Image", {
            "header": {"stamp": {"sec": k, "nanosec": 0}, "frame_id": "camera"}, "height": 480,
            "width": 640, "encoding": "rgba8", "is_bigendian": 0, "step": 2560,
            "data": pixels.tobytes()})

    arrived: dict[int, float] = {}
    cond = threading.Condition()

    def on_sample(payload: bytes, _info: object) -> None:
        k = int.from_bytes(payload[4:8], "little")        # header.stamp.sec
        with cond:
            arrived[k] = time.perf_counter()
            cond.notify_all()

    src_node, sink_node = Ros2Node("bench_source", domain), Ros2Node("bench_sink", domain)
    try:
        src = src_node.create_publisher("/cam", "sensor_msgs/Image")
        sink_node.create_subscriber(out, "sensor_msgs/Image", on_sample)
        if not src.wait_for_subscribers(1, 15):
            raise SystemExit("the hop did not match in 15 s")
        time.sleep(1.0)
        samples = [sample(k) for k in range(1, 2 * frames + 1)]
        lat = []
        for k in range(1, frames + 1):          # latency: one frame at a time
            t0 = time.perf_counter()
            src.publish(samples[k - 1])
            with cond:
                cond.wait_for(lambda: k in arrived, 5)
            if k in arrived:
                lat.append(arrived[k] - t0)
        t0 = time.perf_counter()                # throughput: all at once (KEEP_LAST 10)
        for k in range(frames + 1, 2 * frames + 1):
            src.publish(samples[k - 1])
        with cond:
            cond.wait_for(lambda: 2 * frames in arrived, 20)
        got = [t for k, t in arrived.items() if k > frames]
        fps = len(got) / (max(got) - t0) if got else 0.0
        return fps, lat
    finally:
        src_node.close()
        sink_node.close()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--domain", type=int, default=199)
    args = ap.parse_args()
    dds = cyclone()
    from rosfpga_lab.component.ros2 import Ros2Component
    from rosfpga_lab.config import parse_config

    d_fps, d_lat = measure(args.domain + 2, args.frames, out="/cam")
    stop = threading.Event()
    relay(dds, args.domain, stop)
    r_fps, r_lat = measure(args.domain, args.frames)
    stop.set()
    comp = Ros2Component(parse_config(CONFIG), domain=args.domain + 1).start()
    try:
        c_fps, c_lat = measure(args.domain + 1, args.frames)
    finally:
        comp.stop()

    def p(x: list[float], q: float) -> float:
        return sorted(x)[min(len(x) - 1, int(q * len(x)))] * 1e3 if x else float("nan")

    print(f"640x480 rgba8, {args.frames} frames, RELIABLE KEEP_LAST 10, 127.0.0.1, pid {os.getpid()}")
    print(f"{'hop':<10} {'frames/s':>9} {'lat med ms':>11} {'lat p90 ms':>11}")
    print(f"{'direct':<10} {d_fps:9.1f} {statistics.median(d_lat) * 1e3:11.2f} {p(d_lat, .9):11.2f}")
    print(f"{'relay':<10} {r_fps:9.1f} {statistics.median(r_lat) * 1e3:11.2f} {p(r_lat, .9):11.2f}")
    print(f"{'component':<10} {c_fps:9.1f} {statistics.median(c_lat) * 1e3:11.2f} {p(c_lat, .9):11.2f}")
    print(f"added latency over direct (median): relay "
          f"{(statistics.median(r_lat) - statistics.median(d_lat)) * 1e3:.2f} ms, component "
          f"{(statistics.median(c_lat) - statistics.median(d_lat)) * 1e3:.2f} ms")
    print(f"component minus relay (median): {(statistics.median(c_lat) - statistics.median(r_lat)) * 1e3:.2f} ms; "
          f"component time per frame in the CDR circuit model (fast): "
          f"{statistics.median(comp.latencies) * 1e3:.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
