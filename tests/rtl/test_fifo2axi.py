"""``rfl_fifo2axi`` under cocotb: start-of-frame re-sync on damaged byte streams, beat for beat
against the hw models (``tests/rtl/bench_rfl_fifo2axi.py``), with gaps and backpressure."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support.rtltools import TB_DIR, VERILOG_DIR, require_cocotb

# (width, height, bytes, frames, gap per mille, backpressure per mille)
CASES = {
    "rgba8": (3, 2, 4, 7, 200, 300),
    "rgb8-no-stalls": (4, 2, 3, 7, 0, 0),
    "mono8": (5, 3, 1, 7, 300, 300),
    "mono8-one-pixel": (1, 1, 1, 4, 200, 200),
}


@pytest.mark.parametrize("name", list(CASES))
def test_fifo2axi_resyncs(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    sim = require_cocotb()
    from cocotb_tools.runner import get_results, get_runner

    width, height, nbytes, frames, gap, bp = CASES[name]
    case = {"width": width, "height": height, "bytes": nbytes, "frames": frames, "gap": gap,
            "bp": bp, "seed": sum(map(ord, name))}
    runner = get_runner(sim)
    runner.build(sources=[VERILOG_DIR / "rfl_fifo2axi.v"], hdl_toplevel="rfl_fifo2axi",
                 parameters={"WIDTH": width, "HEIGHT": height, "BYTES": nbytes},
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    monkeypatch.syspath_prepend(str(TB_DIR))
    try:
        xml = runner.test(test_module="bench_rfl_fifo2axi", hdl_toplevel="rfl_fifo2axi",
                          build_dir=tmp_path / "build", test_dir=tmp_path,
                          extra_env={"FIFO2AXI_CASE": json.dumps(case)},
                          log_file=tmp_path / "sim.log")
        total, failed = get_results(xml)
    except (SystemExit, RuntimeError):
        total, failed = 1, 1
    log = (tmp_path / "sim.log").read_text(errors="replace")
    assert total == 1 and failed == 0, log[-6000:]
