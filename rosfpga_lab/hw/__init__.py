"""Bit-exact models of the FPGA component's data path: one engine for every message type.

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

Quick start::

    from rosfpga_lab.config import load_config
    from rosfpga_lab.hw import MessagePipeline, image_frame
    pipe = MessagePipeline.from_config(load_config("data/fpga_dilate_rgba8.yaml"))
    res = pipe.process(frame_bytes)      # one TCPROS frame: 4-byte length + body
    res.output_frame, res.extracted, res.cycles, res.input_image, res.output_image

A bad frame raises a :class:`PipelineError` subclass naming the field and byte offset.

The video stretch of an Image circuit (module ``videostages``), importable for notebooks:

* ``fifo2axi`` / ``axi2fifo``: :func:`fifo2axi_reference`, :func:`fifo2axi_fast`,
  :func:`axi2fifo_reference`, :func:`axi2fifo_fast` (module ``axis``; packing rules in
  :data:`PIXEL_FORMATS`);
* ``AXIvideo2Mat`` / ``Mat2AXIvideo``: :func:`axivideo2mat_reference`, :func:`axivideo2mat_fast`,
  :func:`mat2axivideo_reference`, :func:`mat2axivideo_fast` with :class:`Mat`;
* application: :func:`morph_reference` / :func:`morph_fast` (``dilate``, ``erode``, ``copy``);
  on a beat stream, damaged or not, as ``rfl_morph.v``: :func:`morph_stream_reference` /
  :func:`morph_stream_fast` (framing rules and flags :data:`FRAMING_FLAGS`, module ``framing``).

Streams: :class:`Fifo`, :class:`ByteFIFO`, :class:`Beat`, :class:`Beats`. Faults:
:class:`DropByte`, :class:`DuplicateByte`, :class:`SwapByteOrder`, :class:`LoseTlast`,
:class:`LoseTuser` (module ``faults``, at the taps of
:func:`~rosfpga_lab.hw.videostages.video_stages`): a fault gives a wrong image, a status flag or
a typed :class:`PipelineError`, never a hang. Errors: :class:`PipelineError` and subclasses.
The packing rule (the generalised Figure 7: which bytes of a pixel go where in ``tdata``, and
``tkeep``) is module ``encodings``'s docstring and :data:`PIXEL_FORMATS`.
"""

from rosfpga_lab.hw.axis import axi2fifo_fast, axi2fifo_reference, fifo2axi_fast, fifo2axi_reference
from rosfpga_lab.hw.encodings import PIXEL_FORMATS, PixelFormat, pixel_format
from rosfpga_lab.hw.errors import (
    FrameFieldError, FrameLengthError, FrameTruncatedError,
    PipelineConfigError, PipelineError, StreamStarvedError, UnsupportedEncodingError,
)
from rosfpga_lab.hw.faults import (
    DropByte, DuplicateByte, Fault, LoseTlast, LoseTuser, SwapByteOrder,
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
from rosfpga_lab.hw.sample import image_frame
from rosfpga_lab.hw.streams import Beat, Beats, ByteFIFO, Fifo
from rosfpga_lab.hw.video import (
    ERROR_IO_EOL_EARLY, ERROR_IO_EOL_LATE, ERROR_IO_SOF_EARLY, Mat, axivideo2mat_fast,
    axivideo2mat_reference, mat2axivideo_fast, mat2axivideo_reference,
)

__all__ = [
    "ERROR_IO_EOL_EARLY", "ERROR_IO_EOL_LATE", "ERROR_IO_SOF_EARLY", "OPS", "PIXEL_FORMATS",
    "Beat", "Beats", "ByteFIFO", "DropByte", "DuplicateByte", "Fault", "Fifo",
    "FrameFieldError", "FrameLengthError", "FrameTruncatedError",
    "LoseTlast", "LoseTuser", "Mat", "PipelineConfigError", "PipelineError", "wire_bytes",
    "PixelFormat", "StreamStarvedError", "SwapByteOrder",
    "UnsupportedEncodingError", "axi2fifo_fast", "axi2fifo_reference", "axivideo2mat_fast",
    "axivideo2mat_reference", "fifo2axi_fast", "fifo2axi_reference", "image_frame",
    "mat2axivideo_fast", "mat2axivideo_reference", "morph_fast", "morph_reference",
    "pixel_format", "Layout", "derive_layout", "format_layout", "layout_from_config",
    "morph1d_fast", "morph1d_reference", "Extracted", "LayoutInterpreter", "extract_fast",
    "extract_reference", "publish_fast", "publish_reference", "MessagePipeline",
    "MessageResult", "CdrPipeline", "CdrResult", "FRAMING_FLAGS", "morph_stream_fast",
    "morph_stream_reference",
]
