"""Benchmark: the component's output across a ROS master restart (prints figures; not a test).

A camera streams into the FPGA component (the lab's default configuration, 640x480 rgba8
dilate, at ``--rate``) and a viewer counts what comes out. Then the master is stopped, stays
down ``--down`` seconds and comes back empty on the same port; the component's watchdog
registers it again. The camera never registers again (as rospy and roscpp nodes never do), so
its link must survive the restart for frames to keep coming (issue 10, defect 8). Printed per
round: output frames while the master was down, seconds from the master's return to the
component's re-registration, seconds from the re-registration to the next output frame, and
the longest gap between two output frames over the whole round.

Measured (20 frames/s): the next output comes 0.02-0.05 s after the component registers again,
the longest gap is 0.12-0.17 s; before issue 10, no output at all until the camera registered
again.

Usage: ``python tests/benchmarks/bench_master_restart.py [--rounds 3] [--rate 20] [--down 1.0]``
"""

from __future__ import annotations

import argparse
import math
import threading
import time

from rosfpga_lab.component import Camera, FpgaComponent, default_config
from rosfpga_lab.graph import EmbeddedMaster, Node


class Arrivals:
    """Monotonic arrival times of output frames."""

    def __init__(self, master: EmbeddedMaster, topic: str) -> None:
        self.times: list[float] = []
        self.lock = threading.Lock()
        self.node = Node("/bench_viewer", master=master)
        self.node.subscribe(topic, "sensor_msgs/Image", self._on, raw=True, queue_size=0)

    def _on(self, body, info) -> None:
        with self.lock:
            self.times.append(time.monotonic())

    def between(self, t0: float, t1: float) -> list[float]:
        with self.lock:
            return [t for t in self.times if t0 <= t < t1]


def one_round(rate: float, down: float, after: float) -> dict[str, float]:
    config = default_config()
    master = EmbeddedMaster(port=0).start()
    port = master.port
    comp = FpgaComponent(config, master_uri=master.uri).start()
    viewer = Arrivals(master, config.publisher.topic)
    camera = Camera(config.subscriber.topic, width=config.image.width,
                    height=config.image.height, encoding=config.image.encoding, rate=rate,
                    master=master)
    master2 = None
    try:
        camera.publisher.wait_for_subscribers(1, timeout=10)
        viewer.node.subscribers[config.publisher.topic].wait_for_connection(1, 10)
        start = time.monotonic()
        camera.start()
        time.sleep(2.0)
        t_stop = time.monotonic()
        master.stop()
        time.sleep(down)
        master2 = EmbeddedMaster(port=port).start()
        t_back = time.monotonic()
        deadline = t_back + 15
        while comp.stats.master_reregistrations == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        t_rereg = time.monotonic() if comp.stats.master_reregistrations else math.nan
        time.sleep(after)
        end = time.monotonic()
        times = viewer.between(start, end)
        later = [t for t in times if t >= t_rereg] if not math.isnan(t_rereg) else []
        gaps = [b - a for a, b in zip(times, times[1:])] + ([end - times[-1]] if times else [])
        return {
            "while down": len(viewer.between(t_stop, t_back)),
            "to re-registration": t_rereg - t_back,
            "re-registration to output": (later[0] - t_rereg) if later else math.inf,
            "longest gap": max(gaps) if gaps else math.inf,
            "out after": len(later),
            "expected after": rate * (end - t_rereg) if not math.isnan(t_rereg) else 0,
        }
    finally:
        camera.stop()
        viewer.node.shutdown()
        comp.stop()
        if master2 is not None:
            master2.stop()
        master.stop()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3, help="restarts to measure (default 3)")
    parser.add_argument("--rate", type=float, default=20.0, help="camera frames/s (default 20)")
    parser.add_argument("--down", type=float, default=1.0,
                        help="seconds the master stays down (default 1.0)")
    parser.add_argument("--after", type=float, default=5.0,
                        help="seconds watched after the re-registration (default 5)")
    args = parser.parse_args(argv)
    print(f"master restart while a camera streams 640x480 rgba8 at {args.rate:g} frames/s "
          f"into the component; the master is down {args.down:g} s")
    print(f"{'round':>5} {'out while down':>14} {'back->re-reg s':>14} {'re-reg->output s':>16} "
          f"{'longest gap s':>13} {'out after re-reg':>18}")
    for k in range(args.rounds):
        f = one_round(args.rate, args.down, args.after)
        print(f"{k + 1:>5} {f['while down']:>14.0f} {f['to re-registration']:>14.2f} "
              f"{f['re-registration to output']:>16.3f} {f['longest gap']:>13.3f} "
              f"{f['out after']:>8.0f} of ~{f['expected after']:.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
