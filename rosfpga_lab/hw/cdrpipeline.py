"""The whole circuit on ROS 2 samples: CDR subscriber -> application -> CDR publisher.

:class:`CdrPipeline` is what the ROS 2 component calls for every sample its RTPS reader
reassembled: ``CdrPipeline(config).process(sample)`` takes the serialized payload (the CDR
encapsulation header and body, as an RTPS DATA carries it) and returns the payload to write
(encapsulation ``00 01 00 00``, options 0). Inside, the RTPS reader's software writes the sample
length before the payload into the circuit's byte FIFO (the record the CDR subscriber walks,
:mod:`~rosfpga_lab.hw.cdrwalker`), the application runs on the streamed field (the 1-D
:mod:`~rosfpga_lab.hw.morph1d`, or for ``sensor_msgs/Image`` the 2-D dilate/erode of
:mod:`~rosfpga_lab.hw.morph` on the configured image), and the publisher's record loses its
length on the way back to the RTPS writer. A refused sample raises the walker's
:class:`~rosfpga_lab.hw.errors.FrameFieldError` (field, byte offset, rule); the pipeline holds
no state between samples, so the next good sample comes out right.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config.vocabulary import (CUSTOM, PIPELINE_MODELS, RTL_MODEL, canonical_op,
                                           model_ksize)
from rosfpga_lab.hw.cdrlayout import CdrLayout
from rosfpga_lab.hw.circuit import CircuitLayouts, circuit_layouts
from rosfpga_lab.hw.cdrwalker import (
    extract_cdr_fast, extract_cdr_reference, publish_cdr_fast, publish_cdr_reference,
)
from rosfpga_lab.hw.errors import FrameTruncatedError, PipelineConfigError
from rosfpga_lab.hw.morph import check_op
from rosfpga_lab.hw.morph1d import check_op1d
from rosfpga_lab.hw.msgpipeline import apply_application
from rosfpga_lab.hw.subscriberwalker import Extracted
from rosfpga_lab.msg import MsgRegistry


@dataclass
class CdrResult:
    """One sample through the circuit.

    Attributes:
        output_sample: the CDR payload the publisher wrote (encapsulation header first).
        output_record: the publisher's record: 4-byte sample length + ``output_sample``.
        extracted: what the subscriber took (CDR walk tokens, the stream, offsets in the
            input record).
        output_stream: the application's output elements (flat).
        cycles: ``{"subscriber": .., "application": .., "publisher": ..}`` clocks at II=1
            (a byte per clock in and out, an element per clock in the application).
        model: ``"fast"`` or ``"reference"``.
        stamp: ``(sec, nanosec)`` of ``header.stamp`` when the type has one.
    """

    output_sample: bytes
    output_record: bytes
    extracted: Extracted
    output_stream: np.ndarray
    cycles: dict[str, int]
    model: str
    stamp: tuple[int, int] | None = None

    @property
    def input_stream(self) -> np.ndarray:
        """The streamed field as received."""
        return self.extracted.stream


class CdrPipeline:
    """The CDR circuit of a node configuration (any type, ``sensor_msgs/Image`` included).

    Args:
        config: a loaded node configuration (its ``subscriber.type``, ``publisher.type``,
            ``stream``, ``checks``, ``limits``, ``image:``, ``application``), read in the
            types' ROS 2 forms (a check of ``header.seq`` is refused: ROS 2 has none).
        model: ``fast`` or ``reference``.
        reg: the registry of ROS 1 definitions (default: ``config.registry()``).
        layouts: the configuration's layouts when the caller holds them
            (:func:`~rosfpga_lab.hw.circuit.circuit_layouts`; default: derived, or the ones
            kept for ``config``).

    Raises:
        PipelineConfigError: ``op: custom`` (no Python model of the user's C++), a bad model,
            or a configuration the layout refuses (``LayoutError``).
    """

    def __init__(self, config: NodeConfig, model: str = "fast",
                 reg: MsgRegistry | None = None, *,
                 layouts: CircuitLayouts | None = None) -> None:
        if model == RTL_MODEL:
            raise PipelineConfigError(
                "CdrPipeline is the Python model of the CDR circuit: its Verilog runs live in the "
                "ROS 2 node (`rosfpga-lab node CONFIG --ros2 --model rtl`, rtl/server.py); here use "
                f"model {' or '.join(PIPELINE_MODELS)}")
        if model not in PIPELINE_MODELS:
            raise PipelineConfigError(
                f"model must be one of {', '.join(PIPELINE_MODELS)}, got {model!r}")
        app = config.application
        if canonical_op(app.op) == CUSTOM:
            raise PipelineConfigError("a custom application has no Python model; compare its C "
                                      "simulation against your own expectation")
        layouts = layouts or circuit_layouts(config, reg)
        self.cdr: CdrLayout = layouts.cdr
        self.out_cdr: CdrLayout | None = layouts.out_cdr
        self.model = model
        self.clock_hz = config.clock_mhz * 1e6
        video = self.cdr.layout.video
        if video is not None:
            self.op = canonical_op(app.op)
            self.ksize2 = check_op(self.op, model_ksize(app.op, app.ksize))
            self.ksize = self.ksize2[0]
        else:
            self.op = check_op1d(app.op, app.ksize, np.dtype(self.cdr.layout.stream.dtype))
            self.ksize = app.ksize
        idents = {s.ident: s.index for s in self.cdr.layout.steps}
        self._stamp = ((idents["header_stamp_sec"], idents["header_stamp_nanosec"])
                       if "header_stamp_sec" in idents and "header_stamp_nanosec" in idents
                       else None)

    def process(self, sample: bytes) -> bytes:
        """One CDR payload in, the output CDR payload out.

        Raises:
            FrameFieldError: the subscriber refused the sample (field, offset and rule named).
        """
        return self.run(sample).output_sample

    def run(self, sample: bytes) -> CdrResult:
        """One CDR payload through the circuit, with what each stage did."""
        if len(sample) >= 2**32:
            raise FrameTruncatedError("a sample of 4 GiB or more has no sample length",
                                      "frame length", 0)
        return self.run_record(struct.pack("<I", len(sample)) + bytes(sample))

    def run_record(self, record: bytes) -> CdrResult:
        """One input record (4-byte sample length + CDR payload), as the circuit's FIFO holds it."""
        reference = self.model == "reference"
        ex = (extract_cdr_reference if reference else extract_cdr_fast)(self.cdr, record)
        stream = np.asarray(ex.stream)
        out_stream = self._apply(stream, reference)
        out = (publish_cdr_reference if reference else publish_cdr_fast)(
            self.cdr, ex.tokens, out_stream, self.out_cdr)
        n = len(out_stream)
        cycles = {"subscriber": len(record),
                  "application": n + (self.ksize // 2 if n else 0),
                  "publisher": len(out)}
        stamp = None
        if self._stamp is not None:
            by_step = {t.step: t.value for t in ex.tokens if not t.at}
            stamp = (int(by_step[self._stamp[0]]), int(by_step[self._stamp[1]]))
        return CdrResult(out[4:], out, ex, out_stream, cycles, self.model, stamp)

    def _apply(self, stream: np.ndarray, reference: bool) -> np.ndarray:
        return apply_application(self.cdr.layout.video, self.op, self.ksize, stream,
                                 reference=reference)


__all__ = ["CdrPipeline", "CdrResult", "apply_application"]
