"""Fault injection for teaching: break one stream between two stages and watch what happens.

A fault acts at a *tap*, the stream between two stages:

=============  ==================================================  =========
tap            stream                                              carries
=============  ==================================================  =========
``pixels_in``  pixel bytes, subscriber to ``fifo2axi``              bytes
``axis_in``    AXI4-Stream, ``fifo2axi`` to ``AXIvideo2Mat``        beats
``axis_out``   AXI4-Stream, ``Mat2AXIvideo`` to ``axi2fifo``        beats
``pixels_out`` pixel bytes, ``axi2fifo`` to the publisher           bytes
=============  ==================================================  =========

The taps are those of an Image circuit's video stretch
(:func:`~rosfpga_lab.hw.videostages.video_stages`). Every fault gives a visibly wrong image
(shifted channels, wrong colours, a sheared image), a status flag in
:attr:`~rosfpga_lab.hw.videostages.VideoStages.status`, or a
:class:`~rosfpga_lab.hw.errors.PipelineError` (whose ``partial`` holds what was made so far);
none can hang the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rosfpga_lab.hw.errors import PipelineConfigError
from rosfpga_lab.hw.streams import Beats

BYTE_TAPS = ("pixels_in", "pixels_out")
BEAT_TAPS = ("axis_in", "axis_out")
TAPS = ("pixels_in", "axis_in", "axis_out", "pixels_out")


def _check_index(index: int, size: int, what: str, tap: str) -> None:
    if not 0 <= index < size:
        raise PipelineConfigError(f"fault at tap {tap!r}: {what} {index} is outside 0..{size - 1}")


@dataclass(frozen=True, kw_only=True)
class Fault:
    """Base class: a fault at ``tap``."""

    tap: str

    def __post_init__(self) -> None:
        taps = BEAT_TAPS if isinstance(self, BeatFault) else BYTE_TAPS if isinstance(self, ByteFault) else TAPS
        if self.tap not in taps:
            raise PipelineConfigError(
                f"{type(self).__name__} cannot act at tap {self.tap!r}; choose one of {', '.join(taps)}")


class ByteFault(Fault):
    """A fault on a byte stream."""

    def apply(self, data: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


class BeatFault(Fault):
    """A fault on an AXI4-Stream."""

    def apply(self, beats: Beats) -> Beats:  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass(frozen=True, kw_only=True)
class DropByte(ByteFault):
    """Lose the byte at ``index`` (everything after it moves up one place)."""

    index: int = 0
    tap: str = "pixels_in"

    def apply(self, data: np.ndarray) -> np.ndarray:
        _check_index(self.index, data.size, "byte", self.tap)
        return np.delete(data, self.index)


@dataclass(frozen=True, kw_only=True)
class DuplicateByte(ByteFault):
    """Send the byte at ``index`` twice (everything after it moves down one place)."""

    index: int = 0
    tap: str = "pixels_in"

    def apply(self, data: np.ndarray) -> np.ndarray:
        _check_index(self.index, data.size, "byte", self.tap)
        return np.insert(data, self.index, data[self.index])


@dataclass(frozen=True, kw_only=True)
class SwapByteOrder(BeatFault):
    """Pack every pixel big-endian: reverse the order of the kept byte lanes of each beat.

    ``rgba8`` comes out as ``abgr``; a ``mono8`` beat has one lane, so nothing changes.
    """

    tap: str = "axis_in"

    def apply(self, beats: Beats) -> Beats:
        out = beats.copy()
        lanes = out.tdata.astype("<u4").view(np.uint8).reshape(-1, 4).copy()
        for keep in np.unique(out.tkeep):
            rows = out.tkeep == keep
            used = [lane for lane in range(4) if (int(keep) >> lane) & 1]
            lanes[np.ix_(rows, used)] = lanes[np.ix_(rows, used[::-1])]
        out.tdata = lanes.view("<u4").reshape(-1).astype(np.uint32)
        return out


@dataclass(frozen=True, kw_only=True)
class LoseTlast(BeatFault):
    """Clear ``tlast`` on the last beat of line ``line`` (the ``line``-th beat with ``tlast``)."""

    line: int = 0
    tap: str = "axis_in"

    def apply(self, beats: Beats) -> Beats:
        ends = np.flatnonzero(beats.tlast)
        _check_index(self.line, ends.size, "line", self.tap)
        out = beats.copy()
        out.tlast[ends[self.line]] = False
        return out


@dataclass(frozen=True, kw_only=True)
class LoseTuser(BeatFault):
    """Clear ``tuser`` (start of frame) on every beat."""

    tap: str = "axis_in"

    def apply(self, beats: Beats) -> Beats:
        out = beats.copy()
        out.tuser[:] = False
        return out
