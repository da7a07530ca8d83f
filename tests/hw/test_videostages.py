"""The video stretch between the generated circuit's walkers (``hw.videostages``): an Image frame
through the subscriber walker, the stages and the publisher walker is the message with its pixels
dilated as OpenCV dilates them; faults at its taps stop or flag it as the stages say."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rosfpga_lab import config as lab_config
from rosfpga_lab.hw import DropByte, DuplicateByte, LoseTuser, SwapByteOrder
from rosfpga_lab.hw.errors import PipelineConfigError, StreamStarvedError
from rosfpga_lab.hw.layout import layout_from_config
from rosfpga_lab.hw.publisherwalker import publish_fast
from rosfpga_lab.hw.streams import Beats
from rosfpga_lab.hw.subscriberwalker import extract_fast
from rosfpga_lab.hw.videostages import video_stages
from rosfpga_lab.msg import default_registry, serialize
from rosfpga_lab.tcpros import encode_frame

REG = default_registry()
CHANNELS = {"rgba8": 4, "rgb8": 3, "mono8": 1}


def layout_for(width: int, height: int, encoding: str, op: str = "dilate"):
    config = lab_config.parse_config(
        "node: {name: /n}\nsubscriber: {topic: /a, type: sensor_msgs/Image}\n"
        f"publisher: {{topic: /b}}\nimage: {{width: {width}, height: {height}, "
        f"encoding: {encoding}}}\napplication: {{op: {op}, ksize: 3}}\n", source="test")
    return layout_from_config(config, REG)


def image_message(image: np.ndarray, encoding: str) -> dict:
    rows, cols = image.shape[:2]
    return {"header": {"seq": 3, "stamp": {"secs": 4, "nsecs": 5}, "frame_id": "cam"},
            "height": rows, "width": cols, "encoding": encoding, "is_bigendian": 0,
            "step": cols * CHANNELS[encoding], "data": image.tobytes()}


@pytest.mark.parametrize("encoding,op", [("rgba8", "dilate"), ("rgb8", "erode"), ("mono8", "dilate")])
def test_a_frame_through_the_walkers_and_stages_is_opencvs(encoding: str, op: str) -> None:
    rng = np.random.default_rng(1)
    image = rng.integers(0, 256, (5, 7, CHANNELS[encoding]), np.uint8)
    layout = layout_for(7, 5, encoding, op)
    msg = image_message(image, encoding)
    ex = extract_fast(layout, encode_frame(serialize(REG, "sensor_msgs/Image", msg)))
    stages = video_stages(layout.video, ex.stream, op)
    morph = cv2.dilate if op == "dilate" else cv2.erode
    want = morph(image, np.ones((3, 3), np.uint8)).reshape(image.shape)
    assert np.array_equal(stages.output_image, want) and stages.status == []
    assert np.array_equal(stages.input_image, image)
    out = publish_fast(layout, ex.tokens, stages.pixels_out)
    assert out == encode_frame(serialize(REG, "sensor_msgs/Image", {**msg, "data": want.tobytes()}))
    assert stages.axis_in.tuser.tolist() == [True] + [False] * 34
    assert np.flatnonzero(stages.axis_in.tlast).tolist() == [6, 13, 20, 27, 34]


def test_faults_stop_or_flag_the_stages() -> None:
    layout = layout_for(4, 3, "rgba8")
    stream = np.arange(48, dtype=np.uint8)
    with pytest.raises(StreamStarvedError) as lost:
        video_stages(layout.video, stream, "dilate", faults=[DropByte(index=5)])
    assert lost.value.stage == "fifo2axi" and isinstance(lost.value.partial, Beats)
    assert len(lost.value.partial) == 11                      # 47 bytes: 11 whole pixels
    with pytest.raises(StreamStarvedError) as no_start:
        video_stages(layout.video, stream, "dilate", faults=[LoseTuser()])
    assert no_start.value.stage == "axivideo2mat"
    extra = video_stages(layout.video, stream, "passthrough", faults=[DuplicateByte(index=5)])
    assert extra.status == ["1 byte left in 'pixels_in' after the frame"]
    assert extra.output_image.reshape(-1)[:7].tolist() == [0, 1, 2, 3, 4, 5, 5]
    swapped = video_stages(layout.video, stream, "passthrough", faults=[SwapByteOrder()])
    assert swapped.output_image[0, 0].tolist() == [3, 2, 1, 0]


def test_a_fault_at_a_tap_the_stages_have_not_is_refused() -> None:
    with pytest.raises(PipelineConfigError, match="choose one of pixels_in, pixels_out"):
        DropByte(tap="rx")
    with pytest.raises(PipelineConfigError, match="choose one of axis_in, axis_out"):
        SwapByteOrder(tap="pixels_in")
