"""The checks of notebook 12 (``checks.fabric``): the right answer, and the usual wrong ones
named. Expected values are counted here by hand (RFC 894/791/768 header sizes) or read from the
dump with numpy, never from the checks."""

from __future__ import annotations

import numpy as np
import pytest

from rosfpga_lab.checks import ExerciseError, check_handoff_clock, check_rtps_offset
from rosfpga_lab.rtl.fabricdemo import demo_frames, shipped_dump
from rosfpga_lab.rtl.vcd import read_vcd

FRAME = demo_frames()[0]
RIGHT = 8 + 14 + 20 + 8                  # preamble+SFD, Ethernet, IPv4 (no options), UDP


def test_rtps_offset_right() -> None:
    assert FRAME[RIGHT:RIGHT + 4] == b"RTPS"
    assert "RTPS starts at byte 50" in str(check_rtps_offset(RIGHT, FRAME))


@pytest.mark.parametrize("answer,hint", [
    (RIGHT - 8, "preamble and the SFD .* - or you left out the 8-byte UDP header"),
    (RIGHT - 20, "IPv4"), (RIGHT - 14, "Ethernet"), (RIGHT + 4, "FCS"),
    (RIGHT + 20, "own 20-byte header"), (7, "add up the headers"),
])
def test_rtps_offset_wrong(answer: int, hint: str) -> None:
    with pytest.raises(ExerciseError, match=hint):
        check_rtps_offset(answer, FRAME)


def test_rtps_offset_type_and_placeholder() -> None:
    with pytest.raises(ExerciseError):
        check_rtps_offset("50", FRAME)
    with pytest.raises(ExerciseError):
        check_rtps_offset(..., FRAME)


def _first(wave, valid: str, ready: str) -> int:
    both = wave.values(valid).astype(bool) & wave.values(ready).astype(bool)
    return int(np.flatnonzero(both)[0])


def test_handoff_clock() -> None:
    wave = read_vcd(shipped_dump(), clock="clk")
    right = _first(wave, "p_rx_tvalid", "p_rx_tready")
    liteeth = _first(wave, "le_rx_valid", "le_rx_ready")
    dv = np.flatnonzero(wave.values("rx_dv"))
    assert liteeth < right and dv[0] < right
    assert "FCS proved good" in str(check_handoff_clock(right, wave))
    for answer, hint in ((liteeth, "LiteEth's first payload byte"), (int(dv[0]), "first byte"),
                         (right + 1, "find the first clock")):
        with pytest.raises(ExerciseError, match=hint):
            check_handoff_clock(answer, wave)
    last = int(dv[np.flatnonzero(np.diff(dv) > 1)[0]])          # the first frame's last byte
    with pytest.raises(ExerciseError, match="last byte"):
        check_handoff_clock(last, wave)
