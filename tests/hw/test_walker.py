"""Subscriber/publisher models rendered from the layout (hw.walker) and the 1-D application (hw.morph1d).

Expected values come from the msg layer (``serialize``/``deserialize``), frames broken by hand,
or numpy written out in the test; never from the model under test.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError, FrameTruncatedError
from rosfpga_lab.hw.layout import (
    Action, Layout, StepKind, derive_layout, encode_token, layout_from_config, tokens,
)
from rosfpga_lab.hw.morph1d import morph1d_fast, morph1d_reference
from rosfpga_lab.hw.msgpipeline import MessagePipeline, wire_bytes
from rosfpga_lab.hw.sample import example_message, image_frame
from rosfpga_lab.hw.walker import (
    LayoutInterpreter, extract_fast, extract_reference, message_of, publish_fast,
    publish_reference,
)
from rosfpga_lab.msg import MsgRegistry, deserialize, new_message, serialize
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.strategies import message

from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "data"


def _frame(body: bytes) -> bytes:
    return struct.pack("<I", len(body)) + body


def _wire(layout: Layout, toks: list) -> list[tuple[int, tuple[int, ...], bytes]]:
    """Tokens as comparable (step, indices, wire bytes): NaN-safe and dtype-exact."""
    return [(t.step, t.at, encode_token(layout.steps[t.step], t.value)) for t in toks]


def push_counting_refusals(interp: LayoutInterpreter, data: bytes) -> int:
    """Push ``data`` a byte at a time; how many frames the circuit refused on the way."""
    refused = 0
    for byte in data:
        try:
            interp.push(byte)
        except FrameFieldError:
            refused += 1
    return refused


# -- a strategy over message definitions -------------------------------------------------------

PRIMS = ["bool", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
         "float32", "float64", "char", "byte", "time", "duration", "string"]
NUMERIC = ["int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
           "float32", "float64", "char", "byte"]


@st.composite
def definitions(draw: st.DrawFn) -> tuple[MsgRegistry, str, str]:
    """A registry with a random message type (every field kind, nesting to depth 3, arrays of
    nested messages, Header) whose top level has one numeric array to stream."""
    texts: dict[str, str] = {}

    def make(depth: int) -> str:
        name = f"T{len(texts)}"
        texts[name] = ""
        lines = []
        for i in range(draw(st.integers(0 if depth else 1, 4))):
            kinds = ["prim", "prim", "msg"] if depth < 3 else ["prim"]
            if draw(st.sampled_from(kinds)) == "prim":
                base = draw(st.sampled_from(PRIMS + ["Header"] if depth == 0 else PRIMS))
            else:
                base = make(depth + 1)
            suffix = "" if base == "Header" else draw(st.sampled_from(["", "[]", "[2]", "[0]"]))
            lines.append(f"{base}{suffix} f{i}")
        texts[name] = "\n".join(lines)
        return name

    top = make(0)
    elem = draw(st.sampled_from(NUMERIC))
    suffix = draw(st.sampled_from(["[]", "[3]"]))
    lines = texts[top].split("\n")
    lines.insert(draw(st.integers(0, len(lines))), f"{elem}{suffix} stream")
    texts[top] = "\n".join(lines)
    reg = MsgRegistry.with_defaults()
    for name, text in reversed(list(texts.items())):
        reg.add(f"h_msgs/{name}", text)
    return reg, f"h_msgs/{top}", "stream"


@st.composite
def cases(draw: st.DrawFn) -> tuple[MsgRegistry, str, Layout, dict, bytes]:
    reg, type_name, stream = draw(definitions())
    value = draw(message(reg, type_name))
    n = len(value[stream])
    layout = derive_layout(reg, type_name, stream=stream, stream_length=n)
    return reg, type_name, layout, value, _frame(serialize(reg, type_name, value))


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases())
def test_reference_fast_and_the_msg_layer_agree_on_every_field(case: Any) -> None:
    reg, type_name, layout, _value, frame = case
    decoded = deserialize(reg, type_name, frame[4:])
    expected = _wire(layout, tokens(layout, decoded))
    ref = extract_reference(layout, frame)
    fast = extract_fast(layout, frame)
    assert _wire(layout, ref.tokens) == expected
    assert _wire(layout, fast.tokens) == expected
    stream = np.asarray(decoded["stream"], layout.stream.dtype)
    assert ref.stream.tobytes() == fast.stream.tobytes() == stream.tobytes()
    assert ref.frame_length == fast.frame_length == len(frame) - 4
    assert ref.stream_offset == fast.stream_offset
    assert frame[ref.stream_offset:ref.stream_offset + stream.nbytes] == stream.tobytes()
    # carried fields: every non-stream token (nothing is skipped here)
    assert _wire(layout, ref.carried(layout)) == [
        w for w, t in zip(expected, tokens(layout, decoded))
        if layout.steps[t.step].action is not Action.STREAM]
    # the tokens rebuild the message (the inverse walk)
    assert serialize(reg, type_name, message_of(layout, ref.tokens, reg)) == frame[4:]
    # the publisher writes the same frame back (passthrough), in both models
    assert publish_fast(layout, ref.tokens, ref.stream) == frame
    assert publish_reference(layout, ref.tokens, ref.stream) == frame


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(definitions(), st.data())
def test_a_refused_check_names_its_field_and_the_next_good_frame_comes_out_right(
        defn: Any, data: st.DataObject) -> None:
    reg, type_name, stream = defn
    good = data.draw(message(reg, type_name))
    spec = reg.get(type_name)
    ints = [f for f in spec.fields if not f.is_array and f.base_type in
            ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "char", "byte")]
    n = len(good[stream])
    if ints:
        f = ints[0]
        bad = dict(good)
        lo, hi = (np.iinfo(SCALARS[f.base_type].dtype).min, np.iinfo(SCALARS[f.base_type].dtype).max)
        bad[f.name] = lo if good[f.name] != lo else hi
        layout = derive_layout(reg, type_name, stream=stream, stream_length=n,
                               checks={f.name: int(good[f.name])})
        words, label = "not what the circuit was built for", f.name
    else:  # no integer to check: a stream of the wrong length is refused instead
        f = next(x for x in spec.fields if x.name == stream)
        if f.array_length is not None:
            return
        bad = dict(good)
        bad[stream] = list(good[stream]) + [0]
        layout = derive_layout(reg, type_name, stream=stream, stream_length=n)
        words, label = "not what the circuit was built for", f"{stream} length"
    bad_frame = _frame(serialize(reg, type_name, bad))
    good_frame = _frame(serialize(reg, type_name, good))
    for extract in (extract_reference, extract_fast):
        with pytest.raises(FrameFieldError) as exc:
            extract(layout, bad_frame)
        assert exc.value.field == label and exc.value.rule == words
    interp = LayoutInterpreter(layout)
    assert push_counting_refusals(interp, bad_frame + good_frame) == 1
    assert interp.frames == 1 and interp.last is not None
    expected = _wire(layout, tokens(layout, deserialize(reg, type_name, good_frame[4:])))
    assert _wire(layout, interp.last.tokens) == expected


# -- the Image path ------------------------------------------------------------------------------

def _layout_outcome(frame: bytes, layout: Layout, extract: Any) -> tuple:
    try:
        ex = extract(layout, frame)
    except FrameFieldError as exc:
        return ("refused", exc.field, exc.offset, isinstance(exc, FrameLengthError))
    v = {layout.steps[t.step].ident: t.value for t in ex.tokens}
    return ("ok", v["header_seq"], v["header_stamp_secs"], v["header_stamp_nsecs"],
            v["header_frame_id"], ex.stream.tobytes(), ex.stream_offset)


def _image_frames(config: Any) -> list[bytes]:
    im = config.image
    rng = np.random.default_rng(3)
    pic = rng.integers(0, 256, (im.height, im.width, im.bytes_per_pixel), np.uint8)
    good = image_frame(pic, im.encoding, seq=5, stamp=(7, 9), frame_id="cam")
    frames = [good, image_frame(pic, im.encoding, frame_id="")]
    frames.append(image_frame(pic[:, :-1], im.encoding))                 # width
    frames.append(image_frame(pic[:-1], im.encoding))                    # height
    other = "mono8" if im.encoding != "mono8" else "rgb8"
    frames.append(image_frame(np.zeros((im.height, im.width, 1 if other == "mono8" else 3),
                                       np.uint8), other))                 # encoding
    frames.append(image_frame(pic, im.encoding, frame_id="x" * (config.frame_id_max + 1)))
    body = good[4:]
    frames.append(struct.pack("<I", 10) + body[:10])                     # too short
    frames.append(struct.pack("<I", len(body) + 3) + body + b"abc")       # longer than data
    frames.append(struct.pack("<I", len(body) - 1) + body[:-1])          # ends inside data
    frames.append(good[:20])                                              # cut short
    step_at = 4 + 12 + 4 + 3 + 8 + 4 + len(im.encoding) + 1
    frames.append(good[:step_at] + struct.pack("<I", 1) + good[step_at + 4:])  # step
    dl_at = step_at + 4
    frames.append(good[:dl_at] + struct.pack("<I", 5) + good[dl_at + 4:])      # data length
    enc_len_at = 4 + 12 + 4 + 3 + 8
    frames.append(good[:enc_len_at] + struct.pack("<I", 99) + good[enc_len_at + 4:])
    fid_at = 4 + 12
    frames.append(good[:fid_at] + struct.pack("<I", 10**6) + good[fid_at + 4:])
    return frames


@pytest.mark.parametrize("name", ["fpga_dilate_rgba8.yaml", "fpga_erode_mono8.yaml",
                                  "fpga_passthrough_rgb8.yaml"])
@pytest.mark.parametrize("model", ["fast", "reference"])
def test_the_walkers_circuit_refuses_every_bad_image_frame_and_resyncs(name: str,
                                                                        model: str) -> None:
    """MessagePipeline on one stream of Image frames, each bad one (each built by hand to break
    one rule, ``_image_frames``) followed by the good one: every bad frame refused with a
    FrameFieldError, and every good frame after it published the same but for header.seq,
    numbered 1, 2, ... over the published frames."""
    text = (DATA / name).read_text()
    for a, b in (("width: 320", "width: 8"), ("height: 240", "height: 6"),
                 ("width: 640", "width: 8"), ("height: 480", "height: 6")):
        text = text.replace(a, b)
    config = parse_config(text)
    pipe = MessagePipeline.from_config(config, model)
    frames = _image_frames(config)
    good = frames[0]
    first = pipe.process(good).output_frame
    assert struct.unpack_from("<I", first, 4)[0] == 1
    for k, bad in enumerate(frames[1:], start=2):
        if bad is frames[1]:   # an empty frame_id is legal: published
            assert pipe.process(bad).output_frame
        else:
            with pytest.raises(FrameFieldError):
                pipe.process(bad)
        out = pipe.process(good).output_frame
        assert out[:4] + out[8:] == first[:4] + first[8:]
        assert struct.unpack_from("<I", out, 4)[0] == pipe.next_seq - 1
    assert pipe.next_seq == 1 + 1 + len(frames[1:]) + 1


def test_a_results_network_times_count_the_frame_and_its_tcp_segments() -> None:
    """network_time_s: the frame's bytes at 1 Gb/s; wire_time_s: with 90 bytes of TCP/IP and
    Ethernet per segment of 1,448 payload bytes (a 3,000-byte frame: three segments)."""
    config = load_config(DATA / "fpga_samples_dilate.yaml")
    pipe = MessagePipeline.from_config(config)
    layout = pipe.layout
    frame = _frame(serialize(config.registry(), layout.type_name,
                             example_message(layout, config.registry())))
    res = pipe.process(frame)
    assert res.network_time_s == pytest.approx(len(frame) * 8 / 1e9)
    segments = -(-len(frame) // 1448)
    assert res.wire_time_s == pytest.approx((len(frame) + 90 * segments) * 8 / 1e9)
    assert wire_bytes(3000) == 3000 + 3 * 90


# -- specific refusals ---------------------------------------------------------------------------

def test_refusals_inside_arrays_of_messages_name_the_element_and_resync() -> None:
    config = load_config(DATA / "fpga_samples_dilate.yaml")
    reg = config.registry()
    layout = layout_from_config(config, reg)
    cal = {"sensor_name": "s", "offset": [0.0, 0.0, 0.0], "mode": 2}
    msg = {"header": {"seq": 1, "stamp": (1, 2), "frame_id": "f"}, "calibration": cal,
           "label": "l", "thresholds": [0, 0, 0, 0], "samples": list(range(64)),
           "period": (0, 0), "history": [cal, dict(cal, sensor_name="y" * 300)], "valid": True}
    bad = _frame(serialize(reg, "lab_msgs/Samples", msg))
    for extract in (extract_reference, extract_fast):
        with pytest.raises(FrameFieldError) as exc:
            extract(layout, bad)
        assert exc.value.field == "history[1].sensor_name length"
        assert exc.value.rule == "over the limit" and "limits: history.sensor_name" in str(exc.value)
        assert bad[exc.value.offset:exc.value.offset + 4] == struct.pack("<I", 300)
    good = _frame(serialize(reg, "lab_msgs/Samples", dict(msg, history=[cal])))
    interp = LayoutInterpreter(layout)
    refused = []
    for byte in bad + good:
        try:
            interp.push(byte)
        except FrameFieldError as e:
            refused.append(e.field)
            assert interp.step is None  # skipping the rest of the refused frame
    assert refused == ["history[1].sensor_name length"] and interp.frames == 1
    assert interp.last is not None and interp.last.stream.tolist() == list(range(64))
    for extract in (extract_reference, extract_fast):
        with pytest.raises(FrameTruncatedError):
            extract(layout, good[:-1])
        with pytest.raises(FrameLengthError, match="more bytes were given"):
            extract(layout, good + b"\0")
    # cut short inside an element: both models name the element (the fast one used to lose
    # the loop indices, naming "history[].offset")
    two = _frame(serialize(reg, "lab_msgs/Samples", dict(msg, history=[cal, cal])))
    cut = []
    for extract in (extract_reference, extract_fast):
        with pytest.raises(FrameTruncatedError) as trunc:
            extract(layout, two[:-3])
        cut.append((trunc.value.field, trunc.value.offset))
    assert cut[0] == cut[1] and cut[0][0].startswith("history[1]."), cut
    wrong_mode = _frame(serialize(reg, "lab_msgs/Samples", dict(msg, calibration=dict(cal, mode=3))))
    with pytest.raises(FrameFieldError, match="built for 2") as exc:
        extract_fast(layout, wrong_mode)
    assert exc.value.field == "calibration.mode" and layout.step("calibration_mode").check.status \
        == "SUB_BAD_CALIBRATION_MODE"


def test_range_checks_refuse_nan_and_out_of_bounds_values() -> None:
    reg_layout = parse_config(
        "node: {name: n}\nsubscriber: {topic: /a, type: sensor_msgs/LaserScan}\n"
        "publisher: {topic: /b}\nstream: {field: ranges, length: 2}\n"
        "checks: {range_max: {min: 1, max: 50}}\n")
    layout = layout_from_config(reg_layout)
    from rosfpga_lab.msg import default_registry, new_message

    base = {**new_message(default_registry(), "sensor_msgs/LaserScan"), "range_max": 10.0,
            "ranges": [1.0, 2.0]}
    for value, rule in ((float("nan"), "not a number"), (0.5, "below the minimum"),
                        (51.0, "over the limit"), (float("inf"), "over the limit")):
        frame = _frame(serialize(default_registry(), "sensor_msgs/LaserScan",
                                 dict(base, range_max=value)))
        for extract in (extract_reference, extract_fast):
            with pytest.raises(FrameFieldError) as exc:
                extract(layout, frame)
            assert (exc.value.field, exc.value.rule) == ("range_max", rule)
    ok = _frame(serialize(default_registry(), "sensor_msgs/LaserScan", base))
    assert extract_fast(layout, ok).stream.tolist() == [1.0, 2.0]


def test_the_publisher_writes_defaults_for_skipped_fields() -> None:
    from rosfpga_lab.msg import default_registry, new_message

    reg = default_registry()
    c = parse_config("node: {name: n}\nsubscriber: {topic: /a, type: sensor_msgs/LaserScan}\n"
                     "publisher: {topic: /b}\nstream: {field: ranges, length: 3}\n"
                     "skip: [intensities, header.frame_id, scan_time]\n")
    layout = layout_from_config(c)
    msg = {**new_message(reg, "sensor_msgs/LaserScan"),
           "header": {"seq": 4, "stamp": (5, 6), "frame_id": "laser"}, "angle_min": -1.0,
           "scan_time": 0.5, "ranges": [3.0, 1.0, 2.0], "intensities": [9.0, 9.0, 9.0]}
    ex = extract_reference(layout, _frame(serialize(reg, "sensor_msgs/LaserScan", msg)))
    out_stream = np.array([3.0, 3.0, 2.0], np.float32)
    expected = dict(msg, header=dict(msg["header"], frame_id=""), scan_time=0.0,
                    intensities=[], ranges=out_stream)
    want = _frame(serialize(reg, "sensor_msgs/LaserScan", expected))
    assert publish_fast(layout, ex.tokens, out_stream) == want
    assert publish_reference(layout, ex.tokens, out_stream) == want


# -- the 1-D application ------------------------------------------------------------------------

def _window_extreme(values: np.ndarray, op: str, k: int) -> list:
    """Written out: numpy's maximum/minimum folded over the in-array window, left to right."""
    r = k // 2
    fold = np.maximum if op == "dilate" else np.minimum
    out = []
    for i in range(len(values)):
        acc = values[max(0, i - r)]
        for j in range(max(0, i - r) + 1, min(len(values), i + r + 1)):
            acc = fold(acc, values[j])
        out.append(acc)
    return out


DTYPES = ["i1", "u1", "<i2", "<u2", "<i4", "<u4", "<i8", "<u8", "<f4", "<f8"]


@settings(max_examples=150, deadline=None)
@given(st.sampled_from(DTYPES), st.sampled_from(["dilate", "erode", "passthrough"]),
       st.sampled_from([1, 3, 5, 7]), st.data())
def test_morph1d_reference_and_fast_are_numpys_fold_bit_for_bit(dtype: str, op: str, k: int,
                                                                 data: st.DataObject) -> None:
    dt = np.dtype(dtype)
    n = data.draw(st.integers(0, 20))
    if dt.kind == "f":
        special = [0.0, -0.0, np.inf, -np.inf, 1.5, -2.5]
        elems = st.one_of(st.sampled_from(special),
                          st.floats(width=8 * dt.itemsize, allow_nan=False))
        values = np.array(data.draw(st.lists(elems, min_size=n, max_size=n)), dt)
    else:
        info = np.iinfo(dt)
        values = np.array(data.draw(st.lists(st.integers(int(info.min), int(info.max)),
                                             min_size=n, max_size=n)), dt)
    ref = morph1d_reference(values, op, k)
    fast = morph1d_fast(values, op, k)
    expected = values if op == "passthrough" else np.array(_window_extreme(values, op, k), dt)
    assert ref.dtype == fast.dtype == dt
    assert ref.tobytes() == fast.tobytes() == expected.tobytes()


def test_morph1d_nan_gives_the_first_nan_of_the_window_with_its_bits() -> None:
    nan_a = np.frombuffer(bytes.fromhex("0100c07f"), np.float32)[0]
    nan_b = np.frombuffer(bytes.fromhex("0200c0ff"), np.float32)[0]
    x = np.array([1.0, nan_a, 2.0, nan_b, 3.0, -0.0, 0.0], np.float32)
    for model in (morph1d_reference, morph1d_fast):
        out = model(x, "dilate", 3)
        bits = [v.tobytes().hex() for v in out]
        assert bits[0] == bits[1] == bits[2] == "0100c07f"  # windows holding nan_a first
        assert bits[3] == bits[4] == "0200c0ff"
        assert bits[5] == np.float32(3.0).tobytes().hex()
        assert bits[6] == "00000000"  # max(-0.0, +0.0) in that order: the later one (numpy)
        low = model(np.array([0.0, -0.0], np.float32), "erode", 3)
        assert [v.tobytes().hex() for v in low] == ["00000080", "00000080"]
    big = np.array([2**64 - 1, 0, 2**63], np.uint64)
    assert morph1d_reference(big, "erode", 3).tolist() == [0, 0, 0]
    assert morph1d_fast(big, "dilate", 3).tolist() == [2**64 - 1, 2**64 - 1, 2**63]


def conversion_config(tmp_path: Path) -> Any:
    """A node from conv_msgs/In to conv_msgs/Out (written under ``tmp_path``): fields of the same
    path and type carried (nested ones too), the others at their defaults."""
    msgs = tmp_path / "conv_msgs" / "msg"
    msgs.mkdir(parents=True)
    (msgs / "InnerA.msg").write_text("int32 a\nstring b\n")
    (msgs / "InnerB.msg").write_text("string b\nint64 a\nuint8 c\n")
    (msgs / "In.msg").write_text("Header header\nstring name\nint16[] values\nfloat64 gain\n"
                                 "InnerA inner\nInnerA[] list\n")
    (msgs / "Out.msg").write_text("Header header\nint16[] values\nstring name\nuint8 extra\n"
                                  "InnerB inner\nInnerB[] list\n")
    (tmp_path / "c.yaml").write_text(
        "node: {name: n}\nsubscriber: {topic: /a, type: conv_msgs/In}\n"
        "publisher: {topic: /b, type: conv_msgs/Out}\nmsg_path: [.]\n"
        "stream: {field: values, length: 4}\napplication: {op: dilate, ksize: 3}\n"
        "limits: {name: 8}\n")
    config = load_config(tmp_path / "c.yaml")
    return config


def test_a_publisher_of_another_type_carries_fields_by_path_and_type(tmp_path: Path) -> None:
    config = conversion_config(tmp_path)
    reg = config.registry()
    msg = {"header": {"seq": 2, "stamp": (3, 4), "frame_id": "x"}, "name": "nm",
           "values": [1, -5, 3, 0], "gain": 2.5, "inner": {"a": 7, "b": "in"},
           "list": [{"a": 1, "b": "z"}]}
    frame = _frame(serialize(reg, "conv_msgs/In", msg))
    want = _frame(serialize(reg, "conv_msgs/Out", {
        "header": msg["header"], "values": [1, 3, 3, 3], "name": "nm", "extra": 0,
        "inner": {"b": "in", "a": 0, "c": 0}, "list": []}))
    for model in ("fast", "reference"):
        res = MessagePipeline.from_config(config, model=model, reg=reg).process(frame)
        assert res.output_frame == want


def test_thousands_of_empty_steps_in_a_row_need_no_recursion() -> None:
    reg = MsgRegistry.with_defaults()
    reg.add("e_msgs/E", "int32[0] nothing\nuint8[0] none")
    reg.add("e_msgs/Many", "E[3000] empties\nint16[] values")
    layout = derive_layout(reg, "e_msgs/Many", stream="values", stream_length=2)
    frame = _frame(serialize(reg, "e_msgs/Many", new_message(reg, "e_msgs/Many", values=[5, -6])))
    for extract in (extract_reference, extract_fast):
        ex = extract(layout, frame)
        assert ex.stream.tolist() == [5, -6] and len(ex.tokens) == 2 * 3000 + 2
