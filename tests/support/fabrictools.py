"""The whole node in the fabric, ``rfl_fabric_node``, under cocotb: built from rtl/fabric's
files, a generated project's top and the parameters of a discovery ROM, run on one case by a
bench (tests/rtl/bench_rfl_fabric_node.py, or tests/rtl/bench_rfl_rtps_ctrl.py for the answer
path alone). Shared by the tests that drive the node (tests/rtl/test_fabric_node.py,
test_fabric_rtps_loop.py, test_fabric_answer.py); the bench's module must be importable
(``TB_DIR`` on the path)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from rosfpga_lab.rtl.discrom import DEST_USER, DiscoveryRom, node_parameters, write_rom
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_NODE
from tests.support.rtltools import require_cocotb, run_bench


def generate_project(config: Path, out: Path) -> Path:
    """``rosfpga-lab generate CONFIG -o OUT`` (the generated top rfl_node is under out/rtl)."""
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(config), "-o",
                           str(out), "-q"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return out


def generated_rtl(gen: Path) -> list[Path]:
    """The generated project's Verilog modules (its testbench rfl_tb.v left out)."""
    return sorted(q for q in (gen / "rtl").glob("*.v") if q.name != "rfl_tb.v")


def run_fabric_node(gen: Path, rom: DiscoveryRom, case: dict[str, object], tmp_path: Path, *,
                    period: int, max_bytes: int = 2048, bench: str = "bench_rfl_fabric_node",
                    **params: str) -> dict:
    """``bench``'s output for ``case`` (its keys: the bench's docstring; both read
    ``FABRIC_NODE_CASE`` and write ``FABRIC_NODE_OUT``), the node built with ``gen``'s generated
    top, ``rom``'s files and parameters, SPDP every ``period`` clocks, a seam of ``max_bytes``
    and ``params`` over them."""
    sim = require_cocotb()
    from cocotb_tools.runner import get_runner

    write_rom(rom, tmp_path)
    (tmp_path / "case.json").write_text(json.dumps(case))
    params = dict(node_parameters(rom, period=period), MAX_BYTES=str(max_bytes),
                  USER_DEST=str(DEST_USER), **params)
    runner = get_runner(sim)
    runner.build(sources=[*(FABRIC_DIR / m for m in FABRIC_NODE), *generated_rtl(gen)],
                 includes=[gen / "rtl", FABRIC_DIR], hdl_toplevel="rfl_fabric_node",
                 parameters=params, build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    run_bench(runner, bench, "rfl_fabric_node", tmp_path / "build", tmp_path,
              {"FABRIC_NODE_CASE": str(tmp_path / "case.json"),
               "FABRIC_NODE_OUT": str(tmp_path / "out.json")})
    return json.loads((tmp_path / "out.json").read_text())
