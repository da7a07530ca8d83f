"""The whole circuit for any message type: subscriber -> 1-D application -> publisher.

:class:`MessagePipeline` is :class:`rosfpga_lab.hw.Pipeline`'s sibling for a layout without a
video shape: one TCPROS frame in, one out, every stage rendered from the layout
(:mod:`~rosfpga_lab.hw.walker`, :mod:`~rosfpga_lab.hw.morph1d`). Cycles at II=1: the
subscriber takes one byte per clock, the application one element per clock (plus ``ksize // 2``
of latency for the window), the publisher writes one byte per clock. A refused frame raises
the walker's :class:`~rosfpga_lab.hw.errors.FrameFieldError`; the pipeline holds no state
between frames, so the next good frame comes out right.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config.vocabulary import CUSTOM, MODELS, canonical_op
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.layoutderive import layout_from_config
from rosfpga_lab.hw.layoutsteps import Layout
from rosfpga_lab.hw.morph1d import check_op1d, morph1d_fast, morph1d_reference
from rosfpga_lab.hw.publisherwalker import publish_fast, publish_reference
from rosfpga_lab.hw.subscriberwalker import Extracted, extract_fast, extract_reference
from rosfpga_lab.msg import MsgRegistry


@dataclass
class MessageResult:
    """One frame through the circuit.

    Attributes:
        output_frame: the TCPROS frame the publisher wrote (4-byte length + body).
        extracted: what the subscriber took (tokens, stream, offsets).
        output_stream: the application's output elements.
        cycles: ``{"subscriber": .., "application": .., "publisher": ..}`` clocks at II=1.
        clock_hz: the circuit's clock.
        status: problems that did not stop the frame (none so far; the Image path has some).
        fifo_high_water: FIFO levels (none modelled here).
        model: ``"fast"`` or ``"reference"``.
    """

    output_frame: bytes
    extracted: Extracted
    output_stream: np.ndarray
    cycles: dict[str, int]
    clock_hz: float
    status: list[str] = field(default_factory=list)
    fifo_high_water: dict[str, int] = field(default_factory=dict)
    model: str = "fast"
    stamp: tuple[int, int] | None = None

    @property
    def input_stream(self) -> np.ndarray:
        """The streamed array as received."""
        return self.extracted.stream

    @property
    def total_cycles(self) -> int:
        """Clocks of the three stages one after another (no overlap assumed)."""
        return sum(self.cycles.values())

    @property
    def frame_time_s(self) -> float:
        """``total_cycles / clock_hz``."""
        return self.total_cycles / self.clock_hz

    # an image viewer's questions, answered for a 1-D stream
    input_image: Any = None
    output_image: Any = None


class MessagePipeline:
    """The circuit of one layout.

    Args:
        layout: the subscribed type's layout (:func:`~rosfpga_lab.hw.layout.derive_layout`).
        op: ``dilate`` | ``erode`` | ``passthrough``.
        ksize: window of the 1-D application (odd).
        model: ``fast`` or ``reference``.
        clock_hz: the circuit's clock, for ``frame_time_s``.
        out_layout: the publisher's layout when its type is not the subscriber's (fields carried
            by path and type, see :func:`~rosfpga_lab.hw.walker.published_tokens`).
        reg: the registry holding both types (with ``out_layout``).
    """

    def __init__(self, layout: Layout, op: str = "passthrough", ksize: int = 3,
                 model: str = "fast", clock_hz: float = limits.DEFAULT_CLOCK_HZ,
                 out_layout: Layout | None = None, reg: MsgRegistry | None = None) -> None:
        if model not in MODELS:
            raise PipelineConfigError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
        if layout.video is not None:
            raise PipelineConfigError(f"{layout.type_name} streams video: use hw.Pipeline")
        self.op = check_op1d(op, ksize, np.dtype(layout.stream.dtype))
        self.layout, self.ksize, self.model, self.clock_hz = layout, ksize, model, clock_hz
        self.out_layout, self.reg = out_layout, reg
        if out_layout is not None and reg is None:
            raise PipelineConfigError("a publisher of another type needs the registry")
        self._stamp = self._stamp_steps()

    @classmethod
    def from_config(cls, config: NodeConfig, model: str = "fast",
                    reg: MsgRegistry | None = None) -> MessagePipeline:
        """The circuit a node configuration of any (non-Image) type describes.

        Raises:
            PipelineConfigError: ``op: custom`` (no Python model of the user's C++).
        """
        if canonical_op(config.application.op) == CUSTOM:
            raise PipelineConfigError("a custom application has no Python model; compare its C "
                                      "simulation against your own expectation")
        reg = reg or config.registry()
        layout = layout_from_config(config, reg)
        out_layout = (layout_from_config(config, reg, output=True)
                      if config.publisher.type != config.subscriber.type else None)
        return cls(layout, config.application.op, config.application.ksize, model,
                   config.clock_mhz * 1e6, out_layout, reg)

    def _stamp_steps(self) -> tuple[int, int] | None:
        idents = {s.ident: s.index for s in self.layout.steps}
        if "header_stamp_secs" in idents and "header_stamp_nsecs" in idents:
            return idents["header_stamp_secs"], idents["header_stamp_nsecs"]
        return None

    def process(self, frame: bytes) -> MessageResult:
        """One TCPROS frame through the circuit.

        Raises:
            FrameFieldError: the subscriber refused the frame (field, offset and rule named).
        """
        reference = self.model == "reference"
        ex = (extract_reference if reference else extract_fast)(self.layout, frame)
        app = morph1d_reference if reference else morph1d_fast
        out_stream = app(np.asarray(ex.stream), self.op, self.ksize)
        out = (publish_reference if reference else publish_fast)(
            self.layout, ex.tokens, out_stream, self.out_layout, self.reg)
        n = len(out_stream)
        cycles = {"subscriber": len(frame), "application": n + (self.ksize // 2 if n else 0),
                  "publisher": len(out)}
        stamp = None
        if self._stamp is not None:
            by_step = {t.step: t.value for t in ex.tokens if not t.at}
            stamp = (int(by_step[self._stamp[0]]), int(by_step[self._stamp[1]]))
        return MessageResult(out, ex, out_stream, cycles, self.clock_hz, model=self.model,
                             stamp=stamp)
