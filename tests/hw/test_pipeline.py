"""The whole pipeline: frames in and out, both models, bad input, faults, cycles, real genpy."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.hw import (
    DropByte, DuplicateByte, FifoOverflowError, FrameFieldError, FrameTruncatedError, LoseTlast,
    LoseTuser, Pipeline, PipelineConfigError, PipelineError, ShallowFifo, StreamStarvedError,
    SwapByteOrder, UnsupportedEncodingError, image_frame,
)
from tests.support.realros import run_ros_python
from tests.hw.test_oracles import CHANNELS, decode_frame, image_msg, images, morph_oracle, tcpros_frame

RNG = np.random.default_rng(2026)


def random_image(rows: int, cols: int, encoding: str) -> np.ndarray:
    return RNG.integers(0, 256, (rows, cols, CHANNELS[encoding]), dtype=np.uint8)


def expected_frame(image, encoding, op="dilate", ksize=(3, 3), seq=1, **header) -> bytes:
    out = image if op == "passthrough" else morph_oracle(image, op, *ksize)
    return tcpros_frame(image_msg(out, encoding, seq=seq, **header))


@pytest.mark.parametrize("model", ["fast", "reference"])
@pytest.mark.parametrize("encoding", list(CHANNELS))
def test_whole_frame_comes_out_as_the_dilated_image_message(model, encoding):
    image = random_image(9, 13, encoding)
    frame = tcpros_frame(image_msg(image, encoding, seq=41, stamp=(1700000000, 5), frame_id="cam"))
    pipe = Pipeline(width=13, height=9, encoding=encoding, model=model)
    res = pipe.process(frame)
    assert res.output_frame == expected_frame(image, encoding, stamp=(1700000000, 5), frame_id="cam")
    assert res.ok and res.status == [] and res.model == model
    msg = decode_frame(res.output_frame)
    assert msg["header"]["seq"] == 1 and msg["header"]["frame_id"] == "cam"
    assert np.array_equal(res.input_image, image)
    assert np.array_equal(res.output_image, morph_oracle(image, "dilate", 3, 3))
    assert res.fields.seq == 41 and res.output_fields.seq == 1
    assert len(res.input_beats) == len(res.output_beats) == 9 * 13
    assert res.streams["pixels_in"].tobytes() == image.tobytes()
    assert res.streams["pixels_out"].tobytes() == res.output_image.tobytes()
    assert res.streams["axis_in"] == res.input_beats and res.streams["tx"] == res.output_frame
    assert not res.output_image.flags.writeable
    # the next frame counts seq up, as a rospy publisher does
    assert decode_frame(pipe.process(frame).output_frame)["header"]["seq"] == 2


@given(images(max_side=6), st.sampled_from(["dilate", "erode", "passthrough"]), st.integers(1, 4),
       st.integers(1, 4), st.text(max_size=6))
@settings(max_examples=40, deadline=None)
def test_reference_pipeline_equals_fast_pipeline(img_enc, op, kw, kh, frame_id):
    image, encoding = img_enc
    frame = tcpros_frame(image_msg(image, encoding, seq=3, frame_id=frame_id))
    ref = Pipeline(op=op, ksize=(kw, kh), model="reference").process(frame)
    fast = Pipeline(op=op, ksize=(kw, kh), model="fast").process(frame)
    assert ref.output_frame == fast.output_frame == expected_frame(image, encoding, op, (kw, kh),
                                                                   frame_id=frame_id)
    assert ref.input_beats == fast.input_beats and ref.output_beats == fast.output_beats
    assert np.array_equal(ref.output_image, fast.output_image)
    assert ref.cycles == fast.cycles and ref.latency == fast.latency
    assert ref.fifo_high_water == fast.fifo_high_water == {"rx": 1}


def test_header_policies_carry_or_set():
    image = random_image(3, 4, "mono8")
    frame = tcpros_frame(image_msg(image, "mono8", seq=77, stamp=(5, 6), frame_id="in"))
    res = Pipeline(seq="carry", stamp=(9, 10), frame_id="out").process(frame)
    assert res.output_frame == expected_frame(image, "mono8", seq=77, stamp=(9, 10), frame_id="out")
    pipe = Pipeline(seq_start=100)
    assert decode_frame(pipe.process(frame).output_frame)["header"]["seq"] == 100
    assert pipe.next_seq == 101
    pipe.reset()
    assert pipe.next_seq == 101
    pipe.reset(seq=True)
    assert decode_frame(pipe.process(frame).output_frame)["header"]["seq"] == 100
    assert "op='dilate'" in repr(pipe)


def test_image_frame_helper_matches_the_message_layer():
    image = random_image(4, 5, "bgr8")
    assert image_frame(image, "bgr8", seq=2, stamp=(3, 4), frame_id="f") == tcpros_frame(
        image_msg(image, "bgr8", seq=2, stamp=(3, 4), frame_id="f"))
    with pytest.raises(PipelineConfigError):
        image_frame(image, "rgba8")


# -- bad input: a typed error, the stages reset, the next good frame comes out right ----------------

GOOD_IMAGE = random_image(4, 6, "rgba8")
GOOD = tcpros_frame(image_msg(GOOD_IMAGE, "rgba8", frame_id="cam"))


@pytest.mark.parametrize("model", ["fast", "reference"])
@pytest.mark.parametrize("frame, error, field", [
    (tcpros_frame(image_msg(GOOD_IMAGE, "rgba8", data=GOOD_IMAGE.tobytes()[:-4])), FrameFieldError,
     "data length"),
    (tcpros_frame(image_msg(GOOD_IMAGE, "yuv422")), UnsupportedEncodingError, "encoding"),
    (tcpros_frame(image_msg(GOOD_IMAGE, "rgba8", width=0)), FrameFieldError, "width"),
    (tcpros_frame(image_msg(GOOD_IMAGE, "rgba8", height=100000)), FrameFieldError, "height"),
    (GOOD[:-5], FrameTruncatedError, "data"),
    (GOOD[:10], FrameTruncatedError, "header.stamp.secs"),
    (b"", FrameTruncatedError, "frame length"),
], ids=["data-length", "encoding", "width0", "height-absurd", "cut-in-data", "cut-in-header", "empty"])
def test_bad_frame_is_refused_and_the_next_frame_is_right(model, frame, error, field):
    pipe = Pipeline(model=model)
    first = pipe.process(GOOD).output_frame
    with pytest.raises(error) as info:
        pipe.process(frame)
    assert info.value.field == field and field in str(info.value)
    assert pipe.errors == 1
    again = pipe.process(GOOD)
    assert again.output_frame == expected_frame(GOOD_IMAGE, "rgba8", seq=2, frame_id="cam")
    assert decode_frame(first)["data"].tobytes() == decode_frame(again.output_frame)["data"].tobytes()


@pytest.mark.parametrize("model", ["fast", "reference"])
def test_frame_id_longer_than_the_configured_limit_is_refused(model):
    pipe = Pipeline(model=model, max_frame_id_bytes=3)
    with pytest.raises(FrameFieldError) as info:
        pipe.process(GOOD)  # frame_id "cam" fits; "cams" does not
        pipe.process(tcpros_frame(image_msg(GOOD_IMAGE, "rgba8", frame_id="cams")))
    assert info.value.field == "header.frame_id length" and "max_frame_id_bytes" in str(info.value)
    assert info.value.offset == 16 and info.value.value == 4
    again = pipe.process(GOOD)
    assert again.output_frame == expected_frame(GOOD_IMAGE, "rgba8", seq=2, frame_id="cam")
    with pytest.raises(PipelineConfigError):
        Pipeline(max_frame_id_bytes=0)


def test_bad_configuration_is_refused():
    for kwargs in ({"model": "rtl"}, {"op": "blur"}, {"encoding": "yuv422"}, {"width": 0},
                   {"ksize": (0, 3)}, {"seq": "random"}, {"clock_hz": 0}, {"rx_fifo_depth": 0},
                   {"faults": ["drop"]}, {"seq_start": -1}, {"stamp": (1, 2, 3)}, {"stamp": 5},
                   {"stamp": (-1, 0)}, {"frame_id": 5}, {"frame_id": "x" * 1000}):
        with pytest.raises(PipelineConfigError):
            Pipeline(**kwargs)
    with pytest.raises(PipelineConfigError):
        LoseTlast(tap="pixels_in")
    with pytest.raises(PipelineConfigError):
        DropByte(tap="axis_in")


# -- faults: a visibly wrong image, a status flag, or a typed error, never a hang -------------------

FAULT_IMAGE = random_image(5, 8, "rgba8")
FAULT_FRAME = tcpros_frame(image_msg(FAULT_IMAGE, "rgba8"))


def both_models(faults, frame=FAULT_FRAME, **kwargs):
    """Run both models with ``faults``; check they agree; return the fast result or error."""
    outcomes = []
    for model in ("reference", "fast"):
        try:
            outcomes.append(Pipeline(model=model, faults=faults, **kwargs).process(frame))
        except PipelineError as exc:
            outcomes.append(exc)
    ref, fast = outcomes
    if isinstance(ref, Exception) or isinstance(fast, Exception):
        assert type(ref) is type(fast) and ref.stage == fast.stage, (ref, fast)
        return fast
    assert ref.output_frame == fast.output_frame and ref.status == fast.status
    assert ref.input_beats == fast.input_beats and ref.output_beats == fast.output_beats
    assert ref.fifo_high_water == fast.fifo_high_water
    assert np.array_equal(ref.input_image, fast.input_image)
    return fast


def test_duplicated_byte_shifts_the_colours_and_is_reported():
    res = both_models([DuplicateByte(index=10, tap="pixels_in")])
    shifted = np.frombuffer(np.insert(FAULT_IMAGE.reshape(-1), 10, FAULT_IMAGE.reshape(-1)[10])
                            [: FAULT_IMAGE.size].tobytes(), np.uint8).reshape(FAULT_IMAGE.shape)
    assert np.array_equal(res.input_image, shifted) and not np.array_equal(shifted, FAULT_IMAGE)
    assert res.status == ["1 byte left in 'pixels_in' after the frame (flushed): the stream was out of step"]


def test_dropped_byte_starves_fifo2axi_with_a_partial_result():
    err = both_models([DropByte(index=3, tap="pixels_in")])
    assert isinstance(err, StreamStarvedError) and err.stage == "fifo2axi"
    assert (err.needed, err.got) == (FAULT_IMAGE.size, FAULT_IMAGE.size - 1)
    assert len(err.partial) == 5 * 8 - 1
    err = both_models([DropByte(index=len(FAULT_FRAME) - 1, tap="rx")])
    assert isinstance(err, FrameTruncatedError) and err.field == "data"
    err = both_models([DropByte(index=5, tap="pixels_out")])
    assert isinstance(err, StreamStarvedError) and err.stage == "generator"


def test_swapped_byte_order_reverses_the_channels():
    res = both_models([SwapByteOrder(tap="axis_in")], ksize=(1, 1))
    assert np.array_equal(res.output_image, FAULT_IMAGE[:, :, ::-1]) and res.ok
    rgb = random_image(3, 3, "rgb8")
    res = both_models([SwapByteOrder(tap="axis_out")], frame=tcpros_frame(image_msg(rgb, "rgb8")),
                      op="passthrough")
    assert decode_frame(res.output_frame)["data"].tobytes() == rgb[:, :, ::-1].tobytes()


def test_lost_tlast_and_tuser():
    err = both_models([LoseTlast(line=2)])
    assert isinstance(err, StreamStarvedError) and err.stage == "axivideo2mat"
    assert np.array_equal(err.partial[:3], FAULT_IMAGE[:3])          # rows before the fault are right
    assert np.array_equal(err.partial[3], FAULT_IMAGE[4])            # then the image slips a line
    err = both_models([LoseTuser()])
    assert isinstance(err, StreamStarvedError) and "made 0 of the 40 pixels" in str(err)
    # a tlast lost on the way out goes unnoticed by axi2fifo: the bytes are still right
    res = both_models([LoseTlast(line=0, tap="axis_out")])
    assert res.output_frame == expected_frame(FAULT_IMAGE, "rgba8")
    assert not res.output_beats.tlast[7]


def test_fifo_too_shallow_for_a_burst():
    err = both_models([ShallowFifo(depth=64, burst_bytes=100)])
    assert isinstance(err, FifoOverflowError) and (err.depth, err.needed) == (64, 100)
    assert "at least 100 bytes deep" in str(err)
    res = both_models([ShallowFifo(depth=100, burst_bytes=100)])
    assert res.fifo_high_water == {"rx": 100} and res.output_frame == expected_frame(FAULT_IMAGE, "rgba8")


@pytest.mark.parametrize("model", ["fast", "reference"])
@pytest.mark.parametrize("fault", [
    DuplicateByte(index=10, tap="pixels_in"), DropByte(index=3, tap="pixels_in"),
    DropByte(index=30, tap="rx"), DuplicateByte(index=30, tap="rx"), DropByte(index=5, tap="pixels_out"),
    SwapByteOrder(tap="axis_in"), LoseTlast(line=2), LoseTuser(), LoseTlast(line=0, tap="axis_out"),
], ids=repr)
def test_after_a_fault_the_next_good_frame_comes_out_right(model, fault):
    """The same pipeline, its fault then removed: no state of the faulty frame lingers."""
    pipe = Pipeline(model=model, faults=[fault])
    try:
        bad = pipe.process(FAULT_FRAME)
    except PipelineError:
        pass
    else:  # the fault did show: in the output bytes, or (a lost TLAST on the way out) the beats
        clean = Pipeline(model=model).process(FAULT_FRAME)
        assert bad.output_frame != clean.output_frame or bad.output_beats != clean.output_beats
    pipe.faults = ()
    res = pipe.process(GOOD)
    assert res.ok and res.output_frame == expected_frame(GOOD_IMAGE, "rgba8", seq=res.output_fields.seq,
                                                         frame_id="cam")


@pytest.mark.parametrize("model", ["fast", "reference"])
def test_after_a_fifo_overflow_the_next_frame_that_fits_comes_out_right(model):
    pipe = Pipeline(model=model, faults=[ShallowFifo(depth=64, burst_bytes=100)])
    with pytest.raises(FifoOverflowError):
        pipe.process(FAULT_FRAME)
    small = random_image(1, 1, "mono8")
    frame = tcpros_frame(image_msg(small, "mono8"))
    assert len(frame) <= 64
    assert pipe.process(frame).output_frame == expected_frame(small, "mono8", seq=1)


def test_fault_index_outside_the_stream_is_a_config_error():
    with pytest.raises(PipelineConfigError, match="outside"):
        Pipeline(faults=[DropByte(index=10**6)]).process(FAULT_FRAME)


# -- cycle accounting ---------------------------------------------------------------------------

def test_cycles_for_the_papers_frame_at_100_mhz():
    image = np.zeros((480, 640, 4), np.uint8)
    frame = image_frame(image, "rgba8")
    res = Pipeline(width=640, height=480, encoding="rgba8").process(frame)
    data = 640 * 480 * 4
    assert len(frame) == data + 46  # 4-byte length + 42-byte Image header
    assert res.cycles == {
        "interpreter": data + 46, "fifo2axi": data, "axivideo2mat": 307200,
        "dilate": 481 * 641, "mat2axivideo": 307200, "axi2fifo": data, "generator": data + 46,
    }
    # The filter's first pixel out after 641 + 2 pixels in, one pixel every 4 clocks.
    assert res.latency["dilate"] == (641 + 1) * 4 + 1 and res.latency["interpreter"] == 47
    assert res.report.bottleneck == "interpreter" and res.report.clocks_per_beat == 4
    # The last byte leaves the filter's lag after the last byte came in (checked in the RTL).
    assert res.total_cycles == data + 46 + res.latency["dilate"]
    assert res.frame_time_s == pytest.approx(res.total_cycles / 100e6)
    assert res.frame_time_s == pytest.approx(0.01231, rel=1e-3)
    assert res.network_time_s == pytest.approx((data + 46) * 8 / 1e9)
    assert "bottleneck: interpreter" in res.summary()
    fast_clock = Pipeline(clock_hz=200e6, line_rate_bps=10e9).process(frame)
    assert fast_clock.frame_time_s == pytest.approx(res.frame_time_s / 2)
    assert fast_clock.network_time_s == pytest.approx(res.network_time_s / 10)


# -- against real ROS ---------------------------------------------------------------------------

GENPY = r"""
import io, json, sys
import rospy.msg
from sensor_msgs.msg import Image
job = json.load(sys.stdin)
out = {}
for name, spec in job.items():
    msg = Image()
    msg.header.stamp.secs, msg.header.stamp.nsecs = spec["stamp"]
    msg.header.frame_id = spec["frame_id"]
    msg.height, msg.width, msg.encoding = spec["height"], spec["width"], spec["encoding"]
    msg.is_bigendian, msg.step = 0, spec["step"]
    msg.data = bytes.fromhex(spec["data"])
    buf = io.BytesIO()
    rospy.msg.serialize_message(buf, spec["seq"], msg)   # what a rospy publisher sends
    out[name] = buf.getvalue().hex()
print(json.dumps(out))
"""


def test_output_frame_equals_what_a_rospy_publisher_sends(real_ros):
    """Input and expected output frames both written by real genpy/rospy."""
    jobs, images_in = {}, {}
    for encoding, (rows, cols) in zip(CHANNELS, [(6, 5), (1, 7), (7, 1), (4, 4), (9, 3)]):
        image = random_image(rows, cols, encoding)
        images_in[encoding] = image
        common = {"stamp": [1700000123, 456], "frame_id": "camera_" + encoding, "height": rows,
                  "width": cols, "encoding": encoding, "step": cols * CHANNELS[encoding]}
        jobs[f"{encoding}/in"] = {**common, "seq": 17, "data": image.tobytes().hex()}
        jobs[f"{encoding}/out"] = {**common, "seq": 1,
                                   "data": morph_oracle(image, "dilate", 3, 3).tobytes().hex()}
    proc = run_ros_python(GENPY, input=json.dumps(jobs).encode())
    frames = {k: bytes.fromhex(v) for k, v in json.loads(proc.stdout).items()}
    for encoding in CHANNELS:
        for model in ("fast", "reference"):
            res = Pipeline(model=model).process(frames[f"{encoding}/in"])
            assert res.fields.seq == 17 and res.fields.frame_id == "camera_" + encoding
            assert res.output_frame == frames[f"{encoding}/out"], (encoding, model)


FAULTS = st.one_of(
    st.builds(DropByte, index=st.integers(0, 120), tap=st.sampled_from(["rx", "pixels_in", "pixels_out"])),
    st.builds(DuplicateByte, index=st.integers(0, 120),
              tap=st.sampled_from(["rx", "pixels_in", "pixels_out"])),
    st.builds(SwapByteOrder, tap=st.sampled_from(["axis_in", "axis_out"])),
    st.builds(LoseTlast, line=st.integers(0, 5), tap=st.sampled_from(["axis_in", "axis_out"])),
    st.builds(LoseTuser, tap=st.sampled_from(["axis_in", "axis_out"])),
    st.builds(ShallowFifo, depth=st.integers(1, 200), burst_bytes=st.integers(1, 200)),
)


@given(images(max_side=5), st.lists(FAULTS, max_size=3))
@settings(max_examples=120, deadline=None)
def test_any_faults_end_the_same_way_in_both_models_and_never_hang(img_enc, faults):
    """A result or a PipelineError (never another exception), identical in both models."""
    image, encoding = img_enc
    frame = tcpros_frame(image_msg(image, encoding, frame_id="f"))
    outcome = both_models(faults, frame=frame)
    if not isinstance(outcome, Exception) and not faults:
        assert outcome.output_frame == expected_frame(image, encoding, frame_id="f")


def test_wire_time_counts_tcp_ip_and_ethernet_overhead() -> None:
    """A frame on gigabit Ethernet: 1,448 payload bytes per 1,500-byte packet (IPv4 20 + TCP 20
    + timestamps 12), and 1,538 bytes per packet on the line (preamble 8, MAC 14, FCS 4, gap 12)."""
    from rosfpga_lab.hw import wire_bytes

    assert wire_bytes(1448) == 1538
    assert wire_bytes(1449) == 1449 + 2 * 90
    assert wire_bytes(10 * 1448) == 10 * 1538
    frame = image_frame(np.zeros((480, 640, 4), np.uint8), "rgba8")
    r = Pipeline(width=640, height=480, encoding="rgba8").process(frame)
    payload = len(frame)
    assert r.network_time_s == pytest.approx(8 * payload / 1e9)
    segments = -(-payload // 1448)
    assert r.wire_time_s == pytest.approx(8 * (payload + 90 * segments) / 1e9)
    assert 10.3e-3 < r.wire_time_s < 10.5e-3   # vs 9.83 ms for the payload alone
