"""``rosfpga-lab bench``: every figure in one run, printed side by side.

How this works: (1) :func:`~rosfpga_lab.bench.pipeline.bench_pipeline` times the fast circuit
model against ``cv2.dilate`` alone; (2) :func:`~rosfpga_lab.bench.path.measure` runs the same
publisher and subscriber around each middle in turn -- nothing (baseline), the FPGA component,
roscpp's ``topic_tools relay`` and a rospy relay (the last two only where real ROS 1 is
installed) -- and the table shows their frames/s, drops and latency in one place.
"""

from __future__ import annotations

import math
import platform
import subprocess
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rosfpga_lab.bench.limits import TOOL_TIMEOUT
from rosfpga_lab.bench.path import (
    PROGRAMS, PathFigures, bench_images, component_command, find_relay, measure,
)
from rosfpga_lab.bench.pipeline import PipelineFigures, bench_pipeline
from rosfpga_lab.component import default_config, expected_output
from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.graph import EmbeddedMaster
from rosfpga_lab.graph.realros import ROS_PYTHON, ros_env, ros_missing

MIDDLES = ("direct", "component", "roscpp", "rospy")


@dataclass
class BenchReport:
    """Everything one ``rosfpga-lab bench`` run measured."""

    machine: str
    config: NodeConfig
    pipeline: PipelineFigures | None
    paths: list[PathFigures] = field(default_factory=list)
    windows: tuple[int, ...] = (1, 2)

    def table(self) -> str:
        """The printed report (Markdown tables)."""
        cfg = self.config
        img = f"{cfg.image.width}x{cfg.image.height} {cfg.image.encoding}"
        out = [f"machine: {self.machine}", ""]
        if self.pipeline is not None:
            p = self.pipeline
            out += [
                f"(1) circuit model vs OpenCV alone, {img}, {cfg.application.op} "
                f"{cfg.application.ksize}x{cfg.application.ksize}, {p.frames} frames:",
                "",
                "| what | frames/s |",
                "|---|---:|",
                f"| fast pipeline model (TCPROS frame in -> frame out, all stages) | {p.pipeline_fps:,.0f} |",
                f"| cv2.{cfg.application.op} alone (image in -> image out) | {p.opencv_fps:,.0f} |",
                f"| modelled circuit at {cfg.clock_mhz:g} MHz (cycle count) | {p.circuit_fps:,.1f} |",
                "",
                f"OpenCV alone is {p.ratio:.1f}x the pipeline model; the model's output equals "
                f"OpenCV's: {'yes' if p.bit_exact else 'NO'}",
                "",
            ]
        if self.paths:
            base = next((f for f in self.paths if f.name.startswith("direct") and f.available), None)
            rounds = max((len(v) for f in self.paths for v in f.sustained.values()), default=0)
            w1, w2 = self.windows
            out += [
                f"(2) publisher -> middle -> subscriber, {img}, loopback, each middle its own "
                f"process; sustained frames/s: median of {rounds} interleaved rounds:",
                "",
                f"| middle | sustained, {w1} in flight | sustained, {w2} in flight | middle's CPU "
                "per frame | at rate: received/sent | latency median | p95 | added median "
                "| outputs correct |",
                "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
            ]
            for f in self.paths:
                if not f.available:
                    out.append(f"| {f.name} | not run: {f.note} | | | | | | | |")
                    continue
                added = (f.latency.median - base.latency.median) * 1e3 if base is not None else math.nan
                added_text = "(baseline)" if f is base else f"{added:+.1f} ms"
                cells = []
                for w in self.windows:
                    lost = f.sustained_lost.get(w, 0)
                    cells.append(f"{f.fps(w):.0f}" + (f" ({lost} lost)" if lost else ""))
                cpu = "-" if math.isnan(f.cpu_ms_per_frame) else f"{f.cpu_ms_per_frame:.2f} ms"
                out.append(
                    f"| {f.name} | {cells[0]} | {cells[1]} | {cpu} | {f.received}/{f.sent} at "
                    f"{f.rate:g}/s | "
                    f"{f.latency.median * 1e3:.1f} ms | {f.latency.p95 * 1e3:.1f} ms | {added_text} | "
                    f"{f.correct}/{f.checked} |")
            out.append("")
            out += self.verdict()
        return "\n".join(out)

    def verdict(self) -> list[str]:
        """The issue's goals, each with what was measured."""
        comp = next((f for f in self.paths if f.name.startswith("FPGA") and f.available), None)
        relay = next((f for f in self.paths if f.name.startswith("roscpp") and f.available), None)
        base = next((f for f in self.paths if f.name.startswith("direct") and f.available), None)
        lines = []
        if comp is not None and relay is not None:
            for w in self.windows:
                ok = comp.fps(w) >= relay.fps(w)
                lines.append(f"goal: component at least as fast as the roscpp relay ({w} in flight): "
                             f"{'met' if ok else 'NOT met'} ({comp.fps(w):.0f} vs "
                             f"{relay.fps(w):.0f} frames/s)")
        if comp is not None:
            ok = comp.drops == 0
            lines.append(f"goal: no drops at {comp.rate:g} frames/s: {'met' if ok else 'NOT met'} "
                         f"({comp.drops} dropped of {comp.sent})")
            if base is not None:
                added = (comp.latency.median - base.latency.median) * 1e3
                lines.append(f"goal: median added latency < 5 ms: {'met' if added < 5 else 'NOT met'} "
                             f"({added:+.1f} ms over the direct path)")
        return lines


def machine_description() -> str:
    """CPU model and core count (as lscpu reports them)."""
    model = platform.processor() or platform.machine()
    cores = ""
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=TOOL_TIMEOUT).stdout
        for line in text.splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "Model name":
                model = value.strip()
            elif key.strip() == "CPU(s)":
                cores = value.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return f"{model}, {cores or '?'} CPU(s), Python {platform.python_version()}, {platform.system()}"


def run_bench(config: NodeConfig | str | Path | None = None, *, middles: tuple[str, ...] = MIDDLES,
              frames: int = 200, windows: tuple[int, int] = (1, 2), rounds: int = 3,
              rate: float = 30.0, rate_frames: int = 90, pipeline_frames: int = 100,
              skip_pipeline: bool = False,
              progress: Callable[[str], None] | None = None) -> BenchReport:
    """Measure everything (see module docstring); middles whose tools are missing are noted.

    Args:
        frames: frames per sustained run; windows: frames in flight for the two sustained
            columns; rounds: interleaved rounds (the table shows the median).
        rate, rate_frames: the at-rate phase (first round only).
    """
    say = progress or (lambda _t: None)
    if config is None:
        config = default_config()
    elif not isinstance(config, NodeConfig):
        config = load_config(config)
    report = BenchReport(machine_description(), config, None, windows=tuple(windows))
    if not skip_pipeline:
        say("pipeline model vs OpenCV ...")
        report.pipeline = bench_pipeline(config, pipeline_frames)
    cfg = config.image
    images = bench_images(cfg.width, cfg.height, cfg.encoding)
    app = config.application
    dilate = lambda img: expected_output(img, app.op, (app.ksize, app.ksize))  # noqa: E731
    same = lambda img: img  # noqa: E731
    in_topic, out_topic = config.subscriber.topic, config.publisher.topic
    with tempfile.TemporaryDirectory(prefix="rosfpga-bench-") as tmp:
        config_path = config.path
        if config_path is None:
            from rosfpga_lab.component.demo import BUILTIN_CONFIG_YAML  # the path-less default_config()

            config_path = Path(tmp) / "fpga.yaml"
            config_path.write_text(BUILTIN_CONFIG_YAML)
        with EmbeddedMaster(port=0) as master:
            env = ros_env(master.uri)
            plan: list[tuple[str, list[str] | None, Callable[[np.ndarray], np.ndarray], str]] = []
            if "direct" in middles:
                plan.append(("direct (no middle, baseline)", None, same, ""))
            if "component" in middles:
                plan.append((f"FPGA component ({app.op}, lab)",
                             component_command(config_path, master.uri), dilate, ""))
            if "roscpp" in middles:
                relay = find_relay()
                plan.append(("roscpp topic_tools relay", [relay, in_topic, out_topic] if relay else None,
                             same, "" if relay else "topic_tools not installed"))
            if "rospy" in middles:
                missing = ros_missing()
                plan.append(("rospy relay (AnyMsg)",
                             None if missing else [ROS_PYTHON, str(PROGRAMS / "rospy_relay.py"),
                                                   in_topic, out_topic],
                             same, missing or ""))
            figures: dict[str, PathFigures] = {}
            for round_no in range(max(1, rounds)):
                for name, command, expect, missing in plan:
                    if missing:
                        figures.setdefault(name, PathFigures(name, available=False, note=missing))
                        continue
                    if name in figures and not figures[name].available:
                        continue
                    say(f"round {round_no + 1}/{rounds}: {name} ...")
                    fig = measure(name, master, in_topic, out_topic, command, env=env,
                                  images=images, encoding=cfg.encoding, expect=expect,
                                  frames=frames, windows=tuple(windows), rate=rate,
                                  rate_frames=rate_frames if round_no == 0 else 0)
                    if name in figures:
                        figures[name].merge(fig)
                    else:
                        figures[name] = fig
            report.paths = [figures[name] for name, *_rest in plan]
    return report
