"""Benchmark: the lab's ROS 2 component next to a Cyclone DDS relay, 640x480 rgba8 (issue 20).

In one process, a Cyclone DDS source writes 640x480 rgba8 ``sensor_msgs::msg::dds_::Image_``
samples (RELIABLE KEEP_LAST 10, rmw's QoS) and a Cyclone sink reads them after one hop:

* relay:     a Cyclone participant that takes each sample and writes it again (no processing);
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

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2tools import cyclone, image, qos  # noqa: E402

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


def measure(dds, domain: int, frames: int, out: str = "rt/cam_out") -> tuple[float, list[float]]:
    dp = dds.DomainParticipant(domain)
    src = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
    dp2 = dds.DomainParticipant(domain)       # the sink in a participant of its own
    sink = dds.DataReader(dp2, dds.Topic(dp2, out, dds.Image_), qos=qos(dds))
    deadline = time.monotonic() + 15
    while not (src.get_matched_subscriptions() and sink.get_matched_publications()):
        if time.monotonic() > deadline:
            raise SystemExit("peers did not match in 15 s")
        time.sleep(0.01)
    time.sleep(0.3)
    pixels = np.random.default_rng(0).integers(0, 256, (480, 640, 4), dtype=np.uint8)
    msg = image(dds, pixels, "rgba8")
    # latency: one frame at a time
    lat = []
    for _ in range(frames):
        t0 = time.perf_counter()
        src.write(msg)
        got = []
        while not got and time.perf_counter() - t0 < 5:
            got = sink.take(1)
            time.sleep(0.0002)
        if got:
            lat.append(time.perf_counter() - t0)
    # throughput: the source writes every frame at once (its KEEP_LAST 10 history may replace
    # frames the hop did not take yet); frames/s = frames at the sink / time to the last one
    n, last = 0, 0.0
    t0 = time.perf_counter()
    for k in range(frames):
        src.write(image(dds, pixels, "rgba8", sec=k + 1))
    while time.perf_counter() - t0 < 20:
        got = [s for s in sink.take(10) if isinstance(s, dds.Image_)]
        if got:
            n += len(got)
            last = time.perf_counter()
            if got[-1].header.stamp.sec == frames:
                break
        time.sleep(0.001)
    fps = n / (last - t0) if n else 0.0
    return fps, lat


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--domain", type=int, default=199)
    args = ap.parse_args()
    dds = cyclone()
    from rosfpga_lab.component.ros2 import Ros2Component
    from rosfpga_lab.config import parse_config

    d_fps, d_lat = measure(dds, args.domain + 2, args.frames, out="rt/cam")
    stop = threading.Event()
    relay(dds, args.domain, stop)
    r_fps, r_lat = measure(dds, args.domain, args.frames)
    stop.set()
    comp = Ros2Component(parse_config(CONFIG), domain=args.domain + 1).start()
    try:
        c_fps, c_lat = measure(dds, args.domain + 1, args.frames)
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
          f"{(statistics.median(c_lat) - statistics.median(d_lat)) * 1e3:.2f} ms; "
          "(the relay is Cyclone's Python binding: it turns each frame into Python objects)")
    print(f"component minus relay (median): {(statistics.median(c_lat) - statistics.median(r_lat)) * 1e3:.2f} ms; "
          f"component time per frame in the CDR circuit model (fast): "
          f"{statistics.median(comp.latencies) * 1e3:.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
