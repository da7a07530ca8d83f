"""Benchmark (1): the fast circuit model's frames/s beside ``cv2.dilate`` alone, same frame."""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from rosfpga_lab.component import open_source
from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hw.sample import image_frame


@dataclass(frozen=True)
class PipelineFigures:
    """Frames per second of the whole modelled circuit and of OpenCV's filter alone."""

    width: int
    height: int
    encoding: str
    frames: int
    pipeline_fps: float
    opencv_fps: float
    circuit_fps: float    # the generated circuit at its clock (its clocks for the frame)
    bit_exact: bool       # the pipeline's output image equals OpenCV's

    @property
    def ratio(self) -> float:
        """OpenCV's frames/s over the pipeline's (how much the ROS framing costs on top)."""
        return self.opencv_fps / self.pipeline_fps if self.pipeline_fps else float("nan")


def _rate(fn, frames: int) -> float:
    fn()  # warm up (allocations, caches)
    t0 = time.perf_counter()
    for _ in range(frames):
        fn()
    return frames / (time.perf_counter() - t0)


def bench_pipeline(config: NodeConfig, frames: int = 100) -> PipelineFigures:
    """Time ``frames`` runs of the fast pipeline on one TCPROS frame, and of cv2 on its image."""
    cfg = config.image
    image = open_source("synthetic", cfg.width, cfg.height, cfg.encoding).frame(0)
    frame = image_frame(image, cfg.encoding, stamp=(1, 2), frame_id="bench")
    circuit = circuit_of(config)
    pipe = circuit.model("fast")
    app = config.application
    kernel = np.ones((app.ksize, app.ksize), np.uint8)
    op = {"dilate": cv2.dilate, "erode": cv2.erode}.get(app.op, lambda img, _k: img.copy())
    pipeline_fps = _rate(lambda: pipe.process(frame), frames)
    opencv_fps = _rate(lambda: op(image, kernel), frames)
    got = pipe.process(frame).output_image
    expected = op(image, kernel).reshape(image.shape)
    return PipelineFigures(cfg.width, cfg.height, cfg.encoding, frames, pipeline_fps, opencv_fps,
                           config.clock_mhz * 1e6 / circuit.frame_clocks(frame).total,
                           got is not None and bool(np.array_equal(got, expected)))
