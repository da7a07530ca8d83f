"""The circuit layout: one walk over a TCPROS frame, derived from a ``.msg`` and the node configuration.

How this works: :func:`derive_layout` walks the message type in wire order (the same order the
``msg`` layer serializes it) and writes one :class:`Step` per thing the subscriber circuit reads:
the 4-byte frame length, each fixed-size scalar (``time``/``duration`` as two: ``secs``,
``nsecs``), each ``uint32`` length prefix, each string's bytes, each array of numbers as one
block, and for arrays of messages, strings, times or durations a ``LOOP`` step, the steps of
one element, and an ``END`` step (the circuit walks the elements one by one). Each step says
what the circuit does with it (:class:`Action`): ``stream`` (the one numeric array the
application processes, as AXI4-Stream beats of the element's width), ``check`` (equal to a
value fixed at synthesis time, or within a bound; kept and re-sent), ``carry`` (kept and
written into the output message) or ``skip`` (read and dropped; the publisher writes the
field's default). Every length prefix is checked too (its maximum, from the configuration's
``limits:`` or the documented defaults ``config.limits.DEFAULT_STRING_MAX`` /
``DEFAULT_ARRAY_MAX``; the stream's must equal ``stream.length``). Renderers (the Python models,
the HLS C++, the Verilog) walk ``layout.steps`` and never need to know a message type: every
name, size, maximum and status code is in the steps.

Worked example: ``pkg/Scan`` = ``Header header``, ``string[] names``, ``float32[] ranges``,
``derive_layout(reg, "pkg/Scan", stream="ranges", stream_length=4, checks={"header.seq": 0})``;
:func:`format_layout` prints (a test holds this text equal to its output)::

    pkg/Scan (md5 115c5a6fcd20cb3c1c340cbd2d284ee1): stream ranges 4 x float32, body 40..16936 bytes
    #   kind      ident                   label                   type     bytes     max  action  check
    0   length    frame_length            frame length            uint32   4         -    check   SUB_BAD_FRAME_LENGTH: 40..67108864
    1   scalar    header_seq              header.seq              uint32   4         -    check   SUB_BAD_HEADER_SEQ: == 0
    2   scalar    header_stamp_secs       header.stamp.secs       uint32   4         -    carry   -
    3   scalar    header_stamp_nsecs      header.stamp.nsecs      uint32   4         -    carry   -
    4   length    header_frame_id_length  header.frame_id length  uint32   4         -    carry   SUB_BAD_HEADER_FRAME_ID_LENGTH: <= 256
    5   string    header_frame_id         header.frame_id         string   1 x [4]   256  carry   -
    6   length    names_length            names length            uint32   4         -    carry   SUB_BAD_NAMES_LENGTH: <= 64
    7   loop      names                   names                   string   0 x [6]   64   carry   -
    8     length  names_item_length       names[] length          uint32   4         -    carry   SUB_BAD_NAMES_ITEM_LENGTH: <= 256
    9     string  names_item              names[]                 string   1 x [8]   256  carry   -
    10  end       names                   names                   string   0         -    carry   -
    11  length    ranges_length           ranges length           uint32   4         -    stream  SUB_BAD_RANGES_LENGTH: == 4
    12  array     ranges                  ranges                  float32  4 x [11]  4    stream  -

(``x [11]``: as many elements as step 11 says). A frame's byte offsets follow from its values
(:func:`frame_geometry`); a refused field is named by its label with indices filled in
(``names[2] length``). Status codes: ``SUB_OK`` then one per checked step, in step order
(:attr:`Layout.statuses`), exactly as ``hw.interpreter.SUBSCRIBER_STATUSES`` does for Image.

Refusal order (what every renderer does, so models, C++ and RTL give the same status): when a
step completes, (1) step 0, the frame length: below ``min_body`` or above
``hw.limits.MAX_FRAME_BYTES`` -> ``SUB_BAD_FRAME_LENGTH``, nothing trusted, wait for the next
frame; (2) the step's own check (``EQUAL``, ``RANGE`` -- a NaN fails it --, ``MAX``) -> its
status; (3) a LENGTH step's :class:`LengthRule` (:func:`length_rules`): when only fixed-size
data follows, the frame must end exactly there (else ``SUB_BAD_FRAME_LENGTH``), otherwise its
elements must fit in the bytes left (else its own status); (4) on to the next step: LOOPs
with no elements and empty strings/arrays are passed at once; reaching the frame's end before
a step that has bytes, or inside one, refuses the frame (``SUB_BAD_FRAME_LENGTH``). After a
refusal with a sane frame length the rest of the frame is skipped.

:func:`tokens` lists a message's values in walk order (what the subscriber emits step by step)
and :func:`marshal` writes tokens back into a frame (what the publisher does): the two are
the layout's definition of the wire, tested against the ``msg`` layer. CDR, the second wire
format, is the same walk of the type's ROS 2 form with the kinds ``ENCAPSULATION`` and ``NUL``
and each step's alignment added (:mod:`rosfpga_lab.hw.cdrlayout`).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, NamedTuple

import numpy as np

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config import limits as config_limits
from rosfpga_lab.config.fields import (
    FieldPathError, check_field, check_value_problem, limit_field, resolve_field, stream_field,
)
from rosfpga_lab.config.vocabulary import STREAM_ELEMENT_TYPES
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import LayoutError
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.msg.builtins import SCALARS, TIME_CLASS


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


#: Words a renderer may not use as a name (C++ and Verilog keywords a field could be called).
_RESERVED = frozenset("""
    alignas alignof and asm auto bool break case catch char class const constexpr continue default
    delete do double else enum explicit extern false float for friend goto if inline int long
    mutable namespace new not operator or private protected public register return short signed
    sizeof static struct switch template this throw true try typedef typename union unsigned using
    virtual void volatile while xor
    always assign begin buf case casex casez cell config deassign defparam design disable edge
    end endcase endfunction endmodule endtask event force forever fork function initial inout
    input integer join localparam macromodule module negedge output parameter posedge reg real
    realtime release repeat signed specify supply0 supply1 task time tri wait wand wire wor
    logic ap_int ap_uint uint8_t uint16_t uint32_t uint64_t int8_t int16_t int32_t int64_t
    frame_length status state clk rst
""".split())
_FRAME_LENGTH = "frame_length"


class _Builder:
    def __init__(self, reg: MsgRegistry, stream: str, checks: Mapping[str, Any],
                 limits_: Mapping[str, int], skip: frozenset[str]) -> None:
        self.reg = reg
        self.stream = stream
        self.checks = checks
        self.limits = limits_
        self.skip = skip
        self.raw: list[dict[str, Any]] = []
        self.idents: set[str] = {_FRAME_LENGTH}

    def ident(self, base: str) -> str:
        name = base.replace(".", "_")
        if name in _RESERVED:
            name += "_f"
        out, n = name, 2
        while out in self.idents:
            out, n = f"{name}_{n}", n + 1
        self.idents.add(out)
        return out

    def add(self, **kw: Any) -> int:
        kw.setdefault("partner", None)
        kw.setdefault("length_step", None)
        kw.setdefault("check", None)
        self.raw.append(kw)
        return len(self.raw) - 1

    def action(self, path: str, inherited: Action | None) -> Action:
        if inherited is Action.SKIP:
            return Action.SKIP
        if path == self.stream:
            return Action.STREAM
        if path in self.checks:
            return Action.CHECK
        if path in self.skip:
            return Action.SKIP
        return Action.CARRY

    def maximum(self, path: str, string: bool) -> int:
        if path in self.limits:
            return int(self.limits[path])
        return config_limits.DEFAULT_STRING_MAX if string else config_limits.DEFAULT_ARRAY_MAX

    def length(self, path: str, label: str, ident: str, rel: tuple[str, ...], depth: int,
               action: Action, maximum: int) -> int:
        return self.add(kind=StepKind.LENGTH, ident=self.ident(ident + "_length"),
                        label=label + " length", path=path, type="uint32", size=4, count=1,
                        max_count=1, action=action, depth=depth, dtype="<u4", rel=rel,
                        check=("max", maximum))

    def scalar(self, path: str, label: str, ident: str, type_: str, rel: tuple[str, ...],
               depth: int, action: Action) -> None:
        sc = SCALARS[type_]
        check = ("user", path) if action is Action.CHECK else None
        self.add(kind=StepKind.SCALAR, ident=self.ident(ident), label=label, path=path,
                 type=type_, size=sc.size, count=1, max_count=1, action=action, depth=depth,
                 dtype=sc.dtype.str, rel=rel, check=check)

    def string(self, path: str, label: str, ident: str, rel: tuple[str, ...], depth: int,
               action: Action, maximum: int) -> None:
        n = self.length(path, label, ident, rel, depth, action, maximum)
        check = ("user", path) if action is Action.CHECK else None
        i = self.add(kind=StepKind.STRING, ident=self.ident(ident), label=label, path=path,
                     type="string", size=1, count=None, length_step=n, max_count=maximum,
                     action=action, depth=depth, dtype="|u1", rel=rel, check=check)
        self.raw[n]["partner"] = i

    def time(self, path: str, label: str, ident: str, type_: str, rel: tuple[str, ...],
             depth: int, action: Action) -> None:
        half = "uint32" if type_ == "time" else "int32"
        for part in ("secs", "nsecs"):
            self.scalar(f"{path}.{part}", f"{label}.{part}", f"{ident}_{part}", half,
                        rel + (part,), depth, action)

    def message(self, type_name: str, path: str, label: str, ident: str, depth: int,
                inherited: Action | None, rel: tuple[str, ...]) -> None:
        spec = self.reg.check(type_name)
        for f in spec.fields:
            fpath = f"{path}.{f.name}" if path else f.name
            flabel = f"{label}.{f.name}" if label else f.name
            fident = f"{ident}_{f.name}" if ident else f.name
            self.field(f.base_type, f.is_array, f.array_length, fpath, flabel, fident, depth,
                       self.action(fpath, inherited), rel + (f.name,))

    def field(self, base: str, is_array: bool, n: int | None, path: str, label: str,
              ident: str, depth: int, action: Action, rel: tuple[str, ...]) -> None:
        if not is_array:
            if base in SCALARS:
                self.scalar(path, label, ident, base, rel, depth, action)
            elif base in TIME_CLASS:
                self.time(path, label, ident, base, rel, depth, action)
            elif base == "string":
                self.string(path, label, ident, rel, depth, action, self.maximum(path, True))
            else:
                self.message(base, path, label, ident, depth, action, rel)
            return
        maximum = n if n is not None else self.maximum(path, False)
        length_step = None
        if n is None:
            length_step = self.length(path, label, ident, rel, depth, action, maximum)
        if base in SCALARS:
            sc = SCALARS[base]
            i = self.add(kind=StepKind.ARRAY, ident=self.ident(ident), label=label, path=path,
                         type=base, size=sc.size, count=n, length_step=length_step,
                         max_count=maximum, action=action, depth=depth, dtype=sc.dtype.str,
                         rel=rel)
        else:
            loop_ident = self.ident(ident)
            i = self.add(kind=StepKind.LOOP, ident=loop_ident, label=label, path=path, type=base,
                         size=0, count=n, length_step=length_step, max_count=maximum,
                         action=action, depth=depth, dtype="", rel=rel)
            elabel = label + "[]"
            if base in TIME_CLASS:
                self.time(path, elabel, ident, base, (), depth + 1, action)
            elif base == "string":
                self.string(path, elabel, ident + "_item", (), depth + 1, action,
                            self.maximum(path + "[]", True))
            else:
                self.message(base, path, elabel, ident, depth + 1, action, ())
            end = self.add(kind=StepKind.END, ident=loop_ident, label=label, path=path,
                           type=base, size=0, count=n, max_count=maximum, action=action,
                           depth=depth, dtype="", rel=rel, partner=i)
            self.raw[i]["partner"] = end
        if length_step is not None:
            self.raw[length_step]["partner"] = i


def _user_check(reg: MsgRegistry, type_name: str, path: str, spec: Any, status: str
                ) -> FieldCheck:
    key = f"checks.{path}"
    f = check_field(reg, type_name, path)
    base = f.base_type
    if isinstance(spec, Mapping):
        unknown = set(spec) - {"min", "max"}
        if unknown or not spec:
            raise LayoutError("a bound is {min: LOW, max: HIGH} (either may be left out)", key)
        if base in ("string", "bool"):
            raise LayoutError(f"a {base} can only be checked for equality", key)
        low, high = spec.get("min"), spec.get("max")
        for v in (low, high):
            if v is not None:
                _value_problem(base, v, key)
        if low is not None and high is not None and low > high:
            raise LayoutError(f"min {low} is above max {high}", key)
        return FieldCheck(CheckOp.RANGE, status, low=low, high=high)
    _value_problem(base, spec, key)
    value = float(spec) if base in ("float32", "float64") else spec
    if base == "float32":
        value = struct.unpack("<f", struct.pack("<f", value))[0]
    return FieldCheck(CheckOp.EQUAL, status, value=value)


def _value_problem(base: str, value: Any, key: str) -> None:
    problem = check_value_problem(base, value)
    if problem:
        raise LayoutError(problem, key)


def derive_layout(reg: MsgRegistry, type_name: str, *, stream: str | None,
                  stream_length: int | None = None, checks: Mapping[str, Any] | None = None,
                  limits_: Mapping[str, int] | None = None, skip: Iterable[str] = (),
                  video: VideoShape | None = None) -> Layout:
    """Derive the circuit's walk over frames of ``type_name``.

    Args:
        reg: the registry holding the type (``default_registry()`` or ``registry_with(paths)``).
        type_name: the subscribed message type.
        stream: dotted path of the array the application processes (``ranges``); ``None``
            for a walk without one (every array carried: a layout to look at, not a circuit).
        stream_length: its element count (required for a variable-length array; a fixed one's
            must equal ``N``).
        checks: ``{path: value}`` (equality) or ``{path: {"min": a, "max": b}}`` (bounds).
        limits_: ``{path: max}`` for strings (bytes) and variable arrays (elements); the
            element strings of a string array are ``path[]``; others get the defaults
            ``config.limits.DEFAULT_STRING_MAX`` / ``DEFAULT_ARRAY_MAX``.
        skip: paths whose values the circuit drops (the publisher writes their defaults).
        video: the stream's video shape (``sensor_msgs/Image``'s ``data``).

    Raises:
        LayoutError: a key names a missing field or one it cannot take (``key`` says which).
    """
    checks = dict(checks or {})
    limits_ = dict(limits_ or {})
    spec_reg = reg
    if stream is None:
        stream_length = 0
    else:
        try:
            f = stream_field(reg, type_name, stream)
        except FieldPathError as exc:
            raise LayoutError(str(exc), "stream.field") from None
        if f.array_length is not None:
            if stream_length is not None and stream_length != f.array_length:
                raise LayoutError(f"{stream} is a {f.type}: its length is {f.array_length}, "
                                  f"not {stream_length}", "stream.length")
            stream_length = f.array_length
        if stream_length is None or not 0 <= stream_length <= config_limits.MAX_STREAM_LENGTH:
            raise LayoutError(f"give the element count of {stream} (0.."
                              f"{config_limits.MAX_STREAM_LENGTH})", "stream.length")
    for path, value in limits_.items():
        key = f"limits.{path}"
        try:
            limit_field(reg, type_name, path.removesuffix("[]"))
        except FieldPathError as exc:
            raise LayoutError(str(exc), key) from None
        if isinstance(value, bool) or not isinstance(value, int) or \
                not 0 <= value <= config_limits.MAX_LIMIT:
            raise LayoutError(f"expected 0..{config_limits.MAX_LIMIT}, got {value!r}", key)
    for path in checks:
        if path == stream:
            raise LayoutError(f"{path} is the stream; check its length with stream.length",
                              f"checks.{path}")
        try:
            check_field(reg, type_name, path)
        except FieldPathError as exc:
            raise LayoutError(str(exc), f"checks.{path}") from None
    skip_set = frozenset(skip)
    for path in skip_set:
        try:
            resolve_field(reg, type_name, path)
        except FieldPathError as exc:
            raise LayoutError(str(exc), f"skip.{path}") from None
        if stream is not None and (path == stream or stream.startswith(path + ".")):
            raise LayoutError("the stream cannot be skipped", f"skip.{path}")
    if stream is not None:
        limits_[stream] = stream_length

    b = _Builder(spec_reg, stream or "", checks, limits_, skip_set)
    b.add(kind=StepKind.LENGTH, ident=_FRAME_LENGTH, label="frame length", path="",
          type="uint32", size=4, count=1, max_count=1, action=Action.CHECK, depth=0,
          dtype="<u4", rel=(), check=("frame", 0))
    b.message(type_name, "", "", "", 0, None, ())
    steps: list[Step] = []
    stream_index: int | None = None
    for i, kw in enumerate(b.raw):
        check = None
        ident = kw["ident"]
        status = f"SUB_BAD_{ident.upper()}"
        spec_check = kw.pop("check")
        if spec_check is not None:
            what, arg = spec_check
            if what == "frame":
                check = FieldCheck(CheckOp.RANGE, status, low=0,   # set below: min_body
                                   high=limits.MAX_FRAME_BYTES)
            elif what == "user":
                check = _user_check(reg, type_name, arg, checks[arg], status)
            elif kw["action"] is Action.STREAM:
                check = FieldCheck(CheckOp.EQUAL, status, value=stream_length)
            else:
                check = FieldCheck(CheckOp.MAX, status, high=arg)
        step = Step(index=i, check=check, **kw)
        if step.kind is StepKind.ARRAY and step.action is Action.STREAM:
            stream_index = i
        steps.append(step)
    statuses = (("SUB_OK", "frame accepted"),) + tuple(
        (s.check.status, s.label) for s in steps if s.check is not None)
    layout = Layout(type_name=type_name, md5=reg.md5(type_name), steps=tuple(steps),
                    stream_index=stream_index, stream_length=stream_length,
                    min_body=0, max_body=0, statuses=statuses, video=video)
    return _with_min_body(_with_max_body(layout))


def _with_min_body(layout: Layout) -> Layout:
    """The layout with ``min_body`` (and the frame length's lower bound) the shortest body its
    checks accept: the type's smallest body plus the stream's elements and the bytes of any
    string checked for one value. A video stream (Image) keeps the type's smallest body, as
    the Image interpreter's ``MIN_BODY_BYTES`` does: a frame of another geometry is refused
    by the field that differs (``width``), not by its length."""
    from dataclasses import replace

    low = _min_bytes(layout, 1, len(layout.steps), accepted=layout.video is None)
    frame = layout.steps[0]
    assert frame.check is not None
    first = replace(frame, check=replace(frame.check, low=low))
    return replace(layout, steps=(first,) + layout.steps[1:], min_body=low)


def _with_max_body(layout: Layout) -> Layout:
    from dataclasses import replace

    def size(lo: int, hi: int) -> int:
        total, i = 0, lo
        while i < hi:
            s = layout.steps[i]
            n = s.max_count if s.count is None else s.count
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                total += n * size(i + 1, s.partner)
                i = s.partner + 1
                continue
            total += s.size * (1 if s.kind in (StepKind.SCALAR, StepKind.LENGTH) else n)
            i += 1
        return total

    return replace(layout, max_body=size(1, len(layout.steps)))


# -- how length prefixes are held against the frame ------------------------------------------

def _min_bytes(layout: Layout, lo: int, hi: int, *, accepted: bool = False) -> int:
    """Fewest bytes steps ``lo..hi-1`` can take (variable parts empty); with ``accepted``, the
    fewest the checks accept (the stream holds ``stream_length`` elements, a string checked
    for one value holds it)."""
    total, i = 0, lo
    while i < hi:
        s = layout.steps[i]
        if s.kind is StepKind.LOOP:
            assert s.partner is not None
            if s.count is not None:
                total += s.count * _min_bytes(layout, i + 1, s.partner, accepted=accepted)
            i = s.partner + 1
            continue
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH):
            total += s.size
        elif s.count is not None:
            total += s.size * s.count
        elif accepted and s.index == layout.stream_index:
            total += s.size * layout.stream_length
        elif accepted and s.kind is StepKind.STRING and s.check is not None \
                and s.check.op is CheckOp.EQUAL:
            total += len(str(s.check.value).encode("utf-8"))
        i += 1
    return total


def _fixed_bytes(layout: Layout, lo: int, hi: int) -> int | None:
    """Bytes of steps ``lo..hi-1`` if they are all fixed-size, else None."""
    total, i = 0, lo
    while i < hi:
        s = layout.steps[i]
        if s.is_variable or s.kind is StepKind.STRING:
            return None
        if s.kind is StepKind.LOOP:
            assert s.partner is not None and s.count is not None
            inner = _fixed_bytes(layout, i + 1, s.partner)
            if inner is None:
                return None
            total += s.count * inner
            i = s.partner + 1
            continue
        total += s.size * (s.count if s.count is not None else 1)
        i += 1
    return total


class LengthRule(NamedTuple):
    """How a LENGTH step's value is held against the frame length (after its own check).

    Attributes:
        element_min: fewest bytes one counted element takes (1 for a string's byte).
        fixed_after: when the counted elements and everything after them are fixed-size (and
            the step is in no loop): the bytes after the counted part, so the frame length must
            equal ``offset + value * element_min + fixed_after`` exactly (else a
            ``frame length`` refusal, as Image's ``data length``); otherwise ``None`` and only
            ``value * element_min <= bytes left`` is required (else ``past the frame end``).
    """

    element_min: int
    fixed_after: int | None


def length_rules(layout: Layout) -> dict[int, LengthRule]:
    """The :class:`LengthRule` of every LENGTH step but the frame length, by step index."""
    rules: dict[int, LengthRule] = {}
    steps = layout.steps
    for s in steps:
        if s.kind is not StepKind.LENGTH or s.partner is None:
            continue
        part = steps[s.partner]
        exact = True
        if part.kind is StepKind.LOOP:
            assert part.partner is not None
            element_min = _min_bytes(layout, part.index + 1, part.partner)
            exact = _fixed_bytes(layout, part.index + 1, part.partner) is not None
            end = part.partner + 1
        else:
            element_min = part.size
            end = part.index + 1
        rules[s.index] = LengthRule(element_min, _fixed_bytes(layout, end, len(steps))
                                    if s.depth == 0 and exact else None)
    return rules


# -- values in walk order ----------------------------------------------------------------------

class Token(NamedTuple):
    """One value of a frame in walk order: the step, what it read (LENGTH: the count;
    SCALAR: int/float/bool; STRING: str; ARRAY: numpy array; LOOP and END have none) and the
    element indices of the enclosing LOOPs (``step.label_at(token.at)`` names it)."""

    step: int
    value: Any
    at: tuple[int, ...] = ()


def _get(obj: Any, rel: tuple[str, ...]) -> Any:
    for name in rel:
        obj = obj[name] if isinstance(obj, Mapping) else getattr(obj, name)
    return obj


def tokens(layout: Layout, message: Any) -> list[Token]:
    """The values of ``message`` (as ``msg.deserialize`` returns it, or any object with the
    attributes) in the circuit's walk order, without the frame length (step 0).

    This is what the subscriber reads, field by field; :func:`marshal` writes them back.
    """
    out: list[Token] = []
    steps = layout.steps

    def walk(lo: int, hi: int, obj: Any, at: tuple[int, ...]) -> None:
        i = lo
        while i < hi:
            s = steps[i]
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                for k, element in enumerate(_get(obj, s.rel)):
                    walk(i + 1, s.partner, element, at + (k,))
                i = s.partner + 1
                continue
            value = _get(obj, s.rel)
            if s.kind is StepKind.LENGTH:
                value = len(value.encode("utf-8", "surrogateescape")) if isinstance(value, str) \
                    else len(value)
            elif s.kind is StepKind.ARRAY:
                value = (np.frombuffer(bytes(value), np.uint8)
                         if isinstance(value, (bytes, bytearray, memoryview))
                         else np.asarray(value, dtype=np.dtype(s.dtype)))
            elif s.kind is StepKind.SCALAR:
                value = bool(value) if s.type == "bool" else value
            out.append(Token(i, value, at))
            i += 1

    walk(1, len(steps), message, ())
    return out


def encode_token(step: Step, value: Any) -> bytes:
    """The wire bytes of one token."""
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        return struct.pack("<" + (SCALARS[step.type].struct_char), value)
    if step.kind is StepKind.STRING:
        return value.encode("utf-8", "surrogateescape") if isinstance(value, str) else bytes(value)
    if step.kind is StepKind.ARRAY:
        return np.ascontiguousarray(value, dtype=np.dtype(step.dtype)).tobytes()
    raise ValueError(f"step {step.index} ({step.kind}) has no bytes")


def marshal(layout: Layout, toks: Iterable[Token]) -> bytes:
    """A TCPROS frame (4-byte length + body) from tokens in walk order (the publisher)."""
    body = b"".join(encode_token(layout.steps[t.step], t.value) for t in toks)
    return struct.pack("<I", len(body)) + body


class FrameGeometry(NamedTuple):
    """Where a frame's parts are, for given values.

    Attributes:
        frame_length: the 4-byte frame length's value (bytes of the body).
        stream_offset: byte offset in the frame (0 = first byte of the frame length) of the
            streamed array's first element.
        stream_bytes: bytes of the streamed array (both -1 without a stream).
    """

    frame_length: int
    stream_offset: int
    stream_bytes: int


def frame_geometry(layout: Layout, message: Any) -> FrameGeometry:
    """Frame length and stream offset of ``message`` (the values of the layout's type)."""
    offset = 4
    stream_offset = stream_bytes = -1
    for t in tokens(layout, message):
        n = len(encode_token(layout.steps[t.step], t.value))
        if t.step == layout.stream_index:
            stream_offset, stream_bytes = offset, n
        offset += n
    return FrameGeometry(offset - 4, stream_offset, stream_bytes)


# -- text ---------------------------------------------------------------------------------------

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
    "Action", "CheckOp", "FieldCheck", "FrameGeometry", "Layout", "LengthRule", "Step", "StepKind",
    "Token", "length_rules",
    "VideoShape", "STREAM_ELEMENT_TYPES", "derive_layout", "encode_token", "format_layout",
    "frame_geometry", "marshal", "tokens",
]


def layout_from_config(config: NodeConfig, reg: MsgRegistry | None = None, *,
                       output: bool = False) -> Layout:
    """The layout of a node configuration's subscribed (or, with ``output``, published) type.

    ``sensor_msgs/Image``: stream ``data`` with the video shape of ``image:``, checks of
    ``height``, ``width``, ``encoding`` and ``step`` equal to it, ``encoding`` at most
    ``hw.limits.MAX_ENCODING_BYTES``. Every type: ``header.frame_id`` (when there is one) at most
    ``frame_id_max`` unless ``limits:`` says otherwise. A publisher of another type than the
    subscriber's has no checks and skips nothing (it writes what it carries, defaults for the
    rest); its maxima are the ``limits:`` entries whose paths it has.

    Args:
        config: a loaded configuration.
        reg: its registry (default: ``config.registry()``).
        output: the publisher's type instead of the subscriber's.
    """
    reg = reg or config.registry()
    type_name = config.publisher.type if output else config.subscriber.type
    assert config.stream is not None
    # the publisher's own type checks nothing; its maxima are those of the paths it has
    other = output and type_name != config.subscriber.type
    checks: dict[str, Any] = {} if other else {c.path: c.spec for c in config.checks}
    maxima: dict[str, int] = {}
    try:
        resolve_field(reg, type_name, _FRAME_ID)
        maxima[_FRAME_ID] = config.frame_id_max
    except FieldPathError:
        pass
    video = None
    length = config.stream.length
    if config.is_image and type_name == config_limits.IMAGE_TYPE:
        im = config.image  # (its data_bytes: a replaced image: keeps the stream in step)
        checks.update(height=im.height, width=im.width, encoding=im.encoding, step=im.step)
        maxima["encoding"] = limits.MAX_ENCODING_BYTES
        video = VideoShape(im.width, im.height, im.encoding, im.bytes_per_pixel)
        length = im.data_bytes
    for path, value in config.limits:
        if other:
            try:
                limit_field(reg, type_name, path.removesuffix("[]"))
            except FieldPathError:
                continue
        maxima[path] = value
    return derive_layout(reg, type_name, stream=config.stream.field,
                         stream_length=length, checks=checks, limits_=maxima,
                         skip=() if other else config.skip, video=video)


_FRAME_ID = "header.frame_id"
__all__ += ["layout_from_config"]
