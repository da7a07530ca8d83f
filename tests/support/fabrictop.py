"""The node in the fabric on the network, ``rfl_fabric_top`` (GMII variant), under cocotb and
Verilator: the generated project, the top's parameters from the rendered ROMs, the cached build
and one run of a bench module. Shared by tests/rtl/test_fabric_top.py, test_fabric_wire.py and
tests/benchmarks/bench_fabric_wire.py.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rosfpga_lab.rtl.discrom import DiscoveryRom, fabric_top_literals
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_INCLUDES, FABRIC_TOP_GMII
from rosfpga_lab.rtl.sim import cache_root, simulator_version

if TYPE_CHECKING:
    from cocotb_tools.runner import Runner

TOP = "rfl_fabric_top"
SOURCES = [FABRIC_DIR / m for m in FABRIC_TOP_GMII]


class BenchFailed(RuntimeError):
    """The cocotb bench did not pass (the log's tail says why)."""


def generate(config: Path, out: Path) -> Path:
    """``rosfpga-lab generate CONFIG -o out``: the project folder."""
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(config), "-o",
                           str(out), "-q"], capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        raise BenchFailed(f"generate {config}: {proc.stderr[-2000:]}")
    return out


def top_parameters_of(rom: DiscoveryRom, max_bytes: int, period: int) -> dict[str, str]:
    """The top's Verilog parameters for the ROMs ``rom`` (written by ``write_rom`` into the run's
    folder), the seam's buffer and the SPDP period."""
    return dict(fabric_top_literals(rom, period=period), MAX_BYTES=str(max_bytes))


def build(runner: Runner, gen: Path, params: dict[str, str], log_dir: Path) -> Path:
    """Verilator's build, kept in the lab's RTL cache keyed by the sources (the generated ones
    too), the parameters and the tools (its dependency files name absolute paths)."""
    import cocotb

    rtl = sorted(q for q in (gen / "rtl").glob("*.v") if q.name != "rfl_tb.v")
    digest = hashlib.sha256(f"{cocotb.__file__} {simulator_version('verilator')}".encode())
    included = [FABRIC_DIR / name for name in FABRIC_INCLUDES]
    for path in [*SOURCES, *included, *rtl, *sorted((gen / "rtl").glob("*.vh"))]:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    digest.update(json.dumps(params, sort_keys=True).encode())
    where = cache_root() / f"cocotb-fabric-top-{digest.hexdigest()[:20]}"
    # the generated files kept beside the build: the runner rebuilds for sources newer than it
    kept = where / "generated"
    if not kept.is_dir():
        kept.mkdir(parents=True)
        for path in (gen / "rtl").iterdir():
            if path.suffix in (".v", ".vh") and path.name != "rfl_tb.v":
                shutil.copy2(path, kept / path.name)
    runner.build(
        sources=[*SOURCES, *sorted(kept.glob("*.v"))], includes=[kept, FABRIC_DIR],
        hdl_toplevel=TOP,
        parameters=params, build_dir=where, timescale=("1ns", "1ps"),
        build_args=["-Wno-fatal", "-Wno-lint", "-Wno-style", "-Wno-UNOPTFLAT"],
        log_file=log_dir / "build.log")
    return where


def run(runner: Runner, where: Path, module: str, case: dict[str, Any], work: Path,
        env_case: str, env_out: str) -> dict[str, Any]:
    """Run the cocotb bench ``module`` (tests/rtl) on the build with ``case``; its output."""
    from cocotb_tools.runner import get_results

    (work / "case.json").write_text(json.dumps(case))
    try:
        xml = runner.test(test_module=module, hdl_toplevel=TOP, build_dir=where, test_dir=work,
                          extra_env={env_case: str(work / "case.json"),
                                     env_out: str(work / "out.json")},
                          log_file=work / "sim.log")
        total, failed = get_results(xml)
    except (SystemExit, RuntimeError):
        total, failed = 1, 1
    if not (total == 1 and failed == 0):
        log = (work / "sim.log").read_text(errors="replace") if (work / "sim.log").exists() else ""
        raise BenchFailed(log[-4000:])
    return json.loads((work / "out.json").read_text())
