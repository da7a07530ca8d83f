"""Benchmark the VCD reader (prints figures; not a test).

Icarus Verilog simulates ``rfl_morph`` on a WIDTHxHEIGHT rgba8 frame (input gaps and output
backpressure from tests/rtl/morph_vcd_tb.v) and dumps every signal; the reader then reads the
dump whole and with three signals kept. Prints the dump's size, clocks and signals, and MB/s.

Usage: ``python tests/benchmarks/bench_vcd.py [--size 160x120]``
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from rosfpga_lab.rtl.vcd import read_vcd

HERE = Path(__file__).resolve().parent
TB = HERE.parent / "rtl" / "morph_vcd_tb.v"
MORPH = HERE.parent.parent / "rosfpga_lab" / "rtl" / "verilog" / "rfl_morph.v"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="160x120", help="frame size WxH (default 160x120)")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    if not (shutil.which("iverilog") and shutil.which("vvp")):
        print("Icarus Verilog not installed (apt-get install iverilog)", file=sys.stderr)
        return 1
    clocks = 2 * width * height + 4 * width + 100       # enough for gaps and backpressure
    with tempfile.TemporaryDirectory(prefix="rosfpga-bench-vcd-") as tmp:
        work = Path(tmp)
        rng = np.random.default_rng(1)
        words = rng.integers(0, 1 << 32, width * height, dtype=np.uint64)
        (work / "pixels.hex").write_text("".join(f"{int(w):08x}\n" for w in words))
        subprocess.run(["iverilog", "-g2005", "-o", "tb.vvp", f"-Pmorph_vcd_tb.WIDTH={width}",
                        f"-Pmorph_vcd_tb.HEIGHT={height}", f"-Pmorph_vcd_tb.CLOCKS={clocks}",
                        str(TB), str(MORPH)], cwd=work, check=True)
        start = time.perf_counter()
        subprocess.run(["vvp", "-n", "tb.vvp"], cwd=work, check=True, capture_output=True)
        sim = time.perf_counter() - start
        dump = work / "morph.vcd"
        size = dump.stat().st_size / 1e6
        print(f"dump: {size:.1f} MB, {clocks:,} clocks ({width}x{height} rgba8), "
              f"iverilog took {sim:.1f} s")
        start = time.perf_counter()
        wave = read_vcd(dump)
        for name in wave.signals:
            wave.values(name)
        whole = time.perf_counter() - start
        print(f"read_vcd, all {len(wave.signals)} signals: {whole:.2f} s ({size / whole:.1f} MB/s, "
              f"{wave.cycles / whole:,.0f} clocks/s)")
        start = time.perf_counter()
        few = read_vcd(dump, signals=["dut.m_axis_tdata", "dut.m_axis_tvalid",
                                      "dut.m_axis_tready"])
        few.values("dut.m_axis_tdata")
        some = time.perf_counter() - start
        print(f"read_vcd, 3 signals kept: {some:.2f} s ({size / some:.1f} MB/s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
