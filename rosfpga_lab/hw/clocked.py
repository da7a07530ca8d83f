"""Clock-by-clock model of ``fifo2axi``: the byte stream and the beat stream with valid/ready.

The other models move whole bytes and beats; this one says *when*. It follows the RTL
(``rosfpga_lab/rtl/exhibit/rfl_fifo2axi.v``) register for register, so its per-clock arrays
are what a simulator's dump shows at every rising edge of ``aclk``:

* one byte is taken from the 8-bit stream per clock when ``s_tvalid`` and ``s_tready`` are
  both 1; a pixel of ``B`` bytes therefore needs ``B`` clocks (4 for ``rgba8``);
* the pixel's last byte loads the output register: ``m_axis_tvalid`` rises at the next clock
  and stays 1 until ``m_axis_tready`` takes the beat;
* while a beat waits, only the last byte of the next pixel is held back (``s_tready`` low),
  so the first ``B - 1`` bytes of a pixel keep flowing under backpressure.

Without gaps or backpressure, beat ``j`` is taken at clock ``(j + 1) * B``: one pixel every
``B`` clocks, the rate ``hw.cycles`` counts for the byte-wide stages.

The bytes are one clean frame (or a window of one), the first carrying the subscriber's
start-of-frame marker; the RTL's re-sync on a damaged byte stream (``hw.framing``) changes
nothing in that case and is modelled beat by beat, not clock by clock, by
``hw.axis.fifo2axi_stream_reference`` / ``_fast``.
"""

from __future__ import annotations

import numpy as np

from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.limits import CLOCKED_MAX_CLOCKS


def _stimulus(size: int, width: int, b: int, first_pixel: int, in_valid: np.ndarray | None,
              out_ready: np.ndarray | None, clocks: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Per clock, whether a byte is offered and whether the beat is taken, for ``size`` bytes
    of pixels of ``b`` bytes: as many clocks as asked, else as the arrays given hold, else
    ``(size + 2) * 4 + 8`` (more than the data takes when nothing holds it back).

    Raises:
        PipelineConfigError: a bad geometry, arrays too short, or more than
            :data:`CLOCKED_MAX_CLOCKS` clocks.
    """
    if not 1 <= b <= 4 or width < 1 or first_pixel < 0:
        raise PipelineConfigError(f"bad geometry: width={width}, bytes_per_pixel={b}, first_pixel={first_pixel}")
    if size % b:
        raise PipelineConfigError(f"{size} bytes are not whole pixels of {b} bytes")
    n = clocks if clocks is not None else (size + 2) * 4 + 8
    if in_valid is not None or out_ready is not None:
        given = [a.size for a in (in_valid, out_ready) if a is not None]
        n = clocks if clocks is not None else min(given)
    if n > CLOCKED_MAX_CLOCKS:
        raise PipelineConfigError(f"{n} clocks is more than this model simulates "
                                  f"({CLOCKED_MAX_CLOCKS}); "
                                  "use the RTL simulation for whole frames")
    ivalid = np.ones(n, bool) if in_valid is None else np.asarray(in_valid, bool)[:n]
    oready = np.ones(n, bool) if out_ready is None else np.asarray(out_ready, bool)[:n]
    if ivalid.size < n or oready.size < n:
        raise PipelineConfigError("in_valid and out_ready need a value for every clock")
    return ivalid, oready


def fifo2axi_clocks(data: bytes | np.ndarray, width: int, bytes_per_pixel: int, *,
                    first_pixel: int = 0, in_valid: np.ndarray | None = None,
                    out_ready: np.ndarray | None = None, clocks: int | None = None,
                    ) -> dict[str, np.ndarray]:
    """Per-clock signals of ``fifo2axi`` moving the pixel bytes ``data``.

    Args:
        data: the pixel bytes, starting at pixel ``first_pixel`` of the frame.
        width: pixels per line (for ``tlast``).
        bytes_per_pixel: 1 to 4.
        first_pixel: index in the frame of the first pixel of ``data`` (``tuser`` is set on
            pixel 0). When it is not 0, the output register starts holding the previous
            pixel's beat, as it does in a running frame without backpressure.
        in_valid: per clock, whether the byte stream offers a byte (default: always).
        out_ready: per clock, ``m_axis_tready`` (default: always ready).
        clocks: how many clocks to simulate (default: until the last beat is taken).

    Returns:
        ``aclk`` (all 1: one entry per rising edge), ``s_tdata``, ``s_tvalid``, ``s_tready``,
        ``m_axis_tdata``, ``m_axis_tkeep``, ``m_axis_tuser``, ``m_axis_tlast``,
        ``m_axis_tvalid``, ``m_axis_tready``: arrays of one value per clock.

    Raises:
        PipelineConfigError: a bad geometry, or more than :data:`CLOCKED_MAX_CLOCKS` clocks.
    """
    raw = np.frombuffer(bytes(data), np.uint8) if not isinstance(data, np.ndarray) else data.astype(np.uint8).ravel()
    b = int(bytes_per_pixel)
    ivalid, oready = _stimulus(raw.size, width, b, first_pixel, in_valid, out_ready, clocks)
    n = ivalid.size
    sig = {name: np.zeros(n, np.uint64) for name in (
        "s_tdata", "s_tvalid", "s_tready", "m_axis_tdata", "m_axis_tuser", "m_axis_tlast",
        "m_axis_tvalid", "m_axis_tready")}
    keep = (1 << b) - 1
    # registers, as in rfl_fifo2axi.v
    acc, k = 0, 0
    pixel = first_pixel
    m_tdata = m_tuser = m_tlast = m_tvalid = 0
    if first_pixel > 0:  # a running frame: the previous pixel's beat is on the bus
        m_tvalid, m_tuser = 1, int(first_pixel - 1 == 0)
        m_tlast = int((first_pixel - 1) % width == width - 1)
    pos, last_clock = 0, n
    pixels = raw.size // b
    from_data, taken = False, 0   # is the beat on the bus one of data's; beats of data taken
    for c in range(n):
        s_valid = bool(ivalid[c]) and pos < raw.size
        out_free = (not m_tvalid) or bool(oready[c])
        last_byte = k == b - 1
        s_ready = (not last_byte) or out_free
        byte = int(raw[pos]) if pos < raw.size else 0
        sig["s_tdata"][c] = byte if s_valid else 0
        sig["s_tvalid"][c], sig["s_tready"][c] = s_valid, s_ready
        sig["m_axis_tdata"][c], sig["m_axis_tuser"][c] = m_tdata, m_tuser
        sig["m_axis_tlast"][c], sig["m_axis_tvalid"][c] = m_tlast, m_tvalid
        sig["m_axis_tready"][c] = oready[c]
        # the clock edge
        if m_tvalid and oready[c]:
            m_tvalid = 0
            taken += from_data
        if s_valid and s_ready:
            pos += 1
            if last_byte:
                m_tdata = acc | (byte << (8 * (b - 1)))
                m_tuser = int(pixel == 0)
                m_tlast = int(pixel % width == width - 1)
                m_tvalid, from_data = 1, True
                acc, k = 0, 0
                pixel += 1
            else:
                acc |= byte << (8 * k)
                k += 1
        if clocks is None and taken == pixels:
            last_clock = c + 1
            break
    out = {"aclk": np.ones(last_clock, np.uint64)}
    for name, arr in sig.items():
        out[name] = arr[:last_clock]
    out["m_axis_tkeep"] = np.full(last_clock, keep, np.uint64)
    order = ("aclk", "s_tdata", "s_tvalid", "s_tready", "m_axis_tvalid", "m_axis_tready",
             "m_axis_tdata", "m_axis_tkeep", "m_axis_tuser", "m_axis_tlast")
    return {name: out[name] for name in order}
