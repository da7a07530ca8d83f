"""Deriving the circuit layout from a ``.msg`` and the node configuration.

How this works: :func:`derive_layout` first holds every key of the configuration against the
type (the stream, ``limits:``, ``checks:``, ``skip:``: a missing field or one it cannot take is
a :class:`~rosfpga_lab.hw.errors.LayoutError` naming the key), then walks the type in wire
order, one :class:`~rosfpga_lab.hw.layoutsteps.Step` per thing the subscriber circuit reads
(``_Builder``), gives each its check and status code, and measures the shortest and longest
body the checks accept. :func:`layout_from_config` gathers those keys from a loaded
configuration (``sensor_msgs/Image``'s video shape and checks included). The rules the walk
follows are told in :mod:`rosfpga_lab.hw.layout`.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping
from typing import Any

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config import limits as config_limits
from rosfpga_lab.config.fields import (
    FieldPathError, check_field, check_value_problem, limit_field, resolve_field, stream_field,
)
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import LayoutError
from rosfpga_lab.hw.layoutlengths import min_bytes
from rosfpga_lab.hw.layoutsteps import (
    Action, CheckOp, FieldCheck, Layout, Step, StepKind, VideoShape,
)
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.msg.builtins import SCALARS, TIME_CLASS


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
    length = _stream_length(reg, type_name, stream, stream_length)
    _check_limits(reg, type_name, limits_)
    _check_checks(reg, type_name, stream, checks)
    skip_set = _skipped(reg, type_name, stream, skip)
    if stream is not None:
        limits_[stream] = length

    b = _Builder(reg, stream or "", checks, limits_, skip_set)
    b.add(kind=StepKind.LENGTH, ident=_FRAME_LENGTH, label="frame length", path="",
          type="uint32", size=4, count=1, max_count=1, action=Action.CHECK, depth=0,
          dtype="<u4", rel=(), check=("frame", 0))
    b.message(type_name, "", "", "", 0, None, ())
    steps: list[Step] = []
    stream_index: int | None = None
    for i, kw in enumerate(b.raw):
        check = _step_check(reg, type_name, kw, checks, length)
        step = Step(index=i, check=check, **kw)
        if step.kind is StepKind.ARRAY and step.action is Action.STREAM:
            stream_index = i
        steps.append(step)
    statuses = (("SUB_OK", "frame accepted"),) + tuple(
        (s.check.status, s.label) for s in steps if s.check is not None)
    layout = Layout(type_name=type_name, md5=reg.md5(type_name), steps=tuple(steps),
                    stream_index=stream_index, stream_length=length,
                    min_body=0, max_body=0, statuses=statuses, video=video)
    return _with_min_body(_with_max_body(layout))


def _stream_length(reg: MsgRegistry, type_name: str, stream: str | None,
                   stream_length: int | None) -> int:
    """The stream's element count: 0 without a stream, a fixed array's ``N``, else the one
    given (which must be within ``config.limits.MAX_STREAM_LENGTH``)."""
    if stream is None:
        return 0
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
    return stream_length


def _check_limits(reg: MsgRegistry, type_name: str, limits_: Mapping[str, int]) -> None:
    """Each ``limits:`` key names a string or variable array of the type, with a sane value."""
    for path, value in limits_.items():
        key = f"limits.{path}"
        try:
            limit_field(reg, type_name, path.removesuffix("[]"))
        except FieldPathError as exc:
            raise LayoutError(str(exc), key) from None
        if isinstance(value, bool) or not isinstance(value, int) or \
                not 0 <= value <= config_limits.MAX_LIMIT:
            raise LayoutError(f"expected 0..{config_limits.MAX_LIMIT}, got {value!r}", key)


def _check_checks(reg: MsgRegistry, type_name: str, stream: str | None,
                  checks: Mapping[str, Any]) -> None:
    """Each ``checks:`` key names a field that can be checked, and not the stream."""
    for path in checks:
        if path == stream:
            raise LayoutError(f"{path} is the stream; check its length with stream.length",
                              f"checks.{path}")
        try:
            check_field(reg, type_name, path)
        except FieldPathError as exc:
            raise LayoutError(str(exc), f"checks.{path}") from None


def _skipped(reg: MsgRegistry, type_name: str, stream: str | None,
             skip: Iterable[str]) -> frozenset[str]:
    """The ``skip:`` paths, each a field of the type and neither the stream nor around it."""
    skip_set = frozenset(skip)
    for path in skip_set:
        try:
            resolve_field(reg, type_name, path)
        except FieldPathError as exc:
            raise LayoutError(str(exc), f"skip.{path}") from None
        if stream is not None and (path == stream or stream.startswith(path + ".")):
            raise LayoutError("the stream cannot be skipped", f"skip.{path}")
    return skip_set


def _step_check(reg: MsgRegistry, type_name: str, kw: dict[str, Any],
                checks: Mapping[str, Any], stream_length: int) -> FieldCheck | None:
    """The check of the builder's step ``kw`` (its ``check`` entry taken out): the frame
    length's range (its low bound set later: ``min_body``), a ``checks:`` entry, the stream's
    length, or a length prefix's maximum."""
    spec_check = kw.pop("check")
    if spec_check is None:
        return None
    status = f"SUB_BAD_{kw['ident'].upper()}"
    what, arg = spec_check
    if what == "frame":
        return FieldCheck(CheckOp.RANGE, status, low=0, high=limits.MAX_FRAME_BYTES)
    if what == "user":
        return _user_check(reg, type_name, arg, checks[arg], status)
    if kw["action"] is Action.STREAM:
        return FieldCheck(CheckOp.EQUAL, status, value=stream_length)
    return FieldCheck(CheckOp.MAX, status, high=arg)


def _with_min_body(layout: Layout) -> Layout:
    """The layout with ``min_body`` (and the frame length's lower bound) the shortest body its
    checks accept: the type's smallest body plus the stream's elements and the bytes of any
    string checked for one value. A video stream (Image) keeps the type's smallest body, as
    the Image interpreter's ``MIN_BODY_BYTES`` does: a frame of another geometry is refused
    by the field that differs (``width``), not by its length."""
    from dataclasses import replace

    low = min_bytes(layout, 1, len(layout.steps), accepted=layout.video is None)
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
__all__ = ["derive_layout", "layout_from_config"]
