"""The clock-by-clock fifo2axi model: its beats are the fast model's, its timing the RTL's rule."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.hw import PIXEL_FORMATS, fifo2axi_fast
from rosfpga_lab.hw.clocked import fifo2axi_clocks
from rosfpga_lab.hw.errors import PipelineConfigError


def _handshakes(sig: dict[str, np.ndarray]) -> np.ndarray:
    return np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))


@pytest.mark.parametrize("encoding", list(PIXEL_FORMATS))
def test_without_gaps_one_beat_every_bytes_per_pixel_clocks(encoding: str) -> None:
    fmt = PIXEL_FORMATS[encoding]
    width, height = 5, 3
    data = np.arange(width * height * fmt.bytes_per_pixel, dtype=np.uint8)
    sig = fifo2axi_clocks(data, width, fmt.bytes_per_pixel)
    clocks = _handshakes(sig)
    b = fmt.bytes_per_pixel
    # beat j is taken at clock (j + 1) * B: B clocks per pixel, as hw.cycles counts
    assert clocks.tolist() == [(j + 1) * b for j in range(width * height)]
    beats, _left = fifo2axi_fast(data, height, width, PIXEL_FORMATS[encoding])
    assert sig["m_axis_tdata"][clocks].tolist() == beats.tdata.tolist()
    assert sig["m_axis_tuser"][clocks].astype(bool).tolist() == beats.tuser.tolist()
    assert sig["m_axis_tlast"][clocks].astype(bool).tolist() == beats.tlast.tolist()
    assert int(sig["m_axis_tkeep"][0]) == fmt.tkeep
    # one byte per clock on the 8-bit side
    taken = np.flatnonzero(sig["s_tvalid"].astype(bool) & sig["s_tready"].astype(bool))
    assert taken.tolist() == list(range(data.size))


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(list(PIXEL_FORMATS)), st.integers(1, 4), st.integers(1, 3), st.data())
def test_gaps_and_backpressure_lose_nothing(encoding: str, width: int, height: int, draw: st.DataObject) -> None:
    b = PIXEL_FORMATS[encoding].bytes_per_pixel
    n = width * height * b
    data = np.array(draw.draw(st.lists(st.integers(0, 255), min_size=n, max_size=n)), np.uint8)
    clocks = 40 * n + 40
    rng = np.random.default_rng(draw.draw(st.integers(0, 2**16)))
    in_valid = rng.random(clocks) < 0.6
    out_ready = rng.random(clocks) < 0.5
    sig = fifo2axi_clocks(data, width, b, in_valid=in_valid, out_ready=out_ready)
    hs = _handshakes(sig)
    beats, _left = fifo2axi_fast(data, height, width, PIXEL_FORMATS[encoding])
    assert sig["m_axis_tdata"][hs].tolist() == beats.tdata.tolist()
    assert sig["m_axis_tlast"][hs].astype(bool).tolist() == beats.tlast.tolist()
    # a byte is only taken when offered, and while a beat waits the pixel's last byte is held
    s_take = sig["s_tvalid"].astype(bool) & sig["s_tready"].astype(bool)
    assert not (s_take & ~in_valid[: s_take.size]).any()
    waiting = sig["m_axis_tvalid"].astype(bool) & ~sig["m_axis_tready"].astype(bool)
    before = np.concatenate(([0], np.cumsum(s_take)[:-1]))  # bytes taken before each clock
    lane = before % b
    assert (sig["s_tready"][waiting].astype(bool) == (lane[waiting] != b - 1)).all()
    assert (sig["s_tready"][~waiting] == 1).all()


def test_a_window_in_a_running_frame_starts_with_the_previous_beat_on_the_bus() -> None:
    sig = fifo2axi_clocks(bytes(range(8)), 4, 4, first_pixel=6)
    assert sig["m_axis_tvalid"][0] == 1 and sig["m_axis_tuser"][0] == 0
    hs = _handshakes(sig)
    assert hs.tolist() == [0, 4, 8]  # the previous beat, then one every 4 clocks
    assert sig["m_axis_tlast"][hs].tolist() == [0, 0, 1]  # pixel 7 ends line 1 of a 4-wide frame


def test_bad_geometry_and_too_many_clocks_are_refused() -> None:
    with pytest.raises(PipelineConfigError, match="whole pixels"):
        fifo2axi_clocks(b"\x00" * 5, 2, 4)
    with pytest.raises(PipelineConfigError, match="RTL simulation"):
        fifo2axi_clocks(b"\x00" * 4, 2, 4, clocks=1 << 22)
