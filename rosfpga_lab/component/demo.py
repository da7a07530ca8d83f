"""The whole paper in one call: master, camera, FPGA component and a bit-exact checker.

How this works: :func:`run_demo` starts an embedded master on a free loopback port, the
component from a node configuration (its master URI replaced by the embedded one), a checker
subscribed to the component's output and a camera publishing on the component's input at the
configured size and encoding. It waits until every frame came back (or a time-out), checks
each output against OpenCV on its input (:mod:`rosfpga_lab.component.checker`), writes a PNG
of input, output and difference, stops everything and returns a :class:`DemoResult`.
:func:`run_demo_ros2` is the same story on ROS 2 (DDS participants on 127.0.0.1, the component
of :mod:`rosfpga_lab.component.ros2`), returning a :class:`Ros2DemoResult`.

Exit code 0 only when every output is bit-exact and every frame sent is accounted for: on a
machine slower than the camera's rate the full queue in front of the circuit drops the oldest
frame, as ROS queues do, and the summary counts it (``--input-queue N`` with N at least
``--frames`` never drops). Its picture is ``data/demo_output.png``: input, output, and what the
circuit changed (output minus input, amplified); the notebooks' *output vs reference* view is the
other difference, the check against OpenCV.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.component.camera import Camera, Viewer
from rosfpga_lab.component.checker import CheckReport, Checker, expected_output
from rosfpga_lab.component.errors import ComponentConfigError, ComponentError
from rosfpga_lab.component.fpga import FpgaComponent
from rosfpga_lab.component.limits import DEFAULT_INPUT_QUEUE, DEFAULT_OUTPUT_QUEUE
from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.component.sources import to_rgb
from rosfpga_lab.component.stats import ComponentStats, LatencySummary, format_duration
from rosfpga_lab.component.webview import DemoPage
from rosfpga_lab.config import CUSTOM, PASSTHROUGH, NodeConfig, load_config, parse_config
from rosfpga_lab.graph import EmbeddedMaster
from rosfpga_lab.graph.capture import write_capture

#: The demo's configuration file in the lab's data/ directory.
DEFAULT_CONFIG_NAME = "fpga_dilate_rgba8.yaml"
#: The same values, for when data/ is not at hand; ``default_config()`` then parses this text,
#: so a path-less configuration from it is this one.
BUILTIN_CONFIG_YAML = """\
node: {name: /fpga_dilate}
subscriber: {topic: /image_raw, type: sensor_msgs/Image}
publisher: {topic: /image_dilated, type: sensor_msgs/Image}
image: {width: 640, height: 480, encoding: rgba8}
application: {op: dilate, ksize: 3}
"""
#: Difference images are multiplied by this to be visible.
DIFF_GAIN = 8


def default_config() -> NodeConfig:
    """``data/fpga_dilate_rgba8.yaml`` from the lab's checkout, or the same values built in."""
    path = Path(__file__).resolve().parents[2] / "data" / DEFAULT_CONFIG_NAME
    if path.exists():
        return load_config(path)
    return parse_config(BUILTIN_CONFIG_YAML, source=f"<built-in {DEFAULT_CONFIG_NAME}>")


@dataclass
class DemoResult:
    """What the demo measured.

    Attributes:
        sent: frames the camera published; received: outputs the checker got.
        check: the checker's report (bit-exact count, mismatches).
        fps: output frames per second at the checker.
        latency: camera publish -> checker receive (header.stamp to arrival).
        component: the component's own counters at the end.
        elapsed: seconds from the first frame to the last output.
        png: the figure written (or None).
    """

    sent: int
    received: int
    check: CheckReport
    fps: float
    latency: LatencySummary
    component: ComponentStats
    elapsed: float
    png: Path | None
    config: NodeConfig
    pcap: Path | None = None
    pcap_packets: int = 0

    @property
    def lost(self) -> int:
        """Frames sent that neither came back nor were dropped by the component's queues."""
        return self.sent - self.received - self.component.dropped

    @property
    def ok(self) -> bool:
        """Outputs came back, every one bit-exact, and every frame sent is accounted for: it came
        back or the component's queue dropped it (a circuit slower than the camera drops the
        oldest waiting frame, as a ROS queue does; the summary says so)."""
        return (self.received > 0 and self.lost == 0
                and self.check.bit_exact == self.received)

    def lines(self) -> list[str]:
        """The demo's printed summary."""
        cfg = self.config
        c = self.component
        kernel = (f" {cfg.application.ksize}x{cfg.application.ksize}"
                  if cfg.application.op not in (PASSTHROUGH, CUSTOM) else "")
        out = [
            f"circuit: {cfg.application.op}{kernel} on "
            f"{cfg.image.width}x{cfg.image.height} {cfg.image.encoding}, "
            f"{cfg.subscriber.topic} -> {cfg.node.global_name} -> {cfg.publisher.topic}",
            f"frames: sent {self.sent}, received {self.received}, dropped {c.dropped}, "
            f"refused {c.refused} in {self.elapsed:.2f} s",
            f"fps: {self.fps:.1f} at the checker",
            f"latency camera -> component -> checker: {self.latency.ms()}; inside the component "
            f"(receive -> publish): {c.latency.ms()}",
        ]
        if c.cycles:
            out.append(f"modelled circuit: {format_duration(c.circuit_time_s)} per frame at "
                       f"{cfg.clock_mhz:g} MHz" + (f"; FIFO high water {c.fifo_high_water}"
                                                   if c.fifo_high_water else ""))
        out.append(f"bit-exact: {self.check.bit_exact}/{self.received}")
        if c.dropped:
            out.append(f"  dropped {c.dropped} of {self.sent}: the circuit model was slower than "
                       "the camera and its queue kept the newest frames (as ROS queues do); "
                       "--rate lower or --input-queue higher keeps every frame")
        if self.lost:
            out.append(f"  lost {self.lost} of {self.sent}: sent, never came back, and not "
                       "dropped by the component")
        out += [f"  mismatch: {m}" for m in self.check.mismatches[:5]]
        if self.png is not None:
            out.append(f"figure: {self.png}")
        if self.pcap is not None:
            out.append(f"capture: {self.pcap} ({self.pcap_packets} packets)")
        return out


class DemoRig:
    """Master, component, checker and camera, started together (for notebooks: non-blocking).

    Use as a context manager, or call :meth:`stop`. The camera is not running until
    :meth:`run` (blocking) or :meth:`start_camera` (background); attach a live view with
    ``rig.component.add_observer(...)``.

    Args:
        config: node configuration (path or loaded); None: :func:`default_config`.
        rate, source: the camera's frames per second and picture source.
        model: the circuit model, ``fast`` or ``reference``.
        oracle_op: check against this op instead of the configuration's.
        input_queue: frames waiting in front of the circuit.
    """

    def __init__(self, config: NodeConfig | str | Path | None = None, *, rate: float = 30.0,
                 source: str = "grace_hopper", model: str = "fast", oracle_op: str | None = None,
                 input_queue: int = DEFAULT_INPUT_QUEUE) -> None:
        if config is None:
            config = default_config()
        elif not isinstance(config, NodeConfig):
            config = load_config(config)
        self.config = config
        app = config.application
        self.op = oracle_op or app.op
        self.master = EmbeddedMaster(port=0).start()
        self.component: FpgaComponent | None = None
        self.checker: Checker | None = None
        self.camera: Camera | None = None
        try:
            self.component = FpgaComponent.from_config(config, master=self.master, model=model,
                                                       watchdog=False,
                                                       input_queue=input_queue,
                                                       output_queue=max(input_queue,
                                                                        DEFAULT_OUTPUT_QUEUE)).start()
            self.checker = Checker(config.publisher.topic, self.op, (app.ksize, app.ksize),
                                   master=self.master)
            self.camera = Camera(config.subscriber.topic, width=config.image.width,
                                 height=config.image.height, encoding=config.image.encoding,
                                 rate=rate, source=source, master=self.master,
                                 on_sent=self.checker.sent, queue_size=0)
        except BaseException:
            self.stop()
            raise
        self.connected = (self.camera.publisher.wait_for_subscribers(1, 10.0)
                          and self.component.wait_for_subscribers(1, 10.0))

    def run(self, frames: int, timeout: float = 30.0) -> float:
        """Send ``frames`` frames on schedule and wait until each is accounted for (its output
        checked, or the component dropped or refused it: those never come back), at most
        ``timeout`` seconds after the last; return seconds taken."""
        assert self.camera is not None and self.checker is not None
        t0 = time.monotonic()
        self.camera.run(count=frames)
        deadline = time.monotonic() + timeout
        while True:
            gone = 0  # a drop or refusal is counted by the component, not signalled: poll it
            if self.component is not None:
                stats = self.component.stats
                gone = stats.dropped + stats.refused
            left = deadline - time.monotonic()
            if self.checker.wait_for(self.camera.sent - gone, max(0.0, min(left, 0.05))) \
                    or left <= 0:
                break
        return time.monotonic() - t0

    def start_camera(self, frames: int | None = None) -> None:
        """Run the camera in the background (``frames=None``: until :meth:`stop`)."""
        assert self.camera is not None
        self.camera.start(count=frames)

    def traces(self) -> list:
        """The master's and every node's recorded conversation (for a capture file)."""
        nodes = [self.component.node if self.component else None,
                 self.checker.node if self.checker else None,
                 self.camera.node if self.camera else None]
        return [self.master.trace] + [n.trace for n in nodes if n is not None]

    def stop(self) -> None:
        """Stop everything (idempotent)."""
        for part in (self.camera, self.checker, self.component):
            if part is not None:
                part.stop()
        self.master.stop()

    def __enter__(self) -> DemoRig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


# long: a third of it is the Args list of its docstring, and the rest
# is one story (start, stream, wait, check, stop) whose every step the DemoResult reports.
def run_demo(config: NodeConfig | str | Path | None = None, *, frames: int = 60,
             rate: float = 30.0, source: str = "grace_hopper", png: str | Path | None = "demo.png",
             model: str = "fast", timeout: float = 30.0, png_scale: float = 1.0,
             oracle_op: str | None = None,
             progress: Callable[[str], None] | None = None,
             view: Callable[[str], None] | None = None,
             pcap: str | Path | None = None, pcap_frame_bytes: int | None = None,
             input_queue: int | None = None) -> DemoResult:
    """Run the demo (see module docstring).

    Args:
        config: node configuration (path or loaded); None: :func:`default_config`.
        frames: frames the camera sends; rate: frames per second.
        source: camera source (``grace_hopper``, ``synthetic``, a file or directory).
        png: where to write the input/output/difference figure (None: no figure).
        model: the circuit model, ``fast`` or ``reference``.
        timeout: seconds to wait for the last output after the last input.
        png_scale: scale of the figure (0.5 halves it).
        oracle_op: check against this op instead of the configuration's (a negative control:
            a wrong oracle must give mismatches).
        progress: called with a line of text at each step.
        view: serve a live page (input, output, counters) on a free loopback port while the
            demo runs; called with its URL before the first frame. The page stops with the demo.
        pcap: write the whole conversation (XML-RPC and TCPROS, every connection as a TCP
            stream) to this capture file (``.pcap`` or pcapng), after everything stopped.
        pcap_frame_bytes: body bytes of each TCPROS frame the traces keep (default: the
            trace's excerpt, ``Trace.frame_bytes``); at least the frame size keeps whole frames
            (memory and file then grow by a frame per frame sent and received, up to each
            trace's ``max_bytes``: past it the oldest events go, and the capture says so).
        input_queue: frames waiting in front of the circuit (and behind it, for the checker);
            None: 2 for the fast model, every frame for the reference model. A circuit slower
            than the camera drops the oldest waiting frame; ``frames`` or more never drops.
    """
    say = progress or (lambda _text: None)
    if png is not None:
        _png_path(png)   # a wrong name is refused before the run, not after it
    # The reference model is slow (a byte per Python step): queue every frame in front of it
    # rather than drop, so the demo still checks all of them.
    if input_queue is None:
        input_queue = max(frames, DEFAULT_INPUT_QUEUE) if model == "reference" else DEFAULT_INPUT_QUEUE
    if input_queue < 1:
        raise ComponentConfigError(f"input_queue must be at least 1, not {input_queue}")
    with DemoRig(config, rate=rate, source=source, model=model, oracle_op=oracle_op,
                 input_queue=input_queue) as rig:
        assert rig.component is not None and rig.checker is not None and rig.camera is not None
        say(f"master: embedded at {rig.master.uri}")
        say(f"component: {rig.component!r}")
        if not rig.connected:
            say("warning: connections were not all up after 10 s")
        if pcap_frame_bytes is not None:
            for trace in rig.traces():   # frames are kept up to both bounds of a trace
                trace.frame_bytes = pcap_frame_bytes
                trace.excerpt_bytes = max(trace.excerpt_bytes, pcap_frame_bytes + 4)
        say(f"camera: {frames} frames of {source!r} at {rate:g} fps")
        page = None
        if view is not None:
            page = DemoPage(lambda: _counters(rig), encoding=rig.config.image.encoding,
                            title=f"ROS-compliant FPGA component: {rig.op} {rig.config.application.ksize}"
                                  f"x{rig.config.application.ksize}, live").start()
            rig.component.add_observer(page.observe)
            view(page.url)
        try:
            elapsed = rig.run(frames, timeout)
        finally:
            if page is not None:
                page.stop()
        stats = rig.component.stats
    checker, config = rig.checker, rig.config
    pcap_path, packets = None, 0
    if pcap is not None:
        pcap_path = Path(pcap)
        packets = write_capture(pcap_path, *rig.traces())
        say(f"capture: {packets} packets in {pcap_path}")
    app = config.application
    report = checker.report
    png_path = None
    shown = report.first_bad or checker.last
    if png is not None and shown is not None:
        png_path = write_figure(shown, config.image.encoding, png,
                                scale=png_scale, title=f"{rig.op} {app.ksize}x{app.ksize}")
    return DemoResult(rig.camera.sent, report.received, report, checker.fps,
                      checker.latency.summary(), stats, elapsed, png_path, config, pcap_path, packets)


def _counters(rig: DemoRig) -> dict[str, object]:
    """What the live page shows (see ``webview.COUNTER_LABELS``)."""
    assert rig.camera is not None and rig.checker is not None and rig.component is not None
    report, stats = rig.checker.report, rig.component.stats
    latency = rig.checker.latency.summary()
    return {"sent": rig.camera.sent, "processed": stats.processed, "received": report.received,
            "bit_exact": f"{report.bit_exact}/{report.received}", "refused": stats.refused,
            "fps": f"{rig.checker.fps:.1f}",
            "latency_ms": f"{latency.median * 1e3:.1f} ms" if latency.count else "n/a"}


def write_figure(images: tuple[np.ndarray, np.ndarray, np.ndarray], encoding: str,
                 path: str | Path, *, scale: float = 1.0, title: str = "dilate") -> Path:
    """Write input | output | (output - input) x DIFF_GAIN side by side as a PNG.

    The third panel is what the circuit changed (output against its input), not a check: the
    notebooks' "output vs reference" view compares the output with OpenCV's.

    Args:
        images: ``(input, output, expected)`` pictures in ``encoding``.
        path: the PNG to write (parent directories are created).
        scale: resize factor of each panel.
    """
    src, out, _expected = images
    diff = np.clip((out.astype(np.int16) - src.astype(np.int16)) * DIFF_GAIN, 0, 255).astype(np.uint8)
    panels = [to_rgb(src, encoding), to_rgb(out, encoding), to_rgb(diff, encoding)]
    labels = ["input (camera)", f"output (FPGA {title})", f"output - input, x{DIFF_GAIN}"]
    h, w = panels[0].shape[:2]
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    band = max(18, size[1] // 16)
    tiles = []
    for panel, label in zip(panels, labels):
        tile = cv2.resize(panel, size, interpolation=cv2.INTER_AREA) if scale != 1.0 else panel
        head = np.full((band, size[0], 3), 255, np.uint8)
        cv2.putText(head, label, (4, band - 5), cv2.FONT_HERSHEY_SIMPLEX, band / 32, (0, 0, 0), 1,
                    cv2.LINE_AA)
        tiles.append(np.vstack([head, tile]))
        tiles.append(np.full((size[1] + band, 4, 3), 255, np.uint8))
    figure = np.hstack(tiles[:-1])
    path = _png_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        written = cv2.imwrite(str(path), cv2.cvtColor(figure, cv2.COLOR_RGB2BGR),
                              [cv2.IMWRITE_PNG_COMPRESSION, 9])
    except OSError:
        written = False
    if not written:
        raise ComponentError(f"could not write {path} (is the directory writable?)")
    return path


def _png_path(path: str | Path) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ComponentError(f"the figure is a PNG: give a file name ending in .png, not {path}")
    return path


@dataclass
class Ros2DemoResult:
    """What :func:`run_demo_ros2` saw: frames sent, received, bit-exact against OpenCV."""

    domain: int
    sent: int
    received: int
    exact: int
    mismatched: list[int] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.sent > 0 and self.exact == self.sent and not self.mismatched

    def lines(self) -> list[str]:
        out = [f"ROS 2, DDS domain {self.domain}: camera -> component (CDR circuit) -> viewer",
               f"frames sent {self.sent}, received {self.received}, bit-exact against OpenCV "
               f"{self.exact}" + (f", mismatched {self.mismatched[:10]}" if self.mismatched else ""),
               f"component: {self.counts}"]
        return out + [f"  {n}" for n in self.notes if n.startswith("not matched")]


def run_demo_ros2(config: NodeConfig | str | Path | None = None, *, frames: int = 30,
                  rate: float = 30.0, source: str = "grace_hopper", domain: int = 0,
                  model: str = "fast", timeout: float = 30.0) -> Ros2DemoResult:
    """The demo on ROS 2: the component, a viewer on its output and a camera on its input, each
    its own DDS participant on 127.0.0.1 in ``domain``; every output compared with OpenCV run
    on its input (matched by header.stamp)."""
    cfg = default_config() if config is None else (
        config if isinstance(config, NodeConfig) else load_config(config))
    img = cfg.image
    comp = Ros2Component(cfg, domain=domain, model=model).start()
    try:
        with Viewer(cfg.publisher.topic, name="/viewer", domain=domain) as viewer, \
                Camera(cfg.subscriber.topic, width=img.width, height=img.height,
                       encoding=img.encoding, rate=rate, source=source, name="/camera",
                       domain=domain) as cam:
            outputs: dict[tuple[int, int], np.ndarray] = {}
            lock = threading.Lock()

            def keep(frame: Any) -> None:
                stamp = frame.header["stamp"]
                key = (stamp["secs"], stamp["nsecs"]) if isinstance(stamp, dict) else tuple(stamp)
                if frame.image is not None:
                    with lock:
                        outputs[key] = frame.image

            viewer.on_frame = keep
            deadline = time.monotonic() + timeout
            while not (comp.wait_for_peers(0.1) and cam.publisher.get_num_connections()):
                if time.monotonic() > deadline:
                    raise ComponentError(f"the camera, component and viewer did not find each "
                                         f"other in {timeout:g} s in DDS domain {domain}")
            sent: list[Any] = []
            cam.on_sent = sent.append
            cam.run(count=frames)
            while viewer.received < len(sent) and time.monotonic() < deadline:
                time.sleep(0.02)
            time.sleep(0.1)
            ksize = (cfg.application.ksize, cfg.application.ksize)
            exact, bad = 0, []
            with lock:
                for s in sent:
                    got = outputs.get(tuple(s.stamp))
                    if got is None:
                        continue
                    want = expected_output(s.image, cfg.application.op, ksize)
                    if np.array_equal(got, want.reshape(got.shape)):
                        exact += 1
                    else:
                        bad.append(s.seq)
            return Ros2DemoResult(domain, len(sent), viewer.received, exact, bad,
                                  dict(comp.counts), comp.notes())
    finally:
        comp.stop()
