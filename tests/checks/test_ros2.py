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

    path = Path(__file__).resolve().parents[2] / "notebooks" / "solutions" / "09_ros2_wire.ipynb"
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


# ---- notebook 11: the component live on ROS 2 ------------------------------------------------

from rosfpga_lab.checks import check_discovery_port, check_pixel_offsets, check_qos_mismatch  # noqa: E402
from rosfpga_lab.rtps.participant import Qos  # noqa: E402


def test_discovery_port_right_and_each_usual_mistake() -> None:
    # by hand: 7400 + 250*42 + 10 + 2*3 = 17916 (user data 17917)
    assert check_discovery_port(17916, 42, 3).ok
    assert check_discovery_port(7410, 0, 0).ok
    assert check_discovery_port(7412, 0, 1).ok      # the lab's second participant in domain 0
    for wrong, why in ((17917, "user-data port"), (17900, "multicast discovery port"),
                       (17901, "multicast user-data port"), (17913, "participant gain is 2"),
                       (7416, "domain gain"), (17906, "offset d1 = 10"),
                       (17918, "one index too many"), (17914, "one index too few"),
                       (17910, r"participant 0's port: left out the participant term "
                               r"PG\*index = 2\*3"),
                       (1234, "PB \\+ DG\\*domain")):
        with pytest.raises(ExerciseError, match=why):
            check_discovery_port(wrong, 42, 3)
    for blank in (None, ...):
        with pytest.raises(ExerciseError, match="still"):
            check_discovery_port(blank, 42, 3)
    with pytest.raises(ExerciseError, match="should be int"):
        check_discovery_port("17916", 42, 3)


def _both(frame_id: str) -> tuple[bytes, bytes]:
    img = new_message(REG, "sensor_msgs/Image", header={"frame_id": frame_id}, height=2, width=2,
                      encoding="rgba8", step=8, data=bytes(16))
    message = serialize(REG, "sensor_msgs/Image", img)
    cdr = serialize_cdr(None, "sensor_msgs/Image", to_ros2_value(REG, "sensor_msgs/Image", img))
    return len(message).to_bytes(4, "little") + message, cdr


def test_pixel_offsets_right_wrong_and_blank() -> None:
    frame, cdr = _both("camera_link")
    # by hand, TCPROS: 4 length + 4 seq + 8 stamp + 4+11 "camera_link" -> 31, height, width
    # -> 39, 4+5 "rgba8" -> 48, is_bigendian -> 49, step -> 53, count -> 57.
    # CDR: 4 header + 8 stamp + 4+12 "camera_link\0" -> 28, height, width -> 36, 4+6 "rgba8\0"
    # -> 46, is_bigendian -> 47, pad 1 -> 48, step -> 52, count -> 56.
    assert frame[53:57] == (16).to_bytes(4, "little") and cdr[52:56] == (16).to_bytes(4, "little")
    result = check_pixel_offsets((57, 56), frame, cdr)
    assert result.ok and "byte 57 of the TCPROS frame and at byte 56 of the CDR payload (-1)" \
        in str(result)
    assert check_pixel_offsets([57, 56], frame, cdr).ok
    with pytest.raises(ExerciseError, match="tcpros_offset 53.*message body"):
        check_pixel_offsets((53, 56), frame, cdr)
    with pytest.raises(ExerciseError, match="encapsulation header") as info:
        check_pixel_offsets((57, 52), frame, cdr)
    assert "tcpros_offset" not in str(info.value)          # only the wrong one is named
    with pytest.raises(ExerciseError) as info:             # the two swapped: both named
        check_pixel_offsets((56, 57), frame, cdr)
    assert "that is the CDR offset" in str(info.value) and "that is the TCPROS offset" \
        in str(info.value)
    with pytest.raises(ExerciseError, match="header.seq"):
        check_pixel_offsets((57, 60), frame, cdr)
    with pytest.raises(ExerciseError, match="1 item"):
        check_pixel_offsets((57,), frame, cdr)
    with pytest.raises(ExerciseError, match="still None"):
        check_pixel_offsets(None, frame, cdr)
    # "camera": the same offset on both wires (52), a coincidence the check follows
    frame, cdr = _both("camera")
    assert check_pixel_offsets((52, 52), frame, cdr).ok


PAIRS = [(Qos(True, 10), Qos(False, 5)),                  # matches: RELIABLE serves BEST_EFFORT
         (Qos(False, 10), Qos(False, 1)),                 # matches
         (Qos(True, 1), Qos(True, 1, transient_local=True)),  # DURABILITY: VOLATILE < T_LOCAL
         (Qos(True, 1, transient_local=True), Qos(True, 100))]  # matches: depth is not compared


def test_qos_mismatch_right_wrong_and_blank() -> None:
    result = check_qos_mismatch((2, "DURABILITY"), PAIRS)
    assert result.ok and "VOLATILE" in str(result)
    assert check_qos_mismatch([2, " durability "], PAIRS).ok
    with pytest.raises(ExerciseError, match="pair 3 matches.*history depth is not compared"):
        check_qos_mismatch((3, "HISTORY"), PAIRS)
    with pytest.raises(ExerciseError, match="pair 0 matches"):
        check_qos_mismatch((0, "RELIABILITY"), PAIRS)
    with pytest.raises(ExerciseError, match="on DURABILITY, not 'RELIABILITY'"):
        check_qos_mismatch((2, "RELIABILITY"), PAIRS)
    with pytest.raises(ExerciseError, match="index 4 is not a pair"):
        check_qos_mismatch((4, "DURABILITY"), PAIRS)
    with pytest.raises(ExerciseError, match="still Ellipsis"):
        check_qos_mismatch(..., PAIRS)
    with pytest.raises(ExerciseError, match="policy should be str"):
        check_qos_mismatch((2, 1), PAIRS)
    # a best-effort writer and a reliable reader: RELIABILITY
    assert check_qos_mismatch((1, "RELIABILITY"), [PAIRS[0], (Qos(False), Qos(True))]).ok


def test_notebook_11_exercises_come_last_and_11_2_tells_the_wires_apart() -> None:
    from pathlib import Path

    from rosfpga_lab.checks import nbbuild

    path = Path(__file__).resolve().parents[2] / "notebooks" / "solutions" / "11_ros2_live.ipynb"
    cells = nbbuild.load(path)["cells"]
    exercise = [i for i, c in enumerate(cells) if nbbuild.is_exercise_cell(c)]
    heading = next(i for i, c in enumerate(cells) if nbbuild.cell_source(c).startswith("## Exercises"))
    assert len(exercise) == 3 and min(exercise) > heading
    assert not any(nbbuild.cell_source(c).startswith("## ") for c in cells[heading + 1:])
    text = "".join(nbbuild.cell_source(c) for c in cells)
    frame_id = re.search(r'header=\{"seq": 0, "stamp": \(STAMP, 500\), "frame_id": "([^"]+)"\}',
                         text[text.index("exercise_msg"):]).group(1)
    assert frame_id == "left_camera_optical"
    frame, cdr = _both(frame_id)
    # by hand, TCPROS: 4 + 4 seq + 8 stamp + 4+19 -> 39, height, width -> 47, 4+5 -> 56,
    # is_bigendian -> 57, step -> 61, count -> 65. CDR: 4 + 8 + 4+20 -> 36 (aligned), height,
    # width -> 44, 4+6 -> 54, is_bigendian -> 55, pad 1 -> 56, step -> 60, count -> 64.
    assert check_pixel_offsets((65, 64), frame, cdr).ok
