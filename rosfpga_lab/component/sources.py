"""Pictures for the camera when there is no camera: a moving synthetic scene, a real photo, files.

How this works: :func:`open_source` returns an :class:`ImageSource` whose ``frame(k)`` gives
the k-th picture, already at the requested size and in the requested ``sensor_msgs/Image``
encoding, as a ``(height, width, channels)`` uint8 array. Every source moves, so consecutive
frames differ (a frozen picture would hide a component that repeats its last output):

* ``synthetic``: a gradient, a grid, a bouncing disc, a sweeping bar and sparse bright dots
  (single bright pixels make a dilation easy to see: each becomes a kernel-sized square);
* ``grace_hopper``: the photo matplotlib ships (``matplotlib.cbook.get_sample_data``), panned
  slowly;
* a file path: that picture, panned; a directory: its ``.png``/``.jpg`` files in turn;
* a ROS 1 bag (``.bag``, read with ``rosbags``, no ROS needed): its ``sensor_msgs/Image`` frames
  of one topic as recorded (converted only when the size or encoding asked for differs), with
  their recorded times in :attr:`ImageSource.times` so a camera replays them on that timing.

Frames repeat with period :attr:`ImageSource.period`, so a camera can render each once.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from rosfpga_lab.component import limits
from rosfpga_lab.component.errors import SourceError
from rosfpga_lab.config import PIXEL_FORMATS

#: Named sources (besides a path).
SOURCES = ("synthetic", "grace_hopper")
#: Distinct frames before a source repeats.
DEFAULT_PERIOD = limits.DEFAULT_SOURCE_PERIOD
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp")



def _cv_name(channels: str) -> str:
    """OpenCV's name of a channel order (``"Y"`` is ``GRAY``)."""
    return "GRAY" if channels == "Y" else channels


# OpenCV colour conversions per encoding, derived from the channel order each encoding declares
# (None: already in that order).
_FROM_BGR: dict[str, int | None] = {
    enc: None if _cv_name(fmt.channels) == "BGR" else getattr(cv2, f"COLOR_BGR2{_cv_name(fmt.channels)}")
    for enc, fmt in PIXEL_FORMATS.items()
}
_TO_RGB: dict[str, int | None] = {
    enc: None if _cv_name(fmt.channels) == "RGB" else getattr(cv2, f"COLOR_{_cv_name(fmt.channels)}2RGB")
    for enc, fmt in PIXEL_FORMATS.items()
}


def check_geometry(width: int, height: int, encoding: str) -> None:
    """Refuse sizes and encodings the circuit models cannot carry.

    Raises:
        SourceError: naming the bad value and the accepted ones.
    """
    if encoding not in PIXEL_FORMATS:
        raise SourceError(f"unsupported encoding {encoding!r}; choose one of {', '.join(PIXEL_FORMATS)}")
    for name, side in (("width", width), ("height", height)):
        if not 1 <= side <= limits.MAX_CAMERA_SIDE:
            raise SourceError(f"{name} {side} is outside 1..{limits.MAX_CAMERA_SIDE}")


def from_bgr(image: np.ndarray, encoding: str) -> np.ndarray:
    """Convert an OpenCV BGR picture to ``encoding``; always 3-D ``(rows, cols, channels)``."""
    code = _FROM_BGR[encoding]
    out = image if code is None else cv2.cvtColor(image, code)
    if out.ndim == 2:
        out = out[:, :, None]
    return np.ascontiguousarray(out)


def to_rgb(image: np.ndarray, encoding: str) -> np.ndarray:
    """An ``encoding`` picture as 3-channel RGB for display or PNG writing.

    Raises:
        SourceError: an encoding this lab does not display.
    """
    if encoding not in _TO_RGB:
        raise SourceError(f"cannot display encoding {encoding!r}; known: {', '.join(_TO_RGB)}")
    img = image if image.ndim == 3 else image[:, :, None]
    code = _TO_RGB[encoding]
    if code is None:
        return np.ascontiguousarray(img)
    src = img[:, :, 0] if PIXEL_FORMATS[encoding].bytes_per_pixel == 1 else img
    return cv2.cvtColor(np.ascontiguousarray(src), code)


class ImageSource:
    """Frames of one source at one size and encoding (see module docstring).

    Args:
        name: ``"synthetic"``, ``"grace_hopper"``, or a path to an image file or a directory.
        width, height, encoding: what ``frame(k)`` returns.
        period: distinct frames before the sequence repeats.

    Raises:
        SourceError: unknown source, unreadable file, empty directory, bad size or encoding.
    """

    def __init__(self, name: str, width: int, height: int, encoding: str,
                 period: int = DEFAULT_PERIOD, topic: str | None = None) -> None:
        check_geometry(width, height, encoding)
        self.name, self.width, self.height, self.encoding = name, width, height, encoding
        self.period = max(1, int(period))
        self._pictures: list[np.ndarray] = []
        #: A bag's frames as recorded, the bag topic read, and their times in seconds from the first.
        self._frames: list[np.ndarray] = []
        self.bag_topic: str | None = None
        self.times: list[float] | None = None
        if name == "synthetic":
            return
        if name.endswith(".bag") and Path(name).is_file():
            self._load_bag(Path(name), topic)
            return
        if name == "grace_hopper":
            self._pictures = [_grace_hopper()]
        else:
            path = Path(name)
            if path.is_dir():
                files = sorted(p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
                if not files:
                    raise SourceError(f"{path}: no {'/'.join(IMAGE_SUFFIXES)} files in this directory")
                self._pictures = [_read(p) for p in files]
            elif path.exists():
                self._pictures = [_read(path)]
            else:
                raise SourceError(f"unknown image source {name!r}: give {', '.join(SOURCES)}, an "
                                  "image file or a directory of images")
        # Each picture is scaled to cover the frame with 12% to spare, for the pan.
        self._pictures = [self._cover(p) for p in self._pictures]

    def __repr__(self) -> str:
        return f"ImageSource({self.name!r}, {self.width}x{self.height} {self.encoding})"

    def _cover(self, picture: np.ndarray) -> np.ndarray:
        h, w = picture.shape[:2]
        scale = 1.12 * max(self.width / w, self.height / h)
        size = (max(self.width + 2, round(w * scale)), max(self.height + 2, round(h * scale)))
        return cv2.resize(picture, size, interpolation=cv2.INTER_AREA)

    def _load_bag(self, path: Path, topic: str | None) -> None:
        from rosfpga_lab.msg import MsgError, default_registry, deserialize
        from rosfpga_lab.msg.bag import bag_topics, read_bag

        try:
            images = sorted(t for t, ty in bag_topics(path).items() if ty == "sensor_msgs/Image")
            if topic is None and len(images) == 1:
                topic = images[0]
            if topic not in images:
                raise SourceError(f"{path}: {'no' if topic is None else f'no topic {topic} of'} "
                                  f"sensor_msgs/Image to replay; its image topics: "
                                  f"{', '.join(images) or 'none'} (choose one with --topic)")
            reg, held, t0 = default_registry(), 0, None
            self.times = []
            for m in read_bag(path, [topic]):
                frame = self._bag_frame(deserialize(reg, "sensor_msgs/Image", m.body), path)
                held += frame.nbytes
                if held > limits.MAX_BAG_SOURCE_BYTES:
                    raise SourceError(f"{path}: the frames of {topic} need more than "
                                      f"{limits.MAX_BAG_SOURCE_BYTES >> 20} MiB; cut the bag "
                                      "(rosbag filter) or record fewer frames")
                t0 = m.time_ns if t0 is None else t0
                self.times.append((m.time_ns - t0) / 1e9)
                self._frames.append(frame)
        except MsgError as exc:
            raise SourceError(f"{path}: {exc}") from None
        if not self._frames:
            raise SourceError(f"{path}: no messages on {topic}")
        self.bag_topic, self.period = topic, len(self._frames)

    def _bag_frame(self, msg: dict, path: Path) -> np.ndarray:
        """A bag's Image as a frame of this source's size and encoding (as is when they match)."""
        enc, w, h, step = msg["encoding"], msg["width"], msg["height"], msg["step"]
        if enc not in PIXEL_FORMATS:
            raise SourceError(f"{path}: frames in encoding {enc!r}; the lab reads "
                              f"{', '.join(PIXEL_FORMATS)}")
        bpp = PIXEL_FORMATS[enc].bytes_per_pixel
        data = np.asarray(msg["data"], np.uint8)
        if w * bpp > step or data.size < step * h or not w or not h:
            raise SourceError(f"{path}: a frame's data does not match {w}x{h} {enc} step {step}")
        image = data[:step * h].reshape(h, step)[:, :w * bpp].reshape(h, w, bpp)
        if (w, h, enc) == (self.width, self.height, self.encoding):
            return np.ascontiguousarray(image)
        bgr = cv2.cvtColor(to_rgb(image, enc), cv2.COLOR_RGB2BGR)
        if (w, h) != (self.width, self.height):
            bgr = cv2.resize(bgr, (self.width, self.height), interpolation=cv2.INTER_AREA)
        return from_bgr(bgr, self.encoding)

    def frame(self, k: int) -> np.ndarray:
        """The k-th frame, ``(height, width, channels)`` uint8 in :attr:`encoding`."""
        k %= self.period
        if self._frames:
            return self._frames[k]
        if not self._pictures:
            bgr = _synthetic(k, self.width, self.height, self.period)
        else:
            picture = self._pictures[(k * len(self._pictures)) // self.period]
            ph, pw = picture.shape[:2]
            phase = 2 * np.pi * k / self.period
            x = int(round((pw - self.width) * (0.5 + 0.5 * np.sin(phase))))
            y = int(round((ph - self.height) * (0.5 + 0.5 * np.sin(2 * phase + 0.7))))
            bgr = picture[y:y + self.height, x:x + self.width]
        return from_bgr(np.ascontiguousarray(bgr), self.encoding)


def open_source(name: str, width: int, height: int, encoding: str,
                period: int = DEFAULT_PERIOD, topic: str | None = None) -> ImageSource:
    """Open an image source (see :class:`ImageSource`; ``topic``: a bag's topic to read)."""
    return ImageSource(name, width, height, encoding, period, topic)


def _read(path: Path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise SourceError(f"{path}: not an image OpenCV can read")
    return image


def _grace_hopper() -> np.ndarray:
    try:
        from matplotlib import cbook

        sample = Path(cbook.get_sample_data("grace_hopper.jpg", asfileobj=False))
        data = np.frombuffer(sample.read_bytes(), np.uint8)
    except (OSError, ValueError) as exc:
        raise SourceError(f"matplotlib's sample photo grace_hopper.jpg is missing ({exc}); "
                          "use --source synthetic") from None
    image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    if image is None:
        raise SourceError("matplotlib's grace_hopper.jpg could not be decoded; use --source synthetic")
    return image


def _synthetic(k: int, width: int, height: int, period: int) -> np.ndarray:
    """A moving test scene in BGR (deterministic in ``k``)."""
    y, x = np.mgrid[0:height, 0:width]
    img = np.empty((height, width, 3), np.uint8)
    shift = (k * 256) // period
    img[:, :, 0] = ((x * 255) // max(1, width - 1) + shift) % 256
    img[:, :, 1] = (y * 255) // max(1, height - 1)
    img[:, :, 2] = ((x + y) // 4 + 2 * shift) % 256 // 2
    img[(y % 32 == 0) | (x % 32 == 0)] = (40, 40, 40)
    phase = 2 * np.pi * k / period
    r = max(2, min(width, height) // 8)
    cx = int(width / 2 + (width / 2 - r) * np.cos(phase))
    cy = int(height / 2 + (height / 2 - r) * np.sin(2 * phase))
    cv2.circle(img, (cx, cy), r, (0, 215, 255), -1)
    bar = (k * width) // period
    cv2.rectangle(img, (bar, 0), (min(width - 1, bar + max(1, width // 40)), height - 1),
                  (255, 255, 255), -1)
    rng = np.random.default_rng(k)
    n = max(1, width * height // 400)
    img[rng.integers(0, height, n), rng.integers(0, width, n)] = 255
    return img
