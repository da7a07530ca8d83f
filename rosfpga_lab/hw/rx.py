"""The receive FIFO between the hard-wired TCP/IP stack and the interpreter.

The network side lands a TCP segment of ``burst_bytes`` in the FIFO at once, one segment every
``burst_bytes`` clocks (the average rate then matches the interpreter's one byte per clock);
the interpreter drains one byte per clock. The FIFO therefore fills to ``burst_bytes`` right
after each segment, and a FIFO shallower than that overflows: the circuit would lose bytes, the
model raises :class:`~rosfpga_lab.hw.errors.FifoOverflowError`. ``burst_bytes=1`` is a byte per
clock, the FIFO never holds more than one byte.
"""

from __future__ import annotations

from rosfpga_lab.hw.errors import FifoOverflowError, PipelineConfigError
from rosfpga_lab.hw.interpreter import Interpreter, check_trailing, require_frame
from rosfpga_lab.hw.streams import ByteFIFO


def check_rx(depth: int, burst_bytes: int) -> None:
    """Validate the receive FIFO's parameters.

    Raises:
        PipelineConfigError: a depth or burst below 1.
    """
    if depth < 1 or burst_bytes < 1:
        raise PipelineConfigError(
            f"receive FIFO depth ({depth}) and burst_bytes ({burst_bytes}) must be at least 1")


def _overflow(depth: int, burst: int) -> FifoOverflowError:
    return FifoOverflowError(
        f"FIFO 'rx' ({depth} bytes deep) overflowed: the network lands {burst} bytes at once "
        f"and the interpreter drains one per clock; make the FIFO at least {burst} bytes deep",
        stage="rx", depth=depth, needed=burst)


def receive_reference(frame: bytes, interp: Interpreter, depth: int, burst_bytes: int) -> int:
    """Clock ``frame`` through the receive FIFO into ``interp`` until the frame is decoded.

    Returns:
        the FIFO's high-water mark.

    Raises:
        FifoOverflowError: a write met a full FIFO.
        FrameFieldError: from the interpreter (bad field, frame cut short, trailing bytes).
    """
    check_rx(depth, burst_bytes)
    rx = ByteFIFO(depth, "rx")
    frames_before = interp.frames
    pos, clock = 0, 0
    while pos < len(frame) or not rx.empty:
        if clock % burst_bytes == 0 and pos < len(frame):     # a segment lands
            for byte in frame[pos:pos + burst_bytes]:
                if not rx.write(byte):
                    raise _overflow(depth, min(burst_bytes, len(frame)))
            pos += burst_bytes
        if not rx.empty:
            interp.push(rx.read("interpreter"))
            if interp.frames != frames_before:
                break
        clock += 1
    interp.finish()
    require_frame(interp, frames_before)
    left = rx.level + len(frame) - min(pos, len(frame))
    if left:
        check_trailing(interp, left)
    return rx.high_water


def receive_fast_check(size: int, depth: int, burst_bytes: int) -> int:
    """The same FIFO's high-water mark, in closed form; raises as :func:`receive_reference`."""
    check_rx(depth, burst_bytes)
    high = min(burst_bytes, size)
    if high > depth:
        raise _overflow(depth, high)
    return high
