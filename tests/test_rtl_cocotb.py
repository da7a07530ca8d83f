"""cocotb (with cocotbext-axi) drives the RTL from Python: real TCPROS frames in with random
gaps, random backpressure on the output, every byte equal to the Python models'.

The testbench is ``tests/rtl/cocotb_rfl_node.py``; the simulator is Icarus Verilog (cocotb's
runner builds and runs it). Small images: cocotb runs Python on every clock.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from realros import require_rtl
from rosfpga_lab.hw.interpreter import SUBSCRIBER_STATUSES
from rosfpga_lab.rtl import rtl_params, write_sources
from test_hls_csim import ros_frame
from test_rtl_sim import model_output, random_image, small_config

pytestmark = pytest.mark.rtl
HERE = Path(__file__).resolve().parent


@pytest.mark.parametrize("encoding", ["rgba8", "mono8"])
def test_cocotb_drives_real_frames_through_the_rtl(encoding: str, tmp_path: Path) -> None:
    require_rtl("iverilog")
    runner_mod = pytest.importorskip("cocotb_tools.runner", reason="cocotb not installed")
    config = small_config(encoding, width=9, height=5)
    frames = [ros_frame(random_image(config, s), encoding, seq=s, frame_id="cam" * s)
              for s in (1, 2)]
    bad = ros_frame(random_image(config, 3)[:, :-1], encoding)
    stream = frames[0] + bad + frames[1]
    expected, verdicts = model_output(config, [frames[0], bad, frames[1]])
    assert verdicts == ["SUB_OK", "refused", "SUB_OK"]
    (tmp_path / "frames.bin").write_bytes(stream)
    (tmp_path / "expected.bin").write_bytes(expected)
    files = write_sources(rtl_params(config), tmp_path / "src")
    sources = [tmp_path / "src" / f for f in files if f.endswith(".v") and f != "rfl_tb.v"]
    runner = runner_mod.get_runner("icarus")
    runner.build(sources=sources, includes=[tmp_path / "src"], hdl_toplevel="rfl_node",
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"))
    results = runner.test(hdl_toplevel="rfl_node", test_module="cocotb_rfl_node",
                          test_dir=HERE / "rtl", build_dir=tmp_path / "build",
                          extra_env={"RFL_FRAMES": str(tmp_path / "frames.bin"),
                                     "RFL_EXPECTED": str(tmp_path / "expected.bin"),
                                     "RFL_STATUS_OUT": str(tmp_path / "status.txt"),
                                     "RFL_SEED": "5"})
    failed = runner_mod.get_results(results)[1]
    assert failed == 0, (tmp_path / "build").as_posix()
    codes = [int(c) for c in (tmp_path / "status.txt").read_text().split()]
    assert [SUBSCRIBER_STATUSES[c][0] for c in codes] == ["SUB_OK", "SUB_BAD_WIDTH", "SUB_OK"]
