"""A camera for when there is no camera, and a viewer that saves what arrives.

How this works: :class:`Camera` is a ROS node that publishes ``sensor_msgs/Image`` frames from
an :class:`~rosfpga_lab.component.sources.ImageSource` on a fixed schedule (frame k is due at
``start + k / rate``, or at its recorded offset for a bag source; a late frame is sent at once and the schedule is kept, so the average rate
holds). Each frame's ``header.stamp`` is the wall-clock time it was published and
``header.seq`` its number: a subscriber computes latency from the stamp, and a checker finds
the input frame an output came from by its stamp (the component carries stamps through).
Frames are written by the lab's own serializer of the layout (:func:`rosfpga_lab.hw.sample.image_frame`) and sent
as raw bytes.

:class:`Viewer` subscribes to an image topic, decodes every frame with the message layer, and
keeps the newest one; it can save every n-th frame as PNG.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.component import limits
from rosfpga_lab.component.errors import ComponentError, SourceError
from rosfpga_lab.component.sources import ImageSource, open_source, to_rgb
from rosfpga_lab.component.stats import LatencyWindow, fps_meter, since_stamp
from rosfpga_lab.config import DEFAULT_ENCODING, PIXEL_FORMATS
from rosfpga_lab.graph import EmbeddedMaster, MessageInfo, Node
from rosfpga_lab.hw.sample import image_frame


@dataclass(frozen=True)
class SentFrame:
    """One frame the camera published: its number, stamp and picture."""

    seq: int
    stamp: tuple[int, int]
    image: np.ndarray
    sent: float  # time.time() when handed to the publisher
    encoding: str = ""
    frame_id: str = ""


def stamp_of(t: float) -> tuple[int, int]:
    """``time.time()`` as a ROS ``(secs, nsecs)`` pair."""
    ns = int(round(t * 1e9))
    return ns // 1_000_000_000, ns % 1_000_000_000


class Camera:
    """Publishes images on ``topic`` at ``rate`` frames per second.

    Args:
        topic: image topic (``/image_raw`` by default).
        width, height, encoding: the frames' geometry.
        rate: frames per second (0 < rate <= MAX_CAMERA_RATE).
        source: ``"synthetic"``, ``"grace_hopper"``, an image file or a directory.
        name: node name. master, master_uri, host: as for :class:`rosfpga_lab.graph.Node`.
        frame_id: ``header.frame_id`` of every frame.
        queue_size: frames queued per subscriber (oldest dropped when full).
        domain: publish on ROS 2 in this DDS domain instead (a DDS participant, no master).
        on_sent: ``on_sent(SentFrame)`` just before each publish (e.g. a checker remembering
            inputs).

    Raises:
        SourceError: bad source, size, encoding or rate.
    """

    def __init__(self, topic: str = "/image_raw", *, width: int = 640, height: int = 480,
                 encoding: str = DEFAULT_ENCODING, rate: float = 30.0, source: str | ImageSource = "synthetic",
                 name: str = "/camera", master: EmbeddedMaster | None = None,
                 master_uri: str | None = None, host: str | None = None, frame_id: str = "camera",
                 queue_size: int = 2, on_sent: Callable[[SentFrame], Any] | None = None,
                 domain: int | None = None) -> None:
        if not 0 < rate <= limits.MAX_CAMERA_RATE:
            raise SourceError(f"rate {rate} is outside (0, {limits.MAX_CAMERA_RATE:g}] frames/s")
        self.source = source if isinstance(source, ImageSource) else open_source(
            source, width, height, encoding)
        self.topic, self.rate, self.frame_id = topic, float(rate), frame_id
        self.on_sent = on_sent
        self._images = [self.source.frame(k) for k in range(self.source.period)]
        self.node: Any
        self.publisher: Any
        if domain is not None:     # ROS 2: a DDS participant instead of a ROS 1 node
            from rosfpga_lab.component.ros2 import Ros2ImagePublisher
            from rosfpga_lab.graph.ros2 import Ros2Node

            self.node = Ros2Node(name.strip("/") or "camera", domain, host or "127.0.0.1")
            self.publisher = Ros2ImagePublisher(self.node, topic)
        else:
            self.node = Node(name, master_uri, host, master=master)
            try:
                self.publisher = self.node.advertise(topic, "sensor_msgs/Image",
                                                     queue_size=queue_size)
            except BaseException:
                self.node.shutdown()
                raise
        self.sent = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __repr__(self) -> str:
        return f"<Camera {self.topic} {self.source!r} {self.rate:g} fps sent={self.sent}>"

    def publish_one(self) -> SentFrame:
        """Publish the next frame now; return what was sent."""
        k = self.sent
        image = self._images[k % len(self._images)]
        now = time.time()
        stamp = stamp_of(now)
        frame = image_frame(image, self.source.encoding, seq=k & 0xFFFFFFFF, stamp=stamp,
                            frame_id=self.frame_id)
        sent = SentFrame(k, stamp, image, now, self.source.encoding, self.frame_id)
        if self.on_sent is not None:
            self.on_sent(sent)  # before publishing: an answer may come back at once
        self.publisher.publish_body(memoryview(frame)[4:])
        self.sent += 1
        return sent

    def run(self, count: int | None = None, duration: float | None = None,
            stop: threading.Event | None = None) -> int:
        """Publish on schedule until ``count`` frames, ``duration`` seconds, or ``stop`` is set.

        Returns:
            frames published by this call.
        """
        stop = stop or self._stop
        start = time.monotonic()
        k = 0
        times = self.source.times  # a bag's recorded timing, repeated; else k / rate
        span = (times[-1] * len(times) / (len(times) - 1) if len(times) > 1 and times[-1] > 0
                else len(times) / self.rate) if times else 0.0
        while not stop.is_set() and (count is None or k < count):
            due = start + (k // len(times) * span + times[k % len(times)] if times else k / self.rate)
            if duration is not None and due - start >= duration:
                break
            if stop.wait(max(0.0, due - time.monotonic())):
                break
            self.publish_one()
            k += 1
        return k

    def start(self, count: int | None = None, duration: float | None = None) -> Camera:
        """Run :meth:`run` in a background thread (stop with :meth:`stop`)."""
        if self._thread is not None and self._thread.is_alive():
            raise ComponentError("camera already running")
        self._stop.clear()
        self._thread = threading.Thread(target=self.run, args=(count, duration), daemon=True,
                                        name=f"rosfpga-camera-{self.topic}")
        self._thread.start()
        return self

    def join(self, timeout: float | None = None) -> None:
        """Wait for the background run to end."""
        if self._thread is not None:
            self._thread.join(timeout)

    def stop(self) -> None:
        """Stop publishing and shut the node down."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(5.0)
        self.node.shutdown()

    def __enter__(self) -> Camera:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


@dataclass(frozen=True)
class ViewedFrame:
    """One image the viewer received."""

    index: int
    header: dict
    width: int
    height: int
    encoding: str
    image: np.ndarray | None   # (rows, cols, channels) uint8, None when undisplayable
    info: MessageInfo
    latency: float | None      # receive time minus header.stamp (s); None: no wall-clock stamp


class Viewer:
    """Subscribes to an image topic; keeps the newest frame, counts, saves PNGs.

    Args:
        topic: the image topic.
        save_dir: save every ``every``-th frame as ``frame_NNNNNN.png`` here (None: do not save).
        every: save one frame in this many.
        latest_only: overwrite ``latest.png`` instead of numbering files.
        name, master, master_uri, host: as for :class:`rosfpga_lab.graph.Node`.
        on_frame: ``on_frame(ViewedFrame)`` after each frame.
        domain: subscribe on ROS 2 in this DDS domain instead (a DDS participant, no master).
    """

    def __init__(self, topic: str, *, save_dir: str | Path | None = None, every: int = 1,
                 latest_only: bool = False, name: str = "/viewer",
                 master: EmbeddedMaster | None = None, master_uri: str | None = None,
                 host: str | None = None, on_frame: Callable[[ViewedFrame], Any] | None = None,
                 queue_size: int = 2, domain: int | None = None) -> None:
        self.topic = topic
        self.save_dir = Path(save_dir) if save_dir is not None else None
        if self.save_dir is not None:
            try:
                self.save_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise ComponentError(f"cannot save frames into {self.save_dir}: {exc.strerror}; "
                                     "give a writable directory") from None
        self.every, self.latest_only, self.on_frame = max(1, every), latest_only, on_frame
        self.received = 0
        self.saved: list[Path] = []
        self.problems: list[str] = []
        self.latency = LatencyWindow(limits.LATENCY_WINDOW)
        self.last: ViewedFrame | None = None
        self._rate = fps_meter()
        self._lock = threading.Lock()
        self.node: Any
        if domain is not None:     # ROS 2: a DDS participant instead of a ROS 1 node
            from rosfpga_lab.component.ros2 import subscribe_ros1_bodies
            from rosfpga_lab.graph.ros2 import Ros2Node

            self.node = Ros2Node(name.strip("/") or "viewer", domain, host or "127.0.0.1")
            subscribe_ros1_bodies(self.node, topic, self._on_body)
            return
        self.node = Node(name, master_uri, host, master=master)
        try:
            self.subscriber = self.node.subscribe(topic, "sensor_msgs/Image", self._on_body,
                                                  raw=True, queue_size=queue_size)
        except BaseException:
            self.node.shutdown()
            raise

    def _on_body(self, body: bytes | memoryview, info: MessageInfo) -> None:
        from rosfpga_lab.msg import default_registry, deserialize

        msg = deserialize(default_registry(), "sensor_msgs/Image", bytes(body))
        header = msg["header"]
        stamp = header["stamp"]
        secs, nsecs = (stamp["secs"], stamp["nsecs"]) if isinstance(stamp, dict) else stamp
        latency = since_stamp(info.received, secs, nsecs)
        if latency is not None:
            self.latency.add(latency)
        h, w, enc = msg["height"], msg["width"], msg["encoding"]
        image = None
        try:
            channels = PIXEL_FORMATS[enc].bytes_per_pixel
            data = np.frombuffer(msg["data"], np.uint8)
            image = data[:h * msg["step"]].reshape(h, msg["step"])[:, :w * channels].reshape(
                h, w, channels)
        except (KeyError, ValueError) as exc:
            with self._lock:
                self.problems.append(f"frame {self.received}: cannot show {enc!r} {w}x{h}: {exc}")
        with self._lock:
            index = self.received
            self.received += 1
            self._rate.tick()
        frame = ViewedFrame(index, header, w, h, enc, image, info, latency)
        self.last = frame
        if image is not None and self.save_dir is not None and index % self.every == 0:
            name = "latest.png" if self.latest_only else f"frame_{index:06d}.png"
            path = self.save_dir / name
            cv2.imwrite(str(path), cv2.cvtColor(to_rgb(image, enc), cv2.COLOR_RGB2BGR))
            with self._lock:
                if not self.latest_only or not self.saved:
                    self.saved.append(path)
        if self.on_frame is not None:
            self.on_frame(frame)

    @property
    def fps(self) -> float:
        """Frames per second over the last seconds (:func:`~rosfpga_lab.component.stats.fps_meter`)."""
        with self._lock:
            return self._rate.rate()

    def wait_for(self, frames: int, timeout: float = 10.0) -> bool:
        """Wait until ``frames`` frames arrived; False on time-out."""
        deadline = time.monotonic() + timeout
        while self.received < frames:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)
        return True

    def stop(self) -> None:
        """Unsubscribe and shut the node down."""
        self.node.shutdown()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
