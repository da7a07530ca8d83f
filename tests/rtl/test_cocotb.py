"""cocotb (with cocotbext-axi) drives the generated RTL from Python: real TCPROS frames in with random
gaps, random backpressure on the output, every byte equal to the Python models'.

The testbench is ``tests/rtl/bench_rfl_node.py``; the simulator is Icarus Verilog (cocotb's
runner builds and runs it). Small images: cocotb runs Python on every clock.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.realros import require_rtl, skip_or_fail
from rosfpga_lab.hw import PIXEL_FORMATS
from rosfpga_lab.rtl import write_sources
from rosfpga_lab.rtl.sim import design_from_config, status_table
from tests.hls.test_csim import ros_frame
from tests.rtl.test_sim import model_output, random_image, refusal_frames, small_config

pytestmark = pytest.mark.rtl
HERE = Path(__file__).resolve().parents[1]


def cosimulate(config, frames: list[bytes], tmp_path: Path, seed: int = 5) -> list[str]:
    """Run the cocotb testbench on ``frames`` through the configuration's generated top
    (``design_from_config``; an Image on TCPROS streams through with early release); it asserts
    the output equals the models'.

    Returns:
        The subscriber's statuses, one per frame it decided on.
    """
    require_rtl("iverilog")
    try:
        import cocotb_tools.runner as runner_mod
    except ImportError:
        skip_or_fail("cocotb not installed (pip install cocotb cocotbext-axi)", "ROSFPGA_REQUIRE_RTL")
    expected, _ = model_output(config, frames)
    (tmp_path / "frames.bin").write_bytes(b"".join(frames))
    (tmp_path / "expected.bin").write_bytes(expected)
    design = design_from_config(config)
    files = write_sources(design, tmp_path / "src")
    sources = [tmp_path / "src" / f for f in files
               if f.endswith(".v") and f not in ("rfl_tb.v", "rfl_harness.v")]
    runner = runner_mod.get_runner("icarus")
    runner.build(sources=sources, includes=[tmp_path / "src"], hdl_toplevel="rfl_node",
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"))
    results = runner.test(hdl_toplevel="rfl_node", test_module="bench_rfl_node",
                          test_dir=HERE / "rtl", build_dir=tmp_path / "build",
                          results_xml=str(tmp_path / "results.xml"),
                          extra_env={"RFL_FRAMES": str(tmp_path / "frames.bin"),
                                     "RFL_EXPECTED": str(tmp_path / "expected.bin"),
                                     "RFL_STATUS_OUT": str(tmp_path / "status.txt"),
                                     "RFL_SEED": str(seed)})
    failed = runner_mod.get_results(results)[1]
    assert failed == 0, f"the cocotb test failed; its log is in {tmp_path / 'build'}"
    codes = [int(c) for c in (tmp_path / "status.txt").read_text().split()]
    return [status_table(design)[c][0] for c in codes]


@pytest.mark.parametrize("encoding", list(PIXEL_FORMATS))
def test_cocotb_drives_real_frames_through_the_generated_image_top(encoding: str,
                                                                   tmp_path: Path) -> None:
    """The generated top every tool runs for Image on TCPROS (handed over at the data count,
    the publisher writing while the stream flows): the same frames, gaps and backpressure, the
    models' bytes, the refused frame's status from its walk's table."""
    config = small_config(encoding, width=9, height=5)
    frames = [ros_frame(random_image(config, s), encoding, seq=s, frame_id="cam" * s)
              for s in (1, 2)]
    bad = ros_frame(random_image(config, 3)[:, :-1], encoding)
    _, verdicts = model_output(config, [frames[0], bad, frames[1]])
    assert verdicts == ["SUB_OK", "refused", "SUB_OK"]
    statuses = cosimulate(config, [frames[0], bad, frames[1]], tmp_path)
    assert statuses == ["SUB_OK", "SUB_BAD_WIDTH", "SUB_OK"]


def test_cocotb_every_refusal_reason_then_a_good_frame(tmp_path: Path) -> None:
    config = small_config("mono8", width=6, height=4, frame_id_max=16)
    frames, names = refusal_frames(config)
    # the walk names its refusals after the layout's fields: the same frames refused
    assert [s == "SUB_OK" for s in cosimulate(config, frames, tmp_path, seed=9)] == [
        n == "SUB_OK" for n in names]
