"""Stream types and the STEP 3 stages: packing rules, reference == fast, faulty streams."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.hw import (
    ERROR_IO_EOL_EARLY, ERROR_IO_EOL_LATE, ERROR_IO_SOF_EARLY, PIXEL_FORMATS, Beat, Beats,
    ByteFIFO, Fifo, Mat, PipelineConfigError, StreamStarvedError, axi2fifo_fast,
    axi2fifo_reference, axivideo2mat_fast, axivideo2mat_reference, fifo2axi_fast,
    fifo2axi_reference, mat2axivideo_fast,
    mat2axivideo_reference,
)
from rosfpga_lab.hw.video import beats_to_fifo
from tests.hw.test_oracles import CHANNELS, image_msg, images, tcpros_frame


# -- streams ------------------------------------------------------------------------------------

def test_byte_fifo_depth_level_full_empty_overflow():
    fifo = ByteFIFO(depth=2, name="f")
    assert fifo.empty and not fifo.full and fifo.level == 0
    assert fifo.write(1) and fifo.write(2)
    assert fifo.full and fifo.level == 2 and not fifo.overflow
    assert fifo.write(3) is False
    assert fifo.overflow and fifo.dropped == 1 and fifo.level == 2 and fifo.high_water == 2
    assert fifo.read() == 1 and fifo.read() == 2 and fifo.empty
    with pytest.raises(StreamStarvedError, match="empty FIFO 'f' after 2 items of the 5 needed"):
        fifo.read("stage", 5)
    assert fifo.overflow  # sticky until reset
    fifo.reset()
    assert not fifo.overflow and fifo.high_water == 0
    with pytest.raises(PipelineConfigError):
        fifo.write(256)
    with pytest.raises(PipelineConfigError):
        ByteFIFO(depth=0)


def test_beats_round_trip_and_equality():
    beats = [Beat(0x04030201, 0xF, True, False), Beat(0x00060504, 0x7, False, True)]
    packed = Beats.from_list(beats)
    assert packed.to_list() == beats and packed[1] == beats[1] and len(packed) == 2
    assert packed == Beats.from_list(beats)
    other = packed.copy()
    other.tlast[1] = False
    assert other != packed and packed.first_difference(other) == 1
    assert Beat(0x04030201).lanes() == (1, 2, 3, 4)
    with pytest.raises(PipelineConfigError):
        Beats(np.zeros(3, np.uint32), 0xF, np.zeros(2, bool), False)


# -- fifo2axi / axi2fifo --------------------------------------------------------------------------

@pytest.mark.parametrize("encoding, tdata, tkeep", [
    ("rgba8", [0x04030201, 0x08070605], 0b1111),
    ("bgra8", [0x04030201, 0x08070605], 0b1111),
    ("rgb8", [0x00030201, 0x00060504], 0b0111),
    ("bgr8", [0x00030201, 0x00060504], 0b0111),
    ("mono8", [0x00000001, 0x00000002], 0b0001),
])
def test_packing_rule_for_each_encoding(encoding, tdata, tkeep):
    """Figure 7: byte i of a pixel in bits 8i+7..8i; one pixel per beat; tkeep marks the lanes."""
    bpp = CHANNELS[encoding]
    data = np.arange(1, 2 * 2 * bpp + 1, dtype=np.uint8)  # 2 rows x 2 cols
    beats, left = fifo2axi_fast(data, 2, 2, PIXEL_FORMATS[encoding])
    assert left == 0 and beats.tdata[:2].tolist() == tdata
    assert set(beats.tkeep.tolist()) == {tkeep}
    assert beats.tuser.tolist() == [True, False, False, False]
    assert beats.tlast.tolist() == [False, True, False, True]
    assert axi2fifo_fast(beats, 4)[0].tobytes() == data.tobytes()


def run_fifo2axi_reference(data: bytes, rows: int, cols: int, encoding: str):
    inp, out = ByteFIFO(name="pixels_in"), Fifo(name="axis_in")
    inp.extend(data)
    fifo2axi_reference(inp, out, rows, cols, PIXEL_FORMATS[encoding])
    return Beats.from_list(out), inp.level


@given(images(max_side=7), st.binary(max_size=5))
@settings(max_examples=100, deadline=None)
def test_fifo2axi_and_axi2fifo_reference_equal_fast(img_enc, extra):
    image, encoding = img_enc
    rows, cols = image.shape[:2]
    fmt = PIXEL_FORMATS[encoding]
    data = image.tobytes() + extra
    ref_beats, ref_left = run_fifo2axi_reference(data, rows, cols, encoding)
    fast_beats, fast_left = fifo2axi_fast(np.frombuffer(data, np.uint8), rows, cols, fmt)
    assert ref_beats == fast_beats and ref_left == fast_left == len(extra)
    out = ByteFIFO()
    axi2fifo_reference(beats_to_fifo(ref_beats.to_list()), out, rows * cols)
    fast_bytes, left = axi2fifo_fast(fast_beats, rows * cols)
    assert out.to_bytes() == fast_bytes.tobytes() == image.tobytes() and left == 0


@given(images(max_side=5), st.data())
@settings(max_examples=60, deadline=None)
def test_starved_fifo2axi_and_odd_tkeep_agree(img_enc, data):
    image, encoding = img_enc
    rows, cols = image.shape[:2]
    fmt = PIXEL_FORMATS[encoding]
    cut = data.draw(st.integers(0, image.size - 1))
    short = image.tobytes()[:cut]
    with pytest.raises(StreamStarvedError) as ref:
        run_fifo2axi_reference(short, rows, cols, encoding)
    with pytest.raises(StreamStarvedError) as fast:
        fifo2axi_fast(np.frombuffer(short, np.uint8), rows, cols, fmt)
    assert (ref.value.needed, ref.value.got) == (fast.value.needed, fast.value.got) == (image.size, cut)
    assert ref.value.partial == fast.value.partial
    # arbitrary tkeep per beat: axi2fifo emits exactly the kept lanes, in lane order
    beats, _ = fifo2axi_fast(image.reshape(-1), rows, cols, fmt)
    beats = beats.copy()
    beats.tkeep[:] = data.draw(st.lists(st.integers(0, 15), min_size=len(beats), max_size=len(beats)))
    out = ByteFIFO()
    axi2fifo_reference(beats_to_fifo(beats.to_list()), out, len(beats))
    assert out.to_bytes() == axi2fifo_fast(beats, len(beats))[0].tobytes()
    with pytest.raises(StreamStarvedError) as ref:
        axi2fifo_reference(beats_to_fifo(beats.to_list()), ByteFIFO(), len(beats) + 1)
    with pytest.raises(StreamStarvedError) as fast:
        axi2fifo_fast(beats, len(beats) + 1)
    assert ref.value.partial == fast.value.partial and ref.value.got == fast.value.got


# -- AXIvideo2Mat / Mat2AXIvideo ------------------------------------------------------------------

def run_axivideo2mat_reference(beats: Beats, rows: int, cols: int, channels: int):
    stream = beats_to_fifo(beats.to_list())
    img = Mat(rows, cols, channels)
    status = axivideo2mat_reference(stream, img)
    return img.to_numpy(), status, stream.level


@given(images(max_side=6), st.data())
@settings(max_examples=120, deadline=None)
def test_video_conversions_reference_equal_fast_even_on_broken_sideband(img_enc, data):
    image, encoding = img_enc
    rows, cols, channels = image.shape
    fmt = PIXEL_FORMATS[encoding]
    mat = Mat.from_numpy(image)
    out = Fifo(name="axis")
    mat2axivideo_reference(mat, out, fmt)
    beats = Beats.from_list(out)
    assert beats == mat2axivideo_fast(image, fmt)
    assert beats == fifo2axi_fast(image.reshape(-1), rows, cols, fmt)[0]
    # break the sideband signals at random (or not at all), add beats
    beats = beats.copy()
    for _ in range(data.draw(st.integers(0, 3))):
        signal = data.draw(st.sampled_from(["tuser", "tlast"]))
        at = data.draw(st.integers(0, len(beats) - 1))
        getattr(beats, signal)[at] ^= True
    if data.draw(st.booleans()):
        beats = Beats.from_list(beats.to_list() + [Beat(0xAABBCCDD, fmt.tkeep, False, True)])
    try:
        ref = run_axivideo2mat_reference(beats, rows, cols, channels)
    except StreamStarvedError as exc:
        with pytest.raises(StreamStarvedError) as fast:
            axivideo2mat_fast(beats, rows, cols, fmt)
        assert np.array_equal(exc.partial, fast.value.partial)
        return
    image_fast, status, left = axivideo2mat_fast(beats, rows, cols, fmt)
    assert np.array_equal(ref[0], image_fast) and ref[1:] == (status, left)


def test_axivideo2mat_flags_and_starvation_by_hand():
    image = np.arange(2 * 3, dtype=np.uint8).reshape(2, 3, 1)
    fmt = PIXEL_FORMATS["mono8"]
    good = mat2axivideo_fast(image, fmt)
    assert axivideo2mat_fast(good, 2, 3, fmt)[1] == 0
    # tlast one beat early on line 0: EOL_EARLY, the line's last pixel repeats the beat in hand
    early = good.copy()
    early.tlast[1] = True
    img, status, left = axivideo2mat_fast(early, 2, 3, fmt)
    assert status & ERROR_IO_EOL_EARLY and img[0, :, 0].tolist() == [0, 1, 1]
    # a tuser inside the frame: SOF_EARLY, pixels unchanged
    sof = good.copy()
    sof.tuser[4] = True
    img, status, _ = axivideo2mat_fast(sof, 2, 3, fmt)
    assert status == ERROR_IO_SOF_EARLY and np.array_equal(img, image)
    # a lost tlast on line 0: the circuit reads on to the next tlast (EOL_LATE) and then
    # waits for beats that never come: reported, with the partial image
    late = good.copy()
    late.tlast[2] = False
    with pytest.raises(StreamStarvedError) as info:
        axivideo2mat_fast(late, 2, 3, fmt)
    assert info.value.partial[0, :, 0].tolist() == [0, 1, 2]
    # a lost tuser: the wait-for-start loop eats the whole frame, never a hang
    lost = good.copy()
    lost.tuser[0] = False
    with pytest.raises(StreamStarvedError) as info:
        axivideo2mat_fast(lost, 2, 3, fmt)
    said = str(info.value)
    assert "waiting for a start of frame (tuser); it had made 0 of the 6 pixels" in said
    assert "of the 6 needed" not in said   # it read 6 beats; "6 of the 6 needed" would contradict itself
    assert info.value.got == 0 and info.value.needed == 6
    # an extra tlast late in the stream after a frame-long line: EOL_LATE is flagged
    beats = Beats(good.tdata, good.tkeep, good.tuser, [False, False, False, False, False, True])
    with pytest.raises(StreamStarvedError):
        axivideo2mat_fast(beats, 2, 3, fmt)
    extra = Beats.from_list(late.to_list() + [Beat(9, 1, False, True)] * 3)
    img, status, left = axivideo2mat_fast(extra, 2, 3, fmt)
    assert status & ERROR_IO_EOL_LATE and img[1, :, 0].tolist() == [9, 9, 9]
