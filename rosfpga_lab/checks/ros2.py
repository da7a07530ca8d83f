"""Checks of notebook 9 (ROS 2 on the wire: CDR alignment, DATA_FRAG fragment counts) and of
notebook 11 (the component live on ROS 2: the RTPS port mapping, where the pixels start on
both wires, QoS matching)."""

from __future__ import annotations

from itertools import combinations
from typing import Any

from rosfpga_lab.checks._core import CheckResult, fail, require_type
from rosfpga_lab.msg import cdr_layout
from rosfpga_lab.msg.cdr import ENCAPSULATION_SIZE
from rosfpga_lab.rtps.entities import Qos, discovery_port, incompatibility, user_port
from rosfpga_lab.rtps.limits import (
    DOMAIN_GAIN, OFFSET_DISCOVERY_UNICAST, OFFSET_USER_UNICAST, PARTICIPANT_GAIN, PORT_BASE,
)
from rosfpga_lab.tcpros import frame_spans

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


def check_discovery_port(answer: Any, domain: int, index: int) -> CheckResult:
    """Exercise 11.1: the unicast discovery port of participant ``index`` in DDS ``domain``.

    Raises:
        ExerciseError: a wrong port, with the port it is (user data, multicast) or the term
            of the RTPS port mapping it probably left out.
    """
    ex = "11.1 (the discovery port of a participant)"
    require_type(ex, "port", answer, int)
    want = discovery_port(domain, index)
    if answer == want:
        return CheckResult(ex, [f"participant {index} of domain {domain} listens for SPDP/SEDP on "
                                f"{PORT_BASE} + {DOMAIN_GAIN}*{domain} + {OFFSET_DISCOVERY_UNICAST} "
                                f"+ {PARTICIPANT_GAIN}*{index} = {want} (its user data on "
                                f"{user_port(domain, index)})"])
    base = PORT_BASE + DOMAIN_GAIN * domain
    hints = {
        user_port(domain, index): f"that is its user-data port (offset d3 = "
                                  f"{OFFSET_USER_UNICAST}); discovery uses offset d1 = "
                                  f"{OFFSET_DISCOVERY_UNICAST}",
        base: "that is the domain's multicast discovery port (offset d0 = 0, no participant "
              "index): on loopback without multicast, each participant's own unicast port",
        base + 1: "that is the domain's multicast user-data port (offset d2 = 1)",
        base + OFFSET_DISCOVERY_UNICAST + index: f"the participant gain is {PARTICIPANT_GAIN}: "
                                                 f"each index takes two ports (discovery, user)",
        PORT_BASE + OFFSET_DISCOVERY_UNICAST + PARTICIPANT_GAIN * index:
            f"the domain moves every port by {DOMAIN_GAIN} (domain gain) times its id",
        base + PARTICIPANT_GAIN * index: f"left out the offset d1 = {OFFSET_DISCOVERY_UNICAST} "
                                         f"of unicast discovery",
        base + OFFSET_DISCOVERY_UNICAST: f"that is participant 0's port: left out the "
                                         f"participant term PG*index = {PARTICIPANT_GAIN}*{index}",
        want + PARTICIPANT_GAIN: "one index too many: participant indices count from 0",
        want - PARTICIPANT_GAIN: "one index too few: participant indices count from 0",
    }
    hints.pop(want, None)
    hint = hints.get(int(answer), f"PB + DG*domain + d1 + PG*index with PB {PORT_BASE}, DG "
                                  f"{DOMAIN_GAIN}, PG {PARTICIPANT_GAIN}, d1 "
                                  f"{OFFSET_DISCOVERY_UNICAST}")
    raise fail(ex, f"port {answer}, expected another value: {hint}")


def tcpros_data_offset(frame: bytes, type_name: str = IMAGE) -> int:
    """Offset of the first byte of ``data`` in a TCPROS frame (4-byte length first)."""
    return next(s.end for s in frame_spans(frame, type_name) if s.label == "data length")


def check_pixel_offsets(answer: Any, tcpros_frame: bytes, cdr_payload: bytes) -> CheckResult:
    """Exercise 11.2: where the pixels start in the TCPROS frame and in the CDR payload of
    the same image: ``(tcpros_offset, cdr_offset)``.

    Raises:
        ExerciseError: each wrong offset, with what was probably left out or added.
    """
    ex = "11.2 (the same pixels on both wires)"
    require_type(ex, "pixel_offsets", answer, (tuple, list), "a pair: (tcpros_offset, cdr_offset)")
    if len(answer) != 2:
        raise fail(ex, f"pixel_offsets has {len(answer)} item(s): give a pair "
                       f"(tcpros_offset, cdr_offset)")
    ros1, ros2 = answer
    require_type(ex, "tcpros_offset", ros1, int)
    require_type(ex, "cdr_offset", ros2, int)
    frame, payload = bytes(tcpros_frame), bytes(cdr_payload)
    want1, want2 = tcpros_data_offset(frame), cdr_data_offset(payload)
    problems = []
    if ros1 != want1:
        hint = {want1 - 4: "you counted from the message body, or stopped at the uint32 count "
                           "of 'data' (the frame's 4-byte length comes first, the pixels after "
                           "the count)",
                want1 - 8: "left out both the frame's 4-byte length and the count of 'data'",
                want2: "that is the CDR offset: the TCPROS frame has seq, no NULs and no padding",
                }.get(ros1, "count again: frame length, seq, stamp (secs, nsecs), frame_id "
                            "(length + text), height, width, encoding (length + text), "
                            "is_bigendian, step, count of data")
        problems.append(f"tcpros_offset {ros1}, expected another value: {hint}")
    if ros2 != want2:
        spans = cdr_layout(None, IMAGE, payload)
        padding = sum(s.size for s in spans if s.role == "padding" and s.end <= want2)
        nuls = sum(1 for s in spans if s.type == "string" and s.end <= want2)
        hint = ("that is the TCPROS offset: CDR has an encapsulation header, no seq, strings "
                "with their NUL and alignment padding" if ros2 == want1 and want1 != want2
                else _cdr_offset_hint(ros2, want2, nuls, padding))
        problems.append(f"cdr_offset {ros2}, expected another value: {hint}")
    if problems:
        raise fail(ex, *problems)
    shift = want2 - want1
    return CheckResult(ex, [f"the pixels start at byte {want1} of the TCPROS frame and at byte "
                            f"{want2} of the CDR payload ({shift:+d}): the circuit's subscriber "
                            f"walks {want1} bytes of fields on ROS 1 and {want2} on ROS 2 "
                            f"before it streams pixels"])


POLICIES = ("RELIABILITY", "DURABILITY")


def check_qos_mismatch(answer: Any, pairs: list[tuple[Qos, Qos]]) -> CheckResult:
    """Exercise 11.3: which ``(writer offered, reader requested)`` pair does not match, and on
    which policy: ``(index, "RELIABILITY" | "DURABILITY")``.

    Raises:
        ExerciseError: a pair that matches (and why it does), or the wrong policy.
    """
    ex = "11.3 (which QoS pair does not match)"
    require_type(ex, "unmatched", answer, (tuple, list), 'a pair: (index, "RELIABILITY" or "DURABILITY")')
    if len(answer) != 2:
        raise fail(ex, f"unmatched has {len(answer)} item(s): give (index, policy)")
    index, policy = answer
    require_type(ex, "index", index, int)
    require_type(ex, "policy", policy, str, " or ".join(POLICIES))
    whys = [incompatibility(w, r) for w, r in pairs]
    bad = [i for i, why in enumerate(whys) if why]
    if not 0 <= index < len(pairs):
        raise fail(ex, f"index {index} is not a pair: there are {len(pairs)} (0..{len(pairs) - 1})")
    if not whys[index]:
        w, r = pairs[index]
        raise fail(ex, f"pair {index} matches: the writer offers {w.describe()}, the reader "
                       f"requests {r.describe()}; a writer must offer at least what the reader "
                       f"requests in RELIABILITY (RELIABLE > BEST_EFFORT) and DURABILITY "
                       f"(TRANSIENT_LOCAL > VOLATILE), and the history depth is not compared")
    want = "RELIABILITY" if "RELIABILITY" in whys[index] else "DURABILITY"
    if policy.strip().upper() != want:
        raise fail(ex, f"pair {index} does not match, but on {want}, not {policy!r}: "
                       f"{whys[index]}")
    others = [i for i in bad if i != index]
    return CheckResult(ex, [f"pair {index}: {whys[index]}"] + (
        [f"(pair(s) {others} do not match either)"] if others else []))
