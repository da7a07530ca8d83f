"""Cycles measured in the RTL, per frame and per stage, beside the cycle model (``hw.cycles``).

How this works: :func:`measure` simulates one frame and reads, for every stream between the
stages, the clock of its first and last handshake (the testbench records them). A stage's
*span* is from its first byte (or beat) in to its last byte (or beat) out; the frame's span is
from the first byte into the subscriber to the last byte out of the node (the output FIFO
included, so that backpressure on the output counts). :func:`compare` sets the spans
beside :func:`rosfpga_lab.hw.cycles.account`'s figures for the same frame.
"""

from __future__ import annotations

from dataclasses import dataclass

from rosfpga_lab.hw import Pipeline
from rosfpga_lab.hw.cycles import CycleReport, account
from rosfpga_lab.rtl.sim import RtlBuild, RtlResult, run

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
