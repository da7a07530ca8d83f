"""Notebook 8's checks: right answers pass, each typical wrong answer gets its own diagnosis, and
the packer's clock model is the generated circuit's rfl_elem_pack, clock for clock."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rosfpga_lab.checks import ExerciseError
from rosfpga_lab.checks.circuit import (
    BUG_SIGNAL, check_frame_clocks, check_ksize_rerun, check_planted_bug, elem_pack_clocks,
    model_frames, planted_bug_arrays,
)
from rosfpga_lab.hls.generic import spec_from_config
from rosfpga_lab.rtl import build, run, simulator_missing_reason
from rosfpga_lab.rtl.demo import DEMO_BP, DEMO_GAP, DEMO_SEED, demo_config, demo_frames
from rosfpga_lab.rtl.sim import env_required
from rosfpga_lab.rtl.vcd import read_vcd


def _simulator_or_skip() -> None:
    reason = simulator_missing_reason()
    if reason is not None:
        if env_required():
            pytest.fail(f"ROSFPGA_REQUIRE_RTL is set but {reason}")
        pytest.skip(reason)


def test_elem_pack_clocks_is_the_generated_circuits_packer(tmp_path) -> None:
    """The demo's two frames through the generated Image top (input gaps, 40 % backpressure):
    fed the packer's own input handshakes and output ready, the clock model gives every
    signal of rfl_elem_pack (nets pk_* in, axis_in_* out) on every clock of the good frame."""
    _simulator_or_skip()
    config = demo_config()
    refused, good = demo_frames(config)
    sim = build(spec_from_config(config), trace=True, cache=True)
    run(sim, refused + good, gap=DEMO_GAP, bp=DEMO_BP, seed=DEMO_SEED, vcd=tmp_path / "d.vcd")
    wave = read_vcd(tmp_path / "d.vcd", clock="clk")
    offered, taken = wave.values("pk_tvalid").astype(bool), wave.values("pk_tready").astype(bool)
    first = int(np.flatnonzero(offered)[0])
    pixels = wave.values("pk_tdata")[offered & taken].astype(np.uint8)
    assert pixels.tobytes() == good[-16 * 8 * 4:]          # the good frame's pixels, nothing else
    sig = elem_pack_clocks(pixels, 16, 4, in_valid=offered[first:],
                           out_ready=wave.values("axis_in_tready")[first:])
    for net, port in (("pk_tready", "s_tready"), ("axis_in_tvalid", "m_axis_tvalid"),
                      ("axis_in_tdata", "m_axis_tdata"), ("axis_in_tuser", "m_axis_tuser"),
                      ("axis_in_tlast", "m_axis_tlast")):
        rtl = wave.values(net)[first:].astype(np.uint64)
        assert np.array_equal(rtl, sig[port]), (net, np.flatnonzero(rtl != sig[port])[:5])


def test_model_frames_is_the_generated_circuits_output() -> None:
    """The refused frame gets the width status; the good one the RTL's bytes (simulated here,
    no model in the expectation) and its picture OpenCV's dilate."""
    import cv2

    config = demo_config()
    refused, good = demo_frames(config)
    spec = spec_from_config(config)
    out, statuses = model_frames(spec, [refused, good])
    assert statuses == ["SUB_BAD_WIDTH", "SUB_OK"]
    picture = np.frombuffer(good[-16 * 8 * 4:], np.uint8).reshape(8, 16, 4)
    dilated = cv2.dilate(picture, np.ones((3, 3), np.uint8))
    assert out[-16 * 8 * 4:] == dilated.tobytes()
    if simulator_missing_reason() is None:
        assert run(build(spec, cache=True), refused + good).output == out


def test_the_planted_bug_is_tlast_one_beat_late() -> None:
    sig = planted_bug_arrays()
    fire = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
    assert sig[BUG_SIGNAL][fire].astype(int).tolist() == [0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0]
    assert sig["m_axis_tuser"][fire].astype(int).tolist() == [1] + [0] * 11
    assert "m_axis_tlast" in str(check_planted_bug("m_axis_tlast", 3))


@pytest.mark.parametrize("signal,beat,says", [
    ("m_axis_tuser", 0, "as rfl_elem_pack makes it"),
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


def test_ksize_rerun_checks_the_spec_and_reruns_the_circuit() -> None:
    config = demo_config()
    base = spec_from_config(config)
    good = demo_frames(config)[1]
    five = dataclasses.replace(base, ksize=5)
    text = str(check_ksize_rerun(five, base, good))
    assert "KSIZE 3 -> 5" in text
    if simulator_missing_reason() is None:
        assert "equals the 5x5 model's" in text and "not re-run" not in text
    else:
        assert "not re-run here" in text
    with pytest.raises(ExerciseError, match="ksize is 3"):
        check_ksize_rerun(base, base, good)
    with pytest.raises(ExerciseError, match="these changed too: op"):
        check_ksize_rerun(dataclasses.replace(five, op="erode"), base, good)
    with pytest.raises(ExerciseError, match="must be the GenericSpec"):
        check_ksize_rerun({"ksize": 5}, base, good)
