"""Image diff and beat viewer: mismatch counts and positions, zoom, beat <-> pixel mapping."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.widgets import BeatMap, BeatViewer, FrameDiff, ImageDiffViewer, WidgetError
from rosfpga_lab.widgets._common import DIFF_POSITIONS_LIMIT


def _image(h: int = 12, w: int = 16, c: int = 3, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (h, w, c), dtype=np.uint8)


# --- image diff ---------------------------------------------------------------------------------

def test_equal_images_are_bit_exact() -> None:
    img = _image()
    ref = cv2.dilate(img, np.ones((3, 3), np.uint8))
    d = FrameDiff(ref.copy(), ref, img)
    assert d.equal and d.count == 0 and d.positions == [] and d.bbox is None
    assert d.summary() == "bit-exact: all 192 pixels equal"
    assert d.next_mismatch(0, 0) is None


def test_counts_positions_bbox_and_tolerance() -> None:
    ref = _image()
    out = ref.copy()
    out[2, 5, 0] ^= 1        # (x=5, y=2): off by one in one channel
    out[7, 1] = 255 - out[7, 1]  # (x=1, y=7): all channels
    out[7, 9, 2] ^= 0x80     # (x=9, y=7)
    d = FrameDiff(out, ref)
    assert d.count == 3
    assert d.positions == [(5, 2), (1, 7), (9, 7)]  # row-major
    assert d.bbox == (1, 2, 9, 7)
    assert d.mask.sum() == 3 and d.mask[2, 5] and d.mask[7, 1] and d.mask[7, 9]
    assert d.summary().startswith("3 of 192 pixels differ (1.56 %), in x 1..9, y 2..7")
    assert FrameDiff(out, ref, tolerance=1).count == 2  # the off-by-one is tolerated
    assert d.next_mismatch(5, 2) == (1, 7) and d.next_mismatch(9, 7) == (5, 2)  # wraps
    assert d.next_mismatch(0, 0) == (5, 2)


def test_positions_are_capped_but_count_is_exact() -> None:
    ref = np.zeros((50, 50), np.uint8)
    out = np.ones((50, 50), np.uint8)
    d = FrameDiff(out, ref)
    assert d.count == 2500 and len(d.positions) == DIFF_POSITIONS_LIMIT
    assert d.positions[:3] == [(0, 0), (1, 0), (2, 0)] and d.positions[50] == (0, 1)


def test_shape_and_dtype_errors_are_clear() -> None:
    with pytest.raises(WidgetError, match=r"output shape \(4, 4, 3\) differs from reference shape \(4, 5, 3\)"):
        FrameDiff(np.zeros((4, 4, 3), np.uint8), np.zeros((4, 5, 3), np.uint8))
    with pytest.raises(WidgetError, match="expected dtype uint8"):
        FrameDiff(np.zeros((4, 4), np.float32), np.zeros((4, 4), np.float32))
    with pytest.raises(WidgetError, match="HxW or HxWxC"):
        FrameDiff(np.zeros((4, 4, 2), np.uint8), np.zeros((4, 4, 2), np.uint8))


def test_difference_view_marks_mismatches_red_even_when_shrunk() -> None:
    ref = np.zeros((40, 2000, 3), np.uint8)
    out = ref.copy()
    out[13, 1001] = 9  # one pixel in a wide image
    d = FrameDiff(out, ref)
    view = d.diff_rgb(max_width=500)  # shrunk by 4
    assert view.shape == (10, 500, 3)
    red = np.argwhere((view == (255, 0, 0)).all(axis=2))
    assert red.tolist() == [[13 // 4, 1001 // 4]]


def test_zoom_region_and_value_tables() -> None:
    ref = np.arange(10 * 10, dtype=np.uint8).reshape(10, 10)
    out = ref.copy()
    out[4, 6] = 200
    d = FrameDiff(out, ref)
    assert d.region(6, 4, 4) == (4, 2, 7, 5)
    assert d.region(0, 0, 4) == (0, 0, 3, 3) and d.region(9, 9, 4) == (6, 6, 9, 9)  # clamped inside
    assert d.region(5, 5, 99) == (0, 0, 9, 9)  # at most the image (and ZOOM_MAX)
    html = d.zoom_html(6, 4, 3)
    assert "output x 5..7, y 3..5" in html and "reference x 5..7, y 3..5" in html
    assert html.count("#ff9e9e") == 2  # the one mismatching cell, in output and reference tables
    assert ">200</td>" in html and f">{ref[4, 6]}</td>" in html
    with pytest.raises(WidgetError, match="outside"):
        d.zoom_html(10, 0)


def test_zoom_box_is_outlined_outside_the_region_on_the_enlarged_view() -> None:
    ref = np.zeros((10, 10), np.uint8)
    d = FrameDiff(ref, ref)
    png = d.diff_png(max_width=40, box=(2, 3, 4, 5))  # enlarged 4x: region covers x 8..19, y 12..23
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)[:, :, ::-1]
    blue = (img == (0, 0, 255)).all(axis=2)
    assert img.shape == (40, 40, 3)
    assert blue[11, 7:21].all() and blue[24, 7:21].all() and blue[11:25, 7].all() and blue[11:25, 20].all()
    assert not blue[12:24, 8:20].any()  # the region's own pixels stay visible
    assert blue.sum() == 2 * 14 + 2 * 12


def test_static_html_is_self_contained() -> None:
    ref = _image(6, 8)
    out = ref.copy()
    out[1, 2] = 0
    html = FrameDiff(out, ref, ref).to_html()
    assert html.count("data:image/png;base64,") == 5 and "<script" not in html
    assert "1 of 48 pixels differ" in html and "(2, 1)" in html
    assert "<figcaption>output vs reference (grey: equal, red: differs)</figcaption>" in html
    assert "<figcaption>input vs output (grey: unchanged, red: changed, the redder the more)</figcaption>" in html
    assert "<details><summary>pixel values around (2, 1)</summary>" in html  # the zoom is folded


def test_viewer_single_frame_and_sequence() -> None:
    ref = _image(8, 8)
    bad = ref.copy()
    bad[3, 4] = 0
    bad[6, 1] = 1
    v = ImageDiffViewer(frames=[(ref, ref.copy(), ref), (ref, bad, ref), {"output": bad, "reference": bad}])
    assert v.frame.max == 2 and v.current.equal
    v.show(1)
    assert v.current.count == 2 and (v.x.value, v.y.value) == (4, 3)  # zoomed onto first mismatch
    assert "2 of 64 pixels differ" in v.summary.value
    assert v.next_mismatch() == (1, 6) and (v.x.value, v.y.value) == (1, 6)
    assert set(v.images) == {"input", "output", "reference", "output vs reference", "input vs output"}
    assert v.images["output vs reference"].png.startswith(b"\x89PNG")
    assert v.images["output vs reference"].caption == "output vs reference (grey: equal, red: differs)"
    assert v.images["input vs output"].caption == "input vs output (grey: unchanged, red: changed, the redder the more)"
    assert v.zoom_fold.selected_index is None  # the value tables start folded
    v.images["output"].click(6, 7)  # a click on any image zooms there
    assert (v.x.value, v.y.value) == (6, 7) and "output x 0..7, y 0..7" in v.zoom.value
    marked = ",".join(str(c) for c in bad[7, 6])
    assert f"outline:2px solid #00f\">{marked}</td>" in v.zoom.value
    with pytest.raises(WidgetError, match="frame 3 does not exist"):
        v.show(3)
    single = ImageDiffViewer(bad, ref)
    assert single.frame.layout.display == "none"
    assert set(single.images) == {"output", "reference", "output vs reference"}
    with pytest.raises(WidgetError, match="give output= and reference="):
        ImageDiffViewer()


def test_from_pipeline_result() -> None:
    from rosfpga_lab.hw import MessagePipeline, derive_layout, image_frame
    from rosfpga_lab.hw.layoutsteps import VideoShape
    from rosfpga_lab.msg import MsgRegistry

    img = _image(6, 5)
    layout = derive_layout(MsgRegistry.with_defaults(), "sensor_msgs/Image", stream="data",
                           stream_length=90, limits_={"encoding": 32},
                           checks={"height": 6, "width": 5, "encoding": "rgb8", "step": 15},
                           video=VideoShape(5, 6, "rgb8", 3))
    res = MessagePipeline(layout, "dilate", 3).process(image_frame(img, "rgb8"))
    d = FrameDiff.from_result(res, cv2.dilate(img, np.ones((3, 3), np.uint8)))
    assert d.equal and d.input is not None
    wrong = FrameDiff.from_result(res, img)  # not dilated: many pixels differ
    assert wrong.count > 0


# --- beats ----------------------------------------------------------------------------------------

def _rgb_beats(img: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One pixel per 32-bit beat, written out by hand: R in bits 7..0, G 15..8, B 23..16."""
    h, w, _ = img.shape
    px = img.reshape(-1, 3).astype(np.uint32)
    tdata = px[:, 0] | (px[:, 1] << 8) | (px[:, 2] << 16)
    tuser = np.zeros(h * w, bool)
    tuser[0] = True
    tlast = (np.arange(h * w) % w) == w - 1
    return tdata, np.full(h * w, 0b0111, np.uint8), tuser, tlast


def test_beat_pixel_mapping_one_pixel_per_beat() -> None:
    img = _image(3, 4)
    td, tk, tu, tl = _rgb_beats(img)
    m = BeatMap(tdata=td, tkeep=tk, tuser=tu, tlast=tl, width=4, height=3, bytes_per_pixel=3)
    assert len(m) == 12 and m.stream_bytes == 36 and m.marker_mismatches() == []
    assert m.beat_pixels(6) == [(2, 1)]
    assert m.pixel_beat(2, 1) == 6 and m.pixel_beat(3, 2) == 11
    assert m.beat_bytes(6) == img[1, 2].tobytes() == m.pixel_bytes(2, 1)
    assert m.describe_beat(0).startswith(f"beat 0: tdata 0x{int(td[0]):08x} tkeep 0b0111 tuser 1 tlast 0")
    with pytest.raises(WidgetError, match="outside the 4x3 image"):
        m.pixel_beat(4, 0)
    with pytest.raises(WidgetError, match="beat 12 does not exist"):
        m.beat_pixels(12)


def test_hw_beats_object_and_marker_mismatches_after_faults() -> None:
    from rosfpga_lab.hw import LoseTlast, LoseTuser, fifo2axi_fast, pixel_format

    img = _image(5, 4, 4)
    beats, left = fifo2axi_fast(img.ravel(), 5, 4, pixel_format("rgba8"))
    assert left == 0
    m = BeatMap(beats, width=4, height=5, bytes_per_pixel=4)
    assert m.marker_mismatches() == [] and m.beat_bytes(9) == img[2, 1].tobytes()
    lost = BeatMap(LoseTlast(line=1).apply(beats), width=4, height=5, bytes_per_pixel=4)
    assert [(x.beat, x.signal, x.expected, x.actual) for x in lost.marker_mismatches()] == [(7, "tlast", True, False)]
    nouser = BeatMap(LoseTuser().apply(beats), width=4, height=5, bytes_per_pixel=4)
    assert [(x.beat, x.signal) for x in nouser.marker_mismatches()] == [(0, "tuser")]
    assert "1 marker mismatch" in nouser.summary()


def test_a_lost_beat_shifts_pixels_and_markers() -> None:
    img = _image(2, 3)
    td, tk, tu, tl = _rgb_beats(img)
    keep = np.arange(6) != 1  # beat 1 is lost
    m = BeatMap(tdata=td[keep], tkeep=tk[keep], tuser=tu[keep], tlast=tl[keep], width=3, height=2, bytes_per_pixel=3)
    assert m.beat_pixels(1) == [(1, 0)]  # what was pixel (2, 0) now lands at (1, 0)
    assert m.pixel_beat(2, 1) is None  # the stream ends before the last pixel
    # beats now carry pixels 0, 1, 2, 3, 4 but their tlast flags were meant for pixels 0, 2, 3, 4, 5
    assert [(x.beat, x.signal, x.expected) for x in m.marker_mismatches()] == [
        (1, "tlast", False), (2, "tlast", True), (4, "tlast", False)]


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 5), st.integers(1, 5), st.sampled_from([1, 2, 3, 4, 6]),
       st.lists(st.integers(0, 15), min_size=1, max_size=60))
def test_mapping_matches_a_naive_byte_walk(w: int, h: int, bpp: int, keeps: list[int]) -> None:
    n = len(keeps)
    rng = np.random.default_rng(n)
    lanes = rng.integers(0, 256, (n, 4), dtype=np.uint8)
    m = BeatMap(tdata=lanes, tkeep=np.array(keeps), width=w, height=h, bytes_per_pixel=bpp)
    # naive model: walk every lane of every beat in order, numbering kept bytes
    owner_beat, stream, pixels_of = [], [], [[] for _ in range(n)]
    for i, k in enumerate(keeps):
        for lane in range(4):
            if k >> lane & 1:
                p = len(stream) // bpp
                if p < w * h and (p % w, p // w) not in pixels_of[i]:
                    pixels_of[i].append((p % w, p // w))
                owner_beat.append(i)
                stream.append(int(lanes[i, lane]))
    for i in range(n):
        assert m.beat_pixels(i) == pixels_of[i]
        assert m.beat_bytes(i) == bytes(int(lanes[i, ln]) for ln in range(4) if keeps[i] >> ln & 1)
    for p in range(w * h):
        first = p * bpp
        assert m.pixel_beat(p % w, p // w) == (owner_beat[first] if first < len(stream) else None)
        assert m.pixel_bytes(p % w, p // w) == bytes(stream[first:first + bpp])


def test_beat_viewer_links_beats_and_pixels() -> None:
    img = _image(3, 4)
    td, tk, tu, tl = _rgb_beats(img)
    v = BeatViewer(tdata=td, tkeep=tk, tuser=tu, tlast=tl, width=4, height=3, bytes_per_pixel=3)
    assert v.select_beat(7) == [(3, 1)] and (v.x.value, v.y.value) == (3, 1)
    assert v.select_pixel(1, 2) == 9 and v.beat.value == 9
    assert f"pixel (1, 2): bytes {img[2, 1].tobytes().hex(' ')}" in v.info.value
    v.x.value = 0  # editing a pixel coordinate moves the beat
    assert v.beat.value == 8
    v.beat.value = 3  # and the other way round
    assert (v.x.value, v.y.value) == (3, 0)
    assert "<svg" in v.wave.value and '<tr style="background:#ffe08a"><td style="padding:1px 4px">3</td>' in v.table.value


def test_beat_table_and_static_html_mark_tuser_tlast_and_errors() -> None:
    img = _image(2, 3)
    td, tk, tu, tl = _rgb_beats(img)
    tl[2] = False
    m = BeatMap(tdata=td, tkeep=tk, tuser=tu, tlast=tl, width=3, height=2, bytes_per_pixel=3)
    table = m.table_html()
    assert table.count("#b9fbc0") == 1  # tuser on beat 0
    assert table.count("#a0c4ff") == 1  # tlast on beat 5 only
    assert "0 (expected 1)" in table    # beat 2 lost its tlast
    html = m.to_html()
    assert "beat 2: tlast is 0, expected 1" in html and "<svg" in html and "<script" not in html


def test_beat_viewer_picture_click_selects_the_pixels_beat() -> None:
    img = _image(3, 4)
    td, tk, tu, tl = _rgb_beats(img)
    v = BeatViewer(tdata=td, tkeep=tk, tuser=tu, tlast=tl, width=4, height=3, bytes_per_pixel=3, image=img)
    assert v.picture is not None and v.picture.png.startswith(b"\x89PNG")
    v.picture.click(2, 1)
    assert v.beat.value == 6 and (v.x.value, v.y.value) == (2, 1)
    shown = cv2.imdecode(np.frombuffer(v.picture.png, np.uint8), cv2.IMREAD_COLOR)[:, :, ::-1]
    scale = shown.shape[1] // 4
    blue = np.argwhere((shown == (0, 0, 255)).all(axis=2))
    # the outline sits just outside pixel (2, 1) of the enlarged picture
    assert blue[:, 1].min() == 2 * scale - 1 and blue[:, 1].max() == 3 * scale
    assert blue[:, 0].min() == 1 * scale - 1 and blue[:, 0].max() == 2 * scale
    with pytest.raises(WidgetError, match="image is 3x3 but the beats carry 4x3 pixels"):
        BeatViewer(tdata=td, width=4, height=3, bytes_per_pixel=3, image=img[:, :3])


def test_beat_viewer_from_video_stages() -> None:
    from rosfpga_lab.hw.layoutsteps import VideoShape
    from rosfpga_lab.hw.videostages import video_stages

    img = _image(4, 5, 4)
    stages = video_stages(VideoShape(5, 4, "rgba8", 4), img.reshape(-1), "dilate")
    v = BeatViewer.from_stages(stages, "output")
    assert len(v.map) == 20 and v.map.marker_mismatches() == []
    dilated = cv2.dilate(img, np.ones((3, 3), np.uint8))
    assert v.map.beat_bytes(7) == dilated[1, 2].tobytes()
    assert v.picture is not None


def test_selected_beat_row_is_not_drawn_in_the_error_colour() -> None:
    """Red marks wrong markers in the beat table; the selected row uses the highlight colour."""
    from rosfpga_lab.widgets.beats import WRONG_COLOUR

    td, tk, tu, tl = _rgb_beats(_image(2, 4))
    html = BeatMap(width=4, height=2, bytes_per_pixel=3, tdata=td, tkeep=tk, tuser=tu,
                   tlast=tl).table_html(0, 8, selected=2)
    row = html.split("<tr")[4]  # before the rows, header, beat 0, beat 1, beat 2
    assert "#ffe08a" in row and "#d00" not in row and WRONG_COLOUR not in row


def test_beat_waveform_is_clock_true_and_agrees_with_the_clocked_model() -> None:
    """rgba8: one beat every 4 clocks, as the generated circuit's byte-wide packer makes them
    (``checks.circuit.elem_pack_clocks``, held to ``rfl_elem_pack`` by tests/checks/test_circuit)."""
    from rosfpga_lab.checks.circuit import elem_pack_clocks
    from rosfpga_lab.hw import PIXEL_FORMATS, fifo2axi_fast

    rows, cols = 2, 3
    data = np.arange(rows * cols * 4, dtype=np.uint8) * 7
    beats, _ = fifo2axi_fast(data, rows, cols, PIXEL_FORMATS["rgba8"])
    m = BeatMap(beats, width=cols, height=rows, bytes_per_pixel=4)
    arrays = m.clock_arrays(0, rows * cols)
    model = elem_pack_clocks(data, cols, 4)
    n = arrays["aclk"].size
    for name in ("s_tdata", "m_axis_tvalid", "m_axis_tdata", "m_axis_tuser", "m_axis_tlast"):
        assert arrays[name].astype(np.uint64).tolist() == model[name][:n].tolist(), name
    assert np.flatnonzero(arrays["m_axis_tvalid"]).tolist() == [4, 8, 12, 16, 20, 24]
    svg = m.waveform_svg(0, 6, selected=2)
    assert "m_axis_tready" in svg and "s_tdata" in svg and 'stroke="#d00"' in svg


def test_named_frames_and_the_input_vs_output_view() -> None:
    """Frames carry names (the slider says which fault it is) and a reference of their own; the
    zoom starts where something changed even when the output is right."""
    inp = np.zeros((6, 6, 3), np.uint8)
    out = inp.copy()
    out[2:5, 1:4] = 200            # what the circuit did
    v = ImageDiffViewer(frames=[
        {"input": inp, "output": out, "reference": out.copy(), "name": "no fault"},
        {"input": inp, "output": inp.copy(), "reference": inp.copy(), "name": "tuser lost",
         "reference_name": "what AXIvideo2Mat should have made"},
    ])
    assert "1 of 2" in v.frame_name.value and "no fault" in v.frame_name.value
    assert v.current.equal and (v.x.value, v.y.value) == (1, 2)   # the largest change, first in row-major order
    changed = cv2.imdecode(np.frombuffer(v.current.diff_png(which="input vs output"), np.uint8),
                           cv2.IMREAD_COLOR)
    assert changed is not None
    assert int(v.current.changed.sum()) == 9
    v.show(1)
    assert "2 of 2" in v.frame_name.value and "tuser lost" in v.frame_name.value
    assert v.images["reference"].caption == "what AXIvideo2Mat should have made"
    assert v.images["output vs reference"].caption.startswith("output vs what AXIvideo2Mat should have made")
    html = v.to_html()
    assert "tuser lost" in html and "no fault" in html


def test_input_vs_output_shows_how_much_changed() -> None:
    inp = np.zeros((1, 3, 3), np.uint8)
    out = inp.copy()
    out[0, 1] = 6      # a small change
    out[0, 2] = 200    # a big one
    view = FrameDiff(out, out.copy(), inp).diff_rgb(which="input vs output")
    grey, small, big = (view[0, k].astype(int) for k in range(3))
    assert grey[0] == grey[1] == grey[2]                    # unchanged: grey
    assert big.tolist() == [255, 0, 0]                      # a big change: full red
    assert small[0] > small[1] and small[1] > 0             # a small one: a paler red, still visible
