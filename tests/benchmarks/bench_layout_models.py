"""Benchmark: the layout-derived models (issue 19) on the shipped examples, as figures.

For each shipped non-Image configuration: the time to derive its layout, and per frame the
reference (byte at a time) and fast (numpy) subscriber + application + publisher
(``hw.msgpipeline.MessagePipeline``), plus the frame's bytes and the circuit's modelled cycles.
For ``sensor_msgs/Image`` the fast layout subscriber is timed against the hand-written Image
interpreter on one 640x480 rgba8 frame, and the whole circuit the live node runs, before issue
28 (``hw.Pipeline``) beside now (``MessagePipeline`` of the circuit record). Figures are
printed, not asserted.

Run:  .venv/bin/python tests/benchmarks/bench_layout_models.py [--frames N]
"""

from __future__ import annotations

import argparse
import struct
from pathlib import Path

import numpy as np

from benchtools import per_call

from rosfpga_lab.config import load_config
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hw import image_frame
from rosfpga_lab.hw.layout import layout_from_config
from rosfpga_lab.hw.msgpipeline import MessagePipeline
from rosfpga_lab.hw.walker import extract_fast
from rosfpga_lab.msg import new_message, serialize

DATA = Path(__file__).resolve().parents[2] / "data"
EXAMPLES = ("fpga_laserscan_min.yaml", "fpga_samples_dilate.yaml")


def _frame(config_name: str) -> tuple[object, bytes]:
    config = load_config(DATA / config_name)
    reg = config.registry()
    type_name = config.subscriber.type
    value = new_message(reg, type_name)
    assert config.stream is not None
    value[config.stream.field] = np.arange(config.stream.length) % 100
    for check in config.checks:
        if check.value is not None:
            obj = value
            *parents, last = check.path.split(".")
            for p in parents:
                obj = obj[p]
            obj[last] = check.value
    body = serialize(reg, type_name, value)
    return config, struct.pack("<I", len(body)) + body


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=20, help="frames per figure (default 20)")
    args = ap.parse_args()
    print(f"{'example':28} {'bytes':>6} {'layout ms':>9} {'ref ms/frame':>12} "
          f"{'fast ms/frame':>13} {'cycles':>7}")
    for name in EXAMPLES:
        config, frame = _frame(name)
        t_layout = per_call(lambda: layout_from_config(config), 5)
        ref = MessagePipeline.from_config(config, model="reference")
        fast = MessagePipeline.from_config(config, model="fast")
        cycles = fast.process(frame).total_cycles
        t_ref = per_call(lambda: ref.process(frame), max(1, args.frames // 4))
        t_fast = per_call(lambda: fast.process(frame), args.frames)
        print(f"{name:28} {len(frame):6} {t_layout * 1e3:9.2f} {t_ref * 1e3:12.2f} "
              f"{t_fast * 1e3:13.3f} {cycles:7}")
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    layout = layout_from_config(config)
    pic = np.random.default_rng(0).integers(0, 256, (480, 640, 4), np.uint8)
    frame = image_frame(pic, "rgba8", frame_id="cam")
    t_layout_sub = per_call(lambda: extract_fast(layout, frame), args.frames)
    print(f"640x480 rgba8 subscriber, fast: layout walker {t_layout_sub * 1e3:.3f} ms per frame")
    # the whole circuit, the live node's model (the circuit record's MessagePipeline)
    new = circuit_of(config).model()
    t_new = per_call(lambda: new.process(frame), args.frames)
    print(f"640x480 rgba8 dilate 3x3, whole circuit, fast: MessagePipeline {t_new * 1e3:.3f} ms "
          f"per frame (hw.Pipeline, the model before issue 28, is gone)")


if __name__ == "__main__":
    main()
