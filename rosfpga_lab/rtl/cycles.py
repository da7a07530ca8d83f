"""Cycles measured in the RTL, per frame and per stage, beside the cycle model (``hw.cycles``).

How this works: :func:`measure` simulates one frame and reads, for every stream between the
stages, the clock of its first and last handshake (the testbench records them). A stage's
*span* is from its first byte (or beat) in to its last byte (or beat) out; the frame's span is
from the first byte into the subscriber to the last byte out of the node (the output FIFO
included, so that backpressure on the output counts). :func:`compare` sets the spans
beside :func:`rosfpga_lab.hw.cycles.account`'s figures for the same frame.

That is the hand-written Image circuit's table (the exhibit beside Table 1; its model is
``hw.cycles``). Every configuration's generated circuit, ``sensor_msgs/Image`` on TCPROS
included (what ``rtl cycles`` measures), is measured through its generated project's ``make
rtlsim`` (:func:`generic_rows`) and set beside the walk's
cycle model, :func:`rosfpga_lab.hls.program.frame_clocks`: a byte per clock through subscriber
and publisher and the clocks of each walker's decisions (per state, as
:func:`rosfpga_lab.hls.program.subscribe` and :func:`~rosfpga_lab.hls.program.publish` say);
equal to the RTL without backpressure, an estimate with it (the output's random ready share).
"""

from __future__ import annotations

import struct
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.config import CUSTOM, NodeConfig
from rosfpga_lab.hls.program import Program, Refused, frame_clocks
from rosfpga_lab.hw import Pipeline
from rosfpga_lab.hw.cycles import CycleReport, account
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.sim import STREAMS, RtlBuild, RtlResult, StreamTiming, run

#: Stage -> (stream of its first input, stream of its last output).
STAGES: dict[str, tuple[str, str]] = {
    "subscriber": ("rx", "pixels_in"),
    "fifo2axi": ("pixels_in", "axis_in"),
    "application": ("app_in", "app_out"),
    "axi2fifo": ("axis_out", "pixels_out"),
    "publisher": ("publisher_out", "publisher_out"),
    "frame": ("rx", "tx"),
}


@dataclass(frozen=True)
class RtlCycles:
    """Spans of one frame in the RTL (clocks, first handshake in to last out, both counted)."""

    spans: dict[str, int]
    bp: int
    result: RtlResult

    @property
    def frame(self) -> int:
        """Clocks from the frame's first byte in to its last byte out."""
        return self.spans["frame"]


def spans(result: RtlResult) -> dict[str, int]:
    """Per stage of :data:`STAGES`, its span in ``result`` (one frame)."""
    out = {}
    for stage, (first, last) in STAGES.items():
        a, b = result.streams[first], result.streams[last]
        out[stage] = b.last - a.first + 1 if a.count and b.count else 0
    return out


def measure(sim: RtlBuild, frame: bytes, *, bp: int = 0, seed: int = 1) -> RtlCycles:
    """Simulate one frame with ``bp`` per mille output backpressure (no input gaps)."""
    result = run(sim, frame, bp=bp, seed=seed)
    return RtlCycles(spans(result), bp, result)


def model_report(pipe: Pipeline, frame: bytes, bp: int = 0) -> CycleReport:
    """The cycle model's report of ``frame`` with the output ready ``1 - bp/1000`` of clocks."""
    res = pipe.process(frame)
    return account(res.fields, pipe.op, pipe.ksize, len(frame), len(res.output_frame),
                   ready=1 - bp / 1000)


@dataclass(frozen=True)
class CycleRow:
    """One line of the model-vs-RTL table."""

    label: str
    bp: int
    model: int
    rtl: int
    spans: dict[str, int]

    @property
    def error(self) -> float:
        """(RTL - model) / model."""
        return (self.rtl - self.model) / self.model


def compare(label: str, sim: RtlBuild, pipe: Pipeline, frame: bytes, *, bp: int = 0,
            seed: int = 1) -> CycleRow:
    """Measure ``frame`` in the RTL and set it beside the model's ``total``."""
    measured = measure(sim, frame, bp=bp, seed=seed)
    return CycleRow(label, bp, model_report(pipe, frame, bp).total, measured.frame,
                    measured.spans)


def format_rows(rows: list[CycleRow]) -> str:
    """The rows as an aligned text table (frame = first byte in to last byte out, clocks)."""
    stages = [s for s in STAGES if s != "frame"]
    head = (f"{'config':<22}{'backpr.':>8}{'model':>10}{'RTL':>10}{'diff':>8}  "
            + "".join(f"{s:>12}" for s in stages))
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.label:<22}{r.bp / 10:>7.0f}%{r.model:>10,}{r.rtl:>10,}"
                     f"{r.error * 100:>+7.2f}%  " + "".join(f"{r.spans[s]:>12,}" for s in stages))
    return "\n".join(lines)


# -- generated (generic) circuits: any message type ----------------------------------------------

@dataclass(frozen=True)
class GenericCycleRow:
    """One frame of a generated circuit: the model's clocks (``hls.program.frame_clocks``) and
    the RTL's, first byte into the subscriber to last byte out of the node, and the
    publisher's span (first byte out to last)."""

    label: str
    bp: int
    in_bytes: int
    out_bytes: int
    model: int
    rtl: int
    model_publisher: int
    rtl_publisher: int

    @property
    def error(self) -> float:
        """(RTL - model) / model."""
        return (self.rtl - self.model) / self.model


def read_stats(path: Path) -> dict[str, StreamTiming]:
    """The per-stream first/last handshake clocks and counts of a testbench's ``stats.txt``."""
    out = {}
    for line in path.read_text().splitlines():
        parts = line.split()
        if parts and parts[0].isdigit():
            out[STREAMS[int(parts[0])]] = StreamTiming(*(int(v) for v in parts[1:]))
    return out


def good_frames(frames: bytes, prog: Program) -> list[bytes]:
    """The frames of ``frames`` (back to back, each behind its 4-byte length) the circuit
    accepts."""
    out, at = [], 0
    while at + 4 <= len(frames):
        frame = frames[at:at + 4 + struct.unpack_from("<I", frames, at)[0]]
        at += len(frame)
        try:
            frame_clocks(prog, frame)
        except Refused:
            continue
        out.append(frame)
    return out


def generic_rows(config: NodeConfig, *, bp: int = 500, simulator: str | None = None,
                 frames: list[bytes] | None = None, work_dir: Path | None = None,
                 progress: Callable[[str], None] | None = None) -> list[GenericCycleRow]:
    """Each accepted frame (default: the generated project's test frames) through the generated
    project's RTL (``make rtlsim``) without and with ``bp`` per mille output backpressure, beside
    the cycle model.

    Raises:
        RtlError: the configuration has no generated circuit (no walk for its type;
            ``op: custom``), or the simulation failed.
    """
    from rosfpga_lab.hls.errors import GenerateError
    from rosfpga_lab.hls.generic import spec_from_config, stream_path
    from rosfpga_lab.rtl.generic import simulate_project
    from rosfpga_lab.rtl.project import generate_project

    say = progress or (lambda _line: None)
    try:
        spec = spec_from_config(config)
    except GenerateError as exc:
        raise RtlError(f"no generated circuit to count: {exc}") from None
    if config.application.op == CUSTOM:
        raise RtlError("application.op is custom: the generated project has no RTL")
    prog, latency = spec.program, stream_path(spec)
    with tempfile.TemporaryDirectory(prefix="rosfpga-cycles-") as tmp:
        project = Path(work_dir or tmp) / "project"
        say(f"generating the project of {prog.type_in} on {config.wire} in {project} ...")
        generate_project(config, project, force=True)
        if frames is None:
            frames = good_frames((project / "tb_input.bin").read_bytes(), prog)
        rows = []
        for k, frame in enumerate(frames):
            for share in sorted({0, bp}):
                say(f"frame {k} ({len(frame):,} bytes), backpressure {share / 10:g} % ...")
                out, statuses = simulate_project(project, frame, target="rtlsim",
                                                 simulator=simulator, bp=share, out="cycles")
                if statuses != ["SUB_OK"]:
                    raise RtlError(f"frame {k}: the RTL said {statuses}, the model accepts it")
                rtl = read_stats(project / "cycles" / "stats.txt")
                model = frame_clocks(prog, frame, 1 - share / 1000, latency=latency)
                rows.append(GenericCycleRow(
                    f"frame {k}", share, len(frame), len(out), model.total,
                    rtl["tx"].last - rtl["rx"].first + 1, model.publisher,
                    rtl["publisher_out"].last - rtl["publisher_out"].first + 1))
        return rows


def format_generic_rows(rows: list[GenericCycleRow]) -> str:
    """The rows as an aligned text table."""
    head = (f"{'frame':<10}{'in B':>11}{'out B':>11}{'backpr.':>8}{'model':>11}{'RTL':>11}"
            f"{'diff':>8}  {'publisher: model':>16}{'RTL':>11}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.label:<10}{r.in_bytes:>11,}{r.out_bytes:>11,}{r.bp / 10:>7.0f}%"
                     f"{r.model:>11,}{r.rtl:>11,}{r.error * 100:>+7.2f}%  "
                     f"{r.model_publisher:>16,}{r.rtl_publisher:>11,}")
    return "\n".join(lines)
