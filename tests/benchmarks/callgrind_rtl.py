"""Instructions a clock of the fast Verilator harness, counted by callgrind (prints figures; not
a test). Unlike bench_rtl.py's wall clock, the count does not depend on the machine's load or on
where the binary's pages landed, so a change to the Verilog can be judged by a few instructions.

The frame is bench_rtl.py's: one 640x480 ``rgba8`` frame of data/fpga_dilate_rgba8.yaml, through
the generated top (``gen``) or the hand-written exhibit circuit (``hand``). About 20 s each
under valgrind (the build apart).

Usage: ``python tests/benchmarks/callgrind_rtl.py [gen|hand ...] [--keep DIR]`` (``--keep``:
build and run there, callgrind.out included, for ``callgrind_annotate``)
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.hls import sample_frames
from rosfpga_lab.rtl import build
from rosfpga_lab.rtl.exhibit.params import rtl_params  # the exhibit, counted beside the engine
from rosfpga_lab.rtl.sim import design_from_config

DATA = Path(__file__).resolve().parents[2] / "data"


def instructions_a_clock(which: str, where: Path) -> tuple[int, int]:
    """Build the harness of ``which`` ("gen" or "hand") in ``where``, run the frame under
    callgrind; return (instructions, clocks)."""
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    frame, _ = sample_frames(config)
    design = rtl_params(config) if which == "hand" else design_from_config(config)
    sim = build(design, where / "build", simulator="verilator", harness=True)
    (where / "input.bin").write_bytes(frame)
    args = [f"+input={where / 'input.bin'}", f"+output={where / 'output.bin'}",
            f"+status={where / 'status.txt'}", f"+stats={where / 'stats.txt'}",
            "+seed=1", "+gap=0", "+bp=0", "+idle_limit=100000"]
    env = {**os.environ, "RFL_NO_HUGE_TEXT": "1"}    # valgrind does not follow the moved code
    done = subprocess.run(["valgrind", "--tool=callgrind",
                           f"--callgrind-out-file={where / 'callgrind.out'}", *sim.command, *args],
                          capture_output=True, text=True, env=env, check=True)
    found = re.search(r"Collected : (\d+)", done.stderr)
    clocks = re.search(r"^cycles (\d+)$", (where / "stats.txt").read_text(), re.M)
    if not found or not clocks:
        raise RuntimeError(f"no count or no clocks:\n{done.stderr[-2000:]}")
    return int(found.group(1)), int(clocks.group(1))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("which", nargs="*", choices=("gen", "hand"), default=["gen", "hand"])
    parser.add_argument("--keep", type=Path, metavar="DIR")
    opts = parser.parse_args(argv)
    for which in opts.which:
        with tempfile.TemporaryDirectory(prefix="rosfpga-callgrind-") as tmp:
            where = (opts.keep / which) if opts.keep else Path(tmp)
            where.mkdir(parents=True, exist_ok=True)
            count, clocks = instructions_a_clock(which, where)
        print(f"{'generated' if which == 'gen' else 'hand':<10} {count:>15,} instructions "
              f"{clocks:>11,} clocks {count / clocks:8.1f} a clock", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
