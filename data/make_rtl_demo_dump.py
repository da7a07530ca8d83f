"""Make data/rtl_demo.vcd: the RTL demo of notebook 08, simulated by Icarus Verilog.

Run from the repository root with the lab installed and Icarus Verilog on PATH:

    python data/make_rtl_demo_dump.py

The circuit, the frames and the simulator settings are rosfpga_lab.rtl.demo's (one owner);
tests/rtl/test_demo.py regenerates the dump the same way and fails when it drifts.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rosfpga_lab.rtl.demo import DUMP_NAME, DUMP_SIMULATOR, run_demo


def main() -> int:
    out = Path(__file__).resolve().parent / DUMP_NAME
    result = run_demo(out, simulator=DUMP_SIMULATOR)
    print(f"{out}: {result.cycles} clocks, frames {result.status}, {out.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
