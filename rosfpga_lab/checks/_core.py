"""What every exercise check shares: the result, the error, and byte-by-byte explanations.

How this works: a check function compares the reader's answer with the right one and either
returns a :class:`CheckResult` (which a notebook shows as a green line saying what was right)
or raises :class:`ExerciseError` listing *what* is wrong, e.g. ``byte 12 (field
header.frame_id length, uint32 at bytes 12..15) is 5, expected 7``. The error renders in
IPython as those lines only (no traceback through the library), so a student sees the finding,
not the machinery. :func:`describe_byte_difference` is the workhorse of the byte-level checks:
given the expected bytes and a list of :class:`ByteField` it names the field of the first
differing byte and decodes numbers.
"""

from __future__ import annotations

import html
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rosfpga_lab.checks.limits import MAX_PROBLEMS, MAX_SHIFT, SHIFT_WINDOW
from rosfpga_lab.errors import LabError
from rosfpga_lab.msg.span import Span


_STRUCT = {"uint8": "<B", "int8": "<b", "uint16": "<H", "int16": "<h", "uint32": "<I",
           "int32": "<i", "uint64": "<Q", "int64": "<q", "float32": "<f", "float64": "<d",
           "bool": "<B", "char": "<B", "byte": "<b"}


class ExerciseError(LabError):
    """The answer to an exercise is not (yet) right.

    Attributes:
        exercise: the exercise's name, e.g. ``"3.2 marshal an Image"``.
        problems: what is wrong, one finding per entry.
    """

    def __init__(self, exercise: str, problems: Sequence[str]) -> None:
        self.exercise = exercise
        self.problems = list(problems)
        lines = [f"Exercise {exercise}: not right yet"]
        lines += [f"  - {p}" for p in self.problems[:MAX_PROBLEMS]]
        if len(self.problems) > MAX_PROBLEMS:
            lines.append(f"  ... and {len(self.problems) - MAX_PROBLEMS} more")
        super().__init__("\n".join(lines))

    def _render_traceback_(self) -> list[str]:
        """What IPython shows instead of a traceback: the findings, in red."""
        red, bold, reset = "\x1b[31m", "\x1b[1m", "\x1b[0m"
        text = str(self).splitlines()
        return [f"{red}{bold}\u2718 {text[0]}{reset}"] + [f"{red}{line}{reset}" for line in text[1:]]


@dataclass
class CheckResult:
    """A passed check: which exercise and what was verified.

    Attributes:
        exercise: the exercise's name.
        details: what the check verified, one line each.
    """

    exercise: str
    details: list[str] = field(default_factory=list)
    ok: bool = True

    def __str__(self) -> str:
        lines = [f"\u2714 Exercise {self.exercise}: correct"] + [f"  {d}" for d in self.details]
        return "\n".join(lines)

    __repr__ = __str__

    def _ipython_display_(self) -> None:
        """Show as display data, not as the cell's value: nbgrader would read a test cell's
        value as partial credit (and warns when it is not a number)."""
        from IPython.display import display

        display({"text/plain": str(self), "text/html": self._repr_html_()}, raw=True)

    def _repr_html_(self) -> str:
        items = "".join(f"<li>{html.escape(d)}</li>" for d in self.details)
        return (f"<div style='color:#1b7a32'><b>\u2714 Exercise {html.escape(self.exercise)}: "
                f"correct</b><ul style='margin:2px 0'>{items}</ul></div>")


def fail(exercise: str, *problems: str) -> ExerciseError:
    """An :class:`ExerciseError` to raise (``raise fail(...)``)."""
    return ExerciseError(exercise, [p for p in problems if p])


def require_answer(exercise: str, name: str, value: Any) -> None:
    """Refuse a placeholder answer (``...``, ``None``, ``NotImplemented``).

    Raises:
        ExerciseError: the answer is still a placeholder.
    """
    if value is ... or value is None or value is NotImplemented:
        raise fail(exercise, f"{name} is still {value!r}: replace it with your answer")


def require_type(exercise: str, name: str, value: Any, kinds: type | tuple[type, ...],
                 hint: str = "") -> None:
    """Refuse an answer of the wrong Python type (numpy scalars count as int/float, bool does not).

    Raises:
        ExerciseError: ``value`` is not an instance of ``kinds``.
    """
    require_answer(exercise, name, value)
    kinds_t = kinds if isinstance(kinds, tuple) else (kinds,)
    accepted = kinds_t + ((np.integer,) if int in kinds_t else ()) + (
        (np.integer, np.floating) if float in kinds_t else ())
    bad_bool = isinstance(value, (bool, np.bool_)) and bool not in kinds_t
    if bad_bool or not isinstance(value, accepted):
        want = " or ".join(k.__name__ for k in kinds_t)
        raise fail(exercise, f"{name} should be {want}, you gave {type(value).__name__} "
                             f"{_short(value)}" + (f" ({hint})" if hint else ""))


def as_bytes(exercise: str, name: str, value: Any) -> bytes:
    """``value`` as bytes (bytes, bytearray, memoryview or a uint8 numpy array)."""
    require_answer(exercise, name, value)
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    if hasattr(value, "dtype") and getattr(value, "dtype").itemsize == 1:
        return bytes(value.tobytes())
    raise fail(exercise, f"{name} should be bytes, you gave {type(value).__name__} {_short(value)} "
                         "(build it with struct.pack(...) and b''.join(...))")


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


#: A named run of bytes, for explaining a difference: the lab's one span type
#: (:class:`rosfpga_lab.msg.Span`); checks name bytes by its :attr:`~rosfpga_lab.msg.Span.label`.
ByteField = Span


def field_at(fields: Iterable[ByteField], offset: int) -> ByteField | None:
    """The field holding byte ``offset``, or None."""
    for f in fields:
        if f.offset <= offset < f.end:
            return f
    return None


def _decode(f: ByteField, data: bytes) -> Any:
    if f.end > len(data):
        return None
    raw = data[f.offset:f.end]
    fmt = _STRUCT.get(f.type)
    if fmt is not None and struct.calcsize(fmt) == f.size:
        return struct.unpack(fmt, raw)[0]
    if f.type == "string":
        return raw.decode("utf-8", "replace")
    return None


def _byte(b: int) -> str:
    shown = chr(b) if 32 <= b < 127 else ""
    return f"0x{b:02x} ({b}{', ' + repr(shown) if shown else ''})"




def _shift(got: bytes, expected: bytes, i: int) -> int:
    """``k > 0``: ``got`` has ``k`` extra bytes before ``i``; ``k < 0``: ``-k`` bytes missing; else 0."""
    for k in range(1, MAX_SHIFT + 1):
        want = expected[i:i + SHIFT_WINDOW]
        if len(want) >= 4 and got[i + k:i + k + len(want)] == want:
            return k
        have = got[i:i + SHIFT_WINDOW]
        if len(have) >= 4 and expected[i + k:i + k + len(have)] == have:
            return -k
    return 0


def _explain_shift(k: int, i: int, fields: Sequence[ByteField], got: bytes = b"") -> str:
    before = field_at(fields, i - 1) if i else None
    what = (f" (the field before is {before.label}, {before.type}: {before.size} byte"
            f"{'s' if before.size != 1 else ''})" if before else "")
    if k > 0:
        pad = ""
        if (before is not None and before.end == i and before.size < 4 and k == 4 - before.size
                and not any(got[i:i + k])):
            pad = (f": {k} zero byte(s) follow {before.label}, which is what struct's native mode "
                   "adds (a format without '<', such as 'BI' or '@BI', pads the uint32 after it "
                   "to a multiple of 4; ROS messages have no padding, so start every format "
                   f"with '<'), or {before.label} was packed as a 4-byte integer")
        return (f"from byte {i} on your bytes are the expected ones {k} byte(s) later: something "
                f"before byte {i} is {k} byte(s) too long{what}{pad}")
    here = field_at(fields, i)
    if here is not None and here.offset == i and here.size == -k:
        return (f"field {here.label} ({here.type}, {here.size} byte(s) at {i}..{here.end - 1}) is "
                "missing: your bytes go on with what follows it")
    return (f"from byte {i} on your bytes are the expected ones {-k} byte(s) early: something "
            f"before byte {i} is {-k} byte(s) too short or missing{what}")


def describe_byte_difference(got: bytes, expected: bytes, fields: Sequence[ByteField],
                             limit: int = 3) -> list[str]:
    """Say where ``got`` first departs from ``expected``, naming the field and its value.

    Args:
        got: the reader's bytes.
        expected: the right bytes.
        fields: the fields of ``expected`` (offsets into it).
        limit: at most this many differing fields are described.

    Returns:
        Findings (empty when the bytes are equal).
    """
    if got == expected:
        return []
    out: list[str] = []
    n = min(len(got), len(expected))
    seen: set[int] = set()  # ids of the fields already described
    i = 0
    while i < n and len(out) < limit:
        if got[i] == expected[i]:
            i += 1
            continue
        f = field_at(fields, i)
        if id(f) in seen:
            i += 1
            continue
        seen.add(id(f))
        if f is None:
            out.append(f"byte {i} is {_byte(got[i])}, expected {_byte(expected[i])}")
            i += 1
            continue
        want, have = _decode(f, expected), _decode(f, got)
        where = f"field {f.label}"
        if f.size > 1:
            where += f", {f.type} at bytes {f.offset}..{f.end - 1}"
        shift = _shift(got, expected, i)
        if want is not None and have is not None:
            # a shifted stream can look byte-swapped (zero padding before a small value); the
            # shift is the real cause, so it alone is named
            swapped = (not shift and f.size > 1 and f.end <= len(got)
                       and got[f.offset:f.end] == expected[f.offset:f.end][::-1])
            out.append(f"byte {i} ({where}) is {have!r}, expected {want!r}"
                       + (": its bytes are in big-endian order; ROS is little-endian "
                          "(struct format '<')" if swapped else ""))
        else:
            out.append(f"byte {i} ({where}) is {_byte(got[i])}, expected {_byte(expected[i])}")
        if shift:
            out.append(_explain_shift(shift, i, fields, got))
            return out  # everything after a shift differs; listing it would only confuse
        # differences inside one field count once; continue after it
        i = max(i + 1, f.end)
    if len(out) < limit and len(got) != len(expected):
        if len(got) < len(expected):
            f = field_at(fields, len(got))
            out.append(f"your bytes end after {len(got)} bytes, expected {len(expected)}"
                       + (f" (missing from field {f.label} on)" if f else ""))
        else:
            out.append(f"you have {len(got) - len(expected)} byte(s) too many: {len(got)} bytes, "
                       f"expected {len(expected)}")
    return out
