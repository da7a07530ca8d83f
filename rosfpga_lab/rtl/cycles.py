"""Cycles measured in the RTL, per frame, beside the walk's cycle model.

How this works: every configuration's generated circuit, ``sensor_msgs/Image`` on TCPROS
included (what ``rtl cycles`` measures), is measured through its generated project's ``make
rtlsim`` (:func:`generic_rows`): the testbench records, for every stream between the stages,
the clock of its first and last handshake (:func:`read_stats`). The frame's clocks (first byte
into the subscriber to last byte out of the node) and the publisher's span are set beside the
walk's cycle model, :func:`rosfpga_lab.hls.program.frame_clocks`: a byte per clock through
subscriber and publisher and the clocks of each walker's decisions (per state, as
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
from rosfpga_lab.hls.program import Program, Refused, frame_clocks, stream_clocks
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.sim import STREAMS, StreamTiming


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


@dataclass(frozen=True)
class SteadyRow:
    """One frame ``copies`` times back to back through a generated circuit (no backpressure):
    the clocks from the first byte in to the last byte out of all of them, the model's
    (``hls.program.stream_clocks``) and the RTL's, and of the frame alone."""

    label: str
    copies: int
    in_bytes: int
    out_bytes: int
    model: int
    rtl: int
    model_alone: int
    rtl_alone: int

    @property
    def model_per_frame(self) -> float:
        """Clocks a frame in steady state, the model's: what each copy after the first adds."""
        return (self.model - self.model_alone) / (self.copies - 1)

    @property
    def rtl_per_frame(self) -> float:
        """Clocks a frame in steady state in the RTL."""
        return (self.rtl - self.rtl_alone) / (self.copies - 1)


def _program_of(config: NodeConfig) -> tuple[Program, int]:
    """The configuration's walk and its stream's path (``hls.generic.stream_path``)."""
    from rosfpga_lab.hls.errors import GenerateError
    from rosfpga_lab.hls.generic import spec_from_config, stream_path

    try:
        spec = spec_from_config(config)
    except GenerateError as exc:
        raise RtlError(f"no generated circuit to count: {exc}") from None
    if config.application.op == CUSTOM:
        raise RtlError("application.op is custom: the generated project has no RTL")
    return spec.program, stream_path(spec)


def _rtl_clocks(project: Path, frames: bytes, simulator: str | None, bp: int, count: int,
                ) -> tuple[bytes, dict[str, StreamTiming]]:
    """``frames`` through the project's ``make rtlsim``: its output and stream timings."""
    from rosfpga_lab.rtl.generic import simulate_project

    out, statuses = simulate_project(project, frames, target="rtlsim", simulator=simulator,
                                     bp=bp, out="cycles")
    if statuses != ["SUB_OK"] * count:
        raise RtlError(f"the RTL said {statuses}, the model accepts the frames")
    return out, read_stats(project / "cycles" / "stats.txt")


def generic_rows(config: NodeConfig, *, bp: int = 500, simulator: str | None = None,
                 frames: list[bytes] | None = None, work_dir: Path | None = None,
                 progress: Callable[[str], None] | None = None, copies: int = 0,
                 steady: list[SteadyRow] | None = None) -> list[GenericCycleRow]:
    """Each accepted frame (default: the generated project's test frames) through the generated
    project's RTL (``make rtlsim``) without and with ``bp`` per mille output backpressure, beside
    the cycle model; with ``copies`` (at least 2) each also that many times back to back without
    backpressure, beside ``hls.program.stream_clocks``, appended to ``steady``.

    Raises:
        RtlError: the configuration has no generated circuit (no walk for its type;
            ``op: custom``), or the simulation failed.
    """
    from rosfpga_lab.rtl.project import generate_project

    say = progress or (lambda _line: None)
    prog, latency = _program_of(config)
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
                out, rtl = _rtl_clocks(project, frame, simulator, share, 1)
                model = frame_clocks(prog, frame, 1 - share / 1000, latency=latency)
                rows.append(GenericCycleRow(
                    f"frame {k}", share, len(frame), len(out), model.total,
                    rtl["tx"].last - rtl["rx"].first + 1, model.publisher,
                    rtl["publisher_out"].last - rtl["publisher_out"].first + 1))
                if share == 0 and copies >= 2 and steady is not None:
                    say(f"frame {k} {copies} times back to back ...")
                    _, many = _rtl_clocks(project, frame * copies, simulator, 0, copies)
                    steady.append(SteadyRow(
                        f"frame {k}", copies, len(frame), len(out),
                        stream_clocks(prog, [frame] * copies, latency=latency)[-1],
                        many["tx"].last - many["rx"].first + 1, model.total,
                        rtl["tx"].last - rtl["rx"].first + 1))
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


def format_steady_rows(rows: list[SteadyRow]) -> str:
    """The back-to-back rows as an aligned text table: clocks a frame in steady state."""
    head = (f"{'frame':<10}{'in B':>11}{'out B':>11}{'copies':>8}{'model':>11}{'RTL':>11}"
            f"{'diff':>8}  {'alone: model':>12}{'RTL':>11}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.label:<10}{r.in_bytes:>11,}{r.out_bytes:>11,}{r.copies:>8}"
                     f"{r.model_per_frame:>11,.0f}{r.rtl_per_frame:>11,.0f}"
                     f"{(r.rtl - r.model) / r.model * 100:>+7.2f}%  "
                     f"{r.model_alone:>12,}{r.rtl_alone:>11,}")
    return "\n".join(lines)
