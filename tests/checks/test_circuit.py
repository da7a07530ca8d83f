"""Notebook 8's checks: right answers pass, and each typical wrong answer gets its own diagnosis."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rosfpga_lab.checks import ExerciseError
from rosfpga_lab.checks.circuit import (
    BUG_SIGNAL, check_frame_clocks, check_ksize_rerun, check_planted_bug, planted_bug_arrays,
)
from rosfpga_lab.hls import sample_image
from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl import rtl_params
from rosfpga_lab.rtl.demo import demo_config


def test_the_planted_bug_is_tlast_one_beat_late() -> None:
    sig = planted_bug_arrays()
    fire = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
    assert sig[BUG_SIGNAL][fire].astype(int).tolist() == [0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0]
    assert sig["m_axis_tuser"][fire].astype(int).tolist() == [1] + [0] * 11
    assert "m_axis_tlast" in str(check_planted_bug("m_axis_tlast", 3))


@pytest.mark.parametrize("signal,beat,says", [
    ("m_axis_tuser", 0, "as fifo2axi makes it"),
    ("m_axis_tlast", 4, "an earlier beat is already wrong"),
    ("m_axis_tlast", 1, "its TLAST is right"),
    ("s_tdata", 3, "the 8-bit side is fine"),
    (..., 3, "replace it with your answer"),
])
def test_wrong_bug_answers_are_explained(signal, beat, says) -> None:
    with pytest.raises(ExerciseError, match=says):
        check_planted_bug(signal, beat)


def test_frame_clocks() -> None:
    result = check_frame_clocks(129, 257, 513)
    assert "halves" in str(result)
    with pytest.raises(ExerciseError, match="number of beats"):
        check_frame_clocks(128, 257, 513)
    with pytest.raises(ExerciseError, match="only every other clock"):
        check_frame_clocks(129, 129, 513)
    with pytest.raises(ExerciseError, match="costs nothing"):
        check_frame_clocks(129, 257, 1025)


@pytest.mark.parametrize("mono_half, rgba_half, says", [
    (256, 513, ["mono_half is 256, too few", "one short"]),                # the +1 forgotten
    (200, 513, ["mono_half is 200, too few", "2 x 128 clocks"]),
    (300, 513, ["mono_half is 300, too many", "next even clock"]),
    (257, 512, ["rgba_half is 512, too few", "one short"]),
    (257, 257, ["rgba_half is 257, too few", "4 x 128 clocks"]),          # rgba8 paced as mono8
    (257, 1025, ["rgba_half is 1025, too many", "costs nothing for rgba8"]),
])
def test_frame_clocks_wrong_halves_get_a_direction_and_a_hint(mono_half: int, rgba_half: int,
                                                              says: list[str]) -> None:
    """8.2's hardest part got only its value echoed ("mono_half is 256")."""
    with pytest.raises(ExerciseError) as err:
        check_frame_clocks(129, mono_half, rgba_half)
    for text in says:
        assert text in str(err.value), str(err.value)


def test_frame_clocks_blank_answers() -> None:
    for blank in (None, ...):
        with pytest.raises(ExerciseError, match="still"):
            check_frame_clocks(129, blank, 513)


def test_ksize_rerun_checks_the_parameters_and_reruns_the_circuit() -> None:
    from rosfpga_lab.rtl import simulator_missing_reason

    config = demo_config()
    base = rtl_params(config)
    good = image_frame(sample_image(config), config.image.encoding)
    five = dataclasses.replace(base, KSIZE=5)
    text = str(check_ksize_rerun(five, base, good))
    if simulator_missing_reason() is None:
        assert "equals the 5x5 model's" in text and "not re-run" not in text
    else:
        assert "not re-run here" in text
    with pytest.raises(ExerciseError, match="KSIZE is 3"):
        check_ksize_rerun(base, base, good)
    with pytest.raises(ExerciseError, match="these changed too: WIDTH"):
        check_ksize_rerun(dataclasses.replace(five, WIDTH=17), base, good)
    with pytest.raises(ExerciseError, match="must be the RtlParams"):
        check_ksize_rerun({"KSIZE": 5}, base, good)
