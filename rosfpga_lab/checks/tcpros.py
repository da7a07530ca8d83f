"""Checks of notebook 2 (STEP 1b): connection headers, md5 sums and message framing."""

from __future__ import annotations

import hashlib
import re
import struct
from collections.abc import Mapping
from typing import Any

from rosfpga_lab.checks._core import (
    ByteField, CheckResult, as_bytes, describe_byte_difference, fail, require_answer,
)
from rosfpga_lab.msg import MsgRegistry, default_registry, strip_comments
from rosfpga_lab.tcpros import FrameDecoder, encode_header, parse_fields


def header_fields(raw: bytes) -> list[ByteField]:
    """Byte fields of an encoded connection header (total length, then length + text per field)."""
    fields = [ByteField(0, 4, "total length", "uint32")]
    spans = parse_fields(raw[4:], base_offset=4)
    for length, text in zip(spans[::2], spans[1::2]):  # a length prefix, then its key=value
        fields.append(ByteField(length.offset, 4, f"length of field '{text.path}=...'", "uint32"))
        fields.append(ByteField(text.offset, text.size, f"text '{text.path}={text.value}'", "bytes"))
    return fields


def check_connection_header(answer: Any, fields: Mapping[str, str]) -> CheckResult:
    """Exercise 2.1: a connection header built by hand with ``struct``.

    Args:
        answer: the reader's bytes.
        fields: the ``key -> value`` fields it should hold.

    Raises:
        ExerciseError: the bytes differ (the first differing field is named).
    """
    ex = "2.1 (connection header by hand)"
    got = as_bytes(ex, "header", answer)
    want = encode_header(fields)
    if got == want:
        return CheckResult(ex, [f"{len(got)} bytes: a 4-byte total length ({len(want) - 4}), then "
                                f"{len(fields)} fields sorted by key, each with its own length"])
    problems = []
    if got == want[4:]:
        problems.append("the 4-byte total length at the start is missing")
    elif got == encode_header(fields, sort=False):
        problems.append("the fields are in the order given: the protocol accepts any order, but "
                        "rospy and roscpp write them sorted by key and this exercise asks for "
                        "their bytes (sorted(fields.items()))")
    elif got == _big_endian_header(fields):
        problems.append("the lengths are big-endian; TCPROS lengths are little-endian "
                        "(struct.pack('<I', n))")
    else:
        problems += describe_byte_difference(got, want, header_fields(want))
    raise fail(ex, *problems)


def _big_endian_header(fields: Mapping[str, str]) -> bytes:
    body = b"".join(struct.pack(">I", len(f)) + f for f in
                    (f"{k}={v}".encode() for k, v in sorted(fields.items())))
    return struct.pack(">I", len(body)) + body


def check_md5(type_name: str, answer: Any, registry: MsgRegistry | None = None) -> CheckResult:
    """Exercise 2.2: the md5sum of a message type, computed by hand with ``hashlib``.

    Args:
        type_name: e.g. ``geometry_msgs/Pose``.
        answer: the reader's 32-digit hex string.
        registry: where the type lives (default: the shipped types).

    Raises:
        ExerciseError: not a hex digest, or the md5 of a wrong text (the slip is named).
    """
    ex = "2.2 (md5sum by hand)"
    reg = registry or default_registry()
    require_answer(ex, "md5", answer)
    if hasattr(answer, "hexdigest"):
        raise fail(ex, "md5 is a hashlib object: call .hexdigest() on it")
    if isinstance(answer, bytes):
        raise fail(ex, "md5 is bytes (.digest()); use .hexdigest() for the 32 hex digits")
    if not isinstance(answer, str) or not re.fullmatch(r"[0-9a-f]{32}", answer):
        raise fail(ex, f"md5 should be 32 lower-case hex digits, you gave {answer!r}")
    want = reg.md5(type_name)
    if answer == want:
        return CheckResult(ex, [f"{type_name}: {want}", "nested types enter the text as their own "
                                                        "md5 sums, so any change below changes it"])
    md5 = lambda text: hashlib.md5(text.encode()).hexdigest()  # noqa: E731
    spec = reg.get(type_name)
    plain = "\n".join(f"{f.type} {f.name}" for f in spec.fields)
    short = "\n".join(f"{f.base_type.split('/')[-1] if '/' in f.base_type else f.type} {f.name}"
                      for f in spec.fields)
    slips = {
        md5(spec.text): "that is the md5 of the .msg text as written; nested types must be "
                        "replaced by their own md5 sums",
        md5(spec.text.strip()): "that is the md5 of the .msg text; nested types must be replaced "
                                "by their own md5 sums",
        md5(strip_comments(spec.text)): "that is the md5 of the .msg fields as written; nested "
                                        "types must be replaced by their own md5 sums",
        md5(strip_comments(spec.text).strip()): "that is the md5 of the .msg fields; nested types "
                                                "must be replaced by their own md5 sums",
        md5(plain): "that hashes the full type names of the nested types; replace each by its "
                    "md5 sum",
        md5(short): "that hashes the nested type names; replace each by its md5 sum",
        md5(reg.md5_text(type_name) + "\n"): "almost: the text must not end with a newline",
        md5(reg.full_text(type_name)): "that is the md5 of the full text (message_definition); "
                                       "the md5sum hashes the md5 text",
    }
    raise fail(ex, slips.get(answer, f"{answer} is not the md5sum of {type_name}; print "
                                     "registry.md5_text(...) for a type without nested types "
                                     "and compare your text"))


def check_frame_split(answer: Any, stream: bytes) -> CheckResult:
    """Exercise 2.3: split a TCPROS byte stream into message bodies.

    Args:
        answer: the reader's list of bodies (bytes-like), in order.
        stream: the stream they split.

    Raises:
        ExerciseError: wrong count, a body with its prefix, a wrong body.
    """
    ex = "2.3 (split frames)"
    require_answer(ex, "bodies", answer)
    if isinstance(answer, (bytes, bytearray)) or not hasattr(answer, "__iter__"):
        raise fail(ex, "bodies should be a list of bytes objects, one per frame")
    bodies = [as_bytes(ex, f"bodies[{i}]", b) for i, b in enumerate(answer)]
    dec = FrameDecoder()
    want = [bytes(b) for b in dec.feed(stream)]
    starts = list(dec.starts)
    if bodies == want:
        return CheckResult(ex, [f"{len(want)} frames, bodies of {', '.join(str(len(b)) for b in want)} "
                                "bytes (a zero-length frame is legal)"])
    problems = []
    if len(bodies) != len(want):
        problems.append(f"you found {len(bodies)} bodies, the stream holds {len(want)} frames "
                        f"(lengths {', '.join(str(len(b)) for b in want)})"
                        + ("; an empty body (length 0) is a frame too" if b"" in want else ""))
    for i, (have, body) in enumerate(zip(bodies, want)):
        if have == body:
            continue
        if have == stream[starts[i]:starts[i] + 4 + len(body)]:
            problems.append(f"body {i} still starts with its 4-byte length prefix")
        else:
            problems.append(f"body {i} is {have[:16]!r}{'...' if len(have) > 16 else ''} "
                            f"({len(have)} bytes), expected {body[:16]!r}"
                            f"{'...' if len(body) > 16 else ''} ({len(body)} bytes) from stream "
                            f"byte {starts[i] + 4}")
        break
    raise fail(ex, *problems)
