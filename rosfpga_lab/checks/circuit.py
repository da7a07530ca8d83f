"""Checks of notebook 8: reading the circuit clock by clock (waveforms, backpressure, parameters)."""

from __future__ import annotations

import dataclasses
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type
from rosfpga_lab.hw import Pipeline, PipelineError
from rosfpga_lab.hw.clocked import fifo2axi_clocks
from rosfpga_lab.rtl import build, run, simulator_missing_reason

#: The frame of exercise 8.1: a 4x3 rgba8 picture through fifo2axi, with one signal broken.
BUG_WIDTH, BUG_HEIGHT, BUG_BYTES = 4, 3, 4
#: The planted bug: TLAST one beat late (on the first pixel of the next line).
BUG_SIGNAL = "m_axis_tlast"
#: Signals a reader may name in exercise 8.1 (the beat side of fifo2axi).
_BEAT_SIGNALS = ("m_axis_tdata", "m_axis_tkeep", "m_axis_tuser", "m_axis_tlast", "m_axis_tvalid",
                 "m_axis_tready")


def planted_bug_arrays() -> dict[str, np.ndarray]:
    """Per-clock signals of fifo2axi on a 4x3 ``rgba8`` frame, with TLAST one beat late.

    The arrays are the clock-by-clock model's (:func:`rosfpga_lab.hw.clocked.fifo2axi_clocks`)
    except the planted bug; draw them with ``W.WaveformViewer(W.Waves.from_arrays(...))``.
    """
    data = (np.arange(BUG_WIDTH * BUG_HEIGHT * BUG_BYTES) * 11 % 251).astype(np.uint8)
    sig = fifo2axi_clocks(data, BUG_WIDTH, BUG_BYTES)
    loads = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
    tlast = np.zeros_like(sig["m_axis_tlast"])
    for beat, clock in enumerate(loads):      # the register holds each beat's value until the next
        late = beat % BUG_WIDTH == 0 and beat > 0
        end = loads[beat + 1] if beat + 1 < loads.size else tlast.size
        tlast[clock:end] = int(late)
    sig[BUG_SIGNAL] = tlast
    return sig


def check_planted_bug(signal: Any, beat: Any) -> CheckResult:
    """Exercise 8.1: which signal is wrong, and the number of the first beat where it is wrong.

    Raises:
        ExerciseError: another signal, or another beat (with what that beat shows).
    """
    ex = "8.1 (find the planted bug)"
    require_answer(ex, "bug_signal", signal)
    require_answer(ex, "bug_beat", beat)
    require_type(ex, "bug_signal", signal, str, "a signal's name, e.g. \"m_axis_tuser\"")
    require_type(ex, "bug_beat", beat, int, "a beat number, counted from 0")
    if signal not in _BEAT_SIGNALS:
        known = ", ".join(_BEAT_SIGNALS)
        hint = " (the 8-bit side is fine: look at the beats)" if signal.startswith("s_") else ""
        raise fail(ex, f"{signal!r} is not one of the beat signals ({known}){hint}")
    first_wrong = BUG_WIDTH - 1
    if signal != BUG_SIGNAL:
        raise fail(ex, f"{signal} is as fifo2axi makes it; compare each beat's TUSER and TLAST "
                       f"with the pixel it carries (one pixel per beat, {BUG_WIDTH} pixels a line)")
    if beat == first_wrong + 1:
        raise fail(ex, f"beat {beat} does carry a TLAST it should not, but an earlier beat is "
                       f"already wrong: which beat carries the last pixel of line 0?")
    if beat != first_wrong:
        raise fail(ex, f"beat {beat} carries pixel ({beat % BUG_WIDTH}, {beat // BUG_WIDTH}); its "
                       f"TLAST is {'right' if beat < first_wrong else 'not the first wrong one'}. "
                       f"Count beats from 0 at the TUSER beat")
    return CheckResult(ex, [f"{BUG_SIGNAL} is one beat late: beat {first_wrong}, the last pixel of "
                            "line 0, lacks it, and beat 4, the first pixel of line 1, carries it",
                            "a video core would end every line one pixel late: the picture shears"])


def fifo2axi_frame_clocks(width: int, height: int, bytes_per_pixel: int,
                          ready_every: int = 1) -> int:
    """Clocks until fifo2axi's last beat of a frame is taken: the clock of that handshake + 1.

    Bytes are offered every clock; ``m_axis_tready`` is 1 on every ``ready_every``-th clock.
    """
    n = width * height * bytes_per_pixel
    clocks = (n + 2) * 4 * max(1, ready_every) + 8
    ready = (np.arange(clocks) % max(1, ready_every)) == 0
    sig = fifo2axi_clocks(np.zeros(n, np.uint8), width, bytes_per_pixel,
                          in_valid=np.ones(clocks, bool), out_ready=ready)
    fire = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
    return int(fire[-1]) + 1


def check_frame_clocks(mono_free: Any, mono_half: Any, rgba_half: Any) -> CheckResult:
    """Exercise 8.2: fifo2axi's clocks for a 16x8 frame, with and without backpressure.

    ``mono_free``: ``mono8``, TREADY always 1; ``mono_half``: ``mono8``, TREADY 1 every other
    clock; ``rgba_half``: ``rgba8``, TREADY 1 every other clock.
    """
    ex = "8.2 (clocks of a frame)"
    want = {"mono_free": fifo2axi_frame_clocks(16, 8, 1), "mono_half": fifo2axi_frame_clocks(16, 8, 1, 2),
            "rgba_half": fifo2axi_frame_clocks(16, 8, 4, 2)}
    got = {"mono_free": mono_free, "mono_half": mono_half, "rgba_half": rgba_half}
    problems = []
    for name, value in got.items():
        require_answer(ex, name, value)
        require_type(ex, name, value, int)
    if mono_free != want["mono_free"]:
        if mono_free == 128:
            problems.append("mono_free: 128 is the number of beats; the first beat leaves one clock "
                            "after its byte arrives, so count one clock more")
        else:
            problems.append(f"mono_free is {mono_free}: one byte per clock and one pixel per byte; "
                            "the last beat is taken the clock after the last byte")
    if mono_half != want["mono_half"]:
        problems.append(_half_hint("mono_half", mono_half, want["mono_half"], want["mono_free"],
                                   bytes_per_beat=1))
    if rgba_half != want["rgba_half"]:
        problems.append(_half_hint("rgba_half", rgba_half, want["rgba_half"], want["mono_free"],
                                   bytes_per_beat=4))
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"mono8: {want['mono_free']} clocks free, {want['mono_half']} with TREADY every "
                            "other clock: backpressure halves a byte-per-beat stream",
                            f"rgba8: {want['rgba_half']} clocks either way: the 8-bit FIFO, not the "
                            "stream, limits it"])


def _half_hint(name: str, value: int, want: int, free: int, *, bytes_per_beat: int) -> str:
    """What a wrong 16x8-frame clock count with TREADY on every other clock probably missed."""
    beats = 16 * 8
    direction = "too few" if value < want else "too many"
    if value == want - 1:
        why = ("one short: clock 0 is the clock the first byte is taken, and the count ends the "
               "clock after the last handshake (its clock + 1)")
    elif bytes_per_beat == 1 and value == free:
        why = ("that is the count without backpressure: with TREADY only on even clocks a "
               "1-byte pixel can leave only every other clock, so the beats, not the bytes, "
               "set the pace")
    elif bytes_per_beat == 1 and value < want:
        why = (f"with TREADY 1 only every other clock at most one beat leaves per 2 clocks: "
               f"{beats} beats need about 2 x {beats} clocks")
    elif bytes_per_beat == 4 and value < want:
        why = (f"an rgba8 beat needs 4 bytes, one per clock: {beats} beats need about "
               f"4 x {beats} clocks whatever TREADY does")
    elif bytes_per_beat == 4:
        why = ("backpressure costs nothing for rgba8 here: a beat is ready only every 4th "
               "clock, and TREADY, 1 every other clock, is back in time for each")
    else:
        why = ("a byte arrives on every clock and its beat leaves at the next even clock: count "
               "when the last beat can be taken")
    return f"{name} is {value}, {direction}: {why}"


def check_ksize_rerun(params: Any, base: Any, frame: bytes) -> CheckResult:
    """Exercise 8.3: the parameters changed to a 5x5 kernel; the RTL re-built and re-run with them.

    Where a Verilog simulator is installed the check builds the circuit from ``params``, runs it
    on ``frame`` and compares the output with the 5x5 model; elsewhere it checks the parameters
    only, and says so.

    Args:
        params: the reader's :class:`rosfpga_lab.rtl.RtlParams`.
        base: the parameters before the change.
        frame: the input frame.
    """
    ex = "8.3 (change a parameter, re-run)"
    require_answer(ex, "params5", params)
    if not dataclasses.is_dataclass(params) or not hasattr(params, "KSIZE"):
        raise fail(ex, "params5 must be the RtlParams of the circuit, changed with "
                       "dataclasses.replace(params, KSIZE=...)")
    problems = []
    if params.KSIZE != 5:
        problems.append(f"KSIZE is {params.KSIZE}, expected 5 (a 5x5 window)")
    changed = [f.name for f in dataclasses.fields(params)
               if f.name != "KSIZE" and getattr(params, f.name) != getattr(base, f.name)]
    if changed:
        problems.append(f"only KSIZE should change; these changed too: {', '.join(changed)}")
    if problems:
        raise fail(ex, *problems)
    details = ["KSIZE = 5, every other parameter as before"]
    given: Any = params  # checked above to be an RtlParams instance
    output = None
    if simulator_missing_reason() is None:
        output = run(build(given), frame).output
    if output is None:
        details.append("the RTL was not re-run here (no Verilog simulator); with Icarus Verilog "
                       "or Verilator installed this check also compares the output")
        return CheckResult(ex, details)
    try:
        model = Pipeline(width=given.WIDTH, height=given.HEIGHT, encoding=given.ENCODING,
                         op=given.op_name, ksize=(5, 5)).process(frame)
    except PipelineError as exc:
        raise fail(ex, f"the frame does not fit the circuit: {exc}") from None
    if bytes(output) != model.output_frame:
        raise fail(ex, "the circuit built from params5 does not make the 5x5 dilate of the frame")
    want = cv2.dilate(model.input_image, np.ones((5, 5), np.uint8)).reshape(model.input_image.shape)
    if not np.array_equal(model.output_image, want):  # the model is held to OpenCV by the tests
        raise fail(ex, "the lab's 5x5 model disagrees with cv2.dilate here: please report this")
    details.append("the re-run RTL's frame equals the 5x5 model's, and its picture cv2.dilate's")
    return CheckResult(ex, details)
