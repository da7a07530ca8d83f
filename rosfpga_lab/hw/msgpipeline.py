"""The whole circuit for any message type: subscriber -> application -> publisher.

:class:`MessagePipeline` is the circuit of one layout, ``sensor_msgs/Image`` included: one
TCPROS frame in, one out, every stage rendered from the layout (:mod:`~rosfpga_lab.hw.walker`).
The application is the 1-D window of :mod:`~rosfpga_lab.hw.morph1d`, or on a video stream
(Image's ``data`` with the configured shape) the 2-D dilate/erode of :mod:`~rosfpga_lab.hw.morph`
on its pixels (:func:`apply_application`). A field the publisher numbers itself (``count``,
:data:`~rosfpga_lab.hw.circuit.NUMBERED_FIELD` for Image on TCPROS) is written 1, 2, 3 ... for
the frames it publishes, as rospy numbers ``header.seq``. Cycles at II=1: the subscriber takes
one byte per clock, the application one element (pixel) per clock plus the window's reach, the
publisher writes one byte per clock (the generated circuit's own clocks, stages overlapped:
:func:`rosfpga_lab.hls.program.frame_clocks`). A refused frame raises the walker's
:class:`~rosfpga_lab.hw.errors.FrameFieldError`; nothing but the publisher's count is kept
between frames, so the next good frame comes out right.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config.vocabulary import CUSTOM, MODELS, canonical_op, model_ksize
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.circuit import STAMP_FIELDS, CircuitLayouts, circuit_layouts
from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.layoutsteps import Layout, StepKind, VideoShape
from rosfpga_lab.hw.morph import check_op, flush_extent, morph_fast, morph_reference
from rosfpga_lab.hw.morph1d import check_op1d, morph1d_fast, morph1d_reference
from rosfpga_lab.hw.video import Mat
from rosfpga_lab.hw.publisherwalker import publish_fast, publish_reference
from rosfpga_lab.hw.layouttokens import Token
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
        stamp: ``(secs, nsecs)`` of ``header.stamp`` when the type has one.
        video: the stream's video shape (Image), else None.
        line_rate_bps: the network's line rate, for ``network_time_s`` and ``wire_time_s``.
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
    video: VideoShape | None = None
    line_rate_bps: float = limits.DEFAULT_LINE_RATE_BPS

    @property
    def network_time_s(self) -> float:
        """The input frame's bytes (4-byte length + body) at ``line_rate_bps`` (payload only)."""
        return 8 * (4 + self.extracted.frame_length) / self.line_rate_bps

    @property
    def wire_time_s(self) -> float:
        """The same bytes as TCP over Ethernet (:func:`wire_bytes`) at ``line_rate_bps``."""
        return 8 * wire_bytes(4 + self.extracted.frame_length) / self.line_rate_bps

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

    @property
    def input_image(self) -> np.ndarray | None:
        """The received picture, ``(rows, cols, channels)`` uint8 (a view), or None without a
        video shape."""
        return _picture(self.video, self.extracted.stream)

    @property
    def output_image(self) -> np.ndarray | None:
        """The published picture (a view), or None without a video shape."""
        return _picture(self.video, self.output_stream)


def wire_bytes(payload: int, mtu: int = limits.ETHERNET_MTU) -> int:
    """Bytes on the Ethernet line for ``payload`` bytes of one TCP stream, sent in full-size
    segments: each carries ``mtu - TCP_IP_HEADER_BYTES`` payload bytes and costs ``mtu +
    ETHERNET_FRAMING_BYTES`` on the line (acknowledgements travel the other way)."""
    per_segment = mtu - limits.TCP_IP_HEADER_BYTES
    segments = -(-payload // per_segment)
    return payload + segments * (limits.TCP_IP_HEADER_BYTES + limits.ETHERNET_FRAMING_BYTES)


def _picture(video: VideoShape | None, stream: Any) -> np.ndarray | None:
    if video is None:
        return None
    return np.asarray(stream).reshape(video.height, video.width, video.bytes_per_pixel)


def apply_application(video: VideoShape | None, op: str, ksize: int, stream: np.ndarray, *,
                      reference: bool = False, out: np.ndarray | None = None) -> np.ndarray:
    """The application on one streamed array (flat): with a video shape the 2-D dilate/erode of
    :mod:`~rosfpga_lab.hw.morph` on its ``height x width`` pixels, else the 1-D window of
    :mod:`~rosfpga_lab.hw.morph1d` (``reference``: the one-element-at-a-time model; ``out``:
    where the fast 2-D filter writes, the picture's shape, to reuse it frame after frame).

    Raises:
        PipelineConfigError: an unknown ``op`` or a bad ``ksize``.
    """
    if video is None:
        name = check_op1d(op, ksize, np.dtype(stream.dtype))
        return (morph1d_reference if reference else morph1d_fast)(stream, name, ksize)
    name = canonical_op(op)
    ksize2 = check_op(name, model_ksize(op, ksize))
    image = stream.reshape(video.height, video.width, video.bytes_per_pixel)
    if reference:
        src, dst = Mat.from_numpy(image, "src"), Mat(video.height, video.width,
                                                     video.bytes_per_pixel, "dst")
        morph_reference(src, dst, name, ksize2)
        return dst.to_numpy().reshape(-1)
    return morph_fast(image, name, ksize2, out=out).reshape(-1)


def application_clocks(video: VideoShape | None, op: str, ksize: int, elements: int) -> int:
    """The application's clocks at II=1 for ``elements`` streamed: one element per clock plus
    the 1-D window's ``ksize // 2``, or on a video stream one pixel per clock plus the 2-D
    window's reach (its rows below and pixels right of the anchor)."""
    if not elements:
        return 0
    if video is None:
        return elements + ksize // 2
    dx, dy = flush_extent(check_op(canonical_op(op), model_ksize(op, ksize)))
    return elements // video.bytes_per_pixel + dy * video.width + dx


class MessagePipeline:
    """The circuit of one layout.

    Args:
        layout: the subscribed type's layout (:func:`~rosfpga_lab.hw.layout.derive_layout`);
            with a video shape (Image) the application is the 2-D one on its pixels.
        op: ``dilate`` | ``erode`` | ``passthrough``.
        ksize: window of the application (odd; a video stream's is ``ksize x ksize``).
        model: ``fast`` or ``reference``.
        clock_hz: the circuit's clock, for ``frame_time_s``.
        out_layout: the publisher's layout when its type is not the subscriber's (fields carried
            by path and type, see :func:`~rosfpga_lab.hw.walker.published_tokens`).
        reg: the registry holding both types (with ``out_layout``).
        count: the label of a uint32 field the publisher numbers itself (1, 2, 3 ... over the
            frames it publishes) instead of re-sending it
            (:func:`~rosfpga_lab.hw.circuit.numbered_field`).
    """

    def __init__(self, layout: Layout, op: str = "passthrough", ksize: int = 3,
                 model: str = "fast", clock_hz: float = limits.DEFAULT_CLOCK_HZ,
                 out_layout: Layout | None = None, reg: MsgRegistry | None = None,
                 count: str | None = None) -> None:
        if model not in MODELS:
            raise PipelineConfigError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
        if layout.video is not None:
            self.op = canonical_op(op)
            check_op(self.op, model_ksize(op, ksize))
        else:
            self.op = check_op1d(op, ksize, np.dtype(layout.stream.dtype))
        self.layout, self.ksize, self.model, self.clock_hz = layout, ksize, model, clock_hz
        self.out_layout, self.reg = out_layout, reg
        if out_layout is not None and reg is None:
            raise PipelineConfigError("a publisher of another type needs the registry")
        self._stamp = self._stamp_steps()
        self._numbered = self._numbered_step(count)
        self.frames_out = 0
        # a video stream that ends the frame (Image's data) is filtered into one picture kept
        # from frame to frame (no fresh pages per frame); the result then views the output frame
        self._tail_stream = (layout.video is not None and out_layout is None
                             and layout.stream_index == len(layout.steps) - 1)
        self._picture: np.ndarray | None = None

    @classmethod
    def from_config(cls, config: NodeConfig, model: str = "fast",
                    reg: MsgRegistry | None = None) -> MessagePipeline:
        """The circuit a node configuration of any type describes (its layouts derived once:
        :func:`~rosfpga_lab.hw.circuit.circuit_layouts`).

        Raises:
            PipelineConfigError: ``op: custom`` (no Python model of the user's C++).
        """
        return cls.from_layouts(circuit_layouts(config, reg), model)

    @classmethod
    def from_layouts(cls, parts: CircuitLayouts, model: str = "fast") -> MessagePipeline:
        """The circuit of a configuration's derived layouts
        (:class:`~rosfpga_lab.hw.circuit.CircuitLayouts`).

        Raises:
            PipelineConfigError: ``op: custom`` (no Python model of the user's C++).
        """
        config = parts.config
        if canonical_op(config.application.op) == CUSTOM:
            raise PipelineConfigError("a custom application has no Python model; compare its C "
                                      "simulation against your own expectation")
        return cls(parts.layout, config.application.op, config.application.ksize, model,
                   config.clock_mhz * 1e6, parts.out_layout, parts.reg, parts.numbered)

    def _stamp_steps(self) -> tuple[int, int] | None:
        idents = {s.ident: s.index for s in self.layout.steps}
        secs, nsecs = STAMP_FIELDS
        if secs in idents and nsecs in idents:
            return idents[secs], idents[nsecs]
        return None

    def _numbered_step(self, count: str | None) -> int | None:
        if count is None:
            return None
        for s in self.layout.steps:
            if s.label == count and s.kind is StepKind.SCALAR and s.type == "uint32" \
                    and s.depth == 0:
                return s.index
        raise PipelineConfigError(f"count: {self.layout.type_name} has no uint32 field "
                                  f"{count!r} outside its arrays to number")

    def _scratch(self, reference: bool) -> np.ndarray | None:
        video = self.layout.video
        if not self._tail_stream or reference or video is None:
            return None
        if self._picture is None:
            self._picture = np.empty((video.height, video.width, video.bytes_per_pixel), np.uint8)
        return self._picture

    @property
    def next_seq(self) -> int:
        """The number the publisher writes into the ``count`` field of the next frame."""
        return (1 + self.frames_out) & 0xFFFFFFFF

    def process(self, frame: bytes) -> MessageResult:
        """One TCPROS frame through the circuit.

        Raises:
            FrameFieldError: the subscriber refused the frame (field, offset and rule named).
        """
        reference = self.model == "reference"
        ex = (extract_reference if reference else extract_fast)(self.layout, frame)
        video = self.layout.video
        out_stream = apply_application(video, self.op, self.ksize, np.asarray(ex.stream),
                                       reference=reference, out=self._scratch(reference))
        toks = ex.tokens
        if self._numbered is not None:
            toks = [Token(t.step, self.next_seq) if t.step == self._numbered else t
                    for t in toks]
        out = (publish_reference if reference else publish_fast)(
            self.layout, toks, out_stream, self.out_layout, self.reg)
        self.frames_out += 1
        if self._tail_stream and not reference:  # the result keeps the frame, not the scratch
            out_stream = np.frombuffer(out, out_stream.dtype, len(out_stream),
                                       len(out) - out_stream.nbytes)
        cycles = {"subscriber": len(frame),
                  "application": application_clocks(video, self.op, self.ksize, len(out_stream)),
                  "publisher": len(out)}
        stamp = None
        if self._stamp is not None:
            by_step = {t.step: t.value for t in ex.tokens if not t.at}
            stamp = (int(by_step[self._stamp[0]]), int(by_step[self._stamp[1]]))
        return MessageResult(out, ex, out_stream, cycles, self.clock_hz, model=self.model,
                             stamp=stamp, video=video)


__all__ = ["wire_bytes", "MessagePipeline", "MessageResult", "apply_application",
           "application_clocks"]
