"""Benchmark the hardware models (prints figures; not a test).

* fast pipeline, 640x480 rgba8: whole TCPROS frame in -> parse, pack, dilate 3x3, unpack,
  serialize -> TCPROS frame out, frames/s beside ``cv2.dilate`` alone on the same image in the
  same run (target: the pipeline within 8x of cv2.dilate alone). Measured two ways: each in
  its own loop, and alternating frame by frame (a fair view when allocation costs differ).
* the same, alternating, for 640x480 ``rgb8`` and ``mono8`` (beats with null byte lanes).
* old vs new, alternating frame by frame: ``hw.Pipeline`` (the live node's model before issue
  28) beside ``MessagePipeline`` from the circuit record (the live node's model now), 640x480
  ``rgba8`` dilate 3x3, same frame, same output.
* reference model: beats/s and the time of one 160x120 rgba8 frame through every stage
  (target: under 1 s).

Usage: ``python tests/benchmarks/bench_pipeline.py [--repeat N] [--ref-size 160x120]``
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from rosfpga_lab.config import parse_config
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hw import Pipeline, image_frame


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=200, help="frames per fast measurement (default 200)")
    parser.add_argument("--ref-size", default="160x120", help="WxH of the reference-model frame (default 160x120)")
    parser.add_argument("--ref-repeat", type=int, default=3, help="reference-model runs (default 3)")
    args = parser.parse_args(argv)

    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (480, 640, 4), dtype=np.uint8)
    frame = image_frame(image, "rgba8", frame_id="camera")
    kernel = np.ones((3, 3), np.uint8)
    pipe = Pipeline(width=640, height=480, encoding="rgba8", op="dilate", ksize=(3, 3), model="fast")
    res = pipe.process(frame)
    assert np.array_equal(res.output_image, cv2.dilate(image, kernel)), "pipeline disagrees with cv2"

    print(f"cv2 threads: {cv2.getNumThreads()}, numpy {np.__version__}, opencv {cv2.__version__}")
    print("640x480 rgba8, 3x3 dilate")
    t_pipe = median_time(lambda: pipe.process(frame), args.repeat)
    t_cv2 = median_time(lambda: cv2.dilate(image, kernel), args.repeat)
    print(f"  separate loops : pipeline {t_pipe * 1e3:7.3f} ms ({1 / t_pipe:7.1f} frames/s)   "
          f"cv2.dilate alone {t_cv2 * 1e3:7.3f} ms ({1 / t_cv2:7.1f} frames/s)   ratio {t_pipe / t_cv2:5.2f}x")
    pipe_times, cv2_times = [], []
    for _ in range(args.repeat):
        start = time.perf_counter()
        pipe.process(frame)
        pipe_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        cv2.dilate(image, kernel)
        cv2_times.append(time.perf_counter() - start)
    a, b = statistics.median(pipe_times), statistics.median(cv2_times)
    print(f"  alternating    : pipeline {a * 1e3:7.3f} ms ({1 / a:7.1f} frames/s)   "
          f"cv2.dilate alone {b * 1e3:7.3f} ms ({1 / b:7.1f} frames/s)   ratio {a / b:5.2f}x")
    print(f"  target: pipeline within 8x of cv2.dilate alone -> "
          f"{'met' if max(t_pipe / t_cv2, a / b) <= 8 else 'NOT met'}")
    print(f"  modelled circuit: {res.frame_time_s * 1e3:.3f} ms/frame at 100 MHz "
          f"(bottleneck {res.report.bottleneck}), network {res.network_time_s * 1e3:.3f} ms at 1 Gb/s")
    for encoding, channels in (("rgb8", 3), ("mono8", 1)):
        other = np.ascontiguousarray(image[:, :, :channels])
        other_frame = image_frame(other, encoding, frame_id="camera")
        other_pipe = Pipeline(width=640, height=480, encoding=encoding, model="fast")
        times_p, times_c = [], []
        for _ in range(args.repeat):
            start = time.perf_counter()
            other_pipe.process(other_frame)
            times_p.append(time.perf_counter() - start)
            start = time.perf_counter()
            cv2.dilate(other, kernel)
            times_c.append(time.perf_counter() - start)
        a, b = statistics.median(times_p), statistics.median(times_c)
        print(f"640x480 {encoding:<5} alternating: pipeline {a * 1e3:7.3f} ms ({1 / a:7.1f} frames/s)   "
              f"cv2.dilate alone {b * 1e3:7.3f} ms ({1 / b:7.1f} frames/s)   ratio {a / b:5.2f}x")

    compare_old_new(image, args.repeat)

    w, h = (int(v) for v in args.ref_size.lower().split("x"))
    small = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
    small_frame = image_frame(small, "rgba8")
    ref = Pipeline(model="reference", seq="carry")
    t_ref = median_time(lambda: ref.process(small_frame), args.ref_repeat)
    cpu_start = time.process_time()
    for _ in range(args.ref_repeat):
        ref.process(small_frame)
    cpu_ref = (time.process_time() - cpu_start) / args.ref_repeat
    out = ref.process(small_frame)
    assert out.output_frame == Pipeline(seq="carry").process(small_frame).output_frame
    beats = 2 * w * h               # AXI4-Stream beats in and out
    items = 2 * len(small_frame) + 2 * small.size + 4 * w * h   # bytes + beats + pixels moved
    print(f"reference model, {w}x{h} rgba8 through all stages: {t_ref:.3f} s per frame wall "
          f"(median), {cpu_ref:.3f} s CPU ({beats / t_ref:,.0f} beats/s, "
          f"{items / t_ref:,.0f} bytes+beats+pixels/s wall); "
          f"target < 1 s -> {'met' if t_ref < 1 else 'NOT met'}")
    return 0


def compare_old_new(image: np.ndarray, repeat: int) -> None:
    """Print hw.Pipeline (old) beside the circuit record's MessagePipeline (new), alternating
    frame by frame, for 640x480 rgba8, rgb8 and mono8 (3x3 dilate; outputs checked equal)."""
    text = (Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml").read_text()
    for encoding, channels in (("rgba8", 4), ("rgb8", 3), ("mono8", 1)):
        config = parse_config(text.replace("encoding: rgba8", f"encoding: {encoding}"))
        frame = image_frame(np.ascontiguousarray(image[:, :, :channels]), encoding,
                            frame_id="camera")
        old, new = Pipeline.from_config(config), circuit_of(config).model()
        assert old.process(frame).output_frame == new.process(frame).output_frame
        t_old, t_new = [], []
        for _ in range(repeat):
            start = time.perf_counter()
            old.process(frame)
            t_old.append(time.perf_counter() - start)
            start = time.perf_counter()
            new.process(frame)
            t_new.append(time.perf_counter() - start)
        a, b = statistics.median(t_old), statistics.median(t_new)
        print(f"640x480 {encoding:<5} live node's model, alternating: hw.Pipeline (old) "
              f"{a * 1e3:7.3f} ms ({1 / a:7.1f} frames/s)   MessagePipeline (new) {b * 1e3:7.3f} "
              f"ms ({1 / b:7.1f} frames/s)   new/old {b / a:5.2f}x")


if __name__ == "__main__":
    sys.exit(main())
