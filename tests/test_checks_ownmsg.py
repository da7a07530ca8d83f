"""Notebook 10's exercise checks: the right answer passes, typical wrong ones are explained,
a blank one is refused. Expected figures are counted here by hand from the message below."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.checks import ExerciseError
from rosfpga_lab.checks.ownmsg import (
    check_frame_clocks, check_refused_field, check_stream_offset, walk_spans,
)
from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.hw.layout import Layout, layout_from_config
from rosfpga_lab.msg import MsgRegistry, serialize

MSG = """Header header
string sensor
uint8 gain
float32[2] window
uint16[] values
"""
CONFIG = """node: {name: /fpga_line}
subscriber: {topic: /line, type: t_msgs/Line}
publisher: {topic: /line_out}
msg_path: [msg]
stream: {field: values, length: 8}
checks: {gain: 4}
limits: {sensor: 16}
application: {op: erode, ksize: 3}
"""


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> tuple[NodeConfig, Layout, MsgRegistry]:
    root: Path = tmp_path_factory.mktemp("ownmsg")
    (root / "msg/t_msgs/msg").mkdir(parents=True)
    (root / "msg/t_msgs/msg/Line.msg").write_text(MSG)
    config = parse_config(CONFIG, source="test", base_dir=root)
    reg = config.registry()
    return config, layout_from_config(config, reg), reg


def message(sensor: str = "left", gain: int = 4, n: int = 8) -> dict:
    return {"header": {"seq": 1, "stamp": {"secs": 2, "nsecs": 3}, "frame_id": "cam"},
            "sensor": sensor, "gain": gain, "window": [0.5, 2.0],
            "values": np.arange(n, dtype=np.uint16)}


def frame_of(reg: MsgRegistry, msg: dict) -> bytes:
    body = serialize(reg, "t_msgs/Line", msg)
    return struct.pack("<I", len(body)) + body


# by hand: frame length 4, seq 4, stamp 8, frame_id 4 + 3, sensor 4 + 4, gain 1, window 8,
# values length 4: the elements start at byte 44
OFFSET = 4 + 4 + 8 + 4 + 3 + 4 + 4 + 1 + 8 + 4


def test_stream_offset_right_wrong_blank(setup) -> None:
    _config, layout, reg = setup
    frame = frame_of(reg, message())
    assert "start at byte 44" in str(check_stream_offset(OFFSET, frame, layout, reg))
    with pytest.raises(ExerciseError, match="uint32 'values length' starts; the elements begin 4"):
        check_stream_offset(OFFSET - 4, frame, layout, reg)
    with pytest.raises(ExerciseError, match="off by 8"):
        check_stream_offset(OFFSET - 8, frame, layout, reg)
    # window counted as 4 + 3 bytes: lands inside the window
    with pytest.raises(ExerciseError, match=r"byte 35 is inside field window \(bytes 32..39\); "
                                            r"between it and the stream: values length"):
        check_stream_offset(35, frame, layout, reg)
    with pytest.raises(ExerciseError, match="outside the 60-byte frame"):
        check_stream_offset(500, frame, layout, reg)
    with pytest.raises(ExerciseError, match="replace it with your answer"):
        check_stream_offset(..., frame, layout, reg)
    with pytest.raises(ExerciseError, match="should be int"):
        check_stream_offset("44", frame, layout, reg)


def test_walk_spans_name_every_field_by_hand(setup) -> None:
    _config, layout, reg = setup
    spans = walk_spans(layout, message())
    assert [s[2] for s in spans] == [
        "frame length", "header.seq", "header.stamp.secs", "header.stamp.nsecs",
        "header.frame_id length", "header.frame_id", "sensor length", "sensor", "gain", "window",
        "values length", "values"]
    assert spans[-1] == (OFFSET, 16, "values")


def body_bytes(n: int) -> int:   # the message body above with n uint16 elements, by hand
    return OFFSET - 4 + 2 * n


def right(n: int) -> int:
    frame = 4 + body_bytes(n)
    return frame + (n + 1 if n else 0) + frame


def test_frame_clocks_right_wrong_blank(setup) -> None:
    config, _layout, _reg = setup
    result = str(check_frame_clocks(right, config, message()))
    assert f"clocks(8) = {right(8)} = {4 + body_bytes(8)} (subscriber" in result
    assert f"clocks(4096) = {right(4096)}" in result
    cases = {
        lambda n: 4 + body_bytes(n): "the subscriber alone",
        lambda n: 2 * (4 + body_bytes(n)): "one per element, plus ksize // 2 = 1",
        lambda n: 2 * (4 + body_bytes(n)) + n: "adds ksize // 2 = 1 clocks of latency",
        lambda n: (4 + body_bytes(n)) + n + 1: "publisher writes the output frame",
        lambda n: 2 * (4 + OFFSET - 4 + n) + n + 1: "an element is 2 bytes on the wire",
        lambda n: right(n) - 4: "the subscriber reads it too",
    }
    for fn, finding in cases.items():
        with pytest.raises(ExerciseError, match=finding):
            check_frame_clocks(fn, config, message())
    with pytest.raises(ExerciseError, match=r"clocks\(8\) is 7, expected 129: 60 \(subscriber: the 60-byte frame\) \+ 9 \(application: 8 elements \+ 1\) \+ 60 \(publisher\)"):
        check_frame_clocks(lambda n: 7, config, message())
    with pytest.raises(ExerciseError, match=r"clocks\(8\) raised ZeroDivisionError"):
        check_frame_clocks(lambda n: 1 // 0, config, message())
    with pytest.raises(ExerciseError, match="should be a function of n"):
        check_frame_clocks(119, config, message())
    with pytest.raises(ExerciseError, match="replace it with your answer"):
        check_frame_clocks(None, config, message())


def test_refused_field_right_wrong_blank(setup) -> None:
    _config, layout, reg = setup
    # sensor too long (17 > 16) AND gain wrong AND 7 elements: the first is the one named
    suspect = frame_of(reg, message(sensor="s" * 17, gain=5, n=7))
    ok = str(check_refused_field("sensor length", suspect, layout, reg))
    assert "refuses the frame at sensor length (byte 23, over the limit)" in ok
    assert "SUB_BAD_SENSOR_LENGTH" in ok
    check_refused_field("SUB_BAD_SENSOR_LENGTH", suspect, layout, reg)
    with pytest.raises(ExerciseError, match=r"gain \(byte 44\) comes after the refused field"):
        check_refused_field("gain", suspect, layout, reg)
    with pytest.raises(ExerciseError, match="values length .* comes after"):
        check_refused_field("SUB_BAD_VALUES_LENGTH", suspect, layout, reg)
    with pytest.raises(ExerciseError, match=r"header.frame_id length is 3 in this frame and the "
                                            r"circuit accepts it \(<= 256\)"):
        check_refused_field("header.frame_id length", suspect, layout, reg)
    with pytest.raises(ExerciseError, match="no field 'sensor_length' in this frame's walk"):
        check_refused_field("sensor_length", suspect, layout, reg)
    with pytest.raises(ExerciseError, match="replace it with your answer"):
        check_refused_field(..., suspect, layout, reg)
    with pytest.raises(ExerciseError, match="the circuit accepts this frame"):
        check_refused_field("gain", frame_of(reg, message()), layout, reg)
    # only the gain wrong: named by the gain's own check
    assert "at gain (byte 31" in str(check_refused_field("gain", frame_of(reg, message(gain=5)),
                                                         layout, reg))


def test_the_byte_viewer_names_the_walk_as_the_check_does(setup) -> None:
    """widgets.spans_from_layout (notebook 10's byte viewer) and the check's spans agree, and
    each byte's role is what the circuit does with it (set by hand from the configuration)."""
    from rosfpga_lab.widgets import spans_from_layout

    _config, layout, reg = setup
    msg = message()
    spans = spans_from_layout(layout, msg)
    assert [(s.offset, s.size, s.path) for s in spans] == walk_spans(layout, msg)
    roles = {s.path: s.role for s in spans}
    assert roles == {"frame length": "length", "header.seq": "carry", "header.stamp.secs": "carry",
                     "header.stamp.nsecs": "carry", "header.frame_id length": "length",
                     "header.frame_id": "carry", "sensor length": "length", "sensor": "carry",
                     "gain": "check", "window": "carry", "values length": "length",
                     "values": "stream"}
    assert spans[0].value == 56 and spans[-1].type == "uint16[8]"
    assert sum(s.size for s in spans) == len(frame_of(reg, msg))
