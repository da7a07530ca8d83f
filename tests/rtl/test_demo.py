"""``rtl.demo`` and ``rosfpga-lab rtl demo``: notebook 08's run on any configuration's generated
top, and the dump shipped in data/ (what it shows is right, and it is what the RTL makes now).

Expected outputs come from the Python models or from generate's test vectors
(``hls.vectors.sample_frames``), never from the demo's own report.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import require_rtl

from rosfpga_lab.cli import main
from rosfpga_lab.config import load_config
from rosfpga_lab.hls import sample_frames
from rosfpga_lab.hw import MessagePipeline
from rosfpga_lab.hls.generic import spec_from_config
from rosfpga_lab.rtl.demo import (DUMP_SIMULATOR, demo_config, demo_frames, demo_inputs,
                                  demo_report, run_demo, shipped_dump)
from rosfpga_lab.rtl.vcd import read_vcd

DATA = Path(__file__).resolve().parents[2] / "data"
#: The status codes of the demo's generated Image top (its walk's table).
STATUS_CODES = {name: code for code, (name, _field)
                in enumerate(spec_from_config(demo_config()).program.statuses)}


def _stream_bytes(dump, prefix: str) -> bytes:
    fire = dump.values(f"{prefix}_tvalid").astype(bool) & dump.values(f"{prefix}_tready").astype(bool)
    return dump.values(f"{prefix}_tdata")[fire].astype(np.uint8).tobytes()


def test_the_shipped_dump_shows_a_refusal_then_the_models_output() -> None:
    path = shipped_dump()
    assert path is not None and path.name == "rtl_demo.vcd"
    dump = read_vcd(path, clock="clk")
    refused, good = demo_frames()
    assert _stream_bytes(dump, "s") == refused + good          # everything offered was taken
    model = MessagePipeline.from_config(demo_config()).process(good).output_frame
    assert _stream_bytes(dump, "m") == model                   # one frame out, bit-exact
    decided = dump.values("status_valid").astype(bool)
    codes = dump.values("status")[decided].tolist()
    assert codes == [STATUS_CODES["SUB_BAD_WIDTH"], STATUS_CODES["SUB_OK"]]
    # the backpressure the notebook talks about is in the dump: the output stalls with data waiting
    stalled = dump.values("m_tvalid").astype(bool) & ~dump.values("m_tready").astype(bool)
    assert stalled.sum() > 100


def test_the_shipped_dump_is_what_the_rtl_makes_today(tmp_path: Path) -> None:
    require_rtl(DUMP_SIMULATOR)
    fresh = tmp_path / "rtl_demo.vcd"
    run_demo(fresh, simulator=DUMP_SIMULATOR)
    old, new = read_vcd(shipped_dump(), clock="clk"), read_vcd(fresh, clock="clk")
    assert old.signals == new.signals, "signals changed: run python data/make_rtl_demo_dump.py"
    assert old.cycles == new.cycles, "clock count changed: run python data/make_rtl_demo_dump.py"
    for name in old.signals:
        assert np.array_equal(old.values(name), new.values(name)), (
            f"{name} differs from the RTL's: run python data/make_rtl_demo_dump.py and review")


@pytest.mark.rtl
@pytest.mark.parametrize("name,refusal", [
    ("fpga_laserscan_min.yaml", "SUB_BAD_RANGES_LENGTH"),
    ("fpga_laserscan_min_cdr.yaml", "SUB_BAD_ENCAPSULATION"),
])
def test_the_demo_runs_a_generated_top_frame_by_frame(name: str, refusal: str) -> None:
    """generate's three test frames (good, refused, good) through the generated top with gaps
    and backpressure: the output is generate's expected output (the layout models'), the
    refused frame has the walk's name, and each frame's report line says so."""
    sim = require_rtl("iverilog")
    config = load_config(DATA / name)
    frames, expected = sample_frames(config)
    assert b"".join(demo_inputs(config)) == frames
    result = run_demo(simulator=sim, config=config)
    assert result.output == expected
    report = demo_report(config, demo_inputs(config), result)
    assert [f.status for f in report] == ["SUB_OK", refusal, "SUB_OK"]
    assert [f.offset for f in report] == [0, report[0].size, report[0].size + report[1].size]
    assert report[1].output == report[1].expected == b""
    assert report[0].output + report[2].output == expected
    assert all(f.exact for f in report)


@pytest.mark.rtl
def test_rtl_demo_command_prints_each_frame(capsys: pytest.CaptureFixture[str]) -> None:
    """``rosfpga-lab rtl demo`` (no CONFIG: notebook 08's Image circuit, its generated top)."""
    require_rtl("iverilog")
    assert main(["rtl", "demo", "--simulator", "iverilog"]) == 0
    out = capsys.readouterr().out.splitlines()
    refused, good = demo_frames()
    want = MessagePipeline.from_config(demo_config()).process(good).output_frame
    assert out[0] == (f"frame 1 at byte 0 ({len(refused)} bytes): SUB_BAD_WIDTH (width); "
                      "nothing out, the models refuse it too")
    assert out[1] == (f"frame 2 at byte {len(refused)} ({len(good)} bytes): SUB_OK (frame "
                      f"accepted); {len(want)} bytes out, equal to the models'")
    assert out[-1] == "PASS: every frame as the Python models"


@pytest.mark.rtl
def test_rtl_demo_command_fails_on_a_difference(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    """A circuit whose output differs from the models' (one byte flipped on its way out) is
    named and the command exits 1."""
    import dataclasses

    from rosfpga_lab.rtl import demo

    require_rtl("iverilog")
    real = demo.run_demo

    def flipped(*args, **kwargs):
        result = real(*args, **kwargs)
        out = bytearray(result.output)
        out[-1] ^= 1
        return dataclasses.replace(result, output=bytes(out))

    monkeypatch.setattr(demo, "run_demo", flipped)
    assert main(["rtl", "demo", str(DATA / "fpga_laserscan_min.yaml"), "--simulator",
                 "iverilog"]) == 1
    out = capsys.readouterr().out
    assert "frame 3 at byte" in out and "DIFFERENT" in out and "FAIL" in out
