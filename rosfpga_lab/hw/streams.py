"""Stream types as hardware people name them: a FIFO of bytes, AXI4-Stream beats.

* :class:`Fifo` is an ``hls::stream``: ``write`` at the tail, ``read`` from the head, a ``depth``
  (``None`` = unbounded, what HLS C-simulation gives), ``level`` (occupancy), ``full``/``empty``
  and a sticky ``overflow`` flag. As in a FIFO IP core, a write while full is *ignored* (the
  item is lost) and raises ``overflow``; a read while empty is where the circuit would stall for
  ever, so the model raises :class:`StreamStarvedError` instead of hanging.
* :class:`ByteFIFO` is the paper's 8-bit FIFO: a :class:`Fifo` whose items are 0..255.
* :class:`Beat` is one AXI4-Stream transfer: ``tdata`` (32 bits, byte ``i`` in bits
  ``8i+7..8i``), ``tkeep`` (one bit per byte lane), ``tuser`` (start of frame) and ``tlast``
  (end of line).
* :class:`Beats` holds many beats as four numpy arrays (struct of arrays), the fast models'
  currency; ``Beats[i]`` is a :class:`Beat`, ``Beats.from_list``/``to_list`` convert.
"""

from __future__ import annotations

import functools
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

from rosfpga_lab.hw.errors import PipelineConfigError, StreamStarvedError

T = TypeVar("T")


class Fifo(Generic[T]):
    """A first-in first-out stream between two stages.

    Args:
        depth: capacity in items, or ``None`` for unbounded.
        name: shown in error messages.

    Attributes:
        high_water: the highest ``level`` seen since the last reset.
        overflow: sticky flag, set when a write met a full FIFO.
        dropped: how many writes were lost to ``overflow``.
        reads: how many items were read since the last reset (for error messages).
    """

    def __init__(self, depth: int | None = None, name: str = "fifo") -> None:
        if depth is not None and depth < 1:
            raise PipelineConfigError(f"FIFO {name!r}: depth must be at least 1, got {depth}")
        self.depth = depth
        self.name = name
        self._items: deque[T] = deque()
        self.reset()

    def reset(self) -> None:
        """Empty the FIFO and clear its flags (a synchronous reset)."""
        self._items.clear()
        self.high_water = 0
        self.overflow = False
        self.dropped = 0
        self.reads = 0

    @property
    def level(self) -> int:
        """Items currently stored."""
        return len(self._items)

    @property
    def empty(self) -> bool:
        return not self._items

    @property
    def full(self) -> bool:
        return self.depth is not None and len(self._items) >= self.depth

    def write(self, item: T) -> bool:
        """Push ``item``; returns False (and sets ``overflow``) when the FIFO was full."""
        items = self._items
        if self.depth is not None and len(items) >= self.depth:
            self.overflow = True
            self.dropped += 1
            return False
        items.append(item)
        if len(items) > self.high_water:
            self.high_water = len(items)
        return True

    def read(self, reader: str = "", needed: int = 0) -> T:
        """Pop the oldest item.

        Args:
            reader: the stage reading (for the error message).
            needed: how many items the reader needs in all (for the error message).

        Raises:
            StreamStarvedError: the FIFO is empty (the circuit would stall here for ever).
        """
        if not self._items:
            raise StreamStarvedError(
                f"read from empty FIFO {self.name!r} after {self.reads} items"
                + (f" of the {needed} needed" if needed else "")
                + ": the upstream stage delivered too few (a lost byte, beat or TLAST?)",
                stage=reader or self.name, needed=needed, got=self.reads,
            )
        self.reads += 1
        return self._items.popleft()

    def extend(self, items: Iterable[T]) -> None:
        """Write every item of ``items`` in order."""
        for item in items:
            self.write(item)

    def drain(self) -> list[T]:
        """Remove and return everything stored (no read counting)."""
        items = list(self._items)
        self._items.clear()
        return items

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self) -> Iterator[T]:
        return iter(self._items)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(name={self.name!r}, depth={self.depth}, level={self.level}, "
                f"high_water={self.high_water}, overflow={self.overflow})")


class ByteFIFO(Fifo[int]):
    """The paper's 8-bit FIFO: a :class:`Fifo` of bytes (ints 0..255)."""

    def __init__(self, depth: int | None = None, name: str = "byte_fifo") -> None:
        super().__init__(depth, name)

    def write(self, item: int) -> bool:
        if not 0 <= item <= 0xFF:
            raise PipelineConfigError(f"FIFO {self.name!r} is 8 bits wide; cannot hold {item}")
        return Fifo.write(self, item)

    def to_bytes(self) -> bytes:
        """The stored bytes, oldest first (without removing them)."""
        return bytes(self._items)


@dataclass(frozen=True)
class Beat:
    """One AXI4-Stream transfer on a 32-bit bus."""

    tdata: int
    tkeep: int = 0b1111
    tuser: bool = False
    tlast: bool = False

    def lanes(self) -> tuple[int, int, int, int]:
        """The four byte lanes of ``tdata``, lane 0 (bits 7..0) first."""
        return tuple((self.tdata >> (8 * i)) & 0xFF for i in range(4))  # type: ignore[return-value]

    def __repr__(self) -> str:
        return (f"Beat(tdata=0x{self.tdata:08x}, tkeep=0b{self.tkeep:04b}, "
                f"tuser={int(self.tuser)}, tlast={int(self.tlast)})")


def _signal(value: Any, dtype: Any, n: int, name: str) -> np.ndarray:
    if np.ndim(value) == 0:
        return _constant(int(value), np.dtype(dtype).str, n)
    array = np.asarray(value, dtype=dtype)
    if array.ndim != 1:
        array = array.reshape(-1)  # (a 1-D array is kept as it is: cached flags stay recognisable)
    if array.shape[0] != n:
        raise PipelineConfigError(f"Beats: {name} has {array.shape[0]} entries, tdata has {n}")
    return array


def frame_flags(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Read-only ``(tuser, tlast)`` of a well-formed ``rows x cols`` frame (cached)."""
    return _frame_flags(rows, cols)


def _constant(value: int, dtype: str, n: int) -> np.ndarray:
    # One stored element seen n times (stride 0, read-only): no memory, and recognisable.
    return np.broadcast_to(np.array(value, np.dtype(dtype)), (n,))


@functools.lru_cache(maxsize=16)
def _frame_flags(rows: int, cols: int) -> tuple[np.ndarray, np.ndarray]:
    tuser = np.zeros(rows * cols, bool)
    tuser[0] = True
    tlast = np.zeros((rows, cols), bool)
    tlast[:, -1] = True
    tuser.setflags(write=False)
    tlast.setflags(write=False)
    return tuser, tlast.reshape(-1)


class Beats:
    """Many beats as a struct of numpy arrays (``tdata`` uint32, ``tkeep`` uint8, flags bool).

    Equality compares every signal of every beat.
    """

    __slots__ = ("tdata", "tkeep", "tuser", "tlast")

    def __init__(self, tdata: Any, tkeep: Any, tuser: Any, tlast: Any) -> None:
        # Arrays are taken as they are (no copy); a scalar is spread over every beat.
        self.tdata = np.ascontiguousarray(tdata, dtype=np.uint32).reshape(-1)
        n = self.tdata.shape[0]
        self.tkeep = _signal(tkeep, np.uint8, n, "tkeep")
        self.tuser = _signal(tuser, np.bool_, n, "tuser")
        self.tlast = _signal(tlast, np.bool_, n, "tlast")

    @classmethod
    def empty(cls) -> Beats:
        return cls(np.zeros(0, np.uint32), 0, False, False)

    @classmethod
    def from_list(cls, beats: Iterable[Beat]) -> Beats:
        """Pack a sequence of :class:`Beat` into arrays."""
        items = list(beats)
        return cls(
            np.fromiter((b.tdata for b in items), np.uint32, len(items)),
            np.fromiter((b.tkeep for b in items), np.uint8, len(items)),
            np.fromiter((b.tuser for b in items), bool, len(items)),
            np.fromiter((b.tlast for b in items), bool, len(items)),
        )

    def to_list(self) -> list[Beat]:
        """One :class:`Beat` per transfer (slow for big frames: notebooks and tests)."""
        return [Beat(int(d), int(k), bool(u), bool(la)) for d, k, u, la in
                zip(self.tdata.tolist(), self.tkeep.tolist(), self.tuser.tolist(), self.tlast.tolist())]

    def uniform_tkeep(self, count: int | None = None) -> bool:
        """True when the first ``count`` beats (all by default) share one ``tkeep``.

        Free for beats built with a scalar ``tkeep`` (a read-only constant); a scan otherwise.
        """
        keep = self.tkeep if count is None else self.tkeep[:count]
        if keep.size == 0 or keep.strides == (0,):
            return True
        return bool(np.all(keep == keep[0]))

    def copy(self) -> Beats:
        """A deep copy (its arrays are writable and shared with nothing)."""
        return Beats(self.tdata.copy(), self.tkeep.copy(), self.tuser.copy(), self.tlast.copy())

    def __len__(self) -> int:
        return int(self.tdata.shape[0])

    def __getitem__(self, index: int) -> Beat:
        return Beat(int(self.tdata[index]), int(self.tkeep[index]), bool(self.tuser[index]),
                    bool(self.tlast[index]))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Beats):
            return NotImplemented
        return (len(self) == len(other) and bool(np.array_equal(self.tdata, other.tdata))
                and bool(np.array_equal(self.tkeep, other.tkeep))
                and bool(np.array_equal(self.tuser, other.tuser))
                and bool(np.array_equal(self.tlast, other.tlast)))

    def first_difference(self, other: Beats) -> int | None:
        """Index of the first beat that differs from ``other`` (``None`` when equal)."""
        n = min(len(self), len(other))
        diff = ((self.tdata[:n] != other.tdata[:n]) | (self.tkeep[:n] != other.tkeep[:n])
                | (self.tuser[:n] != other.tuser[:n]) | (self.tlast[:n] != other.tlast[:n]))
        idx = np.flatnonzero(diff)
        if idx.size:
            return int(idx[0])
        return None if len(self) == len(other) else n

    def __repr__(self) -> str:
        head = ", ".join(repr(b) for b in self.to_list()[:3]) if len(self) else ""
        more = ", ..." if len(self) > 3 else ""
        return f"Beats(n={len(self)}: {head}{more})"
