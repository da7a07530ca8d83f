"""Node configurations for any message type: stream, checks, limits, skip, msg_path (issue 19, item 2)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from rosfpga_lab.config import ConfigError, load_config, parse_config
from rosfpga_lab.config.limits import DEFAULT_ARRAY_MAX, DEFAULT_STRING_MAX
from rosfpga_lab.hw.layout import Action, CheckOp, layout_from_config

DATA = Path(__file__).resolve().parents[2] / "data"

SCAN = """\
node: {name: /scan_min}
subscriber: {topic: /scan, type: sensor_msgs/LaserScan}
publisher: {topic: /out}
stream: {field: ranges, length: 360}
application: {op: erode, ksize: 5}
"""


def test_the_issues_minimal_shape_works_with_documented_defaults() -> None:
    c = parse_config(SCAN)
    assert c.publisher.type == "sensor_msgs/LaserScan"  # default: the subscriber's type
    assert (c.stream.field, c.stream.length) == ("ranges", 360)
    assert not c.is_image and repr(c.image) == "NoImage('sensor_msgs/LaserScan')"
    layout = layout_from_config(c)
    assert layout.step("intensities_length").check.high == DEFAULT_ARRAY_MAX
    assert layout.step("header_frame_id_length").check.high == c.frame_id_max
    assert layout.stream.type == "float32" and layout.stream_length == 360
    with pytest.raises(ConfigError, match=r"LaserScan has no image geometry \(image.width\)"):
        c.image.width  # noqa: B018  (an Image-only consumer gets a clear error)
    assert "NoImage" in repr(c) and c == parse_config(SCAN)


def test_the_shipped_examples_load_and_derive_their_layouts() -> None:
    scan = load_config(DATA / "fpga_laserscan_min.yaml")
    lay = layout_from_config(scan)
    assert lay.step("range_max").check.op is CheckOp.RANGE
    assert lay.step("header_frame_id_length").check.high == 64
    samples = load_config(DATA / "fpga_samples_dilate.yaml")
    assert samples.msg_path == ((DATA / "msg").resolve(),)
    lay = layout_from_config(samples)
    assert lay.type_name == "lab_msgs/Samples" and lay.stream.type == "int32"
    assert lay.step("calibration_mode").action is Action.CHECK
    assert lay.step("history_length").check.high == 4
    assert lay.step("history_sensor_name_length").check.high == DEFAULT_STRING_MAX


def test_msg_path_is_relative_to_the_file_and_the_command_line_adds_more(tmp_path: Path) -> None:
    text = (DATA / "fpga_samples_dilate.yaml").read_text()
    (tmp_path / "c.yaml").write_text(text.replace("msg_path: [msg]", "msg_path: [mine]"))
    with pytest.raises(ConfigError) as exc:
        load_config(tmp_path / "c.yaml")
    assert exc.value.key == "msg_path" and exc.value.line == 11
    shutil.copytree(DATA / "msg", tmp_path / "mine")
    assert load_config(tmp_path / "c.yaml").subscriber.type == "lab_msgs/Samples"
    (tmp_path / "d.yaml").write_text(text.replace("msg_path: [msg]", ""))
    with pytest.raises(ConfigError, match="unknown message type"):
        load_config(tmp_path / "d.yaml")
    c = load_config(tmp_path / "d.yaml", msg_path=[DATA / "msg"])
    assert c.msg_path == ((DATA / "msg").resolve(),)


def _bad(text: str, key: str, line: int, words: str) -> None:
    with pytest.raises(ConfigError) as exc:
        parse_config(text, source="x.yaml")
    assert (exc.value.key, exc.value.line) == (key, line), str(exc.value)
    where = f"x.yaml:{line}" if line else "x.yaml"
    assert words in str(exc.value) and str(exc.value).startswith(f"{where}: {key}: ")


@pytest.mark.parametrize(("old", "new", "key", "line", "words"), [
    ("field: ranges", "field: rangez", "stream.field", 4, "has no field 'rangez'"),
    ("field: ranges", "field: angle_min", "stream.field", 4, "not an array"),
    ("field: ranges", "field: header.frame_id", "stream.field", 4, "not an array"),
    ("field: ranges, length: 360", "field: ranges", "stream.length", 4, "element count"),
    ("stream: {field: ranges, length: 360}\n", "", "stream", 0, "missing section 'stream:'"),
    ("stream:", "image: {width: 2, height: 2, encoding: mono8}\nstream:", "image", 4,
     "sensor_msgs/Image only"),
    ("application: {op: erode, ksize: 5}", "application: {op: erode, ksize: 4}",
     "application.ksize", 5, "odd"),
    ("publisher: {topic: /out}", "publisher: {topic: /out, type: sensor_msgs/Imu}",
     "publisher.type", 3, "cannot stream the output"),
])
def test_refusals_name_file_line_and_key(old: str, new: str, key: str, line: int,
                                         words: str) -> None:
    assert old in SCAN
    _bad(SCAN.replace(old, new, 1), key, line, words)


@pytest.mark.parametrize(("extra", "key", "words"), [
    ("checks: {nope: 1}", "checks.nope", "has no field 'nope'"),
    ("checks: {ranges: 1}", "checks.ranges", "is the stream"),
    ("checks: {header.stamp: 1}", "checks.header.stamp", "a time"),
    ("checks: {header.seq: -1}", "checks.header.seq", "does not fit a uint32"),
    ("checks: {angle_min: fast}", "checks.angle_min", "is not a float32"),
    ("checks: {angle_min: .nan}", "checks.angle_min", "NaN equals nothing"),
    ("checks: {angle_min: {max: .nan}}", "checks.angle_min", "NaN equals nothing"),
    ("checks: {angle_min: {min: 2, max: 1}}", "checks.angle_min", "above max"),
    ("checks: {angle_min: {low: 2}}", "checks.angle_min", "{min: LOW, max: HIGH}"),
    ("checks: {header.frame_id: {max: 3}}", "checks.header.frame_id", "only be checked for equality"),
    ("limits: {angle_min: 3}", "limits.angle_min", "only strings and variable-length arrays"),
    ("limits: {intensities: -1}", "limits.intensities", "expected 0.."),
    ("limits: {ranges: 5}", "limits.ranges", "is the stream"),
    ("skip: [ranges]", "skip", "cannot be skipped"),
    ("skip: [nope]", "skip", "no field 'nope'"),
    ("msg_path: 3", "msg_path", "must be a list"),
])
def test_checks_limits_and_skip_are_checked_against_the_type(extra: str, key: str,
                                                              words: str) -> None:
    _bad(SCAN + extra + "\n", key, 6, words)


@pytest.mark.parametrize(("type_name", "field", "words"), [
    ("geometry_msgs/PoseArray", "poses", "array of messages"),
    ("sensor_msgs/JointState", "name", "array of strings"),
    ("sensor_msgs/PointCloud", "points", "array of messages"),
])
def test_streams_the_application_cannot_take_are_refused(type_name: str, field: str,
                                                         words: str) -> None:
    text = SCAN.replace("sensor_msgs/LaserScan", type_name).replace("ranges", field)
    _bad(text, "stream.field", 4, words)


def test_checks_and_skip_reach_the_layout() -> None:
    c = parse_config(SCAN + "checks: {angle_min: -1.5, range_max: {min: 1, max: 50}, "
                     "header.frame_id: laser}\nskip: [intensities]\n")
    lay = layout_from_config(c)
    assert lay.step("angle_min").check.value == -1.5
    assert (lay.step("range_max").check.low, lay.step("range_max").check.high) == (1, 50)
    assert lay.step("header_frame_id").check.value == "laser"
    assert lay.step("intensities").action is Action.SKIP


def test_image_configs_keep_their_shape_and_imply_the_image_checks() -> None:
    c = load_config(DATA / "fpga_erode_mono8.yaml")
    assert c.is_image and (c.stream.field, c.stream.length) == ("data", 320 * 240)
    lay = layout_from_config(c)
    assert [(s.ident, s.check.value) for s in lay.checked() if s.check.op is CheckOp.EQUAL] == [
        ("height", 240), ("width", 320), ("encoding", "mono8"), ("step", 320), ("data_length", 76800)]
    assert lay.video is not None and lay.beat_bits == 32
    text = (DATA / "fpga_erode_mono8.yaml").read_text()
    _bad(text.replace("clock_mhz", "stream: {field: data, length: 5}\nclock_mhz"),
         "stream.field", 19, "76800 elements")
    _bad(text.replace("clock_mhz", "checks: {width: 5}\nclock_mhz"), "checks.width", 19,
         "image: already")
    _bad(text.replace("image:\n  width: 320\n  height: 240\n  encoding: mono8\n", ""),
         "image", 0, "missing section 'image:'")


OWN = """\
node: {name: /fpga_linescan}
subscriber: {topic: /line, type: my_msgs/LineScan}
publisher: {topic: /line_eroded}
msg_path: [msg]
stream: {field: values, length: 32}
application: {op: erode, ksize: 3}
"""


@pytest.mark.parametrize("typo, meant", [("flaot32", "float32"), ("unit8", "uint8"),
                                         ("strng", "string"), ("Float64", "float64")])
def test_a_misspelt_primitive_is_a_config_error_with_its_line_and_the_primitive(
        tmp_path: Path, typo: str, meant: str) -> None:
    """Notebook 10: ``flaot32[] values`` gave a raw UnknownTypeError traceback where other
    .msg mistakes give a ConfigError with the line."""
    (tmp_path / "msg/my_msgs/msg").mkdir(parents=True)
    msg = tmp_path / "msg/my_msgs/msg/LineScan.msg"
    msg.write_text(f"Header header\nuint8 gain\n{typo}[] values\n")
    with pytest.raises(ConfigError) as info:
        parse_config(OWN, source="notebook config", base_dir=tmp_path)
    text = str(info.value)
    assert text.startswith("notebook config:2: subscriber.type: unknown message type "
                           f"'my_msgs/{typo}', used by field 'values' of my_msgs/LineScan "
                           f"({msg.resolve()}:3) -- did you mean the primitive '{meant}'?"), text


def test_an_unknown_message_type_far_from_any_primitive_gets_no_primitive_hint(
        tmp_path: Path) -> None:
    (tmp_path / "msg/my_msgs/msg").mkdir(parents=True)
    (tmp_path / "msg/my_msgs/msg/LineScan.msg").write_text("Pose pose\nuint16[] values\n")
    with pytest.raises(ConfigError, match=r"unknown message type 'my_msgs/Pose', used by field "
                                          r"'pose' of my_msgs/LineScan \(.*LineScan.msg:1\); "
                                          r"searched") as info:
        parse_config(OWN, source="notebook config", base_dir=tmp_path)
    assert "did you mean" not in str(info.value)
