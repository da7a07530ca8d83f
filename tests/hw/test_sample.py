"""hw.sample: a message of any layout's type that its circuit accepts, and a frame it refuses
(what notebook 10 shows for a student's own type). Checked against the msg layer's serializer
and the circuit's model; expected values set by hand."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.hw.errors import FrameFieldError
from rosfpga_lab.hw.layout import layout_from_config
from rosfpga_lab.hw.sample import example_message, framed, random_stream, refused_frame
from rosfpga_lab.hw.walker import extract_fast
from rosfpga_lab.msg import serialize

DATA = Path(__file__).resolve().parents[2] / "data"
OWN = """Header header
uint64 count
string station
uint8 mode
float32[] level
"""
OWN_CONFIG = """node: {name: /fpga_levels}
subscriber: {topic: /tank/levels, type: tank_msgs/Levels}
publisher: {topic: /tank/levels_min}
msg_path: [msg]
stream: {field: level, length: 6}
checks: {mode: 2, count: {min: 10, max: 20}}
limits: {station: 5}
application: {op: erode, ksize: 3}
"""


@pytest.fixture()
def own(tmp_path: Path):
    (tmp_path / "msg/tank_msgs/msg").mkdir(parents=True)
    (tmp_path / "msg/tank_msgs/msg/Levels.msg").write_text(OWN)
    return parse_config(OWN_CONFIG, source="test", base_dir=tmp_path)


def test_the_example_message_is_accepted_and_readable(own) -> None:
    reg = own.registry()
    layout = layout_from_config(own, reg)
    msg = example_message(layout, reg)
    # checked fields at what the circuit takes (a range: its low end), strings their own field
    # names cut to their maximum, the stream its 6 elements, a ramp of 0.25
    assert msg["mode"] == 2 and msg["count"] == 10
    assert msg["station"] == "stati" and msg["header"]["frame_id"] == "frame_id"
    assert msg["level"].tolist() == [0.0, 0.25, 0.5, 0.75, 1.0, 1.25]
    body = serialize(reg, "tank_msgs/Levels", msg)
    # by hand: 4 + 8 + 4 + 8 (header) + 8 (count) + 4 + 5 (station) + 1 + 4 + 6 * 4
    assert len(body) == 4 + 8 + 4 + 8 + 8 + 4 + 5 + 1 + 4 + 24
    extract_fast(layout, framed(body))                     # accepted


def test_the_refused_frame_breaks_the_first_check(own) -> None:
    reg = own.registry()
    layout = layout_from_config(own, reg)
    bad = refused_frame(layout, example_message(layout, reg))
    # count comes before mode in the walk: its range 10..20, so 21
    assert bad.step.label == "count" and bad.value == 21
    with pytest.raises(FrameFieldError) as info:
        extract_fast(layout, bad.frame)
    assert info.value.field == "count" and info.value.offset == 4 + 4 + 8 + 4 + 8


def test_without_checks_the_stream_is_one_element_too_long() -> None:
    config = parse_config("""node: {name: /scan_min}
subscriber: {topic: /scan, type: sensor_msgs/LaserScan}
publisher: {topic: /out}
stream: {field: ranges, length: 4}
application: {op: erode, ksize: 3}
""")
    reg = config.registry()
    layout = layout_from_config(config, reg)
    bad = refused_frame(layout, example_message(layout, reg))
    assert bad.step.label == "ranges length" and bad.value == 5
    with pytest.raises(FrameFieldError) as info:
        extract_fast(layout, bad.frame)
    assert info.value.field == "ranges length"
    assert struct.unpack_from("<I", bad.frame)[0] == len(bad.frame) - 4


def test_random_streams_fit_the_element_type() -> None:
    config = load_config(DATA / "fpga_samples_dilate.yaml")
    reg = config.registry()
    layout = layout_from_config(config, reg)
    values = random_stream(layout, np.random.default_rng(1))
    assert values.dtype == np.dtype("<i4") and len(values) == 64
    assert values.min() >= 0 and values.max() < 4096
    msg = example_message(layout, reg, stream=values)
    out = extract_fast(layout, framed(serialize(reg, "lab_msgs/Samples", msg)))
    assert np.array_equal(out.stream, values)


@pytest.mark.parametrize("encoding, channels", [("bgr8", 3), ("mono8", 1), ("rgba8", 4)])
def test_image_frame_is_the_message_layers_image(encoding: str, channels: int) -> None:
    """hw.sample.image_frame (the camera's and the benchmarks' frames) writes what the msg
    layer's serializer writes for the same Image; a picture of the wrong depth is refused."""
    from rosfpga_lab.hw.errors import PipelineConfigError
    from rosfpga_lab.hw.sample import image_frame
    from rosfpga_lab.msg import default_registry

    image = np.random.default_rng(5).integers(0, 256, (4, 5, channels), dtype=np.uint8)
    msg = {"header": {"seq": 2, "stamp": (3, 4), "frame_id": "f"}, "height": 4, "width": 5,
           "encoding": encoding, "is_bigendian": 1, "step": 5 * channels,
           "data": image.tobytes()}
    body = serialize(default_registry(), "sensor_msgs/Image", msg)
    assert image_frame(image, encoding, seq=2, stamp=(3, 4), frame_id="f",
                       is_bigendian=1) == struct.pack("<I", len(body)) + body
    with pytest.raises(PipelineConfigError, match="bytes per pixel"):
        image_frame(image, "rgba8" if channels != 4 else "mono8")
