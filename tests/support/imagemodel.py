"""The one engine's model of an Image configuration, with the beats on both sides of its
application: :class:`~rosfpga_lab.hw.msgpipeline.MessagePipeline` for the frames and
:func:`~rosfpga_lab.hw.videostages.video_stages` for the beats (what ``fifo2axi`` hands the
application and what it hands ``axi2fifo``), which the C simulation and the RTL tap."""

from __future__ import annotations

from dataclasses import dataclass

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hw import Beats, MessagePipeline
from rosfpga_lab.hw.videostages import video_stages


@dataclass(frozen=True)
class ImageFrameResult:
    """One frame through the model: the published frame and the application's beats."""

    output_frame: bytes
    input_beats: Beats
    output_beats: Beats


class ImageModel:
    """:class:`MessagePipeline` of an Image configuration, returning the beats too."""

    def __init__(self, config: NodeConfig) -> None:
        self.pipe = MessagePipeline.from_config(config)
        assert self.pipe.layout.video is not None, "an Image configuration streams video"

    def process(self, frame: bytes) -> ImageFrameResult:
        """One TCPROS frame (raises the pipeline's ``PipelineError`` on a refused one)."""
        res = self.pipe.process(frame)
        video = self.pipe.layout.video
        assert video is not None
        stages = video_stages(video, res.extracted.stream, self.pipe.op, self.pipe.ksize)
        return ImageFrameResult(res.output_frame, stages.axis_in, stages.axis_out)
