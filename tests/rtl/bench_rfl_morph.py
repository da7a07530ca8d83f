"""cocotb testbench of ``rfl_morph`` alone (run by tests/rtl/test_morph.py, not by pytest).

The case comes in the environment (``MORPH_CASE``, JSON): image size, kernel, operation,
bytes per pixel, frames, seed, and the per-mille shares of input gaps and output backpressure.
Random images go in as beats with random junk in the unused byte lanes and a few junk beats
(no ``tuser``) before every frame; every output beat must equal the hw models' beats of
``cv2.dilate``/``cv2.erode`` of the image, and the output must keep AXI4-Stream's rule (a
beat once valid stays valid and unchanged until taken). With no gaps and no backpressure the
input must flow one pixel per clock and the frame take the cycles rfl_morph.v states.
A ``damaged`` case damages the frames in turn (hw.framing's rules); the output must equal the
hw models' beats and the ``framing`` port the flags of the damage done.
"""

from __future__ import annotations

import json
import os
import random

import cocotb
import cv2
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ReadOnly, RisingEdge

from rosfpga_lab.hw.encodings import pack_lanes
from rosfpga_lab.hw.morph import morph_fast
from rosfpga_lab.hw.video import axivideo2mat_fast, mat2axivideo_fast
from rosfpga_lab.hw.streams import Beats

ENCODING = {4: "rgba8", 3: "rgb8", 1: "mono8"}
OPS = {0: "dilate", 1: "erode", 2: "copy"}


def _case() -> dict:
    return json.loads(os.environ["MORPH_CASE"])


def _frames(case: dict, rng: np.random.Generator) -> list[np.ndarray]:
    shape = (case["height"], case["width"], case["bytes"])
    frames = []
    for n in range(case["frames"]):
        if n % 3 == 2:      # sparse bright dots, where a wrong window shows at once
            img = np.where(rng.random(shape) < 0.1, 255, 0).astype(np.uint8)
        else:
            img = rng.integers(0, 256, shape, dtype=np.uint8)
        frames.append(img)
    return frames


def _expected(case: dict, img: np.ndarray) -> Beats:
    """The hw models' beats for ``img``, after checking the models against cv2 itself."""
    from rosfpga_lab.hw.encodings import pixel_format
    fmt = pixel_format(ENCODING[case["bytes"]])
    op, k = OPS[case["op"]], case["ksize"]
    rows, cols = img.shape[:2]
    beats_in = Beats(pack_lanes(img.reshape(rows * cols, -1)), fmt.tkeep,
                     *_flags(rows, cols))
    image, status, left = axivideo2mat_fast(beats_in, rows, cols, fmt)
    assert status == 0 and left == 0
    out = morph_fast(image, op, (k, k) if op != "copy" else (1, 1))
    if op != "copy":
        fn = cv2.dilate if op == "dilate" else cv2.erode
        direct = fn(img.reshape(rows, cols, -1).squeeze(-1) if img.shape[2] == 1 else img,
                    np.ones((k, k), np.uint8)).reshape(img.shape)
        assert np.array_equal(out, direct), "hw model differs from cv2"
    return mat2axivideo_fast(out, fmt)


def _damaged(case: dict, frames: list[np.ndarray], fmt, prng: random.Random
             ) -> tuple[list[tuple[int, int, int, int]], list[tuple[int, int, int, int]], int]:
    """A stream of frames, each but the last damaged in turn (early TLAST, late TLAST, TUSER
    inside the frame, junk before TUSER: after a whole frame, else it is that frame's pixels);
    the expected output beats from both hw models of
    the framing rules (held equal here), and the flags the damage must raise (by hand)."""
    from rosfpga_lab.hw.framing import EOL_EARLY, EOL_LATE, SOF_EARLY, SOF_MISSING
    from rosfpga_lab.hw.morph import morph_stream_fast, morph_stream_reference
    rows, cols = case["height"], case["width"]
    beats: list[list[int]] = []
    flags = 0
    for n, img in enumerate(frames):
        tdata = pack_lanes(img.reshape(rows * cols, -1))
        tuser, tlast = _flags(rows, cols)
        lines = [[[int(tdata[r * cols + c]), fmt.tkeep, int(tuser[r * cols + c]),
                   int(tlast[r * cols + c])] for c in range(cols)] for r in range(rows)]
        kind = n % 5 if n < len(frames) - 1 else 0
        r = prng.randrange(rows)
        if kind == 1 and cols > 1:                  # early TLAST: a line cut short
            lines[r] = lines[r][:prng.randint(1, cols - 1)]
            lines[r][-1][3] = 1
            lines[r][0][2] = int(r == 0)
            flags |= EOL_EARLY
        elif kind == 2:                             # late TLAST: a line too long
            lines[r][-1][3] = 0
            lines[r] += [[prng.getrandbits(32), fmt.tkeep, 0, 0]
                         for _ in range(prng.randint(1, 3))]
            lines[r][-1][3] = 1
            flags |= EOL_LATE
        elif kind == 4 and rows * cols > 1:         # the next TUSER inside this frame
            keep = prng.randint(1, rows * cols - 1)
            flat = [b for line in lines for b in line][:keep]
            lines = [flat]
            flags |= SOF_EARLY
        elif kind == 3:                             # junk before the TUSER (after a whole frame)
            beats += [[prng.getrandbits(32), fmt.tkeep, 0, prng.getrandbits(1)]
                      for _ in range(prng.randint(1, 4))]
            flags |= SOF_MISSING
        beats += [b for line in lines for b in line]
    stream = Beats(np.array([b[0] for b in beats], np.uint32), np.array([b[1] for b in beats]),
                   np.array([b[2] for b in beats], bool), np.array([b[3] for b in beats], bool))
    op, k = OPS[case["op"]], case["ksize"]
    ksize = (k, k) if op != "copy" else (1, 1)
    out, framed = morph_stream_fast(stream, rows, cols, fmt, op, ksize)
    ref, ref_framed = morph_stream_reference(stream, rows, cols, fmt, op, ksize)
    assert out == ref and ref_framed.flags == framed.flags, "fast and reference models differ"
    assert framed.flags == flags, f"model flags {framed.flags:#06b}, by hand {flags:#06b}"
    assert len(framed.frames) == len(frames) and framed.used == len(beats)
    assert framed.frame_flags[-1] == 0, "the last, clean frame was flagged"
    expected = [(int(out.tdata[i]), int(out.tkeep[i]), int(out.tuser[i]), int(out.tlast[i]))
                for i in range(len(out))]
    return [(b[0], b[1], b[2], b[3]) for b in beats], expected, flags


def _flags(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    n = rows * cols
    tuser = np.zeros(n, bool)
    tuser[0] = True
    tlast = (np.arange(n) % cols) == cols - 1
    return tuser, tlast


async def _drive(dut, beats: list[tuple[int, int, int, int]], gap: float,
                 rng: random.Random, log: list[int]) -> None:
    i, clock = 0, 0
    while i < len(beats):
        valid = rng.random() >= gap
        tdata, tkeep, tuser, tlast = beats[i]
        dut.s_axis_tvalid.value = int(valid)
        dut.s_axis_tdata.value = tdata if valid else rng.getrandbits(32)
        dut.s_axis_tkeep.value = tkeep
        dut.s_axis_tuser.value = tuser if valid else rng.getrandbits(1)
        dut.s_axis_tlast.value = tlast if valid else rng.getrandbits(1)
        await ReadOnly()
        fire = valid and int(dut.s_axis_tready.value) == 1
        await RisingEdge(dut.aclk)
        if fire:
            log.append(clock)
            i += 1
        clock += 1
    dut.s_axis_tvalid.value = 0


async def _collect(dut, count: int, bp: float, rng: random.Random,
                   got: list[tuple[int, int, int, int]], log: list[int]) -> None:
    clock, held = 0, None
    while len(got) < count:
        ready = rng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        valid = int(dut.m_axis_tvalid.value) == 1
        beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tkeep.value),
                int(dut.m_axis_tuser.value), int(dut.m_axis_tlast.value)) if valid else None
        if held is not None:
            assert valid and beat == held, (
                f"clock {clock}: a valid beat changed or vanished before it was taken: "
                f"{held} -> {beat if valid else 'tvalid low'}")
        if valid and ready:
            got.append(beat)
            log.append(clock)
            held = None
        else:
            held = beat if valid else None
        await RisingEdge(dut.aclk)
        clock += 1


@cocotb.test()
async def morph_frames(dut) -> None:
    """Random frames through rfl_morph, beat for beat against the hw models and cv2."""
    case = _case()
    rng = np.random.default_rng(case["seed"])
    prng = random.Random(case["seed"])
    from rosfpga_lab.hw.encodings import pixel_format
    fmt = pixel_format(ENCODING[case["bytes"]])
    junk_mask = (0xFFFFFFFF << (8 * case["bytes"])) & 0xFFFFFFFF

    frames = _frames(case, rng)
    beats_in: list[tuple[int, int, int, int]] = []
    expected: list[tuple[int, int, int, int]] = []
    want_flags = 0
    if case.get("damaged"):
        beats_in, expected, want_flags = _damaged(case, frames, fmt, prng)
        frames = []
    for img in frames:
        for _ in range(case.get("junk", 0) and prng.randint(0, case["junk"])):
            beats_in.append((prng.getrandbits(32), fmt.tkeep, 0, prng.getrandbits(1)))
            want_flags = 8      # sof_missing: junk dropped before a TUSER (hw.framing)
        rows, cols = img.shape[:2]
        tdata = pack_lanes(img.reshape(rows * cols, -1))
        tuser, tlast = _flags(rows, cols)
        for n in range(rows * cols):
            junk = prng.getrandbits(32) & junk_mask
            beats_in.append((int(tdata[n]) | junk, fmt.tkeep, int(tuser[n]), int(tlast[n])))
        exp = _expected(case, img)
        expected += [(int(exp.tdata[n]), int(exp.tkeep[n]), int(exp.tuser[n]),
                      int(exp.tlast[n])) for n in range(len(exp))]

    cocotb.start_soon(Clock(dut.aclk, 10, unit="ns").start())
    dut.aresetn.value = 0
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 0
    for _ in range(3):
        await RisingEdge(dut.aclk)
    dut.aresetn.value = 1

    in_log: list[int] = []
    out_log: list[int] = []
    got: list[tuple[int, int, int, int]] = []
    cocotb.start_soon(_drive(dut, beats_in, case["gap"] / 1000, prng, in_log))
    await _collect(dut, len(expected), case["bp"] / 1000, random.Random(case["seed"] + 1),
                   got, out_log)
    for _ in range(5):          # nothing more may come out
        dut.m_axis_tready.value = 1
        await ReadOnly()
        assert int(dut.m_axis_tvalid.value) == 0, "rfl_morph sent more beats than pixels"
        await RisingEdge(dut.aclk)

    flags = int(dut.framing.value)
    assert flags == want_flags, f"framing flags {flags:#06b}, expected {want_flags:#06b}"

    for n, (g, e) in enumerate(zip(got, expected)):
        assert g == e, (f"beat {n} (frame {n // (case['width'] * case['height'])}): "
                        f"got tdata={g[0]:#010x} tkeep={g[1]:#x} tuser={g[2]} tlast={g[3]}, "
                        f"expected tdata={e[0]:#010x} tkeep={e[1]:#x} tuser={e[2]} tlast={e[3]}")
    assert len(got) == len(expected)

    if case["gap"] == 0 and case["bp"] == 0 and not case.get("junk") and not case.get("damaged"):
        w, h, k = case["width"], case["height"], case["ksize"] if case["op"] != 2 else 1
        d = k // 2
        pixels = w * h
        first = in_log[:pixels]
        assert first == list(range(first[0], first[0] + pixels)), "input not one pixel per clock"
        outs = out_log[:pixels]
        lead = outs[0] - first[0]
        assert lead == d * w + d + 6, f"first output {lead} clocks after the first input"
        assert outs == list(range(outs[0], outs[0] + pixels)), "output not one pixel per clock"
        # the next frame's first pixel is taken the clock after the last step of this one
        second = in_log[pixels] - first[0]
        assert second == (h + d) * w + d, f"next frame starts after {second} clocks"
        dut._log.info("frame of %dx%d, ksize %d: %d clocks between first pixels, first output "
                      "after %d", w, h, k, second, lead)
