"""Benchmark the design flow for message types other than Image (prints figures; not a test).

For every shipped example of a generic project (``data/fpga_laserscan_min.yaml``,
``data/fpga_samples_dilate.yaml``): the time ``rosfpga-lab generate`` takes (layout, rendering,
test frames and the Python models' output), then ``make csim`` (g++ build + run on the shipped
frames) and ``make rtlsim`` (build + run, with random input gaps and output backpressure) per
simulator installed, each checked against ``tb_expected.bin``; the figures are wall-clock
seconds on this machine, the build included (it is paid once per configuration).

Usage: ``python tests/benchmarks/bench_generic_flow.py [--simulator iverilog|verilator]``
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.project import generate_project
from rosfpga_lab.rtl.sim import find_tool, simulator_missing_reason

DATA = Path(__file__).resolve().parents[2] / "data"
EXAMPLES = ("fpga_laserscan_min.yaml", "fpga_samples_dilate.yaml")


def timed_make(project: Path, *args: str) -> tuple[float, str]:
    start = time.perf_counter()
    proc = subprocess.run(["make", "-s", *args], cwd=project, capture_output=True, text=True,
                          timeout=1800)
    seconds = time.perf_counter() - start
    last = (proc.stdout.strip().splitlines() or ["?"])[-1]
    if proc.returncode != 0:
        last = f"FAILED: {proc.stdout[-500:]}{proc.stderr[-500:]}"
    return seconds, last


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--simulator", choices=("iverilog", "verilator"), action="append")
    args = parser.parse_args()
    sims = args.simulator or [s for s in ("iverilog", "verilator")
                              if simulator_missing_reason(s) is None]
    print(f"{'example':<28}{'step':<32}{'seconds':>9}  result")
    for name in EXAMPLES:
        config = load_config(DATA / name)
        with tempfile.TemporaryDirectory(prefix="bench-generic-") as tmp:
            project = Path(tmp) / "p"
            start = time.perf_counter()
            generate_project(config, project)
            print(f"{name:<28}{'generate':<32}{time.perf_counter() - start:>9.2f}  "
                  f"{len(list(project.rglob('*')))} paths")
            seconds, last = timed_make(project, "csim")
            print(f"{'':<28}{'make csim (build + run)':<32}{seconds:>9.2f}  {last}")
            seconds, last = timed_make(project, "csim")
            print(f"{'':<28}{'make csim (run)':<32}{seconds:>9.2f}  {last}")
            for sim in sims:
                tool = [] if sim == "iverilog" else [
                    f"VERILATOR={find_tool('verilator') or find_tool('verilator-cli')}"]
                seconds, last = timed_make(project, "rtlsim", f"SIM={sim}", "GAP=200", "BP=300", *tool)
                print(f"{'':<28}{f'make rtlsim {sim} (build+run)':<32}{seconds:>9.2f}  {last}")
                seconds, last = timed_make(project, "rtlsim", f"SIM={sim}", "GAP=200", "BP=300", *tool)
                print(f"{'':<28}{f'make rtlsim {sim} (run)':<32}{seconds:>9.2f}  {last}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
