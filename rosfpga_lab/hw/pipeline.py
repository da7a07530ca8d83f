"""The whole circuit: TCPROS frame in, dilated (or eroded) TCPROS frame out.

:class:`Pipeline` strings the stages together in the paper's order::

    rx FIFO -> interpreter -> [pixels_in] -> fifo2axi -> [axis_in] -> AXIvideo2Mat -> dilate/erode
      -> Mat2AXIvideo -> [axis_out] -> axi2fifo -> [pixels_out] -> message generator -> frame out

``model="reference"`` runs every stage one byte or beat at a time (slow; small images);
``model="fast"`` runs the numpy models. Stages run one after another over the whole frame, as
HLS C-simulation runs a dataflow region; the timing of the concurrent circuit comes from the
cycle accounting (:mod:`rosfpga_lab.hw.cycles`). Faults (:mod:`rosfpga_lab.hw.faults`) are
applied to the named streams between stages.

Any :class:`~rosfpga_lab.hw.errors.PipelineError` resets every stage before it propagates, so
the next good frame comes out right. Items left in a stream after a frame (a duplicated byte,
a missing ``tlast``) are reported in :attr:`PipelineResult.status` and flushed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from rosfpga_lab.config import CUSTOM, DEFAULT_OP, NodeConfig, canonical_op, model_ksize
from rosfpga_lab.config.vocabulary import PIPELINE_MODELS
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.axis import axi2fifo_fast, axi2fifo_reference, fifo2axi_fast, fifo2axi_reference
from rosfpga_lab.hw.cycles import CycleReport, account
from rosfpga_lab.hw.encodings import PIXEL_FORMATS, pixel_format
from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError, PipelineConfigError, PipelineError
from rosfpga_lab.hw.faults import BeatFault, ByteFault, Fault, ShallowFifo
from rosfpga_lab.hw.generator import frame_length, generate_fast, generate_reference
from rosfpga_lab.hw.interpreter import SUBSCRIBER_STATUSES, ImageFields, Interpreter, interpret_fast
from rosfpga_lab.hw.morph import check_op, morph_fast, morph_reference
from rosfpga_lab.hw.rx import check_rx, receive_fast_check, receive_reference
from rosfpga_lab.hw.msgpipeline import wire_bytes  # noqa: F401  (its home now)
from rosfpga_lab.hw.sample import image_frame  # noqa: F401  (its home now; imported from here)
from rosfpga_lab.hw.streams import Beat, Beats, ByteFIFO, Fifo
from rosfpga_lab.hw.video import (
    Mat, axivideo2mat_fast, axivideo2mat_reference, mat2axivideo_fast, mat2axivideo_reference,
    status_names,
)

SEQ_MODES = ("count", "carry")


#: A refused field's label (``FrameFieldError.field``) -> the subscriber's status name.
_STATUS_OF_LABEL = {label: name for name, label in SUBSCRIBER_STATUSES[1:]}


def _circuit_status(exc: FrameFieldError) -> str:
    """The subscriber circuit's status for a refused field.

    The models name the frame length where it disagrees with the message (data length not
    ending at the frame's end); the circuit finds that as it checks the data length.
    """
    if isinstance(exc, FrameLengthError) and exc.field == "frame length" \
            and exc.rule == FrameLengthError.default_rule:
        return _STATUS_OF_LABEL["data length"]
    if exc.field not in _STATUS_OF_LABEL:
        raise exc
    return _STATUS_OF_LABEL[exc.field]


@dataclass(frozen=True)
class StreamResult:
    """What :meth:`Pipeline.process_stream` made of a byte stream.

    Attributes:
        output: the bytes the publisher sent.
        status: per frame the circuit read, its byte offset and the subscriber's status name.
        unread: bytes at the end left unread (a frame cut short).
    """

    output: bytes
    status: tuple[tuple[int, str], ...]
    unread: int


@dataclass
class PipelineResult:
    """Everything one frame did in the pipeline.

    Attributes:
        output_frame: the TCPROS frame the publisher circuit wrote (4-byte length + body).
        fields: the fields the interpreter decoded from the input frame.
        output_fields: the fields the generator wrote (seq, stamp, frame_id as configured).
        input_image / output_image: ``(rows, cols, channels)`` uint8 before / after the filter.
        input_beats / output_beats: the AXI4-Stream into ``AXIvideo2Mat`` / out of
            ``Mat2AXIvideo`` (after any fault at that tap).
        cycles, latency: per stage (see :mod:`rosfpga_lab.hw.cycles`).
        total_cycles, sequential_cycles: first byte in to last byte out (the circuit's
            concurrent stages, checked against the RTL) and the no-overlap sum.
        frame_time_s: ``total_cycles / clock_hz``.
        network_time_s: the input frame's bytes at ``line_rate_bps`` (payload only).
        wire_time_s: the same bytes as TCP over Ethernet: with the IP, TCP and Ethernet
            overhead of every full-size packet (:func:`wire_bytes`).
        fifo_high_water: ``{"rx": bytes}``, the receive FIFO's highest level.
        status: problems that did not stop the frame (``AXIvideo2Mat`` flags, leftovers).
        model: ``"fast"`` or ``"reference"``.
        streams: what travelled on each tap (after its faults): ``"rx"`` (bytes),
            ``"pixels_in"``, ``"pixels_out"`` (read-only uint8 arrays), ``"axis_in"``,
            ``"axis_out"`` (:class:`Beats`), ``"tx"`` (the output frame).
    """

    output_frame: bytes
    fields: ImageFields
    output_fields: ImageFields
    input_image: np.ndarray
    output_image: np.ndarray
    input_beats: Beats
    output_beats: Beats
    report: CycleReport
    clock_hz: float
    line_rate_bps: float
    fifo_high_water: dict[str, int]
    status: list[str] = field(default_factory=list)
    model: str = "fast"
    streams: dict[str, bytes | np.ndarray | Beats] = field(default_factory=dict)

    @property
    def cycles(self) -> dict[str, int]:
        return self.report.cycles

    @property
    def latency(self) -> dict[str, int]:
        return self.report.latency

    @property
    def total_cycles(self) -> int:
        return self.report.total

    @property
    def sequential_cycles(self) -> int:
        return self.report.sequential

    @property
    def frame_time_s(self) -> float:
        return self.report.total / self.clock_hz

    @property
    def network_time_s(self) -> float:
        return 8 * (4 + self.fields.frame_length) / self.line_rate_bps

    @property
    def wire_time_s(self) -> float:
        return 8 * wire_bytes(4 + self.fields.frame_length) / self.line_rate_bps

    @property
    def ok(self) -> bool:
        """True when the frame passed without any status flag."""
        return not self.status

    def summary(self) -> str:
        """A small text table of the cycle figures (for notebooks and the CLI)."""
        lines = [f"{'stage':<14}{'cycles':>12}{'latency':>10}"]
        for name, cyc in self.cycles.items():
            lines.append(f"{name:<14}{cyc:>12,}{self.latency[name]:>10,}")
        lines.append(f"total {self.total_cycles:,} cycles = {self.frame_time_s * 1e3:.3f} ms at "
                     f"{self.clock_hz / 1e6:g} MHz (bottleneck: {self.report.bottleneck}); "
                     f"network {self.network_time_s * 1e3:.3f} ms at {self.line_rate_bps / 1e9:g} Gb/s "
                     f"(payload; {self.wire_time_s * 1e3:.3f} ms as TCP over Ethernet)")
        return "\n".join(lines)


class Pipeline:
    """The FPGA component's data path, configured like the circuit HLS would build.

    Args:
        width, height, encoding: the image the circuit is built for; ``None`` accepts any legal
            value (up to ``hw.limits``). A frame that disagrees is refused.
        op: ``"dilate"`` (the paper's), ``"erode"`` or ``"passthrough"`` (``"copy"`` accepted).
        ksize: the rectangle ``(width, height)``, OpenCV's order; the paper uses ``(3, 3)``.
        model: ``"fast"`` (numpy) or ``"reference"`` (one byte/beat at a time).
        clock_hz: the circuit's clock, for ``frame_time_s``.
        line_rate_bps: the network's line rate, for ``network_time_s``.
        rx_fifo_depth, rx_burst_bytes: the receive FIFO and the network's burst size.
        seq: ``"count"`` (the generator numbers frames from ``seq_start``, as rospy does) or
            ``"carry"`` (copy the input's seq).
        seq_start: first seq when counting.
        stamp: ``(secs, nsecs)`` to write, or ``None`` to carry the input's stamp.
        frame_id: the frame_id to write, or ``None`` to carry the input's.
        max_frame_id_bytes: longest input ``header.frame_id`` the interpreter keeps (the
            generated circuit's ``FRAME_ID_MAX``); a frame with a longer one is refused.
        faults: faults to inject (:mod:`rosfpga_lab.hw.faults`).

    Raises:
        PipelineConfigError: an impossible setting (the message names it).
    """

    @classmethod
    def from_config(cls, config: NodeConfig, model: str = "fast") -> Pipeline:
        """The model of the circuit a node configuration describes (the generator's, the RTL's
        and the emulated node's one wiring of configuration to model).

        Raises:
            PipelineConfigError: ``op: custom`` (the lab cannot model the user's C++).
        """
        app = config.application
        if app.op == CUSTOM:
            raise PipelineConfigError("a custom application has no Python model; compare its C "
                                      "simulation against your own expectation")
        return cls(width=config.image.width, height=config.image.height,
                   encoding=config.image.encoding, op=app.op,
                   ksize=model_ksize(app.op, app.ksize), model=model,
                   clock_hz=config.clock_mhz * 1e6, rx_fifo_depth=config.fifo.input_depth,
                   max_frame_id_bytes=config.frame_id_max)

    def __init__(self, width: int | None = None, height: int | None = None,
                 encoding: str | None = None, op: str = DEFAULT_OP,
                 ksize: tuple[int, int] = (3, 3), model: str = "fast",
                 clock_hz: float = limits.DEFAULT_CLOCK_HZ,
                 line_rate_bps: float = limits.DEFAULT_LINE_RATE_BPS,
                 rx_fifo_depth: int = limits.DEFAULT_RX_FIFO_DEPTH,
                 rx_burst_bytes: int = limits.DEFAULT_RX_BURST_BYTES,
                 seq: str = "count", seq_start: int = 1,
                 stamp: tuple[int, int] | None = None, frame_id: str | None = None,
                 max_frame_id_bytes: int = limits.MAX_FRAME_ID_BYTES,
                 faults: Sequence[Fault] = ()) -> None:
        if model not in PIPELINE_MODELS:
            raise PipelineConfigError(
                f"model must be one of {', '.join(PIPELINE_MODELS)}, got {model!r}")
        if seq not in SEQ_MODES:
            raise PipelineConfigError(f"seq must be one of {', '.join(SEQ_MODES)}, got {seq!r}")
        if encoding is not None:
            pixel_format(encoding)
        for name, value, limit in (("width", width, limits.MAX_WIDTH), ("height", height, limits.MAX_HEIGHT)):
            if value is not None and not 1 <= value <= limit:
                raise PipelineConfigError(f"{name} must be in 1..{limit}, got {value}")
        if clock_hz <= 0 or line_rate_bps <= 0:
            raise PipelineConfigError("clock_hz and line_rate_bps must be positive")
        if not 0 <= seq_start < 2**32:
            raise PipelineConfigError(f"seq_start must be a uint32, got {seq_start}")
        if stamp is not None:
            try:
                secs, nsecs = (int(v) for v in stamp)
                good = 0 <= secs < 2**32 and 0 <= nsecs < 2**32
            except (TypeError, ValueError):
                good = False
            if not good:
                raise PipelineConfigError(f"stamp must be (secs, nsecs), two uint32, got {stamp!r}")
            stamp = (secs, nsecs)
        if frame_id is not None and (not isinstance(frame_id, str)
                                     or len(frame_id.encode("utf-8", "surrogateescape"))
                                     > limits.MAX_FRAME_ID_BYTES):
            raise PipelineConfigError(
                f"frame_id must be a str of at most {limits.MAX_FRAME_ID_BYTES} bytes, got {frame_id!r}")
        self.ksize = check_op(op, ksize)
        self.width, self.height, self.encoding, self.model = width, height, encoding, model
        self.op = canonical_op(op)
        self.clock_hz, self.line_rate_bps = float(clock_hz), float(line_rate_bps)
        self.seq_mode, self.seq_start, self.stamp, self.frame_id = seq, seq_start, stamp, frame_id
        self.max_frame_id_bytes = max_frame_id_bytes
        self.faults = tuple(faults)
        for fault in self.faults:
            if not isinstance(fault, Fault):
                raise PipelineConfigError(f"not a fault: {fault!r}")
        shallow = [f for f in self.faults if isinstance(f, ShallowFifo)]
        self.rx_fifo_depth = shallow[-1].depth if shallow else rx_fifo_depth
        self.rx_burst_bytes = shallow[-1].burst_bytes if shallow else rx_burst_bytes
        check_rx(self.rx_fifo_depth, self.rx_burst_bytes)
        self.frames_out = 0
        self.errors = 0
        self._scratch_image: np.ndarray | None = None
        self.reset()

    def reset(self, *, seq: bool = False) -> None:
        """Reset every stage.

        Args:
            seq: also restart the generator's frame counter (``seq_start`` comes next); by
                default it keeps counting, as a publisher's does across a bad frame.
        """
        self._interp = Interpreter(ByteFIFO(name="pixels_in"), self.width, self.height, self.encoding,
                                   max_frame_id_bytes=self.max_frame_id_bytes)
        if seq:
            self.frames_out = 0

    def __repr__(self) -> str:
        return (f"Pipeline(width={self.width}, height={self.height}, encoding={self.encoding!r}, "
                f"op={self.op!r}, ksize={self.ksize}, model={self.model!r}, "
                f"clock_hz={self.clock_hz:g}, faults={list(self.faults)})")

    def _scratch(self, shape: tuple[int, ...]) -> np.ndarray:
        if self._scratch_image is None or self._scratch_image.shape != shape:
            self._scratch_image = np.empty(shape, np.uint8)
        return self._scratch_image

    @property
    def next_seq(self) -> int:
        """The seq the generator writes on the next frame (``seq="count"``)."""
        return (self.seq_start + self.frames_out) & 0xFFFFFFFF

    def process(self, frame: bytes) -> PipelineResult:
        """Run one whole TCPROS frame (4-byte length + ``sensor_msgs/Image`` body) through.

        Raises:
            PipelineError: (a subclass) bad frame, stream starved, FIFO overflow; every stage
                has been reset, the next good frame will come out right.
        """
        try:
            if self.model == "fast":
                result = self._run_fast(bytes(frame))
            else:
                result = self._run_reference(bytes(frame))
        except PipelineError:
            self.errors += 1
            self.reset()
            raise
        self.frames_out += 1
        return result

    def process_stream(self, data: bytes) -> StreamResult:
        """Run a continuous byte stream of TCPROS frames through, as the circuit reads it.

        The subscriber circuit (HLS and Verilog) reads a frame length; one above
        ``hw.limits.MAX_FRAME_BYTES`` cannot be trusted for skipping, so it takes only those 4
        bytes and reads the next 4 as a new frame length; any other frame (a short one too) is
        read or skipped to its end. A frame cut short by the end of ``data`` is left unread.

        Returns:
            The bytes sent, the subscriber's status per frame (byte offset, name as in
            :data:`~rosfpga_lab.hw.interpreter.SUBSCRIBER_STATUSES`) and the bytes left unread.

        Raises:
            PipelineError: an error other than a refused field (a fault, a FIFO overflow).
        """
        out = bytearray()
        status: list[tuple[int, str]] = []
        offset, n = 0, len(data)
        while offset + 4 <= n:
            length = int.from_bytes(data[offset:offset + 4], "little")
            if length > limits.MAX_FRAME_BYTES:
                status.append((offset, _STATUS_OF_LABEL["frame length"]))
                self.errors += 1
                offset += 4
                continue
            if 4 + length > n - offset:
                break
            try:
                out += self.process(data[offset:offset + 4 + length]).output_frame
                status.append((offset, SUBSCRIBER_STATUSES[0][0]))
            except FrameFieldError as exc:
                status.append((offset, _circuit_status(exc)))
            offset += 4 + length
        return StreamResult(bytes(out), tuple(status), n - offset)

    # -- helpers shared by both models --------------------------------------------------------
    def _faults(self, tap: str) -> list[Fault]:
        return [f for f in self.faults if f.tap == tap and not isinstance(f, ShallowFifo)]

    def _bytes_at(self, tap: str, data: np.ndarray) -> np.ndarray:
        for fault in self._faults(tap):
            assert isinstance(fault, ByteFault)
            data = fault.apply(data)
        return data

    def _beats_at(self, tap: str, beats: Beats) -> Beats:
        for fault in self._faults(tap):
            assert isinstance(fault, BeatFault)
            beats = fault.apply(beats)
        return beats

    def _output_fields(self, fields: ImageFields) -> ImageFields:
        changes: dict = {}
        if self.seq_mode == "count":
            changes["seq"] = self.next_seq
        if self.stamp is not None:
            changes["stamp_secs"], changes["stamp_nsecs"] = self.stamp
        if self.frame_id is not None:
            changes["frame_id"] = self.frame_id
        out = dataclasses.replace(fields, **changes)
        return dataclasses.replace(out, frame_length=frame_length(out))

    def _finish(self, frame: bytes, fields: ImageFields, out_fields: ImageFields, output: bytes,
                images: tuple[np.ndarray, np.ndarray], beats: tuple[Beats, Beats], high_water: int,
                status: list[str], pixels: tuple[np.ndarray, np.ndarray]) -> PipelineResult:
        report = account(fields, self.op, self.ksize, len(frame), len(output))
        for array in (*pixels, *images):
            array.setflags(write=False)  # results are records: nothing may change them later
        streams: dict[str, bytes | np.ndarray | Beats] = {
            "rx": frame, "pixels_in": pixels[0], "axis_in": beats[0], "axis_out": beats[1],
            "pixels_out": pixels[1], "tx": output}
        return PipelineResult(output, fields, out_fields, images[0], images[1], beats[0], beats[1],
                              report, self.clock_hz, self.line_rate_bps, {"rx": high_water},
                              status, self.model, streams)

    @staticmethod
    def _leftover(status: list[str], stream: str, left: int, unit: str) -> None:
        if left:
            status.append(f"{left} {unit}{'s' if left != 1 else ''} left in '{stream}' after the "
                          "frame (flushed): the stream was out of step")

    # -- the fast model -----------------------------------------------------------------------
    def _run_fast(self, frame: bytes) -> PipelineResult:
        status: list[str] = []
        raw = self._bytes_at("rx", np.frombuffer(frame, np.uint8))
        frame = raw.tobytes() if self._faults("rx") else frame
        high_water = receive_fast_check(len(frame), self.rx_fifo_depth, self.rx_burst_bytes)
        fields, pixels = interpret_fast(frame, width=self.width, height=self.height,
                                        encoding=self.encoding,
                                        max_frame_id_bytes=self.max_frame_id_bytes)
        fmt = PIXEL_FORMATS[fields.encoding]
        rows, cols = fields.height, fields.width
        pixels = self._bytes_at("pixels_in", pixels)
        pixels_in_bytes = pixels
        beats_in, left = fifo2axi_fast(pixels, rows, cols, fmt)
        self._leftover(status, "pixels_in", left, "byte")
        beats_in = self._beats_at("axis_in", beats_in)
        image_in, flags, left = axivideo2mat_fast(beats_in, rows, cols, fmt)
        status += [f"AXIvideo2Mat: {name}" for name in status_names(flags)]
        self._leftover(status, "axis_in", left, "beat")
        # The filter writes into a scratch image owned by the pipeline (no fresh pages per frame);
        # the result's output image and beats then become read-only views of the output frame.
        image_out = morph_fast(image_in, self.op, self.ksize, out=self._scratch(image_in.shape))
        beats_out = self._beats_at("axis_out", mat2axivideo_fast(image_out, fmt))
        data_out, left = axi2fifo_fast(beats_out, rows * cols)
        self._leftover(status, "axis_out", left, "beat")
        data_out = self._bytes_at("pixels_out", data_out)
        out_fields = self._output_fields(fields)
        output = generate_fast(out_fields, data_out)
        self._leftover(status, "pixels_out", data_out.size - out_fields.data_length, "byte")
        if self._faults("axis_out") or self._faults("pixels_out"):
            image_out, beats_out = image_out.copy(), beats_out.copy()
            pixels_out = data_out.copy()
        else:
            pixels_out = np.frombuffer(output, np.uint8, out_fields.data_length,
                                       len(output) - out_fields.data_length)
            scratch = image_out
            image_out = pixels_out.reshape(scratch.shape)
            if np.may_share_memory(beats_out.tdata, scratch):  # 4-byte pixels: a view of it
                beats_out = mat2axivideo_fast(image_out, fmt)
        return self._finish(frame, fields, out_fields, output, (image_in, image_out),
                            (beats_in, beats_out), high_water, status,
                            (pixels_in_bytes, pixels_out))

    # -- the reference model ------------------------------------------------------------------
    def _refill_bytes(self, tap: str, fifo: ByteFIFO) -> None:
        if self._faults(tap):
            data = self._bytes_at(tap, np.frombuffer(bytes(fifo.drain()), np.uint8))
            fifo.extend(data.tolist())

    def _refill_beats(self, tap: str, fifo: Fifo[Beat]) -> None:
        if self._faults(tap):
            fifo.extend(self._beats_at(tap, Beats.from_list(fifo.drain())).to_list())

    def _run_reference(self, frame: bytes) -> PipelineResult:
        status: list[str] = []
        if self._faults("rx"):
            frame = self._bytes_at("rx", np.frombuffer(frame, np.uint8)).tobytes()
        pixels_in = self._interp.out
        pixels_in.reset()
        high_water = receive_reference(frame, self._interp, self.rx_fifo_depth, self.rx_burst_bytes)
        fields = self._interp.fields
        assert fields is not None
        fmt = PIXEL_FORMATS[fields.encoding]
        rows, cols, channels = fields.height, fields.width, fmt.bytes_per_pixel
        self._refill_bytes("pixels_in", pixels_in)
        pixels_in_bytes = np.frombuffer(pixels_in.to_bytes(), np.uint8)
        axis_in: Fifo[Beat] = Fifo(None, "axis_in")
        fifo2axi_reference(pixels_in, axis_in, rows, cols, fmt)
        self._leftover(status, "pixels_in", len(pixels_in.drain()), "byte")
        self._refill_beats("axis_in", axis_in)
        beats_in = Beats.from_list(axis_in)
        src = Mat(rows, cols, channels, "src")
        flags = axivideo2mat_reference(axis_in, src)
        status += [f"AXIvideo2Mat: {name}" for name in status_names(flags)]
        self._leftover(status, "axis_in", len(axis_in.drain()), "beat")
        image_in = src.to_numpy()
        dst = Mat(rows, cols, channels, "dst")
        morph_reference(src, dst, self.op, self.ksize)
        image_out = dst.to_numpy()
        axis_out: Fifo[Beat] = Fifo(None, "axis_out")
        mat2axivideo_reference(dst, axis_out, fmt)
        self._refill_beats("axis_out", axis_out)
        beats_out = Beats.from_list(axis_out)
        pixels_out = ByteFIFO(name="pixels_out")
        axi2fifo_reference(axis_out, pixels_out, rows * cols)
        self._leftover(status, "axis_out", len(axis_out.drain()), "beat")
        self._refill_bytes("pixels_out", pixels_out)
        pixels_out_bytes = np.frombuffer(pixels_out.to_bytes(), np.uint8)
        out_fields = self._output_fields(fields)
        tx = ByteFIFO(name="tx")
        generate_reference(out_fields, pixels_out, tx)
        self._leftover(status, "pixels_out", len(pixels_out.drain()), "byte")
        return self._finish(frame, fields, out_fields, tx.to_bytes(), (image_in, image_out),
                            (beats_in, beats_out), high_water, status,
                            (pixels_in_bytes, pixels_out_bytes))
