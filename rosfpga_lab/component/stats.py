"""Counters and latency figures of a running component (snapshots, safe to hand to any thread)."""

from __future__ import annotations

import collections
import statistics
import threading
from dataclasses import dataclass, field

from rosfpga_lab.component import limits
from rosfpga_lab.config.vocabulary import RTL_MODEL
from rosfpga_lab.graph.rate import RateMeter


def since_stamp(now: float, secs: int, nsecs: int) -> float | None:
    """Seconds from a ``header.stamp`` to ``now`` (wall clock), or None when the stamp is not a
    recent wall-clock time (zero, a simulated clock, the future): no latency to speak of then.

    Args:
        now: wall-clock time (``time.time()``) of arrival or publication.
        secs, nsecs: the stamp.
    """
    seconds = now - (secs + nsecs * 1e-9)
    return seconds if 0 <= seconds < limits.STAMP_PLAUSIBLE else None


def fps_meter() -> RateMeter:
    """The meter behind every frames-per-second figure of the component layer: arrivals of the
    last :data:`~rosfpga_lab.component.limits.FPS_WINDOW` seconds, 0 once frames stop."""
    return RateMeter(samples=limits.FPS_SAMPLES, window_s=limits.FPS_WINDOW, stale_s=limits.FPS_STALE)


class LatencyWindow:
    """The last ``size`` latency samples (seconds), with median and percentiles.

    Args:
        size: samples kept (older ones are forgotten).
    """

    def __init__(self, size: int) -> None:
        self._samples: collections.deque[float] = collections.deque(maxlen=size)
        self._lock = threading.Lock()
        self.count = 0

    def add(self, seconds: float) -> None:
        """Record one sample."""
        with self._lock:
            self._samples.append(seconds)
            self.count += 1

    def samples(self) -> list[float]:
        """The kept samples, oldest first."""
        with self._lock:
            return list(self._samples)

    def summary(self) -> LatencySummary:
        """Median, 95th percentile and maximum of the kept samples."""
        return LatencySummary.of(self.samples())


@dataclass(frozen=True)
class LatencySummary:
    """Latency figures in seconds (``nan`` when there are no samples)."""

    count: int
    median: float
    p95: float
    max: float

    @classmethod
    def of(cls, samples: list[float]) -> LatencySummary:
        """Summarize ``samples`` (seconds)."""
        if not samples:
            nan = float("nan")
            return cls(0, nan, nan, nan)
        ordered = sorted(samples)
        p95 = ordered[min(len(ordered) - 1, int(round(0.95 * (len(ordered) - 1))))]
        return cls(len(ordered), statistics.median(ordered), p95, ordered[-1])

    def ms(self) -> str:
        """``"median 1.9 ms, p95 2.4 ms"`` (or ``"n/a"``)."""
        if not self.count:
            return "n/a"
        return f"median {self.median * 1e3:.1f} ms, p95 {self.p95 * 1e3:.1f} ms"


def format_duration(seconds: float) -> str:
    """A circuit's time in a unit that shows it: ``"12.31 ms"``, ``"2.55 \u00b5s"`` (below
    1 ms), ``"40 ns"`` (below 1 \u00b5s)."""
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.2f} ms"
    if seconds >= 1e-6:
        return f"{seconds * 1e6:.2f} \u00b5s"
    return f"{seconds * 1e9:.0f} ns"


@dataclass(frozen=True)
class ComponentStats:
    """What the component did so far.

    Attributes:
        received: complete frames read off the input connections.
        processed: frames the circuit turned into output frames.
        published: output frames handed to the publisher (one per processed frame).
        refused: frames the circuit refused (wrong size, encoding, truncated ...).
        refused_reasons: refusal count per kind of reason, ``"field: rule"`` (e.g.
            ``"width: not what the circuit was built for"``), whatever the values were.
        refused_examples: per kind, the full text of its first refusal (with the values).
        dropped_input: frames dropped in front of the circuit (input queue full: the circuit
            was busy).
        dropped_output: frames dropped behind it (a downstream subscriber too slow), over all
            subscribers; ``dropped_output_by_peer`` splits them.
        subscribers: downstream subscribers connected now; ``publishers``: upstream publishers.
        latency: receive-complete to handed-to-publisher, per frame, in this process.
        process_time: time in the circuit model alone.
        since_stamp: input ``header.stamp`` to output handed to the publisher: the end-to-end
            latency from capture, for frames whose stamp is wall-clock time (a camera's).
        circuit_time_s: the modelled circuit's time for the last frame (cycles / clock).
        cycles: per-stage cycles of the last frame; ``fifo_high_water``: highest level seen
            per FIFO over all frames.
        fps: output frames per second over the last two seconds.
        master_reregistrations: times the component registered again (a master restart).
        master_ok: the master answered the last check.
        observer_errors: exceptions raised by observers (they never stop the component).
        last_error: the most recent refusal or problem, as text.
        connection_errors: the input side's recent connection problems (a publisher of another
            type on the input topic, a refused handshake, a publisher gone), newest last.
        timing: ``host`` or ``fpga`` (when outputs are published); ``model``: what ran the
            data path (``fast``, ``reference`` or ``rtl``).
    """

    received: int = 0
    processed: int = 0
    published: int = 0
    refused: int = 0
    refused_reasons: dict[str, int] = field(default_factory=dict)
    refused_examples: dict[str, str] = field(default_factory=dict)
    dropped_input: int = 0
    dropped_output: int = 0
    dropped_output_by_peer: dict[str, int] = field(default_factory=dict)
    subscribers: int = 0
    publishers: int = 0
    latency: LatencySummary = LatencySummary(0, float("nan"), float("nan"), float("nan"))
    process_time: LatencySummary = LatencySummary(0, float("nan"), float("nan"), float("nan"))
    since_stamp: LatencySummary = LatencySummary(0, float("nan"), float("nan"), float("nan"))
    circuit_time_s: float = float("nan")
    cycles: dict[str, int] = field(default_factory=dict)
    fifo_high_water: dict[str, int] = field(default_factory=dict)
    fps: float = 0.0
    master_reregistrations: int = 0
    master_ok: bool = True
    observer_errors: int = 0
    last_error: str = ""
    connection_errors: list[str] = field(default_factory=list)
    timing: str = "host"
    model: str = "fast"

    @property
    def dropped(self) -> int:
        """All drops: in front of and behind the circuit."""
        return self.dropped_input + self.dropped_output

    def status_line(self) -> str:
        """One line for a terminal status display."""
        lat = f"{self.latency.median * 1e3:.1f} ms" if self.latency.count else "-"
        text = (f"in {self.received}  out {self.published}  {self.fps:5.1f} fps  "
                f"latency {lat}  dropped {self.dropped}  refused {self.refused}  "
                f"subs {self.subscribers}")
        if not self.master_ok:
            text += "  MASTER UNREACHABLE"
        return text

    def report(self) -> str:
        """A multi-line summary (printed when ``rosfpga-lab node`` stops)."""
        lines = [
            f"frames: received {self.received}, processed {self.processed}, published "
            f"{self.published}, refused {self.refused}, dropped {self.dropped} "
            f"(input queue {self.dropped_input}, output queues {self.dropped_output})",
            f"data path: {self.model} model; timing: {self.timing}" + (
                " (each output held for the circuit's clocks at clock_mhz; one frame waits while "
                "it is busy, a newer one replaces it)" if self.timing == "fpga" else
                " (outputs published as soon as the data path is done)"),
            f"latency (receive -> publish, wall time here): {self.latency.ms()}; of it the "
            f"{'simulated Verilog' if self.model == RTL_MODEL else 'Python circuit model'}'s own "
            f"run: {self.process_time.ms()}",
        ]
        if self.since_stamp.count:
            lines.append(f"latency since capture (input header.stamp -> publish): "
                         f"{self.since_stamp.ms()} over {self.since_stamp.count} frames")
        if not self.cycles and self.circuit_time_s == self.circuit_time_s:   # rtl: no stages
            lines.append(f"circuit time of the last frame: {format_duration(self.circuit_time_s)} "
                         "(its simulated clocks)")
        if self.cycles:
            lines.append("cycles per stage (last frame): " + ", ".join(
                f"{name} {n:,}" for name, n in self.cycles.items())
                + f"; the real circuit would need {format_duration(self.circuit_time_s)} per "
                "frame at its clock "
                "(cycles / clock, not measured here)")
        if self.fifo_high_water:
            lines.append("FIFO high water: " + ", ".join(
                f"{name} {n}" for name, n in self.fifo_high_water.items()))
        for kind, n in sorted(self.refused_reasons.items(), key=lambda kv: -kv[1]):
            example = self.refused_examples.get(kind)
            lines.append(f"refused x{n}: {kind}" + (f" (first: {example})" if example else ""))
        if self.dropped_input:
            lines.append(f"dropped x{self.dropped_input}: input queue full (the circuit was busy; "
                         "the oldest waiting frame goes)")
        for peer, n in sorted(self.dropped_output_by_peer.items()):
            lines.append(f"dropped x{n}: output queue full for subscriber {peer} (too slow for "
                         "the rate; the oldest queued frame goes)")
        if self.master_reregistrations:
            lines.append(f"registered again with the master {self.master_reregistrations} time(s) "
                         "(master restarted)")
        for problem in self.connection_errors[-3:]:
            lines.append(f"input connection problem: {problem}")
        if self.observer_errors:
            lines.append(f"observer callbacks raised {self.observer_errors} time(s)")
        return "\n".join(lines)
