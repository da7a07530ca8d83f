"""Checks of notebook 3 (STEP 2): ``sensor_msgs/Image`` in bytes, extraction and marshalling."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rosfpga_lab.checks._core import (
    ByteField, CheckResult, as_bytes, describe_byte_difference, fail, field_at, require_answer,
    require_type,
)
from rosfpga_lab.checks.limits import MAX_READ_SHIFT
from rosfpga_lab.msg import MsgRegistry, default_registry, field_layout, serialize
from rosfpga_lab.tcpros import frame_spans

IMAGE = "sensor_msgs/Image"


def message_fields(type_name: str, body: bytes, *, base: int = 0,
                   registry: MsgRegistry | None = None) -> list[ByteField]:
    """Byte fields of a serialized message, named by field path (``... length`` for prefixes)."""
    reg = registry or default_registry()
    return [s.moved(base) for s in field_layout(reg, type_name, body, partial=True)]


def frame_fields(type_name: str, frame: bytes, registry: MsgRegistry | None = None) -> list[ByteField]:
    """Byte fields of a TCPROS frame: ``frame length``, then the message's fields
    (:func:`rosfpga_lab.tcpros.frame_spans`, the same spans the byte viewer shows)."""
    return frame_spans(frame, type_name, registry=registry)


def data_offset(fields: list[ByteField]) -> int:
    """Offset of the first byte of ``data`` (pixels) among an Image's fields."""
    return next(f.end for f in fields if f.label == "data length")


def check_data_offset(answer: Any, frame: bytes) -> CheckResult:
    """Exercise 3.1: the byte offset in a TCPROS Image frame where the pixel bytes begin.

    Raises:
        ExerciseError: a wrong offset (the field it points into is named).
    """
    ex = "3.1 (where the pixels start)"
    require_type(ex, "data_offset", answer, int)
    frame = bytes(frame)
    fields = frame_fields(IMAGE, frame)
    want = data_offset(fields)
    if answer == want:
        return CheckResult(ex, [f"pixels start at byte {want}: 4 (frame length) + "
                                f"{want - 4} bytes of message before 'data'"])
    if answer == want - 4:
        # two different mistakes land here; name both
        hint = ("either you counted from the start of the message body (the frame's 4-byte "
                "length comes first) - or you stopped where the uint32 length of 'data' starts "
                "(the pixels begin 4 bytes after it)")
    elif answer == want - 8:
        hint = ("off by 8: you left out both the frame's 4-byte length and the 4-byte length "
                "of 'data'")
    elif answer == want + 4:
        hint = "off by 4 too many: the frame length and each length prefix count once"
    else:
        f = _name_at(fields, answer)
        hint = (f"byte {answer} is inside field {f}" if f else
                f"byte {answer} is outside the {len(frame)}-byte frame")
    raise fail(ex, f"data_offset {answer}, expected another value: {hint}")


def _name_at(fields: list[ByteField], offset: int) -> str | None:
    f = field_at(fields, offset)
    return f.label if f else None


def check_marshal(answer: Any, message: Mapping[str, Any]) -> CheckResult:
    """Exercise 3.2: an Image message body written by hand (the publisher circuit's job).

    Args:
        answer: the reader's bytes (message body, no frame length).
        message: the message as a dict (what ``rosfpga_lab.msg.serialize`` takes).

    Raises:
        ExerciseError: the first differing field, e.g. ``byte 12 (field header.frame_id
            length, uint32 at bytes 12..15) is 5, expected 7``.
    """
    ex = "3.2 (marshal an Image)"
    got = as_bytes(ex, "body", answer)
    want = serialize(default_registry(), IMAGE, dict(message))
    if got == want:
        return CheckResult(ex, [f"{len(want)} bytes, equal to rospy's serialization: strings and "
                                "uint8[] carry a uint32 length, everything little-endian"])
    problems = []
    if got[4:] == want and int.from_bytes(got[:4], "little") == len(want):
        problems.append("you wrote a whole TCPROS frame; the exercise asks for the message body "
                        "(without the 4-byte frame length)")
    else:
        problems += describe_byte_difference(got, want, message_fields(IMAGE, want))
    raise fail(ex, *problems)


#: Exercise 3.3: the fields the reader extracts.
EXTRACTED = ("width", "height", "encoding", "step")


def _common_shift(frame: bytes, at: Mapping[str, int], wrong: Mapping[str, int]
                  ) -> tuple[int, frozenset[str]] | None:
    """The one offset error (in bytes, negative: read too early) that explains at least two
    wrong numbers, and which: the shift explaining the most of them (the smallest such on a
    tie), or None. Other wrong numbers may have other causes (``unpack_from("<II", mystery,
    27)`` shifts height and width; a step read after them from a wrong position is not).

    A value read a fixed distance from its field (the frame length forgotten: 4 bytes early)
    can look like a swap (width read 4 bytes early *is* the height); the shift is tested
    first, so the hint points at the cause.
    """
    if len(wrong) < 2:
        return None
    explains: dict[int, set[str]] = {}
    for key, value in wrong.items():
        for off in range(0, len(frame) - 3):
            if int.from_bytes(frame[off:off + 4], "little") == value and \
                    0 < abs(off - at[key]) <= MAX_READ_SHIFT:
                explains.setdefault(off - at[key], set()).add(key)
    best = sorted(((-len(keys), abs(d), d) for d, keys in explains.items() if len(keys) >= 2))
    if not best:
        return None
    shift = best[0][2]
    return shift, frozenset(explains[shift])


def check_extract(answer: Any, frame: bytes) -> CheckResult:
    """Exercise 3.3: fields extracted from a TCPROS Image frame (what the interpreter does).

    Args:
        answer: dict with ``width``, ``height``, ``encoding`` and ``step``.
        frame: the frame.

    Raises:
        ExerciseError: missing keys or wrong values (swapped width/height named).
    """
    ex = "3.3 (extract the fields)"
    require_answer(ex, "fields", answer)
    if not isinstance(answer, Mapping):
        raise fail(ex, f"fields should be a dict with keys {', '.join(EXTRACTED)}")
    missing = [k for k in EXTRACTED if k not in answer]
    if missing:
        raise fail(ex, f"keys missing: {', '.join(missing)}")
    frame = bytes(frame)
    spans = {s.path: s for s in field_layout(default_registry(), IMAGE, frame[4:])}
    want = {"width": spans["width"].value, "height": spans["height"].value,
            "encoding": spans["encoding"].value, "step": spans["step"].value}
    at = {k: spans[k].offset + 4 for k in ("width", "height", "step")}   # frame offsets
    wrong = {k: answer[k] for k in at if isinstance(answer[k], int) and answer[k] != want[k]}
    found = _common_shift(frame, at, wrong)
    shifted: frozenset[str] = frozenset() if found is None else found[1]
    problems = []
    if found is not None:
        shift = found[0]
        where = "early" if shift < 0 else "late"
        cause = (": did you leave out the frame's 4-byte length? Offsets in `mystery` count from "
                 "its first byte, and the message starts at byte 4" if shift == -4 else
                 ": count the bytes before each field again")
        problems.append(f"{' and '.join(sorted(shifted))} read {abs(shift)} bytes too {where} "
                        f"(each value is the uint32 {abs(shift)} bytes {'before' if shift < 0 else 'after'} "
                        f"its field){cause}")
    for key in EXTRACTED:
        have = answer[key]
        if key in shifted:
            continue
        if isinstance(have, bytes) and key == "encoding":
            problems.append(f"encoding is bytes {have!r}: decode it to str (.decode())")
            continue
        if have == want[key]:
            continue
        hint = ""
        if key in ("width", "height"):
            other = "height" if key == "width" else "width"
            if have == want[other]:
                hint = f": that is the {other}; in sensor_msgs/Image height comes before width"
        if key == "step" and have == want["width"]:
            hint = ": step is bytes per row (width x bytes per pixel), not pixels"
        problems.append(f"{key} is {have!r}, expected {want[key]!r}{hint}")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"{want['width']}x{want['height']} {want['encoding']}, step "
                            f"{want['step']} bytes per row"])
