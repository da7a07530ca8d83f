"""The video stretch of a generated circuit, between its two walkers, with fault taps.

A layout whose stream has a video shape (``sensor_msgs/Image``'s ``data``:
:class:`~rosfpga_lab.hw.layoutsteps.VideoShape`) is generated as the cores subscriber ->
``fifo2axi`` -> ``stream_filter`` -> ``axi2fifo`` -> publisher (``hls.generic``'s project). The
subscriber and publisher are the walkers of every type (:mod:`~rosfpga_lab.hw.subscriberwalker`,
:mod:`~rosfpga_lab.hw.publisherwalker`); :func:`video_stages` runs what lies between them on the
streamed bytes the subscriber took::

    [pixels_in] -> fifo2axi -> [axis_in] -> AXIvideo2Mat -> dilate/erode -> Mat2AXIvideo
      -> [axis_out] -> axi2fifo -> [pixels_out]

one pixel per beat (TUSER on the first pixel, TLAST ending each line: :mod:`~rosfpga_lab.hw.axis`),
the application's input as the HLS video library frames it (:mod:`~rosfpga_lab.hw.video`: a
frame starts at TUSER; a lost TUSER or TLAST makes it wait for ever, which the model reports as
:class:`~rosfpga_lab.hw.errors.StreamStarvedError` with what it had made as ``partial``).
Of the generated application's inputs, the HLS C++ (``video_filter.cpp.j2``) waits for TUSER
the same way but does not check TLAST, and the Verilog's ``rfl_morph`` re-frames a damaged
stream without waiting (:mod:`~rosfpga_lab.hw.framing`); on a well-formed stream all three agree.
Faults (:mod:`~rosfpga_lab.hw.faults`) act on the bytes and beats of the bracketed taps.
These are the fast (numpy) models; the stages' reference models are the modules named above.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from rosfpga_lab.config.vocabulary import canonical_op, model_ksize
from rosfpga_lab.hw.axis import axi2fifo_fast, fifo2axi_fast
from rosfpga_lab.hw.encodings import pixel_format
from rosfpga_lab.hw.faults import BeatFault, ByteFault, Fault
from rosfpga_lab.hw.layoutsteps import VideoShape
from rosfpga_lab.hw.morph import check_op, morph_fast
from rosfpga_lab.hw.streams import Beats
from rosfpga_lab.hw.video import axivideo2mat_fast, mat2axivideo_fast, status_names


@dataclass
class VideoStages:
    """What travelled between the walkers for one frame (after the faults at each tap).

    Attributes:
        pixels_in: the streamed bytes into ``fifo2axi`` (uint8).
        axis_in: the beats into the application.
        input_image, output_image: ``(height, width, bytes per pixel)`` before / after it.
        axis_out: the beats out of it.
        pixels_out: the bytes ``axi2fifo`` hands the publisher (uint8).
        status: problems that did not stop the frame (``AXIvideo2Mat`` flags, items left over).
    """

    pixels_in: np.ndarray
    axis_in: Beats
    input_image: np.ndarray
    output_image: np.ndarray
    axis_out: Beats
    pixels_out: np.ndarray
    status: list[str] = field(default_factory=list)


def _left(status: list[str], tap: str, left: int, unit: str) -> None:
    if left:
        status.append(f"{left} {unit}{'s' if left != 1 else ''} left in '{tap}' after the frame")


def video_stages(video: VideoShape, stream: np.ndarray, op: str, ksize: int = 3, *,
                 faults: Sequence[Fault] = ()) -> VideoStages:
    """The streamed bytes of one frame through ``fifo2axi``, the 2-D application and ``axi2fifo``.

    Args:
        video: the layout's video shape (``layout.video``).
        stream: the bytes the subscriber streamed (``Extracted.stream``).
        op: ``dilate`` | ``erode`` | ``passthrough``; ``ksize`` its square window.
        faults: byte faults at ``pixels_in``/``pixels_out``, beat faults at ``axis_in``/``axis_out``.

    Raises:
        StreamStarvedError: a stage waited for a byte or beat that never came (``partial``: what
            it had made).
        PipelineConfigError: a bad ``op``/``ksize``.
    """
    name = canonical_op(op)
    window = check_op(name, model_ksize(op, ksize))

    def bytes_at(tap: str, data: np.ndarray) -> np.ndarray:
        for fault in faults:
            if fault.tap == tap and isinstance(fault, ByteFault):
                data = fault.apply(data)
        return data

    def beats_at(tap: str, beats: Beats) -> Beats:
        for fault in faults:
            if fault.tap == tap and isinstance(fault, BeatFault):
                beats = fault.apply(beats)
        return beats

    fmt = pixel_format(video.encoding)
    rows, cols = video.height, video.width
    status: list[str] = []
    pixels_in = bytes_at("pixels_in", np.asarray(stream, np.uint8).reshape(-1))
    beats, left = fifo2axi_fast(pixels_in, rows, cols, fmt)
    _left(status, "pixels_in", left, "byte")
    axis_in = beats_at("axis_in", beats)
    image_in, flags, left = axivideo2mat_fast(axis_in, rows, cols, fmt)
    status += [f"AXIvideo2Mat: {flag}" for flag in status_names(flags)]
    _left(status, "axis_in", left, "beat")
    image_out = morph_fast(image_in, name, window)
    axis_out = beats_at("axis_out", mat2axivideo_fast(image_out, fmt))
    data, left = axi2fifo_fast(axis_out, rows * cols)
    _left(status, "axis_out", left, "beat")
    pixels_out = bytes_at("pixels_out", data)
    return VideoStages(pixels_in, axis_in, image_in, image_out, axis_out, pixels_out, status)


__all__ = ["VideoStages", "video_stages"]
