"""Benchmark: the CDR circuit models (issue 20, hardware half) next to the TCPROS ones, as figures.

Per sample: deriving the CDR walk, the reference (byte at a time) and fast (numpy) CDR
pipeline (``hw.cdrpipeline.CdrPipeline``) on the shipped ``lab_msgs/Samples`` example, and the
fast CDR pipeline on one 640x480 rgba8 ``sensor_msgs/Image`` (3x3 dilation) beside the TCPROS
``hw.MessagePipeline`` on the same image. Figures are printed, not asserted.

Run:  .venv/bin/python tests/benchmarks/bench_cdr_pipeline.py [--samples N]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchtools import per_call

from rosfpga_lab.config import load_config
from rosfpga_lab.hw import MessagePipeline, image_frame
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.msg import new_message
from rosfpga_lab.msg.cdr import serialize_cdr

DATA = Path(__file__).resolve().parents[2] / "data"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=20, help="samples per figure (default 20)")
    args = ap.parse_args()
    n = args.samples

    config = load_config(DATA / "fpga_samples_dilate.yaml")
    fast = CdrPipeline(config)
    ref = CdrPipeline(config, "reference")
    creg = fast.cdr.registry
    value = new_message(creg, "lab_msgs/Samples")
    value["samples"] = np.arange(64, dtype=np.int32) % 100
    value["calibration"]["mode"] = 2
    sample = serialize_cdr(creg, "lab_msgs/Samples", value)
    print(f"lab_msgs/Samples, {len(sample)}-byte sample:")
    print(f"  derive the CDR walk   {per_call(lambda: cdr_layout_from_config(config), 5) * 1e3:8.2f} ms")
    print(f"  reference per sample  {per_call(lambda: ref.process(sample), max(1, n // 4)) * 1e3:8.2f} ms")
    print(f"  fast per sample       {per_call(lambda: fast.process(sample), n) * 1e3:8.2f} ms")
    print(f"  modelled cycles       {sum(fast.run(sample).cycles.values()):8d}")

    image_config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    im = image_config.image
    pixels = np.random.default_rng(1).integers(0, 256, (im.height, im.width, 4), np.uint8)
    cdr_image = CdrPipeline(image_config)
    img = new_message(cdr_image.cdr.registry, "sensor_msgs/Image")
    img.update(height=im.height, width=im.width, encoding=im.encoding, step=im.width * 4,
               data=pixels.tobytes())
    img["header"]["frame_id"] = "camera"
    cdr_sample = serialize_cdr(cdr_image.cdr.registry, "sensor_msgs/Image", img)
    tcpros = MessagePipeline.from_config(image_config)
    frame = image_frame(pixels, im.encoding, frame_id="camera")
    t_cdr = per_call(lambda: cdr_image.process(cdr_sample), n)
    t_tcp = per_call(lambda: tcpros.process(frame), n)
    print(f"sensor_msgs/Image {im.width}x{im.height} {im.encoding}, 3x3 dilate (fast models):")
    print(f"  CDR    {t_cdr * 1e3:8.2f} ms/sample  ({1 / t_cdr:6.1f} samples/s)")
    print(f"  TCPROS {t_tcp * 1e3:8.2f} ms/frame   ({1 / t_tcp:6.1f} frames/s)")


if __name__ == "__main__":
    main()
