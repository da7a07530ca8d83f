"""The lab's shared vocabulary: the image encodings the circuit packs and the applications it runs.

Every other module derives its lists from these tables (the configuration checker, the
hardware models, the generator, the camera and the command line), so adding an encoding or an
operation is one edit here. The packing rule itself (how a pixel's bytes sit in ``tdata``) is
documented and implemented in :mod:`rosfpga_lab.hw.encodings`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PixelFormat:
    """The packing rule of one encoding.

    Attributes:
        encoding: the ROS encoding string.
        bytes_per_pixel: bytes of one pixel in the message (= channels, all are 8-bit).
        tkeep: the ``tkeep`` of every beat carrying one pixel.
        channels: channel names, byte 0 first.
    """

    encoding: str
    bytes_per_pixel: int
    tkeep: int
    channels: str


PIXEL_FORMATS: dict[str, PixelFormat] = {
    "rgba8": PixelFormat("rgba8", 4, 0b1111, "RGBA"),
    "bgra8": PixelFormat("bgra8", 4, 0b1111, "BGRA"),
    "rgb8": PixelFormat("rgb8", 3, 0b0111, "RGB"),
    "bgr8": PixelFormat("bgr8", 3, 0b0111, "BGR"),
    "mono8": PixelFormat("mono8", 1, 0b0001, "Y"),
}

#: Encodings the circuit can pack, with bytes per pixel.
ENCODINGS: dict[str, int] = {name: fmt.bytes_per_pixel for name, fmt in PIXEL_FORMATS.items()}

#: The encoding a camera or a command uses when none is given.
DEFAULT_ENCODING = "rgba8"

#: The identity operation: the image passes through the circuit unchanged. It is called
#: ``passthrough`` in every layer (configuration, models, generator, oracle); the hardware models
#: once called it ``copy``, a name :func:`canonical_op` still accepts.
PASSTHROUGH = "passthrough"
#: The user's own C++ ``stream_filter()`` (no Python model, no OpenCV oracle).
CUSTOM = "custom"
#: The operation a configuration without ``application.op`` gets (the paper's).
DEFAULT_OP = "dilate"
#: Operations the lab computes itself: the hardware models and the OpenCV oracle.
MODEL_OPS = ("dilate", "erode", PASSTHROUGH)
#: Operations the generated application can perform (``application.op`` of a node configuration).
OPS = (*MODEL_OPS, CUSTOM)

_OP_ALIASES = {"copy": PASSTHROUGH}
#: Element types of the one array a circuit streams to its application (``stream.field`` of a
#: node configuration): the numeric builtins, one AXI4-Stream beat of the element's width each
#: (``byte`` is genmsg's signed 8-bit alias, ``char`` its unsigned one). ``bool``, ``time``,
#: ``duration``, ``string`` and messages cannot stream.
STREAM_ELEMENT_TYPES = ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                        "float32", "float64", "byte", "char")
#: The circuit's Python models: ``fast`` (whole arrays) and ``reference`` (a byte at a time).
PIPELINE_MODELS = ("fast", "reference")
#: The simulated Verilog itself (a long-lived RTL simulator on the data path).
RTL_MODEL = "rtl"
#: What a component's data path can run: the Python models, or the Verilog.
MODELS = (*PIPELINE_MODELS, RTL_MODEL)
#: When a component publishes: ``host`` as soon as the model is done; ``fpga`` after the
#: circuit's clocks for the frame at ``clock_mhz`` (frames that come while it is busy dropped).
TIMINGS = ("host", "fpga")
#: The wire formats a circuit reads and writes: ROS 1's TCPROS frames, or ROS 2's CDR samples
#: (each behind a 4-byte sample length the RTPS reader writes into the byte FIFO).
TCPROS_WIRE = "tcpros"
CDR_WIRE = "cdr"
WIRES = (TCPROS_WIRE, CDR_WIRE)
DEFAULT_WIRE = TCPROS_WIRE
#: The Verilog simulators the RTL flow runs (the first one found is the default).
SIMULATORS = ("iverilog", "verilator")
#: The HLS tool the generated C++ is written for (``hls.flavour`` of a node configuration):
#: ``vitis`` (Vitis HLS 2020.2 on: ``#pragma HLS aggregate``, a ``vitis_hls`` script) or
#: ``vivado`` (the paper's Vivado HLS up to 2019.2: ``DATA_PACK``, a ``vivado_hls`` script); the
#: same C++ otherwise. Both run ``make csim`` with g++.
HLS_FLAVOURS = ("vitis", "vivado")
#: The flavour a configuration without ``hls.flavour`` gets: the tool a course installs today.
DEFAULT_HLS_FLAVOUR = "vitis"


def canonical_op(op: str) -> str:
    """The one name of ``op`` (``"copy"`` -> ``"passthrough"``; other names unchanged).

    Args:
        op: an operation name, possibly an accepted older alias.
    """
    return _OP_ALIASES.get(op, op)


def model_ksize(op: str, ksize: int) -> tuple[int, int]:
    """The ``(width, height)`` kernel the models use for ``op`` with a configured square ``ksize``
    (a pass-through has no window: ``(1, 1)``)."""
    return (1, 1) if canonical_op(op) == PASSTHROUGH else (ksize, ksize)
