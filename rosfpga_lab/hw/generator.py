"""STEP 2, publisher side: the message generator writes a whole TCPROS ``sensor_msgs/Image``.

Like the HLS publisher circuit it hard-codes the layout: it walks :data:`GENERATOR_TABLE`,
writing each field little-endian, one byte per clock, into the transmit FIFO; when it reaches
``data`` it copies ``data_length`` pixel bytes from ``axi2fifo``'s FIFO. The 4-byte frame
length goes first, so the circuit computes it from the sizes it already knows (fixed part +
``frame_id`` + ``encoding`` + data). The header values (``seq``, stamp, ``frame_id``) are chosen
by the caller (the :class:`~rosfpga_lab.hw.Pipeline`: ``seq`` counts up from 1 per published
frame, as rospy's publisher does, stamp and ``frame_id`` are carried over unless set).
"""

from __future__ import annotations

import struct

import numpy as np

from rosfpga_lab.hw.errors import StreamStarvedError
from rosfpga_lab.hw.interpreter import MIN_BODY_BYTES, ImageFields, Kind
from rosfpga_lab.hw.streams import ByteFIFO

#: (label, kind, attribute of ImageFields) in wire order; kinds are the interpreter's :class:`Kind`.
GENERATOR_TABLE: tuple[tuple[str, Kind, str], ...] = (
    ("frame length", Kind.U32, "frame_length"),
    ("header.seq", Kind.U32, "seq"),
    ("header.stamp.secs", Kind.U32, "stamp_secs"),
    ("header.stamp.nsecs", Kind.U32, "stamp_nsecs"),
    ("header.frame_id", Kind.STRING, "frame_id"),
    ("height", Kind.U32, "height"),
    ("width", Kind.U32, "width"),
    ("encoding", Kind.STRING, "encoding"),
    ("is_bigendian", Kind.U8, "is_bigendian"),
    ("step", Kind.U32, "step"),
    ("data", Kind.PIXELS, "data_length"),
)


def _text(value: str) -> bytes:
    return value.encode("utf-8", "surrogateescape")


def frame_length(fields: ImageFields) -> int:
    """The body length the generator announces for ``fields`` (4-byte prefix excluded)."""
    return MIN_BODY_BYTES + len(_text(fields.frame_id)) + len(_text(fields.encoding)) + fields.data_length


def generate_reference(fields: ImageFields, inp: ByteFIFO, out: ByteFIFO) -> None:
    """Reference model: write the frame for ``fields`` one byte at a time into ``out``.

    Raises:
        StreamStarvedError: ``inp`` held fewer than ``data_length`` bytes.
    """
    for label, kind, attr in GENERATOR_TABLE:
        value = frame_length(fields) if attr == "frame_length" else getattr(fields, attr)
        if kind is Kind.U32:
            for i in range(4):
                out.write((value >> (8 * i)) & 0xFF)
        elif kind is Kind.U8:
            out.write(value & 0xFF)
        elif kind is Kind.STRING:
            raw = _text(str(value))
            for i in range(4):
                out.write((len(raw) >> (8 * i)) & 0xFF)
            for byte in raw:
                out.write(byte)
        else:  # pixels: the data length prefix, then the bytes from axi2fifo
            for i in range(4):
                out.write((value >> (8 * i)) & 0xFF)
            for _ in range(value):
                out.write(inp.read("generator", value))


def generate_fast(fields: ImageFields, data: np.ndarray) -> bytes:
    """Fast model: the same frame with ``struct`` and one copy of the pixel bytes.

    Raises:
        StreamStarvedError: ``data`` is shorter than ``data_length``.
    """
    if data.size < fields.data_length:
        raise StreamStarvedError(
            f"read from empty FIFO 'pixels_out' after {data.size} items of the "
            f"{fields.data_length} needed: the upstream stage delivered too few "
            "(a lost byte, beat or TLAST?)", stage="generator", needed=fields.data_length,
            got=int(data.size))
    frame_id, encoding = _text(fields.frame_id), _text(fields.encoding)
    head = b"".join((
        struct.pack("<IIIII", frame_length(fields), fields.seq, fields.stamp_secs,
                    fields.stamp_nsecs, len(frame_id)),
        frame_id,
        struct.pack("<III", fields.height, fields.width, len(encoding)),
        encoding,
        struct.pack("<BII", fields.is_bigendian & 0xFF, fields.step, fields.data_length),
    ))
    return b"".join((head, np.ascontiguousarray(data[: fields.data_length]).data))
