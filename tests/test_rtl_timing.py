"""Place and route with nextpnr-ecp5 (``rosfpga-lab rtl timing``): the report is nextpnr's own.

A small configuration (16x8 ``rgba8``, 3x3 dilate, the same modules as the paper's 640x480
one) keeps the run short: Yosys' ``synth_ecp5`` and nextpnr take some 30 s together. The
shipped configurations' figures (all three meet 100 MHz) are in ``rosfpga-lab rtl timing
data/fpga_*.yaml``; they take a minute or two each, too long for the suite.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rosfpga_lab.cli import main
from rosfpga_lab.rtl.errors import TimingError
from rosfpga_lab.rtl.timing import parse_report, place_and_route_dir
from rtltools import require_nextpnr
from test_rtl_sim import small_config

pytestmark = pytest.mark.rtl


def test_rtl_timing_meets_100_mhz_on_a_small_config(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    require_nextpnr()
    config = small_config("rgba8", width=16, height=8)
    path = tmp_path / "small.yaml"
    path.write_text((Path(__file__).resolve().parent.parent / "data" / "fpga_dilate_rgba8.yaml")
                    .read_text().replace("width: 640", "width: 16").replace("height: 480",
                                                                             "height: 8"))
    assert config.clock_mhz == 100
    code = main(["rtl", "timing", str(path), "-q"])
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0] == f"Timing of {path}"
    fmax = float(lines[1].split()[1])
    assert lines[1].endswith(")") and "for a 100 MHz clock: met" in lines[1], out
    assert fmax >= 100 and code == 0, out
    assert lines[2].startswith("critical path ") and " ns " in lines[2]
    # the RTL's state lives in flip-flops and block RAM: the report counts both
    ff = next(line for line in lines if line.strip().startswith("FF"))
    assert int(ff.split()[1].replace(",", "")) > 100
    assert any(line.strip().startswith("BRAM (DP16KD)") for line in lines)


def test_a_report_below_the_clock_is_not_met_and_names_the_path() -> None:
    """parse_report on a report as nextpnr writes it (fields trimmed to those read)."""
    report = {
        "fmax": {"$glbnet$clk": {"achieved": 48.9, "constraint": 100}},
        "critical_paths": [
            {"from": "posedge $glbnet$clk", "to": "<async>", "path": [
                {"type": "clk-to-q", "delay": 30.0, "from": {"cell": "io", "port": "Q"},
                 "to": {"cell": "io", "port": "Q"}}]},
            {"from": "posedge $glbnet$clk", "to": "posedge $glbnet$clk", "path": [
                {"type": "clk-to-q", "delay": 5.83, "from": {"cell": "u_rx_fifo.mem.0.0",
                                                              "port": "DOB0"},
                 "to": {"cell": "u_rx_fifo.mem.0.0", "port": "DOB0"}},
                {"type": "routing", "delay": 2.0, "from": {"cell": "u_rx_fifo.mem.0.0",
                                                            "port": "DOB0"},
                 "to": {"cell": "u_sub.state_TRELLIS_FF_Q_3", "port": "M"}},
                {"type": "setup", "delay": 0.1, "from": {"cell": "u_sub.state_TRELLIS_FF_Q_3",
                                                          "port": "M"},
                 "to": {"cell": "u_sub.state_TRELLIS_FF_Q_3", "port": "M"}}]}],
        "utilization": {"TRELLIS_FF": {"used": 920, "available": 24288},
                        "DP16KD": {"used": 7, "available": 56}},
    }
    got = parse_report(json.loads(json.dumps(report)), 100)
    assert not got.met and got.fmax_mhz == pytest.approx(48.9)
    assert got.path_ns == pytest.approx(7.93)   # the async path to a pin is not the clock's
    assert got.path[0].source == "u_rx_fifo.mem.0.0.DOB0"
    assert got.used("TRELLIS_FF") == 920 and got.used("DP16KD") == 7
    with pytest.raises(TimingError, match="names no clock"):
        parse_report({"fmax": {}}, 100)


def test_a_folder_without_the_node_is_refused(tmp_path: Path) -> None:
    with pytest.raises(TimingError, match="rfl_node.v not found"):
        place_and_route_dir(tmp_path, 100)
