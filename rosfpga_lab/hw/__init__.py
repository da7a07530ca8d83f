"""Bit-exact models of the FPGA component's data path (STEPs 2 and 3 and the application).

The paper's circuit, stage by stage, each in two implementations: a readable ``reference``
model that moves one byte or beat per step and mirrors the HLS C++, and a ``fast`` numpy model
for real frames; property tests hold them equal.

Quick start::

    from rosfpga_lab.hw import Pipeline, image_frame
    pipe = Pipeline(width=640, height=480, encoding="rgba8", op="dilate", ksize=(3, 3))
    res = pipe.process(frame_bytes)      # one TCPROS frame: 4-byte length + Image body
    res.output_frame                     # the TCPROS frame the publisher circuit writes
    res.fields, res.output_fields        # decoded / written header fields (ImageFields)
    res.input_image, res.output_image    # (rows, cols, channels) uint8
    res.input_beats, res.output_beats    # Beats: tdata/tkeep/tuser/tlast numpy arrays
    res.cycles, res.latency              # per stage, at II=1
    res.total_cycles, res.frame_time_s, res.network_time_s, res.fifo_high_water, res.status
    res.streams                          # what travelled on every tap between stages
    print(res.summary())                 # cycles/latency table, frame time vs network time

A bad frame raises a :class:`PipelineError` subclass naming the field and byte offset
(:class:`FrameFieldError`, :class:`UnsupportedEncodingError`, :class:`FrameTruncatedError`,
:class:`FrameLengthError`); a broken stream raises :class:`StreamStarvedError` or
:class:`FifoOverflowError` (``.partial`` holds what was made so far). Either way every stage
has been reset and the next good frame comes out right. ``Pipeline(model="reference")`` runs
the byte/beat-at-a-time models (small images: a 160x120 frame takes about half a second).

The circuit's one layout (every field in wire order and what the circuit does with it) is
derived from a ``.msg`` and the configuration by :func:`derive_layout` (module ``layout``
tells it and gathers the names of ``layoutsteps``, the types, ``layoutderive``, the
derivation, ``layoutlengths``, the length rules, and ``layouttokens``, values in walk order);
the subscriber and publisher of any type are rendered from it (module ``walker`` gathers
``subscriberwalker``: :class:`LayoutInterpreter`, :func:`extract_reference` /
:func:`extract_fast`, and ``publisherwalker``: :func:`publish_reference` /
:func:`publish_fast`), the 1-D application in ``morph1d``, the
whole circuit of any type, ``sensor_msgs/Image`` included (its video stream through the 2-D
application), in :class:`MessagePipeline` (``msgpipeline``), from a configuration's layouts
derived once (``circuit``: :func:`~rosfpga_lab.hw.circuit.circuit_layouts`). CDR (ROS 2)
is the second wire format of the same layout (``cdrlayout``, ``cdrwalker``), the whole circuit
on CDR samples, Image included, :class:`CdrPipeline` (``cdrpipeline``).

Stages (``reference`` / ``fast``), importable for notebooks:

* receive FIFO: :func:`receive_reference` / :func:`receive_fast_check` (module ``rx``);
* interpreter: :class:`Interpreter` (state machine over :data:`INTERPRETER_TABLE`, printed
  by :func:`format_table`; ``Interpreter().trace(frame)`` lists state and field per byte),
  :func:`interpret_reference` / :func:`interpret_fast`;
* ``fifo2axi`` / ``axi2fifo``: :func:`fifo2axi_reference`, :func:`fifo2axi_fast`,
  :func:`axi2fifo_reference`, :func:`axi2fifo_fast` (packing rules in :data:`PIXEL_FORMATS`);
* ``AXIvideo2Mat`` / ``Mat2AXIvideo``: :func:`axivideo2mat_reference`, :func:`axivideo2mat_fast`,
  :func:`mat2axivideo_reference`, :func:`mat2axivideo_fast` with :class:`Mat`;
* application: :func:`morph_reference` / :func:`morph_fast` (``dilate``, ``erode``, ``copy``);
  on a beat stream, damaged or not, as ``rfl_morph.v``: :func:`morph_stream_reference` /
  :func:`morph_stream_fast` (framing rules and flags :data:`FRAMING_FLAGS`, module ``framing``;
  ``fifo2axi``'s start-of-frame re-sync: ``axis.fifo2axi_stream_reference`` / ``_fast``);
* message generator: :func:`generate_reference` / :func:`generate_fast` (:data:`GENERATOR_TABLE`).

Streams: :class:`Fifo`, :class:`ByteFIFO`, :class:`Beat`, :class:`Beats`. Faults:
:class:`DropByte`, :class:`DuplicateByte`, :class:`SwapByteOrder`, :class:`LoseTlast`,
:class:`LoseTuser`, :class:`ShallowFifo` (module ``faults``): a fault gives a wrong image, a
status flag or a typed :class:`PipelineError`, never a hang. Errors: :class:`PipelineError` and
subclasses. The packing rule (the generalised Figure 7: which bytes of a pixel go where in
``tdata``, and ``tkeep``) is module ``encodings``'s docstring and :data:`PIXEL_FORMATS`.

Cycles at II=1 (module ``cycles``): ``res.summary()`` prints each stage's cycles, the frame time
and the payload's time on gigabit Ethernet; for a 640x480 rgba8 frame the byte-wide input FIFO
(one byte per clock), not the application (one pixel per clock), limits the circuit.

When (module ``clocked``): ``clocked.fifo2axi_clocks(data, width, bytes_per_pixel, in_valid=...,
out_ready=...)`` follows ``rfl_fifo2axi.v`` register for register and returns every signal at
every clock (one byte taken per clock, a beat the clock after a pixel's last byte, backpressure
holding back only a pixel's last byte); a test feeds it a real RTL simulation's offers and
readiness and requires the RTL's beats at the RTL's clocks.
"""

from rosfpga_lab.hw.axis import axi2fifo_fast, axi2fifo_reference, fifo2axi_fast, fifo2axi_reference
from rosfpga_lab.hw.cycles import CycleReport, account
from rosfpga_lab.hw.encodings import PIXEL_FORMATS, PixelFormat, pixel_format
from rosfpga_lab.hw.errors import (
    FifoOverflowError, FrameFieldError, FrameLengthError, FrameTruncatedError,
    PipelineConfigError, PipelineError, StreamStarvedError, UnsupportedEncodingError,
)
from rosfpga_lab.hw.faults import (
    DropByte, DuplicateByte, Fault, LoseTlast, LoseTuser, ShallowFifo, SwapByteOrder,
)
from rosfpga_lab.hw.generator import GENERATOR_TABLE, frame_length, generate_fast, generate_reference
from rosfpga_lab.hw.interpreter import (
    INTERPRETER_TABLE, Check, ImageFields, Interpreter, IState, Kind, Transition, format_table,
    interpret_fast,
    interpret_reference,
)
from rosfpga_lab.hw.layoutderive import derive_layout, layout_from_config
from rosfpga_lab.hw.layoutsteps import Layout, format_layout
from rosfpga_lab.hw.morph1d import morph1d_fast, morph1d_reference
from rosfpga_lab.hw.msgpipeline import MessagePipeline, MessageResult, wire_bytes
from rosfpga_lab.hw.cdrpipeline import CdrPipeline, CdrResult
from rosfpga_lab.hw.publisherwalker import publish_fast, publish_reference
from rosfpga_lab.hw.subscriberwalker import (
    Extracted, LayoutInterpreter, extract_fast, extract_reference,
)
from rosfpga_lab.hw.framing import FRAMING_FLAGS
from rosfpga_lab.hw.morph import (
    OPS, morph_fast, morph_reference, morph_stream_fast, morph_stream_reference,
)
from rosfpga_lab.hw.pipeline import Pipeline, PipelineResult
from rosfpga_lab.hw.sample import image_frame
from rosfpga_lab.hw.rx import receive_fast_check, receive_reference
from rosfpga_lab.hw.streams import Beat, Beats, ByteFIFO, Fifo
from rosfpga_lab.hw.video import (
    ERROR_IO_EOL_EARLY, ERROR_IO_EOL_LATE, ERROR_IO_SOF_EARLY, Mat, axivideo2mat_fast,
    axivideo2mat_reference, mat2axivideo_fast, mat2axivideo_reference,
)

__all__ = [
    "ERROR_IO_EOL_EARLY", "ERROR_IO_EOL_LATE", "ERROR_IO_SOF_EARLY", "GENERATOR_TABLE",
    "INTERPRETER_TABLE", "OPS", "PIXEL_FORMATS", "Beat", "Beats", "ByteFIFO", "Check", "CycleReport",
    "DropByte", "DuplicateByte", "Fault", "Fifo", "FifoOverflowError", "FrameFieldError",
    "FrameLengthError", "FrameTruncatedError", "IState", "ImageFields", "Interpreter", "Kind", "LoseTlast",
    "LoseTuser", "Mat", "Pipeline", "PipelineConfigError", "PipelineError", "PipelineResult", "wire_bytes",
    "PixelFormat", "ShallowFifo", "StreamStarvedError", "SwapByteOrder", "Transition",
    "UnsupportedEncodingError", "account", "axi2fifo_fast", "axi2fifo_reference",
    "axivideo2mat_fast", "axivideo2mat_reference", "fifo2axi_fast", "fifo2axi_reference",
    "format_table", "frame_length", "generate_fast", "generate_reference", "image_frame", "interpret_fast",
    "interpret_reference", "mat2axivideo_fast", "mat2axivideo_reference", "morph_fast",
    "morph_reference", "pixel_format", "receive_fast_check", "receive_reference",
    "Layout", "derive_layout", "format_layout", "layout_from_config", "morph1d_fast",
    "morph1d_reference", "Extracted", "LayoutInterpreter", "extract_fast", "extract_reference",
    "publish_fast", "publish_reference", "MessagePipeline", "MessageResult",
    "CdrPipeline", "CdrResult", "FRAMING_FLAGS", "morph_stream_fast", "morph_stream_reference",
]
