"""Checks of notebook 10: your own message, your own circuit (any type's circuit layout).

How this works: every right answer comes from the layout's own models
(:mod:`rosfpga_lab.hw.walker`, :class:`rosfpga_lab.hw.msgpipeline.MessagePipeline`), which the
tests hold against the ``msg`` layer's serializer and real genpy. A wrong answer is explained
with the same vocabulary the notebook shows: the walk's field labels (``sensor length``),
their bytes in the frame, their checks and status codes.
"""

from __future__ import annotations

import dataclasses
import re
import struct
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rosfpga_lab.checks._core import CheckResult, fail, require_answer, require_type
from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hw.errors import FrameFieldError
from rosfpga_lab.hw.layout import Layout, Step, StepKind, encode_token, layout_from_config, tokens
from rosfpga_lab.hw.msgpipeline import MessagePipeline
from rosfpga_lab.hw.walker import extract_fast
from rosfpga_lab.msg import MsgRegistry, deserialize, serialize

#: Element counts exercise 10.2 tries the reader's ``clocks(n)`` with (besides the frame's own).
CLOCK_COUNTS = (1, 100, 4096)


def walk_spans(layout: Layout, message: Any) -> list[tuple[int, int, str]]:
    """``(offset in the frame, bytes, label)`` of every field the circuit reads, in walk order
    (indices filled in: ``history[1].sensor_name length``), starting with the frame length."""
    out = [(0, 4, layout.steps[0].label)]
    offset = 4
    for t in tokens(layout, message):
        step = layout.steps[t.step]
        n = len(encode_token(step, t.value))
        if n:
            out.append((offset, n, step.label_at(t.at)))
        offset += n
    return out


def _at(spans: list[tuple[int, int, str]], offset: int) -> tuple[int, int, str] | None:
    return next((s for s in spans if s[0] <= offset < s[0] + s[1]), None)


def check_stream_offset(answer: Any, frame: bytes, layout: Layout, reg: MsgRegistry, *,
                        shown: bytes | None = None) -> CheckResult:
    """Exercise 10.1: the byte offset in a TCPROS frame of the streamed array's first element
    (``shown``: another frame of the type the notebook showed, whose offset a reader may copy).

    Raises:
        ExerciseError: a wrong offset (the field it points into is named).
    """
    ex = "10.1 (where the stream starts)"
    require_type(ex, "stream_offset", answer, int)
    frame = bytes(frame)
    want = extract_fast(layout, frame).stream_offset
    stream = layout.stream.label
    if answer == want:
        return CheckResult(ex, [f"the elements of {stream} start at byte {want}: 4 (frame length) + "
                                f"{want - 4} bytes of message before them"])
    spans = walk_spans(layout, deserialize(reg, layout.type_name, frame[4:]))
    hit = _at(spans, int(answer))
    prefixes = [label for off, n, label in spans
                if off < want and n == 4 and (label.endswith(" length") or off == 0)]
    short = want - int(answer)
    shown_at = None if shown is None else extract_fast(layout, bytes(shown)).stream_offset
    if answer == want - 4 and hit is not None and hit[2] == f"{stream} length":
        hint = (f"that is where the uint32 '{stream} length' starts; the elements begin 4 bytes "
                "later (and did you count the frame's own 4-byte length?)")
    elif answer == shown_at:
        labels = {lab for _o, _n, lab in spans}
        counted = [f"{label} {n} bytes" for off, n, label in spans
                   if off < want and f"{label} length" in labels]
        hint = (f"{answer} is where the stream starts in the frame shown above, not in this one: "
                f"its strings have other lengths here ({', '.join(counted)})")
    elif 0 < short and (short % 4 == 0 and short // 4 <= len(prefixes) or
                        any(n == short for o, n, _l in spans if o < want)):
        k = short // 4
        same = [label for off, n, label in spans
                if off < want and n == short and label not in prefixes]
        ways = ([f"as many as {' or '.join(same)}"] if same else []) + (
            [f"{k} of the {len(prefixes)} four-byte length prefixes before the stream "
             f"({', '.join(prefixes)})"] if short % 4 == 0 and k <= len(prefixes) else [])
        hint = (f"{short} byte{'s' if short > 1 else ''} short: {', or '.join(ways)}; count "
                "every field and every length prefix once")
    elif hit is None:
        hint = f"byte {answer} is outside the {len(frame)}-byte frame"
    else:
        off, size, label = hit
        hint = f"byte {answer} is inside field {label} (bytes {off}..{off + size - 1})"
        if answer != off:
            hint += ", not where a field begins"
        if answer < want:
            after = [lab for o, n, lab in spans if off < o < want]
            hint += "; the elements begin after it" + (f" and {', '.join(after)}" if after
                                                        else "")
    raise fail(ex, f"stream_offset {answer}, expected another value: {hint}")


def _with_length(config: NodeConfig, n: int) -> NodeConfig:
    assert config.stream is not None
    return dataclasses.replace(config, stream=dataclasses.replace(config.stream, length=n))


def expected_clocks(config: NodeConfig, message: Mapping[str, Any], n: int) -> dict[str, int]:
    """Clocks per stage of one frame like ``message`` with ``n`` elements in the stream, through
    the circuit of ``config`` rebuilt for ``n`` (the model's count, :class:`MessagePipeline`)."""
    assert config.stream is not None
    reg = config.registry()
    layout = layout_from_config(_with_length(config, n), reg)
    dtype = np.dtype(layout.stream.dtype)
    values = np.zeros(n, dtype)
    body = serialize(reg, layout.type_name, {**message, config.stream.field: values})
    pipe = MessagePipeline(layout, config.application.op, config.application.ksize)
    return pipe.process(struct.pack("<I", len(body)) + body).cycles


def check_frame_clocks(answer: Any, config: NodeConfig, message: Mapping[str, Any]) -> CheckResult:
    """Exercise 10.2: ``clocks(n)``, the clocks one frame with ``n`` stream elements takes through
    subscriber, application and publisher (one after another, II=1).

    Raises:
        ExerciseError: ``answer`` is not a function, or its count is wrong for some ``n`` (the
            stage it most likely forgot is named).
    """
    ex = "10.2 (clocks per frame)"
    require_answer(ex, "clocks", answer)
    if not callable(answer):
        raise fail(ex, f"clocks should be a function of n, you gave {type(answer).__name__} "
                       "(def clocks(n): return ...)")
    assert config.stream is not None
    fn: Callable[[int], Any] = answer
    counts = (config.stream.length, *CLOCK_COUNTS)
    k = config.application.ksize
    elem = int(np.dtype(layout_from_config(config).stream.dtype).itemsize)
    checked = []
    for n in counts:
        c = expected_clocks(config, message, n)
        want = sum(c.values())
        try:
            got = fn(n)
        except Exception as exc:  # the reader's code: say what it raised
            raise fail(ex, f"clocks({n}) raised {type(exc).__name__}: {exc}") from None
        if got is None:
            raise fail(ex, f"clocks({n}) returned None: did you forget `return`?")
        require_type(ex, f"clocks({n})", got, int)
        frame = c["subscriber"]
        if got == want:
            checked.append(f"clocks({n}) = {want} = {frame} (subscriber, one byte per clock) + "
                           f"{c['application']} (application) + {c['publisher']} (publisher)")
            continue
        hints = {frame: "that is the subscriber alone: the application and the publisher take "
                        "clocks too",
                 2 * frame: f"the application takes clocks too: one per element, plus "
                            f"ksize // 2 = {k // 2} for its window",
                 2 * frame + n: f"the window of {k} elements adds ksize // 2 = {k // 2} clocks of "
                                "latency",
                 frame + c["application"]: "the publisher writes the output frame one byte per "
                                           "clock too",
                 want - 4: "count the frame's 4-byte length: the subscriber reads it too",
                 want - 8: "count the frame's 4-byte length twice: in and out"}
        shrink = (elem - 1) * n
        if elem > 1:
            hints.setdefault(want - 2 * shrink, f"an element is {elem} bytes on the wire, "
                                                "not one")
        hint = hints.get(got, f"{frame} (subscriber: the {frame}-byte frame) + "
                              f"{c['application']} (application: {n} elements + {k // 2}) + "
                              f"{c['publisher']} (publisher)")
        raise fail(ex, f"clocks({n}) is {got}, expected {want}: {hint}")
    return CheckResult(ex, checked)


def _step_of(layout: Layout, label: str) -> Step | None:
    """The step a label with indices filled in (``history[1].mode``) names."""
    bare = re.sub(r"\[\d+\]", "[]", label)
    return next((s for s in layout.steps if s.label == bare and s.kind is not StepKind.END), None)


def check_refused_field(answer: Any, frame: bytes, layout: Layout, reg: MsgRegistry) -> CheckResult:
    """Exercise 10.3: the field a refused frame is refused at, as the circuit names it (its
    label, ``sensor length``; the status code ``SUB_BAD_SENSOR_LENGTH`` is accepted too).

    Raises:
        ExerciseError: another field (whether the circuit accepts it, or refuses it only later).
    """
    ex = "10.3 (which field is refused)"
    require_type(ex, "refused_field", answer, str)
    frame = bytes(frame)
    try:
        extract_fast(layout, frame)
    except FrameFieldError as exc:
        refused = exc
    else:
        raise fail(ex, "the circuit accepts this frame: nothing to name (was it changed?)")
    label = refused.field
    step = _step_of(layout, label)
    status = step.check.status if step is not None and step.check is not None else ""
    given = answer.strip()
    if given == label or (status and given == status):
        return CheckResult(ex, [f"the circuit refuses the frame at {label} (byte {refused.offset}, "
                                f"{refused.rule}), status {status or 'SUB_BAD_FRAME_LENGTH'}",
                                f"it stops there: nothing after byte {refused.offset} is checked"])
    spans = walk_spans(layout, deserialize(reg, layout.type_name, frame[4:]))
    where: dict[str, int] = {}
    for off, _n, lab in spans:
        where.setdefault(lab, off)
    named = [s for s in layout.steps if s.check is not None and s.check.status == given]
    if named:
        given = named[0].label
    if given not in where:
        known = ", ".join(dict.fromkeys(lab for _o, _n, lab in spans))
        raise fail(ex, f"no field {answer!r} in this frame's walk; its fields are: {known}")
    off = where[given]
    value = struct.unpack_from("<I", frame)[0] if given == layout.steps[0].label else next(
        (t.value for t in tokens(layout, deserialize(reg, layout.type_name, frame[4:]))
         if layout.steps[t.step].label_at(t.at) == given and
         layout.steps[t.step].kind is not StepKind.LOOP), None)
    if off > refused.offset:
        raise fail(ex, f"{given} (byte {off}) comes after the refused field: the circuit stops at "
                       f"the first field it refuses, an earlier one")
    given_step = _step_of(layout, given)
    chk = given_step.check if given_step is not None else None
    rule = f" ({chk.describe()})" if chk is not None else " (no check)"
    raise fail(ex, f"{given} is {value!r} in this frame and the circuit accepts it{rule}; "
                   "look further on")


__all__ = ["CLOCK_COUNTS", "check_frame_clocks", "check_refused_field", "check_stream_offset",
           "expected_clocks", "walk_spans"]
