"""The checks of notebook 9: right answers pass, the usual wrong ones are named."""

from __future__ import annotations

import pytest

from rosfpga_lab.checks import ExerciseError, check_cdr_data_offset, check_fragment_count
from rosfpga_lab.msg import default_registry, new_message, serialize_cdr, to_ros2_value

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
