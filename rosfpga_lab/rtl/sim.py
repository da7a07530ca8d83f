"""Simulating the RTL: the fast C++ harness on Verilator, or the file-based testbench.

How this works: :func:`write_sources` writes the generated top of a configuration, the ``rtl/`` of
``rosfpga-lab generate`` (:data:`Design`, :func:`design_from_config`: every type and wire,
``sensor_msgs/Image`` included), with the lab's testbench ``tb/rfl_tb.v``, ``rfl_node.v`` (the
top with the configuration's parameters) and the fast harness into a directory; a design that
brings its own sources (:class:`OwnSources`) is written the same way. :func:`build` compiles them
once (``iverilog -g2005`` to a ``vvp`` program, or ``verilator --binary`` to a native one);
:func:`run` writes the frames to a file,
runs the simulation and reads back what the testbench wrote: the output bytes, the
subscriber's status per frame and, per stream, the clocks of its first and last handshake.
The testbench drives the input with random gaps and the output with random backpressure
(``gap`` and ``bp`` in per mille of clocks, from a seeded xorshift generator), so no Python
runs per clock.

With Verilator and a C++ compiler (and no waveform wanted), :func:`build` compiles the fast
harness instead (``harness/rfl_harness.cpp`` around ``harness/rfl_harness.v``): a loop without
``--timing`` that keeps the frames in memory, evaluates the model once per clock (its nonblocking
region alone where :func:`nba_only` allows, see :data:`EVAL_MODES`) and does clock for clock what
the testbench does (same reset, same random draws, same outputs and files), several times
faster than the testbench on ``verilator --binary --timing`` (measured, beside it, by
``tests/benchmarks/bench_rtl.py``). Its serve mode is the
long-lived simulator of ``--model rtl`` (:mod:`rosfpga_lab.rtl.server`). How it is built (the
Verilator options, the eval modes and their fallback, the huge-page link flags) is
:mod:`rosfpga_lab.hls.rtlbuild`'s, which a generated project's Makefile renders too.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import time
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, runtime_checkable

from rosfpga_lab.config import CUSTOM, NodeConfig
from rosfpga_lab.hls.csim import read_beats
from rosfpga_lab.hls.errors import HlsError
from rosfpga_lab.hls.generic import GenericSpec
from rosfpga_lab.hls.rtlbuild import (  # the harness's build recipe, shared with the Makefile
    EVAL_MODES, HARNESS_BINARY, HARNESS_CXX_DIAGNOSTIC, HARNESS_FILES, HARNESS_TOP,
    HUGE_TEXT_LDFLAGS, eval_define, harness_options, huge_text_here, nba_only,
)
from rosfpga_lab.hw import Beats
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.generic import generic_rtl_files
from rosfpga_lab.rtl.limits import BUILD_TIMEOUT, IDLE_LIMIT, MAX_PER_MILLE, RUN_TIMEOUT
from rosfpga_lab.rtl.tools import (  # re-exported: the callers' names stay
    HARNESS_DIR, NODE_FILE, TB_DIR, TB_TOP, VERILOG_DIR, _verilator, cxx_compiler, find_simulator,
    find_tool, simulator_missing_reason,
)



@runtime_checkable
class OwnSources(Protocol):
    """A design that brings its own Verilog (an ``rfl_node`` with the generated top's ports and
    stream nets), which the testbench, the fast harness and its serve mode run as they run a
    generated top. No tool of the library builds one; a test may (the exhibit beside Table 1)."""

    @property
    def statuses(self) -> tuple[tuple[str, str], ...]:
        """``(name, field)`` per status code of its subscriber, code 0 (accepted) first."""
        ...

    def rtl_files(self, note: str = "") -> dict[str, bytes]:
        """``{file name: bytes}``: its Verilog, ``rfl_node.v`` and the testbench."""
        ...


#: What a simulation is built from: a generated top's spec
#: (:func:`rosfpga_lab.rtl.generic.generic_rtl_files`: the ``rtl/`` that ``rosfpga-lab
#: generate`` writes), or a design with its own sources.
Design = GenericSpec | OwnSources
#: The streams the testbench times, in its ``hs`` vector's bit order (bit 0 first).
STREAMS = ("rx", "pixels_in", "axis_in", "app_in", "app_out", "pixels_out", "publisher_out", "tx",
           "axis_out")


def design_from_config(config: NodeConfig) -> GenericSpec:
    """The circuit a configuration simulates: the generated top of every type and wire,
    ``sensor_msgs/Image`` included (:func:`rosfpga_lab.hls.generic.spec_from_config`, what
    ``rosfpga-lab generate`` renders; Image on TCPROS streams its frames through with early
    release, :attr:`rosfpga_lab.hls.program.Program.stream_early`). The hand-written Image
    circuit is the exhibit beside Table 1 (``rtl/exhibit/``), which no tool builds.

    Raises:
        RtlError: ``op: custom`` (no RTL of the user's C++) or a configuration the generator
            refuses; the message names the configuration and what to do.
    """
    from rosfpga_lab.hls.errors import GenerateError
    from rosfpga_lab.hls.generic import spec_from_config

    where = str(config.path) if config.path else "the configuration"
    if config.application.op == CUSTOM:
        raise RtlError(f"{where}: application.op is custom, so there is no RTL to simulate (the "
                       "application is your C++): run it on the fast or reference model, or "
                       "simulate the generated project's C++ (rosfpga-lab generate, make csim)")
    try:
        return spec_from_config(config)
    except GenerateError as exc:
        raise RtlError(f"{where}: no generated circuit to simulate: {exc}") from None


def verilog_sources() -> list[Path]:
    """The lab's shared synthesizable Verilog (``verilog/*.v``: FIFO, register slice, the
    video application), sorted."""
    return sorted(VERILOG_DIR.glob("*.v"))


def source_files(params: Design, *, note: str = "") -> dict[str, bytes]:
    """The simulation's files: the generated project's ``rtl/`` (or a design's own sources) and
    the fast harness.

    Args:
        params: a generated top's spec, or a design with its own sources.
        note: a comment line for a design's own ``rfl_node.v`` (a generated top's names its
            configuration).

    Returns:
        ``{file name: bytes}``.

    Raises:
        RtlError: a generated top with ``op: custom`` (its application is the user's C++).
    """
    if isinstance(params, GenericSpec):
        files = generic_rtl_files(params)
        if not files:
            raise RtlError("application.op is custom: the generated project has no RTL to "
                           "simulate (its application is your C++)")
    else:
        files = params.rtl_files(note)
    for name in HARNESS_FILES:
        files[name] = (HARNESS_DIR / name).read_bytes()
    return files


def write_sources(params: Design, dest: str | Path, *, note: str = "") -> list[str]:
    """Write :func:`source_files` into ``dest`` (created when missing).

    Returns:
        The file names written, sorted.
    """
    out = Path(dest)
    out.mkdir(parents=True, exist_ok=True)
    files = source_files(params, note=note)
    for name, data in files.items():
        (out / name).write_bytes(data)
    return sorted(files)


@dataclass(frozen=True)
class RtlBuild:
    """A compiled simulation.

    Attributes:
        simulator: ``"iverilog"`` or ``"verilator"``.
        command: what runs it (plus-arguments are appended).
        directory: where its sources and products are.
        params: the parameters (or generated top's spec) it was built with.
        seconds: how long the build took.
        trace: it can write a VCD (always with Icarus; Verilator only when built with trace).
        harness: the fast C++ harness (Verilator without trace), not the Verilog testbench.
    """

    simulator: str
    command: tuple[str, ...]
    directory: Path
    params: Design
    seconds: float
    trace: bool = True
    harness: bool = False

    @property
    def statuses(self) -> tuple[tuple[str, str], ...]:
        """``(name, field)`` per status code of its subscriber, code 0 (accepted) first."""
        return status_table(self.params)


def status_table(params: Design) -> tuple[tuple[str, str], ...]:
    """The subscriber's status codes: the walk's table of a generated top (or a design's own)."""
    if isinstance(params, GenericSpec):
        return tuple(params.program.statuses)
    return tuple(params.statuses)


def cache_root() -> Path:
    """Where cached builds live: ``$XDG_CACHE_HOME/rosfpga-lab/rtl`` (``~/.cache`` by default)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rosfpga-lab" / "rtl"


def _run_command(sim: str, where: Path, harness: bool = False) -> tuple[str, ...]:
    if sim == "iverilog":
        return (find_tool("vvp") or "vvp", "-n", str(where / "rfl_sim"))
    return (str(where / "obj_dir" / (HARNESS_BINARY if harness else "rfl_sim")),)


def harness_command(where: str | Path = ".", obj_dir: str = "obj_dir",
                    eval_mode: str = EVAL_MODES[0], *, waivers: bool = True) -> list[str]:
    """The Verilator command that builds the fast harness from the sources in ``where``.

    The options are :func:`rosfpga_lab.hls.rtlbuild.harness_options` (a generated project's
    Makefile renders the same; ``waivers=False`` gives its command), linked with the huge-page
    flags on Linux.
    """
    try:
        define = eval_define(eval_mode)      # the modes and their check have one owner
    except HlsError as exc:
        raise RtlError(str(exc)) from exc
    rtl = sorted(p.name for p in Path(where).glob("*.v")
                 if p.name not in (*HARNESS_FILES, f"{TB_TOP}.v"))
    return [_verilator() or "verilator",
            *harness_options(define, obj_dir, waivers=waivers,
                             huge_text=huge_text_here()),
            *HARNESS_FILES, *rtl]


def _compile_harness(where: Path) -> str:
    """Build the harness in the first of :data:`EVAL_MODES` this Verilator's model allows."""
    for mode in EVAL_MODES:
        shutil.rmtree(where / "obj_dir", ignore_errors=True)
        try:
            _run_build(harness_command(where, eval_mode=mode), where)
        except RtlError as error:   # the harness's C++ may not compile against this model
            if mode == EVAL_MODES[-1] or not re.search(HARNESS_CXX_DIAGNOSTIC, str(error)):
                raise
            continue
        if mode != EVAL_MODES[0] or nba_only(where / "obj_dir"):
            return mode
    raise AssertionError("unreachable: the last mode returns or raises")


def _compile(sim: str, where: Path, files: list[str], trace: bool, harness: bool = False) -> None:
    if harness:
        _compile_harness(where)
        return
    files = [f for f in files if f not in HARNESS_FILES]
    if sim == "iverilog":
        cmd = [find_tool("iverilog") or "iverilog", "-g2005", "-I", ".", "-s", TB_TOP, "-o", "rfl_sim",
               *files]
    else:
        cmd = [_verilator() or "verilator", "--binary", "--timing", "-O3", "-Wno-fatal",
               "-Wno-lint", "-Wno-style", "-I.", "--top-module", TB_TOP, "-Mdir", "obj_dir",
               "-o", "rfl_sim", *(["--trace", "--trace-depth", "3"] if trace else []), *files]
    _run_build(cmd, where)


def _run_build(cmd: list[str], where: Path) -> None:
    try:
        proc = subprocess.run(cmd, cwd=where, capture_output=True, text=True, timeout=BUILD_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise RtlError(f"building the simulation took longer than {BUILD_TIMEOUT:g} s") from None
    if proc.returncode != 0:
        raise RtlError(f"building the simulation in {where} failed ({' '.join(cmd)}):\n"
                       f"{proc.stdout}{proc.stderr}")


def build(params: Design, directory: str | Path | None = None, *,
          simulator: str | None = None, trace: bool = False, cache: bool = False, harness: bool | None = None) -> RtlBuild:
    """Write the sources and compile the fast harness or the testbench.

    Args:
        params: a generated top's spec (:func:`design_from_config`), or a design with its own
            sources.
        directory: the build directory (default: a new temporary one).
        simulator: ``"iverilog"`` or ``"verilator"`` (default: the first found).
        trace: Verilator only: compile in VCD tracing (Icarus can always dump).
        cache: without ``directory``: reuse a build of the same sources, simulator and tracing
            from :func:`cache_root` (Verilator takes 20-60 s to compile), or leave this one there.
        harness: Verilator only: the fast C++ harness (default: yes unless ``trace``); False
            builds the Verilog testbench on ``verilator --binary --timing``.

    Raises:
        SimulatorMissingError: no simulator.
        RtlError: the build failed (the compiler's messages are quoted).
    """
    sim = find_simulator(simulator)
    trace = trace or sim == "iverilog"
    if harness and (sim != "verilator" or trace):
        raise RtlError("the fast harness runs on Verilator without waveform tracing")
    fast = sim == "verilator" and not trace if harness is None else harness
    sources = source_files(params)
    files = sorted(f for f in sources if f.endswith(".v"))
    start = time.perf_counter()
    if cache and directory is None:
        digest = hashlib.sha256(f"{sim} {trace} {fast} {simulator_version(sim)}".encode())
        for name in sorted(sources):
            digest.update(name.encode() + b"\0" + sources[name] + b"\0")
        target = cache_root() / f"{sim}-{digest.hexdigest()[:20]}"
        if (target / "BUILT").exists():
            return RtlBuild(sim, _run_command(sim, target, fast), target, params, 0.0, trace, fast)
        cache_root().mkdir(parents=True, exist_ok=True)
        where = Path(tempfile.mkdtemp(prefix=".building-", dir=cache_root()))
        write_sources(params, where)
        _compile(sim, where, files, trace, fast)
        (where / "BUILT").write_text("ok\n")
        try:
            os.replace(where, target)   # another process may have finished first: keep its
        except OSError:
            shutil.rmtree(where, ignore_errors=True)
        return RtlBuild(sim, _run_command(sim, target, fast), target, params,
                        time.perf_counter() - start, trace, fast)
    where = Path(directory) if directory else Path(tempfile.mkdtemp(prefix="rosfpga-rtl-"))
    try:
        write_sources(params, where)
        _compile(sim, where, files, trace, fast)
    except BaseException:
        if directory is None:
            shutil.rmtree(where, ignore_errors=True)
        raise
    built = RtlBuild(sim, _run_command(sim, where, fast), where, params,
                     time.perf_counter() - start, trace, fast)
    if directory is None:  # a temporary build goes when its RtlBuild does (or at exit)
        weakref.finalize(built, shutil.rmtree, where, True)
    return built


def simulator_version(sim: str) -> str:
    """The simulator's version line (part of a cached build's key)."""
    tool = find_tool("iverilog") if sim == "iverilog" else _verilator()
    if tool is None:
        return "?"
    try:
        proc = subprocess.run([tool, "-V" if sim == "iverilog" else "--version"],
                              capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return "?"
    return (proc.stdout.strip().splitlines() or ["?"])[0]


@dataclass(frozen=True)
class StreamTiming:
    """Handshakes of one stream: first and last clock (1 = the first after reset), count."""

    first: int
    last: int
    count: int


@dataclass(frozen=True)
class RtlResult:
    """What one simulation produced.

    Attributes:
        output: the bytes the circuit sent (TCPROS frames).
        status: ``(byte offset, status name)`` per frame the subscriber decided on.
        streams: per stream of :data:`STREAMS`, its handshake timing.
        cycles: clocks simulated.
        log: the simulator's output.
        seconds: wall-clock time of the run.
        input_beats, output_beats: the beats into and out of the application, all frames
            (``run(..., beats=True)``; else None).
        framing: the stages' framing flags at the end (``rfl_top``'s ``framing`` port: bits
            7..4 fifo2axi's, 3..0 the application's, each in ``hw.framing.FRAMING_FLAGS``
            order); 0 when every frame came through whole.
    """

    output: bytes
    status: tuple[tuple[int, str], ...]
    streams: dict[str, StreamTiming]
    cycles: int
    log: str
    seconds: float
    input_beats: Beats | None = None
    output_beats: Beats | None = None
    framing: int = 0

    @property
    def cut_short(self) -> bool:
        """The input ended inside a frame: the circuit was left waiting for the rest (a frame
        it had accepted may have its header, but not all its pixels, in ``output``)."""
        return "the input ended inside a frame" in self.log

    @property
    def clocks_per_second(self) -> float:
        """Simulated clocks per wall-clock second."""
        return self.cycles / self.seconds if self.seconds > 0 else 0.0


def _per_mille(name: str, value: int) -> int:
    if not 0 <= value <= MAX_PER_MILLE:
        raise RtlError(f"{name} must be 0..{MAX_PER_MILLE} per mille, got {value}")
    return value


def run(sim: RtlBuild, frames: bytes, *, seed: int = 1, gap: int = 0, bp: int = 0,
        vcd: str | Path | None = None, work_dir: str | Path | None = None,
        idle_limit: int | None = None, beats: bool = False,
        plusargs: Sequence[str] = ()) -> RtlResult:
    """Simulate the circuit on TCPROS frames.

    Args:
        sim: a build (:func:`build`).
        frames: one or more TCPROS frames.
        seed: the testbench's random seed (1..2**31-1).
        gap: per mille of clocks the input offers no byte.
        bp: per mille of clocks the output is not ready (backpressure).
        vcd: write a VCD of the stream and FIFO signals there (Verilator: build with trace).
        work_dir: where the files go (default: a temporary directory, removed after).
        idle_limit: clocks without any handshake that end the run (default :data:`IDLE_LIMIT`).
        beats: also record the AXI4-Stream beats into and out of the application.
        plusargs: further testbench options (``+clocks_f2a=FILE``: fifo2axi's ports per clock;
            the testbench only: build with ``harness=False``).

    Raises:
        RtlError: bad settings, the simulation failed, stalled or ran out of time.
    """
    gap, bp = _per_mille("gap", gap), _per_mille("bp", bp)
    if vcd is not None and not sim.trace:
        raise RtlError("this Verilator build cannot write a VCD: build it with trace=True")
    if plusargs and sim.harness:
        raise RtlError(f"the fast harness takes no testbench options ({' '.join(plusargs)}): "
                       "build the testbench with harness=False")
    if not 1 <= seed < 2**31:
        raise RtlError(f"seed must be in 1..2**31-1, got {seed}")
    limit = idle_limit or IDLE_LIMIT
    with tempfile.TemporaryDirectory(prefix="rosfpga-rtlsim-") as tmp:
        work = Path(work_dir) if work_dir else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        (work / "input.bin").write_bytes(frames)
        args = [f"+input={work / 'input.bin'}", f"+output={work / 'output.bin'}",
                f"+status={work / 'status.txt'}", f"+stats={work / 'stats.txt'}",
                f"+seed={seed}", f"+gap={gap}", f"+bp={bp}", f"+idle_limit={limit}"]
        if vcd is not None:
            args.append(f"+vcd={Path(vcd).resolve()}")
        if beats:
            args += [f"+beats_in={work / 'input_beats.txt'}", f"+beats_out={work / 'output_beats.txt'}"]
        args += list(plusargs)
        start = time.perf_counter()
        try:
            proc = subprocess.run([*sim.command, *args], cwd=work, capture_output=True, text=True,
                                  timeout=RUN_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise RtlError(f"the RTL simulation ran longer than {RUN_TIMEOUT:g} s") from None
        seconds = time.perf_counter() - start
        log = proc.stdout + proc.stderr
        if proc.returncode != 0 or "rtlsim: ERROR" in log or not (work / "stats.txt").exists():
            raise RtlError(f"the RTL simulation failed (exit {proc.returncode}):\n{log}")
        return _read_result(work, log, seconds, sim.statuses)


def _read_result(work: Path, log: str, seconds: float,
                 table: tuple[tuple[str, str], ...]) -> RtlResult:
    status = []
    for line in (work / "status.txt").read_text().splitlines():
        offset, code = line.split()
        status.append((int(offset), table[int(code)][0]))
    streams: dict[str, StreamTiming] = {}
    cycles = framing = 0
    for line in (work / "stats.txt").read_text().splitlines():
        parts = line.split()
        if parts[0] == "cycles":
            cycles = int(parts[1])
        elif parts[0] == "framing":
            framing = int(parts[1])
        else:
            streams[STREAMS[int(parts[0])]] = StreamTiming(*(int(v) for v in parts[1:]))
    beats = [read_beats(work / f"{side}_beats.txt") if (work / f"{side}_beats.txt").exists()
             else None for side in ("input", "output")]
    return RtlResult((work / "output.bin").read_bytes(), tuple(status), streams, cycles, log,
                     seconds, beats[0], beats[1], framing)


def env_required() -> bool:
    """``ROSFPGA_REQUIRE_RTL`` is set (CI): a missing simulator is an error, not a skip."""
    return os.environ.get("ROSFPGA_REQUIRE_RTL", "") not in ("", "0", "false", "no")
