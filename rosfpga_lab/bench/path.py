"""Benchmark (2): publisher -> [middle] -> subscriber, for several middles, measured the same way.

How this works: one process holds an embedded master, a lab publisher on the input topic and a
lab subscriber on the output topic. The *middle* runs as its own process (so each middle has a
whole interpreter and its own cores to itself): nothing (the subscriber listens on the input:
the baseline), the FPGA component (``python -m rosfpga_lab node CONFIG``), roscpp's
``topic_tools relay`` or a rospy relay (``rospy.AnyMsg``, no deserialization). Two phases:

* *sustained*: publish as fast as the path delivers, with at most ``window`` frames in flight
  (a frame is sent when an earlier one has come out), for ``frames`` frames: frames/s. With
  one frame in flight this is one frame at a time (latency-bound); with two, receiving the next
  frame overlaps handling the current one. The runner repeats this phase in interleaved rounds
  and reports the median, because other programs on the machine make single runs noisy;
* *at a rate*: ``rate`` frames/s for ``rate_frames`` frames: how many came out (drops), and the
  latency from ``header.stamp`` (set when the frame is published) to its arrival.

"Added latency" is a middle's median minus the baseline's. Every ``check_every``-th output is
compared with what the middle should give (OpenCV's dilate for the component, the input itself
for a relay), so a fast but wrong middle is caught.
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rosfpga_lab.bench.limits import (
    START_TIMEOUT, STALL_TIMEOUT, SUSTAINED_MAX_SECONDS, TOOL_TIMEOUT,
)
from rosfpga_lab.component import LatencySummary, open_source
from rosfpga_lab.graph import EmbeddedMaster, GraphError, MessageInfo, Node, call
from rosfpga_lab.hw.sample import image_frame

RELAY_FALLBACK = "/usr/lib/topic_tools/relay"
PROGRAMS = Path(__file__).resolve().parent / "ros_programs"


@dataclass
class PathFigures:
    """What one middle did (figures are NaN / 0 when it could not run; ``note`` says why)."""

    name: str
    available: bool = True
    note: str = ""
    sustained: dict[int, list[float]] = field(default_factory=dict)   # window -> fps per round
    sustained_lost: dict[int, int] = field(default_factory=dict)      # window -> frames lost
    rate: float = 0.0
    sent: int = 0
    received: int = 0
    latency: LatencySummary = LatencySummary(0, float("nan"), float("nan"), float("nan"))
    checked: int = 0
    correct: int = 0
    cpu_seconds: float = 0.0   # CPU time the middle's process used in the sustained runs
    cpu_frames: int = 0        # frames delivered in those runs
    middle_output: str = field(default="", repr=False)

    @property
    def cpu_ms_per_frame(self) -> float:
        """The middle's CPU time per frame (user + system), NaN when unknown."""
        return self.cpu_seconds / self.cpu_frames * 1e3 if self.cpu_frames else float("nan")

    @property
    def drops(self) -> int:
        return self.sent - self.received

    def fps(self, window: int) -> float:
        """Median sustained frames/s over the rounds with ``window`` frames in flight."""
        runs = sorted(self.sustained.get(window, []))
        if not runs:
            return float("nan")
        mid = len(runs) // 2
        return runs[mid] if len(runs) % 2 else (runs[mid - 1] + runs[mid]) / 2

    def merge(self, other: PathFigures) -> None:
        """Add another round's sustained figures (and its notes) to these."""
        for window, runs in other.sustained.items():
            self.sustained.setdefault(window, []).extend(runs)
        for window, lost in other.sustained_lost.items():
            self.sustained_lost[window] = self.sustained_lost.get(window, 0) + lost
        self.checked += other.checked
        self.correct += other.correct
        self.cpu_seconds += other.cpu_seconds
        self.cpu_frames += other.cpu_frames
        if not other.available:
            self.available, self.note = False, other.note


def find_relay() -> str | None:
    """roscpp's topic_tools relay binary (from ``dpkg -L topic-tools``), or None."""
    try:
        listing = subprocess.run(["dpkg", "-L", "topic-tools"], capture_output=True, text=True,
                                 timeout=TOOL_TIMEOUT).stdout.splitlines()
    except (OSError, subprocess.SubprocessError):
        listing = []
    for line in listing + [RELAY_FALLBACK]:
        if line.endswith("/relay") and os.access(line, os.X_OK):
            return line
    return None


class _Probe:
    """The bench's publisher and subscriber, with in-flight accounting."""

    def __init__(self, master: EmbeddedMaster, in_topic: str, out_topic: str,
                 images: list[np.ndarray], encoding: str,
                 expect: Callable[[np.ndarray], np.ndarray], check_every: int) -> None:
        self.images, self.encoding, self.expect = images, encoding, expect
        self.check_every = check_every
        self.cond = threading.Condition()
        self.sent: dict[tuple[int, int], tuple[float, int]] = {}
        self.received = 0
        self.latencies: list[float] = []
        self.checked = self.correct = 0
        self.k = 0
        self.pub_node = Node("/bench_pub", master=master)
        self.sub_node = Node("/bench_sub", master=master)
        self.pub = self.pub_node.advertise(in_topic, "sensor_msgs/Image", queue_size=0)
        self.sub = self.sub_node.subscribe(out_topic, "sensor_msgs/Image", self._on_body,
                                           raw=True, queue_size=0, tcp_nodelay=True)

    def close(self) -> None:
        self.sub_node.shutdown()
        self.pub_node.shutdown()

    def reset(self) -> None:
        with self.cond:
            self.sent.clear()
            self.received = 0
            self.latencies = []

    def publish(self) -> None:
        k = self.k
        self.k += 1
        now = time.time()
        ns = int(now * 1e9)
        stamp = (ns // 1_000_000_000, ns % 1_000_000_000)
        frame = image_frame(self.images[k % len(self.images)], self.encoding, seq=k, stamp=stamp,
                            frame_id="bench")
        with self.cond:
            self.sent[stamp] = (now, k)
        self.pub.publish_body(memoryview(frame)[4:])

    def _on_body(self, body: bytes | memoryview, info: MessageInfo) -> None:
        _seq, secs, nsecs = struct.unpack_from("<III", body, 0)
        with self.cond:
            entry = self.sent.pop((secs, nsecs), None)
            if entry is None:
                return  # warm-up frame or one from an earlier phase
            t_sent, k = entry
            self.received += 1
            self.latencies.append(info.received - t_sent)
            self.cond.notify_all()
        if k % self.check_every == 0:
            image = self.images[k % len(self.images)]
            want = self.expect(image)
            got = np.frombuffer(body, np.uint8, want.size, len(body) - want.size)
            ok = bool(np.array_equal(got, want.reshape(-1)))
            with self.cond:
                self.checked += 1
                self.correct += ok

    def sustained(self, frames: int, window: int, max_seconds: float) -> tuple[float, int, int]:
        """Frames/s with at most ``window`` in flight; returns (fps, delivered, lost)."""
        self.reset()
        lost = 0
        t0 = time.monotonic()
        sent = 0
        while sent < frames and time.monotonic() - t0 < max_seconds:
            with self.cond:
                while sent - self.received - lost >= window:
                    if not self.cond.wait(STALL_TIMEOUT):
                        lost = sent - self.received
                        break
            self.publish()
            sent += 1
        deadline = time.monotonic() + STALL_TIMEOUT
        with self.cond:
            while self.received + lost < sent and time.monotonic() < deadline:
                self.cond.wait(0.05)
            delivered = self.received
        elapsed = time.monotonic() - t0
        return delivered / elapsed, delivered, sent - delivered

    def at_rate(self, rate: float, frames: int) -> tuple[int, int, list[float]]:
        """Publish ``frames`` at ``rate``; returns (sent, received, latencies)."""
        self.reset()
        t0 = time.monotonic()
        for k in range(frames):
            delay = t0 + k / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            self.publish()
        deadline = time.monotonic() + 2.0
        with self.cond:
            while self.received < frames and time.monotonic() < deadline:
                self.cond.wait(0.05)
            return frames, self.received, list(self.latencies)


def cpu_time(proc: subprocess.Popen | None) -> float | None:
    """User + system CPU seconds of ``proc`` so far (Linux /proc), None when unknown."""
    if proc is None:
        return None
    try:
        fields = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _wait_subscribed(master: EmbeddedMaster, topic: str, proc: subprocess.Popen | None) -> None:
    deadline = time.monotonic() + START_TIMEOUT
    while time.monotonic() < deadline:
        if proc is not None and proc.poll() is not None:
            raise GraphError(f"the middle exited with code {proc.returncode} before subscribing")
        reply = call(master.uri, "getSystemState", "/bench")
        subs = dict((t, nodes) for t, nodes in reply[2][1])
        if any(n != "/bench_sub" for n in subs.get(topic, [])):
            return
        time.sleep(0.05)
    raise GraphError(f"nothing subscribed to {topic} within {START_TIMEOUT} s")


def measure(name: str, master: EmbeddedMaster, in_topic: str, out_topic: str,
            command: list[str] | None, *, env: dict[str, str] | None, images: list[np.ndarray],
            encoding: str, expect: Callable[[np.ndarray], np.ndarray], frames: int,
            windows: tuple[int, ...], rate: float, rate_frames: int, check_every: int = 5,
            max_seconds: float = SUSTAINED_MAX_SECONDS) -> PathFigures:
    """Run one middle (``command``; None: direct) and measure: the sustained phase once per
    window in ``windows``, then (if ``rate_frames``) the at-rate phase."""
    fig = PathFigures(name, rate=rate)
    proc = None
    probe = None
    log = tempfile.TemporaryFile()
    try:
        if command is not None:
            proc = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT)
            _wait_subscribed(master, in_topic, proc)
        probe = _Probe(master, in_topic, out_topic if command is not None else in_topic, images,
                       encoding, expect, check_every)
        # Warm up: the relays advertise their output only after their first input, and the
        # first frames pay for connection set-up.
        deadline = time.monotonic() + START_TIMEOUT
        while probe.received < 5 and time.monotonic() < deadline:
            probe.publish()
            time.sleep(0.05)
        if probe.received < 5:
            raise GraphError(f"no output on {out_topic} within {START_TIMEOUT} s")
        time.sleep(0.2)
        cpu0 = cpu_time(proc)
        for window in windows:
            fps, delivered, lost = probe.sustained(frames, window, max_seconds)
            fig.sustained[window] = [fps]
            fig.sustained_lost[window] = lost
            fig.cpu_frames += delivered
        cpu1 = cpu_time(proc)
        if cpu0 is None or cpu1 is None:
            fig.cpu_frames = 0
        else:
            fig.cpu_seconds = cpu1 - cpu0
        if rate_frames:
            fig.sent, fig.received, lat = probe.at_rate(rate, rate_frames)
            fig.latency = LatencySummary.of(lat)
        fig.checked, fig.correct = probe.checked, probe.correct
    except GraphError as exc:
        fig.available, fig.note = False, str(exc)
    finally:
        if probe is not None:
            probe.close()
        if proc is not None:
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(5)
            log.seek(0)
            fig.middle_output = log.read().decode(errors="replace")
        log.close()
    return fig


def component_command(config_path: Path, master_uri: str) -> list[str]:
    """The FPGA component as its own process (the ``rosfpga-lab node`` command)."""
    return [sys.executable, "-m", "rosfpga_lab", "node", str(config_path), "--master-uri",
            master_uri, "--quiet", "--status-interval", "0"]


def bench_images(width: int, height: int, encoding: str, n: int = 8) -> list[np.ndarray]:
    """``n`` distinct synthetic frames."""
    src = open_source("synthetic", width, height, encoding, period=n)
    return [src.frame(k) for k in range(n)]


__all__ = ["PathFigures", "bench_images", "component_command", "find_relay", "measure"]
