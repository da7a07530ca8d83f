"""The circuit layout derived from a .msg (hw.layout), checked against the msg layer.

Expected bytes and offsets come from the msg layer (``serialize``, ``field_layout``), never from
the layout itself.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.hw.errors import LayoutError
from rosfpga_lab.hw.layout import (
    Action, CheckOp, StepKind, derive_layout, format_layout, frame_geometry, marshal, tokens,
)
from rosfpga_lab.msg import (
    Duration, Time, default_registry, deserialize, field_layout, new_message, registry_with,
    serialize,
)

DATA_MSG = Path(__file__).resolve().parents[2] / "data" / "msg"
REG = default_registry()
LAB = registry_with([DATA_MSG])


def _pose(i: int) -> dict:
    return {"position": {"x": 1.5 * i, "y": -2.0, "z": 0.25},
            "orientation": {"x": 0.0, "y": 0.0, "z": float(i), "w": 1.0}}


def _header(frame_id: str = "laser") -> dict:
    return {"seq": 7, "stamp": Time(12, 345), "frame_id": frame_id}


def _calibration(name: str, mode: int) -> dict:
    return {"sensor_name": name, "offset": [0.5, -1.25, mode], "mode": mode}


CASES = {
    "image": (REG, "sensor_msgs/Image", "data", 12, {
        "header": _header("cam"), "height": 2, "width": 2, "encoding": "rgb8",
        "is_bigendian": 0, "step": 6, "data": bytes(range(12))}),
    "laserscan": (REG, "sensor_msgs/LaserScan", "ranges", 5, {
        "header": _header(), "angle_min": -1.5, "angle_max": 1.5, "angle_increment": 0.75,
        "time_increment": 0.0, "scan_time": 0.1, "range_min": 0.1, "range_max": 30.0,
        "ranges": np.array([1.0, 2.5, -0.0, np.inf, 3.0], np.float32),
        "intensities": np.array([], np.float32)}),
    "imu": (REG, "sensor_msgs/Imu", "linear_acceleration_covariance", None, {
        **new_message(REG, "sensor_msgs/Imu"), "header": _header("imu"),
        "orientation_covariance": np.arange(9, dtype=np.float64),
        "linear_acceleration_covariance": np.linspace(-1, 1, 9)}),
    "posearray": (REG, "geometry_msgs/PoseArray", None, None, {
        "header": _header("map"), "poses": [_pose(1), _pose(2), _pose(3)]}),
    "custom": (LAB, "lab_msgs/Samples", "samples", 6, {
        "header": _header("array"), "calibration": _calibration("front", 2),
        "label": "burst ü", "thresholds": [-3, 0, 5, 32767],
        "samples": np.array([5, -7, 2**31 - 1, -2**31, 0, 9], np.int32),
        "period": Duration(-1, 500), "history": [_calibration("a", 1), _calibration("", 0)],
        "valid": True}),
}


def _layout(case: str):
    reg, type_name, stream, length, _ = CASES[case]
    return derive_layout(reg, type_name, stream=stream, stream_length=length)


@pytest.mark.parametrize("case", sorted(CASES))
def test_marshal_of_tokens_is_the_msg_layers_frame(case: str) -> None:
    reg, type_name, _s, _n, value = CASES[case]
    layout = _layout(case)
    body = serialize(reg, type_name, value)
    assert marshal(layout, tokens(layout, value)) == struct.pack("<I", len(body)) + body
    # and from the values the msg layer decodes from those bytes
    assert marshal(layout, tokens(layout, deserialize(reg, type_name, body)))[4:] == body


@pytest.mark.parametrize("case", sorted(CASES))
def test_every_token_sits_where_field_layout_puts_its_span(case: str) -> None:
    reg, type_name, _s, _n, value = CASES[case]
    layout = _layout(case)
    body = serialize(reg, type_name, value)
    spans = [(s.label, s.offset, s.size) for s in
             field_layout(reg, type_name, body, element_spans=0) if s.size]
    mine, offset = [], 0
    for t in tokens(layout, value):
        step = layout.steps[t.step]
        size = len(marshal(layout, [t])) - 4
        if size:
            mine.append((step.label_at(t.at), offset, size))
        offset += size
    assert mine == spans


@pytest.mark.parametrize("case", sorted(c for c in CASES if CASES[c][2]))
def test_frame_geometry_gives_frame_length_and_stream_offset(case: str) -> None:
    reg, type_name, stream, _n, value = CASES[case]
    layout = _layout(case)
    body = serialize(reg, type_name, value)
    span = next(s for s in field_layout(reg, type_name, body, element_spans=0)
                if s.path == stream and s.role != "length")
    geo = frame_geometry(layout, value)
    assert geo.frame_length == len(body)
    assert (geo.stream_offset, geo.stream_bytes) == (4 + span.offset, span.size)


#: The hand-written Image subscriber's statuses (the exhibit's rfl_status.vh), written out.
IMAGE_STATUSES = (
    ("SUB_OK", "frame accepted"), ("SUB_BAD_FRAME_LENGTH", "frame length"),
    ("SUB_BAD_FRAME_ID_LENGTH", "header.frame_id length"), ("SUB_BAD_HEIGHT", "height"),
    ("SUB_BAD_WIDTH", "width"), ("SUB_BAD_ENCODING_LENGTH", "encoding length"),
    ("SUB_BAD_ENCODING", "encoding"), ("SUB_BAD_STEP", "step"),
    ("SUB_BAD_DATA_LENGTH", "data length"))


def test_the_image_layout_names_the_hand_image_subscribers_statuses() -> None:
    layout = derive_layout(REG, "sensor_msgs/Image", stream="data", stream_length=12,
                           checks={"height": 2, "width": 2, "encoding": "rgb8", "step": 6},
                           limits_={"encoding": 32})
    # same fields, same order, same labels; the names differ only by the header_ prefix
    assert [label for _n, label in layout.statuses] == [label for _n, label in IMAGE_STATUSES]
    assert [n.replace("HEADER_", "") for n, _l in layout.statuses] == \
        [n for n, _l in IMAGE_STATUSES]
    # Image's 37 bytes with empty strings and no pixels, plus what the checks fix: "rgb8" and
    # the 12 data bytes (the shortest body accepted)
    assert layout.min_body == 37 + 4 + 12 and layout.stream.ident == "data"
    assert layout.step("encoding").check.value == "rgb8"


def test_loops_walk_arrays_of_messages_strings_and_times() -> None:
    reg = _registry_of({"Inner": "string[] names\ntime[2] stamps\nuint8 flag",
                        "Outer": "Inner[] inners\nInner[2] pair\nint64[] values"})
    layout = derive_layout(reg, "t_msgs/Outer", stream="values", stream_length=3)
    kinds = [(s.kind, s.depth, s.label) for s in layout.steps]
    assert kinds[:4] == [(StepKind.LENGTH, 0, "frame length"), (StepKind.LENGTH, 0, "inners length"),
                         (StepKind.LOOP, 0, "inners"), (StepKind.LENGTH, 1, "inners[].names length")]
    loops = [s for s in layout.steps if s.kind is StepKind.LOOP]
    assert [(s.label, s.count) for s in loops] == [("inners", None), ("inners[].names", None),
                                                   ("inners[].stamps", 2), ("pair", 2),
                                                   ("pair[].names", None), ("pair[].stamps", 2)]
    for s in loops:
        assert layout.steps[s.partner].kind is StepKind.END and layout.steps[s.partner].partner == s.index
    value = {"inners": [{"names": ["x", ""], "stamps": [Time(1, 2), Time(3, 4)], "flag": 1},
                        {"names": [], "stamps": [Time(), Time(5, 6)], "flag": 0}],
             "pair": [{"names": ["p"], "stamps": [Time(), Time()], "flag": 2}] * 2,
             "values": [1, -2, 3]}
    body = serialize(reg, "t_msgs/Outer", value)
    assert marshal(layout, tokens(layout, value))[4:] == body
    labels = [layout.steps[t.step].label_at(t.at) for t in tokens(layout, value)]
    assert "inners[1].stamps[1].nsecs" in labels and "pair[1].names[0] length" in labels


def test_max_body_is_the_size_of_a_message_at_every_maximum() -> None:
    layout = derive_layout(LAB, "lab_msgs/Samples", stream="samples", stream_length=4,
                           limits_={"history": 2, "label": 5, "header.frame_id": 3,
                                    "calibration.sensor_name": 1, "history.sensor_name": 2})
    full = {"header": _header("abc"), "calibration": _calibration("z", 1), "label": "12345",
            "thresholds": [1, 2, 3, 4], "samples": [1, 2, 3, 4], "period": Duration(1, 1),
            "history": [_calibration("ab", 1), _calibration("cd", 2)], "valid": False}
    assert layout.max_body == len(serialize(LAB, "lab_msgs/Samples", full))
    assert layout.step("history_length").check.high == 2
    assert layout.step("history_sensor_name_length").check.high == 2


def test_actions_checks_and_statuses() -> None:
    layout = derive_layout(REG, "sensor_msgs/LaserScan", stream="ranges", stream_length=360,
                           checks={"angle_min": -1.5, "range_max": {"max": 100}},
                           skip=["intensities"])
    act = {s.ident: s.action for s in layout.steps}
    assert act["ranges"] is Action.STREAM and act["ranges_length"] is Action.STREAM
    assert act["angle_min"] is Action.CHECK and act["header_frame_id"] is Action.CARRY
    assert act["intensities"] is Action.SKIP and act["intensities_length"] is Action.SKIP
    assert layout.step("ranges_length").check.op is CheckOp.EQUAL
    assert layout.step("ranges_length").check.value == 360
    assert layout.step("range_max").check.op is CheckOp.RANGE
    assert layout.step("range_max").check.high == 100
    # genpy: 13 x 4 bytes for an empty scan, plus the 360 float32 ranges the circuit is built for
    assert layout.step("frame_length").check.low == 52 + 360 * 4 == layout.min_body
    assert layout.beat_bits == 32 and layout.stream.dtype == "<f4"
    assert [n for n, _l in layout.statuses] == [
        "SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_BAD_HEADER_FRAME_ID_LENGTH", "SUB_BAD_ANGLE_MIN",
        "SUB_BAD_RANGE_MAX", "SUB_BAD_RANGES_LENGTH", "SUB_BAD_INTENSITIES_LENGTH"]
    text = format_layout(layout)
    assert "SUB_BAD_ANGLE_MIN: == -1.5" in text and "ranges length" in text


def test_idents_are_unique_and_safe_in_c_and_verilog() -> None:
    reg = _registry_of({"K": "int32 input\nint32 a_b\nA a\nint32 module\nint32[] output",
                        "A": "int32 b"})
    layout = derive_layout(reg, "t_msgs/K", stream="output", stream_length=1)
    idents = [s.ident for s in layout.steps if s.kind is not StepKind.END]
    assert len(idents) == len(set(idents))
    assert all(re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", i) for i in idents)
    assert {"input_f", "module_f", "a_b", "a_b_2", "output_f"} <= set(idents)


@pytest.mark.parametrize(("kwargs", "key", "words"), [
    ({"stream": "nope"}, "stream.field", "has no field 'nope'"),
    ({"stream": "angle_min"}, "stream.field", "not an array"),
    ({"stream": "header.frame_id"}, "stream.field", "not an array"),
    ({"stream": "ranges", "stream_length": None}, "stream.length", "element count"),
    ({"stream": "ranges", "checks": {"ranges": 1}}, "checks.ranges", "is the stream"),
    ({"stream": "ranges", "checks": {"header.stamp": 1}}, "checks.header.stamp", "time"),
    ({"stream": "ranges", "checks": {"header.seq": -1}}, "checks.header.seq", "does not fit"),
    ({"stream": "ranges", "checks": {"angle_min": "x"}}, "checks.angle_min", "not a float32"),
    ({"stream": "ranges", "limits_": {"angle_min": 3}}, "limits.angle_min", "only strings"),
    ({"stream": "ranges", "limits_": {"header.frame_id": -3}}, "limits.header.frame_id", "expected"),
    ({"stream": "ranges", "skip": ["ranges"]}, "skip.ranges", "cannot be skipped"),
])
def test_refusals_name_the_key(kwargs: dict, key: str, words: str) -> None:
    kwargs.setdefault("stream_length", 4)
    with pytest.raises(LayoutError) as exc:
        derive_layout(REG, "sensor_msgs/LaserScan", **kwargs)
    assert exc.value.key == key and words in str(exc.value)


@pytest.mark.parametrize(("type_name", "stream", "words"), [
    ("geometry_msgs/PoseArray", "poses", "array of messages"),
    ("sensor_msgs/JointState", "name", "array of strings"),
    ("sensor_msgs/JoyFeedbackArray", "array", "array of messages"),
])
def test_arrays_the_application_cannot_take_are_refused(type_name: str, stream: str,
                                                        words: str) -> None:
    with pytest.raises(LayoutError, match=words):
        derive_layout(REG, type_name, stream=stream, stream_length=1)


def test_bool_and_time_arrays_cannot_stream() -> None:
    reg = _registry_of({"B": "bool[] flags\ntime[] stamps"})
    for field in ("flags", "stamps"):
        with pytest.raises(LayoutError, match="application takes arrays of"):
            derive_layout(reg, "t_msgs/B", stream=field, stream_length=1)


def _registry_of(defs: dict[str, str]):
    from rosfpga_lab.msg import MsgRegistry

    reg = MsgRegistry.with_defaults()
    for name, text in defs.items():
        reg.add(f"t_msgs/{name}", text)
    return reg


def test_the_module_docstrings_worked_example_is_format_layouts_output() -> None:
    import rosfpga_lab.hw.layout as module

    reg = _registry_of({})
    reg.add("pkg/Scan", "Header header\nstring[] names\nfloat32[] ranges")
    text = format_layout(derive_layout(reg, "pkg/Scan", stream="ranges", stream_length=4,
                                       checks={"header.seq": 0}))
    doc = module.__doc__ or ""
    block = doc.split("prints (a test holds this text equal to its output)::\n\n")[1]
    shown = "\n".join(line[4:] for line in block.split("\n\n")[0].splitlines())
    assert shown == text
