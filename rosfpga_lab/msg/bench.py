"""Benchmark of the message codecs: ``python -m rosfpga_lab.msg.bench``.

Prints, per message, the time to serialize and deserialize with the lab's fast codecs, the lab's
plain reference decoder, and (when installed) the ``rosbags`` library, with ratios side by side.
Figures, not pass/fail: the point is to show where the numpy fast path matters.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rosfpga_lab.msg import (
    default_registry, deserialize, deserialize_reference, new_message, serialize,
)


def _best(fn: Callable[[], Any], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def _cases() -> list[tuple[str, str, dict]]:
    reg = default_registry()
    rng = np.random.default_rng(0)
    image = new_message(reg, "sensor_msgs/Image", header={"frame_id": "camera"}, height=480,
                        width=640, encoding="rgba8", step=2560,
                        data=rng.integers(0, 256, 640 * 480 * 4, dtype=np.uint8))
    cloud = new_message(reg, "sensor_msgs/PointCloud2", height=1, width=100_000, point_step=16,
                        row_step=1_600_000, is_dense=True,
                        fields=[new_message(reg, "sensor_msgs/PointField", name=n, offset=4 * i,
                                            datatype=7, count=1) for i, n in enumerate("xyz")],
                        data=rng.integers(0, 256, 1_600_000, dtype=np.uint8))
    scan = new_message(reg, "sensor_msgs/LaserScan", ranges=rng.random(1080, np.float32),
                       intensities=rng.random(1080, np.float32))
    poses = new_message(reg, "geometry_msgs/PoseArray", poses=[
        new_message(reg, "geometry_msgs/Pose", position={"x": float(i)}) for i in range(1000)])
    points = new_message(reg, "sensor_msgs/PointCloud", points=[
        {"x": float(i), "y": 0.5, "z": -1.0} for i in range(10_000)])
    joints = new_message(reg, "sensor_msgs/JointState", name=[f"j{i}" for i in range(6)],
                         position=np.arange(6.0), velocity=np.zeros(6), effort=np.zeros(6))
    return [("Image 640x480 rgba8", "sensor_msgs/Image", image),
            ("PointCloud2 100k points", "sensor_msgs/PointCloud2", cloud),
            ("LaserScan 1080 rays", "sensor_msgs/LaserScan", scan),
            ("PoseArray 1000 poses", "geometry_msgs/PoseArray", poses),
            ("PointCloud 10k Point32", "sensor_msgs/PointCloud", points),
            ("JointState 6 joints", "sensor_msgs/JointState", joints)]


def run(repeat: int = 5) -> str:
    """Run the benchmark; return the table as text."""
    reg = default_registry()
    try:
        from rosbags.typesys import Stores, get_typestore
        store = get_typestore(Stores.ROS1_NOETIC)
    except ImportError:  # pragma: no cover - rosbags is a test dependency
        store = None
    header = (f"{'message':26} {'bytes':>9} {'ser ms':>8} {'deser ms':>9} {'ref deser ms':>12} "
              f"{'rosbags ser':>11} {'rosbags deser':>13}")
    lines = [header, "-" * len(header)]
    for label, type_name, value in _cases():
        body = serialize(reg, type_name, value)
        ser = _best(lambda: serialize(reg, type_name, value), repeat)
        de = _best(lambda: deserialize(reg, type_name, body), repeat)
        ref = _best(lambda: deserialize_reference(reg, type_name, body), max(1, repeat // 2))
        rb_ser = rb_de = "-"
        if store is not None:
            pkg, name = type_name.split("/")
            rb_type = f"{pkg}/msg/{name}"
            obj = store.deserialize_ros1(body, rb_type)
            t_s = _best(lambda: store.serialize_ros1(obj, rb_type), repeat)
            t_d = _best(lambda: store.deserialize_ros1(body, rb_type), repeat)
            rb_ser, rb_de = f"{t_s * 1e3:.3f}", f"{t_d * 1e3:.3f}"
        lines.append(f"{label:26} {len(body):9d} {ser * 1e3:8.3f} {de * 1e3:9.3f} "
                     f"{ref * 1e3:12.3f} {rb_ser:>11} {rb_de:>13}")
        lines.append(f"{'':26} {'':9} {'':8} {'':9} {f'x{ref / de:.0f} slower':>12}")
    lines.append("(best of N runs; 'ref' is the plain one-field-at-a-time reference decoder)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m rosfpga_lab.msg.bench",
                                     description="Time the lab's message codecs.")
    parser.add_argument("--repeat", type=int, default=5, help="runs per figure (best is kept)")
    args = parser.parse_args(argv)
    print(run(args.repeat))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
