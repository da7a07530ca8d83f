"""The circuit layout's vocabulary: a :class:`Layout` is the walk over one message type, a
tuple of :class:`Step` (what the circuit reads next, its :class:`StepKind`, what it does with
it, :class:`Action`, and the :class:`FieldCheck` it runs), and :func:`format_layout` prints it.

These are plain frozen records: :mod:`rosfpga_lab.hw.layoutderive` makes them from a ``.msg``
and a configuration, :mod:`rosfpga_lab.hw.layoutlengths` says how length prefixes are held
against the frame, :mod:`rosfpga_lab.hw.layouttokens` lists a message's values in walk order.
:mod:`rosfpga_lab.hw.layout` tells the whole story (with a worked example) and gathers the
public names.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, NamedTuple

from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import LayoutError


class _Name(StrEnum):
    def __repr__(self) -> str:
        return self.value


class StepKind(_Name):
    """How a step sits in the frame."""

    SCALAR = "scalar"   # one fixed-size number or bool (``size`` bytes, little-endian)
    LENGTH = "length"   # a uint32: the frame length, or the element count of the next part
    STRING = "string"   # a string's bytes (count from its LENGTH step)
    ARRAY = "array"     # an array of numbers as one block of ``count`` x ``size`` bytes
    LOOP = "loop"       # the start of an array of messages/strings/times, walked per element
    END = "end"         # the end of one element of that array (back to the LOOP's body)
    # CDR only (hw.cdrlayout: the second wire format of the same walk)
    ENCAPSULATION = "encapsulation"  # the 4-byte encapsulation header (representation, options)
    NUL = "nul"         # the NUL that ends a CDR string (its length counts it)


class Action(_Name):
    """What the circuit does with a step's bytes."""

    STREAM = "stream"   # to the application, one AXI4-Stream beat per element
    CHECK = "check"     # compared with a value fixed at synthesis time (kept, re-sent)
    CARRY = "carry"     # kept and written into the output message
    SKIP = "skip"       # read and dropped; the publisher writes the field's default


class CheckOp(_Name):
    """What a check compares."""

    EQUAL = "equal"     # value == ``value``
    RANGE = "range"     # ``low`` <= value <= ``high`` (either may be None)
    MAX = "max"         # a length prefix: value <= ``high`` (and its bytes fit in the frame)


@dataclass(frozen=True)
class FieldCheck:
    """The check a step runs when it completes.

    Attributes:
        op: :class:`CheckOp`.
        status: the subscriber's status code when it fails, ``SUB_BAD_<IDENT>``.
        value: the value of an ``equal`` check.
        low, high: the bounds of a ``range`` check; ``high`` is the maximum of a ``max`` check.
    """

    op: CheckOp
    status: str
    value: Any = None
    low: Any = None
    high: Any = None

    def describe(self) -> str:
        """``== 480``, ``<= 256``, ``-1..1``."""
        if self.op is CheckOp.EQUAL:
            return f"== {self.value!r}" if isinstance(self.value, str) else f"== {self.value}"
        if self.op is CheckOp.MAX:
            return f"<= {self.high}"
        return f"{'' if self.low is None else self.low}..{'' if self.high is None else self.high}"


@dataclass(frozen=True)
class Step:
    """One step of the circuit's walk over the frame.

    Attributes:
        index: position in :attr:`Layout.steps`.
        kind: :class:`StepKind`.
        ident: a C/Verilog-safe name, unique in the layout, from the field path
            (``header_stamp_secs``; ``<field>_length`` for a length prefix, ``<field>_item`` for
            the string of a string array element).
        label: the field as errors name it, ``[]`` where an element index goes
            (``header.stamp.secs``, ``points[].x``, ``data length``).
        path: the dotted field path without indices (``points.x``), what a configuration names;
            a length step has the path of the field it counts.
        type: ROS type of one element: ``uint32``, ``float32``, ``string`` (STRING, or the LOOP
            of a string array), ``time``/``duration`` (their LOOP), the message type (its LOOP).
        size: bytes of one element: a SCALAR's or LENGTH's size, 1 for a STRING, the element
            size of an ARRAY, 0 for LOOP/END.
        count: the fixed element count of an ARRAY or LOOP (``T[N]``), 1 for a SCALAR/LENGTH,
            ``None`` when a LENGTH step gives it.
        length_step: index of the LENGTH step giving the count (variable parts), else ``None``.
        max_count: most elements (bytes of a STRING) the circuit takes.
        action: :class:`Action`.
        check: the check run when the step completes, or ``None``.
        depth: how many LOOPs enclose the step.
        partner: a LOOP's END index, an END's LOOP index; a LENGTH's counted step; else None.
        dtype: numpy dtype of one element (``<f4``; ``|u1`` for STRING bytes), ``""`` for LOOP/END.
        rel: the attribute names from the enclosing element (or the message) to the value.
    """

    index: int
    kind: StepKind
    ident: str
    label: str
    path: str
    type: str
    size: int
    count: int | None
    length_step: int | None
    max_count: int
    action: Action
    check: FieldCheck | None
    depth: int
    partner: int | None
    dtype: str
    rel: tuple[str, ...]

    def label_at(self, indices: Iterable[int] = ()) -> str:
        """The label with element indices filled in: ``points[].x`` -> ``points[3].x``."""
        out = self.label
        for i in indices:
            out = out.replace("[]", f"[{i}]", 1)
        return out

    @property
    def is_variable(self) -> bool:
        """True when a LENGTH step gives the element count."""
        return self.length_step is not None


class VideoShape(NamedTuple):
    """The streamed field's video shape (``sensor_msgs/Image``: TUSER on the first pixel, TLAST
    ending each line, one beat per pixel of ``bytes_per_pixel`` bytes)."""

    width: int
    height: int
    encoding: str
    bytes_per_pixel: int


@dataclass(frozen=True)
class Layout:
    """The circuit's walk over one message type.

    Attributes:
        type_name: the message type (``sensor_msgs/LaserScan``).
        md5: its md5 sum (the connection header's).
        steps: the walk, step 0 the frame length.
        stream_index: index of the streamed ARRAY step (``None``: a walk without a stream).
        stream_length: elements of the streamed array the circuit was built for.
        min_body: the shortest body the circuit accepts, bytes: strings and arrays empty but
            the stream (its ``stream_length`` elements) and a string checked for one value
            (its bytes); a shorter body is refused at the frame length. (A video stream:
            the type's smallest body, as the Image interpreter's.)
        max_body: the largest body the circuit accepts (every maximum reached), bytes.
        statuses: ``(name, label)`` of each status code, ``SUB_OK`` first.
        video: the stream's video shape (Image), or ``None`` (a plain 1-D stream).
    """

    type_name: str
    md5: str
    steps: tuple[Step, ...]
    stream_index: int | None
    stream_length: int
    min_body: int
    max_body: int
    statuses: tuple[tuple[str, str], ...]
    video: VideoShape | None = None

    @property
    def stream(self) -> Step:
        """The streamed ARRAY step.

        Raises:
            LayoutError: the layout was derived without a stream.
        """
        if self.stream_index is None:
            raise LayoutError(f"the layout of {self.type_name} has no stream", "stream.field")
        return self.steps[self.stream_index]

    @property
    def beat_bits(self) -> int:
        """Width of one AXI4-Stream beat to the application (bits): the element's, or a pixel
        packed in 32 bits for a video stream."""
        return limits.TDATA_BITS if self.video else 8 * self.stream.size

    def step(self, ident: str) -> Step:
        """The step called ``ident``."""
        for s in self.steps:
            if s.ident == ident:
                return s
        raise KeyError(f"no step {ident!r} in the layout of {self.type_name}")

    def checked(self) -> tuple[Step, ...]:
        """Steps with a check, in status order (``statuses[i + 1]`` is ``checked()[i]``'s)."""
        return tuple(s for s in self.steps if s.check is not None)


def walk_order(steps: Sequence[Step], count_of: Callable[[int], int], lo: int = 1,
               hi: int | None = None, at: tuple[int, ...] = ()) -> Iterator[tuple[int, tuple[int, ...]]]:
    """The steps of one message in wire order, each with the element indices of the loops around
    it: a LOOP step's body comes ``count`` times, or ``count_of(its length step)`` times, asked
    only when the loop is reached (so a walker sets a length's count before its loop needs it)."""
    i, end = lo, len(steps) if hi is None else hi
    while i < end:
        s = steps[i]
        if s.kind is StepKind.LOOP:
            assert s.partner is not None
            n = s.count if s.count is not None else count_of(s.length_step or 0)
            for k in range(n):
                yield from walk_order(steps, count_of, i + 1, s.partner, at + (k,))
            i = s.partner + 1
            continue
        yield i, at
        i += 1


def format_layout(layout: Layout, *, idents: bool = True) -> str:
    """The walk as aligned text: one row per step (what notebooks print before drawing it);
    without ``idents``, no ``ident`` column (narrower: the state names are the idents in
    capitals)."""
    rows: list[tuple[str, ...]] = [("#", "kind", "ident", "label", "type", "bytes", "max", "action",
                                    "check")]
    for s in layout.steps:
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH, StepKind.ENCAPSULATION, StepKind.NUL):
            size = str(s.size)
        elif s.kind is StepKind.END:
            size = str(s.size)
        elif s.count is not None:
            size = f"{s.size} x {s.count}"
        else:
            size = f"{s.size} x [{s.length_step}]"
        top = "-" if s.kind in (StepKind.SCALAR, StepKind.LENGTH, StepKind.END,
                                StepKind.ENCAPSULATION, StepKind.NUL) else str(s.max_count)
        check = f"{s.check.status}: {s.check.describe()}" if s.check else "-"
        rows.append((str(s.index), "  " * s.depth + s.kind, s.ident, s.label, s.type, size, top,
                     s.action, check))
    if not idents:
        rows = [r[:2] + r[3:] for r in rows]
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    text = "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)
    what = (f"stream {layout.stream.label} {layout.stream_length} x {layout.stream.type}"
            if layout.stream_index is not None else "no stream")
    return (f"{layout.type_name} (md5 {layout.md5}): {what}, body {layout.min_body}.."
            f"{layout.max_body} bytes\n{text}")


__all__ = [
    "Action", "CheckOp", "FieldCheck", "Layout", "Step", "StepKind", "VideoShape",
    "format_layout",
]
