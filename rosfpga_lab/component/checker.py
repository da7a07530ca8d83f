"""Check every output frame of the component against OpenCV run on the frame that went in.

How this works: the camera tells the checker each frame it sent (:meth:`Checker.sent`, keyed
by ``header.stamp``, which the component carries through). The checker subscribes to the
component's output; for every frame that arrives it finds the input by stamp, runs
``cv2.dilate`` (or ``cv2.erode``, or nothing for a passthrough circuit) with a rectangular
kernel on the input picture, and compares the output's ``data`` with it byte for byte, and its
``height``, ``width``, ``encoding``, ``step``, ``is_bigendian``, ``frame_id`` and ``stamp`` with
the input's. OpenCV is the independent oracle: nothing here uses the lab's own circuit models.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from rosfpga_lab.component import limits
from rosfpga_lab.component.camera import SentFrame
from rosfpga_lab.component.errors import ComponentError
from rosfpga_lab.component.stats import LatencyWindow, since_stamp
from rosfpga_lab.config import PASSTHROUGH, canonical_op
from rosfpga_lab.graph import EmbeddedMaster, MessageInfo, Node, RateMeter
from rosfpga_lab.msg import default_registry, deserialize

#: Inputs remembered for matching (older ones are forgotten).
MAX_PENDING = limits.CHECKER_PENDING


def expected_output(image: np.ndarray, op: str, ksize: tuple[int, int]) -> np.ndarray:
    """OpenCV's answer for ``image`` (``(rows, cols, channels)`` uint8).

    Args:
        op: one of :data:`~rosfpga_lab.config.vocabulary.MODEL_OPS` (or an alias
            :func:`~rosfpga_lab.config.vocabulary.canonical_op` accepts).
        ksize: kernel ``(width, height)`` (OpenCV's order).
    """
    op = canonical_op(op)
    if op == PASSTHROUGH:
        return image
    kernel = np.ones((ksize[1], ksize[0]), np.uint8)
    fn = {"dilate": cv2.dilate, "erode": cv2.erode}.get(op)
    if fn is None:
        raise ComponentError(f"no OpenCV oracle for op {op!r}")
    out = fn(image, kernel)
    return out.reshape(image.shape)


@dataclass
class CheckReport:
    """What the checker saw."""

    received: int = 0
    bit_exact: int = 0
    unmatched: int = 0
    mismatches: list[str] = field(default_factory=list)
    first_bad: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # input, output, expected

    @property
    def checked(self) -> int:
        return self.received - self.unmatched

    @property
    def all_exact(self) -> bool:
        return self.received > 0 and self.bit_exact == self.received


class Checker:
    """Subscribes to ``topic`` and checks every frame (see module docstring).

    Args:
        topic: the component's output topic.
        op, ksize: what the circuit is configured to do.
        name, master, master_uri, host: as for :class:`rosfpga_lab.graph.Node`.
        keep_last: keep the last (input, output, expected) pictures for a figure.
    """

    def __init__(self, topic: str, op: str, ksize: tuple[int, int], *, name: str = "/checker",
                 master: EmbeddedMaster | None = None, master_uri: str | None = None,
                 host: str | None = None, queue_size: int = 0) -> None:
        expected_output(np.zeros((3, 3, 1), np.uint8), op, ksize)  # refuse unknown ops now
        self.op, self.ksize = op, ksize
        self.report = CheckReport()
        self.latency = LatencyWindow(limits.CHECKER_LATENCY_WINDOW)
        self.last: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._inputs: dict[tuple[int, int], SentFrame] = {}
        self._lock = threading.Condition()
        self._arrivals = RateMeter()
        self._registry = default_registry()
        self.node = Node(name, master_uri, host, master=master)
        try:
            # queue_size 0: never drop here, so every output the component sent is checked.
            self.subscriber = self.node.subscribe(topic, "sensor_msgs/Image", self._on_body,
                                                  raw=True, queue_size=queue_size, tcp_nodelay=True)
        except BaseException:
            self.node.shutdown()
            raise

    def sent(self, frame: SentFrame) -> None:
        """Remember an input frame (give this to :class:`Camera` as ``on_sent``)."""
        with self._lock:
            self._inputs[frame.stamp] = frame
            if len(self._inputs) > MAX_PENDING:
                del self._inputs[next(iter(self._inputs))]

    def _on_body(self, body: bytes | memoryview, info: MessageInfo) -> None:
        msg = deserialize(self._registry, "sensor_msgs/Image", bytes(body))
        stamp_v = msg["header"]["stamp"]
        stamp = (stamp_v["secs"], stamp_v["nsecs"]) if isinstance(stamp_v, dict) else tuple(stamp_v)
        latency = since_stamp(info.received, *stamp)
        if latency is not None:
            self.latency.add(latency)
        with self._lock:
            source = self._inputs.pop(stamp, None)
            self.report.received += 1
            self._arrivals.tick(info.received)
        if source is None:
            with self._lock:
                self.report.unmatched += 1
                self._note(f"output frame #{info.index} has stamp {stamp} that no input had")
                self._lock.notify_all()
            return
        problems = []
        img = source.image
        rows, cols, ch = img.shape
        expect = {"height": rows, "width": cols, "step": cols * ch, "is_bigendian": 0}
        for key, value in expect.items():
            if msg[key] != value:
                problems.append(f"{key} {msg[key]} != {value}")
        for key, got_v, want_v in (("encoding", msg["encoding"], source.encoding),
                                   ("header.frame_id", msg["header"]["frame_id"], source.frame_id)):
            if got_v != want_v:
                problems.append(f"{key} {got_v!r} != {want_v!r}")
        want = expected_output(img, self.op, self.ksize)
        data = np.frombuffer(msg["data"], np.uint8)
        if data.size != want.size:
            problems.append(f"data has {data.size} bytes, expected {want.size}")
            got = None
        else:
            got = data.reshape(want.shape)
            diff = int(np.count_nonzero(got != want))
            if diff:
                problems.append(f"{diff} of {want.size} data bytes differ from OpenCV's "
                                f"cv2.{self.op} on the input")
        with self._lock:
            if got is not None:
                self.last = (img, got, want)
            if problems:
                self._note(f"output for input seq {source.seq}: " + "; ".join(problems))
                if self.report.first_bad is None and got is not None:
                    self.report.first_bad = (img, got, want)
            else:
                self.report.bit_exact += 1
            self._lock.notify_all()

    def _note(self, text: str) -> None:
        if len(self.report.mismatches) < 50:
            self.report.mismatches.append(text)

    def wait_for(self, frames: int, timeout: float) -> bool:
        """Wait until ``frames`` outputs were checked; False on time-out."""
        deadline = time.monotonic() + timeout
        with self._lock:
            while self.report.received < frames:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._lock.wait(left)
        return True

    @property
    def fps(self) -> float:
        """Output frames per second between the first and the last arrival."""
        with self._lock:
            return self._arrivals.overall_rate()

    def stop(self) -> None:
        """Unsubscribe and shut the node down."""
        self.node.shutdown()
