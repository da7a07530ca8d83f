"""Checks of notebook 8: reading the generated circuit clock by clock (waveforms, backpressure,
parameters).

Notebook 8 steps through the circuit ``rosfpga-lab generate`` renders for
``sensor_msgs/Image`` (``rosfpga_lab/rtl/generic/rfl_gtop.v`` with the walk ``rfl_layout.vh``).
Its exercises need three small things of that circuit in Python, kept here (the layer that uses
them):

* :func:`elem_pack_clocks`: ``rfl_elem_pack`` (the packer that turns the pixel bytes into
  AXI4-Stream beats, Figure 7 of the paper) clock by clock, its register equations as the
  Verilog writes them; ``tests/checks/test_circuit.py`` holds it equal to the Verilog simulated.
* :func:`model_frames`: what the generated circuit sends for some frames: its walk
  (:func:`rosfpga_lab.hls.program.run_program`, the walkers' program in Python) with the
  application's model (:func:`rosfpga_lab.hw.morph.morph_fast`) on each accepted picture.
* the planted bug of exercise 8.1, drawn from :func:`elem_pack_clocks`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type
from rosfpga_lab.hls.generic import GenericSpec
from rosfpga_lab.hls.program import run_program
from rosfpga_lab.hw.morph import morph_fast
from rosfpga_lab.rtl import build, run, simulator_missing_reason

#: The frame of exercise 8.1: a 4x3 rgba8 picture through rfl_elem_pack, with one signal broken.
BUG_WIDTH, BUG_HEIGHT, BUG_BYTES = 4, 3, 4
#: The planted bug: TLAST one beat late (on the first pixel of the next line).
BUG_SIGNAL = "m_axis_tlast"
#: Signals a reader may name in exercise 8.1 (the beat side of rfl_elem_pack).
_BEAT_SIGNALS = ("m_axis_tdata", "m_axis_tkeep", "m_axis_tuser", "m_axis_tlast", "m_axis_tvalid",
                 "m_axis_tready")
#: The signals :func:`elem_pack_clocks` returns, as ``rfl_elem_pack.v`` names its ports.
ELEM_PACK_SIGNALS = ("s_tdata", "s_tvalid", "s_tready", "m_axis_tdata", "m_axis_tkeep",
                     "m_axis_tuser", "m_axis_tlast", "m_axis_tvalid", "m_axis_tready")


def elem_pack_clocks(data: bytes | np.ndarray, line: int, ebytes: int, *,
                     in_valid: np.ndarray | None = None, out_ready: np.ndarray | None = None,
                     clocks: int | None = None) -> dict[str, np.ndarray]:
    """Per-clock signals of ``rfl_elem_pack`` (video framing) packing the bytes ``data``.

    The registers are the Verilog's: ``acc`` and the lane ``k`` collect an element's bytes, and
    its last byte loads the output register (TUSER on element 0, TLAST on the last of each line)
    when that register is free (``!m_axis_tvalid || m_axis_tready``); ``s_tready`` is low only
    for a last byte that finds it full. ``data`` is one whole array (a frame's pixels).

    Args:
        data: the array's bytes.
        line: elements per line (TLAST on the last of each).
        ebytes: bytes per element (beat).
        in_valid: per clock, whether a byte is offered (default: always, while bytes are left).
        out_ready: per clock, ``m_axis_tready`` (default: always 1).
        clocks: how many clocks (default: the length of the stimulus given, else until the last
            beat is taken).

    Returns:
        ``{name: one value per clock}`` for :data:`ELEM_PACK_SIGNALS`; clock 0 is the first
        after reset.

    Raises:
        ValueError: the bytes are not whole lines of whole elements.
    """
    raw = np.frombuffer(bytes(data), np.uint8) if not isinstance(data, np.ndarray) \
        else data.astype(np.uint8).ravel()
    if ebytes < 1 or line < 1 or raw.size == 0 or raw.size % (ebytes * line):
        raise ValueError(f"{raw.size} bytes are not whole lines of {line} elements of {ebytes} bytes")
    given = [a.size for a in (in_valid, out_ready) if a is not None]
    n = clocks or (min(given) if given else (raw.size + 2) * 2)
    ivalid = np.ones(n, bool) if in_valid is None else np.asarray(in_valid, bool)[:n]
    oready = np.ones(n, bool) if out_ready is None else np.asarray(out_ready, bool)[:n]
    sig = {name: np.zeros(n, np.uint64) for name in ELEM_PACK_SIGNALS}
    sig["m_axis_tkeep"][:] = (1 << ebytes) - 1
    elements = raw.size // ebytes
    acc = k = elem = pos = 0                       # registers, as in rfl_elem_pack.v
    m_tdata = m_tuser = m_tlast = m_tvalid = 0
    for c in range(n):
        s_valid = bool(ivalid[c]) and pos < raw.size
        last_byte = k == ebytes - 1
        s_ready = (not last_byte) or (not m_tvalid) or bool(oready[c])
        byte = int(raw[pos]) if s_valid else 0
        for name, value in (("s_tdata", byte), ("s_tvalid", s_valid), ("s_tready", s_ready),
                            ("m_axis_tdata", m_tdata), ("m_axis_tuser", m_tuser),
                            ("m_axis_tlast", m_tlast), ("m_axis_tvalid", m_tvalid),
                            ("m_axis_tready", oready[c])):
            sig[name][c] = value
        if m_tvalid and oready[c]:                 # the clock edge
            m_tvalid = 0
        if s_valid and s_ready:
            pos += 1
            acc |= byte << (8 * k)
            if last_byte:
                m_tdata, m_tuser = acc, int(elem == 0)
                m_tlast, m_tvalid = int(elem % line == line - 1), 1
                acc, k, elem = 0, 0, (elem + 1) % elements
            else:
                k += 1
    if clocks is None and not given:               # up to the clock after the last beat
        fire = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
        sig = {name: values[:int(fire[-1]) + 1] for name, values in sig.items()}
    return sig


def model_frames(spec: GenericSpec, frames: Sequence[bytes]) -> tuple[bytes, list[str]]:
    """What the generated circuit of ``spec`` (a video stream: ``sensor_msgs/Image``) sends for
    ``frames``: its walk in Python (:func:`rosfpga_lab.hls.program.run_program`) with the
    application's model (:func:`rosfpga_lab.hw.morph.morph_fast`) on each accepted picture.

    Returns:
        The output frames, back to back, and the subscriber's status name per frame.

    Raises:
        ValueError: the spec streams no video.
    """
    video = spec.video
    if video is None:
        raise ValueError(f"{spec.program.type_in} streams no video: use hw.MessagePipeline")

    def apply(pixels: bytes) -> bytes:
        image = np.frombuffer(pixels, np.uint8).reshape(video.height, video.width,
                                                        video.bytes_per_pixel)
        return morph_fast(image, spec.op, (spec.ksize, spec.ksize)).tobytes()

    out, codes = run_program(spec.program, list(frames), apply)
    return out, [spec.program.statuses[code][0] for code in codes]


def planted_bug_arrays() -> dict[str, np.ndarray]:
    """Per-clock signals of ``rfl_elem_pack`` on a 4x3 ``rgba8`` frame, with TLAST one beat late.

    The arrays are :func:`elem_pack_clocks`' except the planted bug; draw them with
    ``W.WaveformViewer(W.Waves.from_arrays(...))``.
    """
    data = (np.arange(BUG_WIDTH * BUG_HEIGHT * BUG_BYTES) * 11 % 251).astype(np.uint8)
    sig = elem_pack_clocks(data, BUG_WIDTH, BUG_BYTES)
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
        raise fail(ex, f"{signal} is as rfl_elem_pack makes it; compare each beat's TUSER and TLAST "
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


def elem_pack_frame_clocks(width: int, height: int, bytes_per_pixel: int,
                           ready_every: int = 1) -> int:
    """Clocks until rfl_elem_pack's last beat of a frame is taken: that handshake's clock + 1.

    Bytes are offered every clock; ``m_axis_tready`` is 1 on every ``ready_every``-th clock.
    """
    n = width * height * bytes_per_pixel
    clocks = (n + 2) * 4 * max(1, ready_every) + 8
    ready = (np.arange(clocks) % max(1, ready_every)) == 0
    sig = elem_pack_clocks(np.zeros(n, np.uint8), width, bytes_per_pixel, out_ready=ready)
    fire = np.flatnonzero(sig["m_axis_tvalid"].astype(bool) & sig["m_axis_tready"].astype(bool))
    return int(fire[-1]) + 1


def check_frame_clocks(mono_free: Any, mono_half: Any, rgba_half: Any) -> CheckResult:
    """Exercise 8.2: rfl_elem_pack's clocks for a 16x8 frame, with and without backpressure.

    ``mono_free``: ``mono8``, TREADY always 1; ``mono_half``: ``mono8``, TREADY 1 every other
    clock; ``rgba_half``: ``rgba8``, TREADY 1 every other clock.
    """
    ex = "8.2 (clocks of a frame)"
    want = {"mono_free": elem_pack_frame_clocks(16, 8, 1),
            "mono_half": elem_pack_frame_clocks(16, 8, 1, 2),
            "rgba_half": elem_pack_frame_clocks(16, 8, 4, 2)}
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


def check_ksize_rerun(spec: Any, base: Any, frame: bytes) -> CheckResult:
    """Exercise 8.3: the generated circuit's spec changed to a 5x5 window; the RTL re-built and
    re-run with it.

    Where a Verilog simulator is installed the check builds the generated top from ``spec``,
    runs it on ``frame`` and compares the output with the 5x5 model (:func:`model_frames`);
    elsewhere it checks the spec only, and says so.

    Args:
        spec: the reader's :class:`rosfpga_lab.hls.generic.GenericSpec`.
        base: the spec before the change.
        frame: the input frame.
    """
    from rosfpga_lab.rtl.generic import generic_params

    ex = "8.3 (change a parameter, re-run)"
    require_answer(ex, "spec5", spec)
    if not isinstance(spec, GenericSpec):
        raise fail(ex, "spec5 must be the GenericSpec of the circuit, changed with "
                       "dataclasses.replace(spec, ksize=...)")
    problems = []
    if spec.ksize != 5:
        problems.append(f"ksize is {spec.ksize}, expected 5 (a 5x5 window)")
    changed = [f.name for f in dataclasses.fields(spec)
               if f.name != "ksize" and getattr(spec, f.name) != getattr(base, f.name)]
    if changed:
        problems.append(f"only ksize should change; these changed too: {', '.join(changed)}")
    if problems:
        raise fail(ex, *problems)
    before, after = generic_params(base), generic_params(spec)
    verilog = [f"{name} {before[name]} -> {after[name]}" for name in after
               if after[name] != before.get(name)]
    details = ["ksize = 5, every other field as before; rfl_gtop's parameters that follow: "
               + ", ".join(verilog)]
    if simulator_missing_reason() is not None:
        details.append("the RTL was not re-run here (no Verilog simulator); with Icarus Verilog "
                       "or Verilator installed this check also compares the output")
        return CheckResult(ex, details)
    output = run(build(spec), frame).output
    model, statuses = model_frames(spec, [frame])
    if statuses != ["SUB_OK"]:
        raise fail(ex, f"the circuit refuses the frame ({statuses[0]}): use the good frame")
    if bytes(output) != model:
        raise fail(ex, f"the circuit built from spec5 does not make the 5x5 {spec.op} of the frame")
    video = spec.video
    assert video is not None   # model_frames refused a spec without one
    shape = (video.height, video.width, video.bytes_per_pixel)
    n = video.height * video.width * video.bytes_per_pixel     # Image's data is its last field
    picture = np.frombuffer(frame[-n:], np.uint8).reshape(shape)
    opencv = cv2.dilate if spec.op == "dilate" else cv2.erode
    want = opencv(picture, np.ones((5, 5), np.uint8)).reshape(shape)
    if not np.array_equal(np.frombuffer(model[-n:], np.uint8).reshape(shape), want):
        raise fail(ex, f"the lab's 5x5 model disagrees with cv2.{spec.op} here: please report this")
    details.append(f"the re-run RTL's frame equals the 5x5 model's, and its picture cv2.{spec.op}'s")
    return CheckResult(ex, details)
