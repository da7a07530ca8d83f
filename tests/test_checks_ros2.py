"""The checks of notebook 9: right answers pass, the usual wrong ones are named."""

from __future__ import annotations

import re

import pytest

from rosfpga_lab.checks import ExerciseError, check_cdr_data_offset, check_fragment_count
from rosfpga_lab.msg import default_registry, new_message, serialize, serialize_cdr, to_ros2_value

REG = default_registry()


def _payload(frame_id: str = "camera", encoding: str = "rgba8") -> bytes:
    img = new_message(REG, "sensor_msgs/Image", header={"frame_id": frame_id}, height=2, width=2,
                      encoding=encoding, step=8, data=bytes(16))
    return serialize_cdr(None, "sensor_msgs/Image", to_ros2_value(REG, "sensor_msgs/Image", img))


def test_cdr_data_offset_right_and_wrong() -> None:
    payload = _payload()
    # by hand: 4 header + 8 stamp + 4+7 "camera\0" -> 23, pad 1 -> 24, height, width -> 32,
    # 4+6 "rgba8\0" -> 42, is_bigendian -> 43, pad 1 -> 44, step -> 48, count -> 52
    assert check_cdr_data_offset(52, payload).ok
    assert payload[48:52] == (16).to_bytes(4, "little")
    with pytest.raises(ExerciseError, match="encapsulation header"):
        check_cdr_data_offset(48, payload)
    with pytest.raises(ExerciseError, match="alignment padding"):
        check_cdr_data_offset(50, payload)
    with pytest.raises(ExerciseError, match="still Ellipsis"):
        check_cdr_data_offset(..., payload)
    # a frame_id of another length moves the padding: the check follows the payload
    other = _payload("cam")
    assert check_cdr_data_offset(48, other).ok


def test_fragment_count_right_and_wrong() -> None:
    assert check_fragment_count(915, 1_228_852, 1344).ok
    with pytest.raises(ExerciseError, match="rounded down"):
        check_fragment_count(914, 1_228_852, 1344)
    with pytest.raises(ExerciseError, match="rounding up"):
        check_fragment_count(3, 1_228_852, 1344)
    assert check_fragment_count(2, 2688, 1344).ok


def _tcpros_offsets(frame_id: str, encoding: str = "rgba8") -> tuple[int, int]:
    """Where the pixels start in the ROS 1 message and in its TCPROS frame, from the ROS 1
    serializer (not from the CDR code under test)."""
    img = new_message(REG, "sensor_msgs/Image", header={"frame_id": frame_id}, height=2, width=2,
                      encoding=encoding, step=8, data=bytes(16))
    message = serialize(REG, "sensor_msgs/Image", img)
    return len(message) - 16, len(message) - 16 + 4


def test_cdr_data_offset_names_each_mistake_for_camera_link() -> None:
    payload = _payload("camera_link")
    # by hand: 4 header + 8 stamp + 4+12 "camera_link\0" -> 28 (aligned), height, width -> 36,
    # 4+6 "rgba8\0" -> 46, is_bigendian -> 47, pad 1 -> 48, step -> 52, count -> 56
    assert check_cdr_data_offset(56, payload).ok
    message, frame = _tcpros_offsets("camera_link")
    assert (message, frame) == (53, 57)                 # the TCPROS ways differ from CDR here
    cases = {
        frame: ["TCPROS frame", "seq", "NUL", "padding"],      # notebook 3's sum, unchanged
        message: ["TCPROS message", "NUL", "padding"],
        54: ["NUL"], 55: ["padding"], 60: ["seq"],
        52: ["encapsulation header", "count of 'data'"],        # both give 52: both named
        40: ["count again"],
    }
    for answer, words in cases.items():
        with pytest.raises(ExerciseError) as err:
            check_cdr_data_offset(answer, payload)
        for word in words:
            assert word in str(err.value), (answer, word, str(err.value))
    assert "encapsulation" not in _hint(53, payload) and "TCPROS" not in _hint(54, payload)
    for blank in (None, ...):
        with pytest.raises(ExerciseError, match="still"):
            check_cdr_data_offset(blank, payload)


def _hint(answer: int, payload: bytes) -> str:
    with pytest.raises(ExerciseError) as err:
        check_cdr_data_offset(answer, payload)
    return str(err.value)


def test_camera_nuls_and_padding_missing_is_not_blamed_on_the_header_alone() -> None:
    # frame_id "camera": 48 is both "no encapsulation header" and the TCPROS message sum
    # (seq kept, no NULs, no padding); the hint says the TCPROS sum, not only the header
    assert _tcpros_offsets("camera")[0] == 48
    assert "TCPROS message" in _hint(48, _payload())


def test_notebook_9_exercise_frame_id_tells_cdr_from_tcpros() -> None:
    """Exercise 9.1 must not pass with notebook 3's TCPROS sum (it did with frame_id 'camera')."""
    from pathlib import Path

    from rosfpga_lab.checks import nbbuild

    path = Path(__file__).resolve().parents[1] / "notebooks" / "solutions" / "09_ros2_wire.ipynb"
    cells = nbbuild.load(path)["cells"]
    text = "".join(nbbuild.cell_source(c) for c in cells if c.get("id") == "c09s")
    frame_id = re.search(r'"frame_id": "([^"]+)"', text).group(1)
    payload = _payload(frame_id)
    message, frame = _tcpros_offsets(frame_id)
    want = next(a for a in range(40, 80) if _ok(a, payload))
    assert want not in (message, frame)
    exercise = [i for i, c in enumerate(cells) if nbbuild.is_exercise_cell(c)]
    assert exercise and all(i >= len(cells) - 4 for i in exercise)  # exercises at the end


def _ok(answer: int, payload: bytes) -> bool:
    try:
        return check_cdr_data_offset(answer, payload).ok
    except ExerciseError:
        return False
