"""Checks of notebook 9 (ROS 2 on the wire): CDR alignment and DATA_FRAG fragment counts."""

from __future__ import annotations

from itertools import combinations
from typing import Any

from rosfpga_lab.checks._core import CheckResult, fail, require_type
from rosfpga_lab.msg import cdr_layout
from rosfpga_lab.msg.cdr import ENCAPSULATION_SIZE

IMAGE = "sensor_msgs/Image"


def cdr_data_offset(payload: bytes, type_name: str = IMAGE) -> int:
    """Payload offset of the first byte of ``data`` in a CDR message (after its count)."""
    return next(s.end for s in cdr_layout(None, type_name, payload) if s.path == "data"
                and s.role == "length")


def check_cdr_data_offset(answer: Any, payload: bytes) -> CheckResult:
    """Exercise 9.1: where the pixels start in a CDR ``sensor_msgs/Image`` payload.

    Raises:
        ExerciseError: a wrong offset, with what was probably left out.
    """
    ex = "9.1 (where the pixels start in CDR)"
    require_type(ex, "cdr_data_offset", answer, int)
    payload = bytes(payload)
    spans = cdr_layout(None, IMAGE, payload)
    want = cdr_data_offset(payload)
    padding = sum(s.size for s in spans if s.role == "padding" and s.end <= want)
    nuls = sum(1 for s in spans if s.type == "string" and s.end <= want)
    if answer == want:
        return CheckResult(ex, [f"pixels start at byte {want}: {ENCAPSULATION_SIZE} bytes of "
                                f"encapsulation header, {nuls} string NULs and {padding} "
                                f"padding byte(s) included"])
    raise fail(ex, f"cdr_data_offset {answer}, expected another value: "
                   f"{_cdr_offset_hint(answer, want, nuls, padding)}")


def _cdr_offset_hint(answer: int, want: int, nuls: int, padding: int) -> str:
    """What an offset ``answer`` instead of ``want`` probably left out or added.

    Each usual mistake moves the answer by a fixed amount; the hint names the fewest mistakes
    that together give ``answer`` (all such sets, when several do), so a TCPROS-style sum (ROS
    1's ``seq`` kept, no NULs, no padding) is named as such instead of as one missing piece.
    """
    mistakes = [  # (delta, what the student did)
        (-ENCAPSULATION_SIZE, f"left out the {ENCAPSULATION_SIZE}-byte encapsulation header"),
        (+4, "counted ROS 1's header.seq (ROS 2's std_msgs/Header has no seq)"),
        (-nuls, f"left out the NUL that ends each CDR string ({nuls} strings; the length "
                "counts it)"),
        (-padding, f"left out the {padding} alignment padding byte(s) (red in the CDR viewer)"),
        (-4, "stopped at the uint32 count of 'data'; the pixels follow it"),
    ]
    found: list[str] = []
    for size in range(1, len(mistakes) + 1):
        for subset in combinations(mistakes, size):
            if all(delta for delta, _ in subset) and want + sum(d for d, _ in subset) == answer:
                found.append(" and ".join(text for _, text in subset))
        if found:
            break
    if not found:
        return ("count again: encapsulation header, header (sec, nanosec, frame_id with its NUL), "
                "padding to 4, height, width, encoding with its NUL, is_bigendian, padding to 4, "
                "step, count of data")
    tcpros_message = want - ENCAPSULATION_SIZE + 4 - nuls - padding
    lead = {tcpros_message: "that is where the pixels start in the TCPROS message (notebook 3), "
                            "not in CDR: ",
            tcpros_message + 4: "that is where the pixels start in the TCPROS frame (notebook 3; "
                                "its 4-byte frame length is not CDR's encapsulation header), "
                                "not in CDR: "}.get(answer, "")
    return lead + "you " + " - or you ".join(dict.fromkeys(found))


def fragment_count(sample_size: int, fragment_size: int) -> int:
    """DATA_FRAG fragments of a serialized sample: every fragment full but the last."""
    return -(-sample_size // fragment_size)


def check_fragment_count(answer: Any, sample_size: int, fragment_size: int) -> CheckResult:
    """Exercise 9.2: how many fragments a ``sample_size``-byte sample needs.

    Raises:
        ExerciseError: a wrong count (rounding down, or the wrong size) is named.
    """
    ex = "9.2 (fragments of a sample)"
    require_type(ex, "fragments", answer, int)
    want = fragment_count(sample_size, fragment_size)
    if answer == want:
        last = sample_size - (want - 1) * fragment_size
        return CheckResult(ex, [f"{sample_size} bytes in {fragment_size}-byte fragments: "
                                f"{want} DATA_FRAG fragments, the last one {last} bytes"])
    if answer == sample_size // fragment_size:
        hint = "rounded down: the last, shorter fragment counts too"
    elif answer == fragment_count(sample_size - ENCAPSULATION_SIZE, fragment_size):
        hint = "the sample includes the 4-byte encapsulation header"
    else:
        hint = "divide the sample size by the fragment size, rounding up"
    raise fail(ex, f"fragments {answer}, expected another value: {hint}")
