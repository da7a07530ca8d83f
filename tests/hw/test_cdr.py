"""CDR, the second wire format of the circuit layout (hw.cdrlayout, hw.cdrwalker, hw.cdrpipeline).

Expected values come from the msg layer's CDR codec (``msg.cdr``, itself held byte-equal to
rosbags' serializer in msg/test_cdr.py), from real Cyclone DDS (PyPI ``cyclonedds``: its IDL
types written out here as rosidl generates them, samples from ``.serialize()``), and numpy/cv2
oracles written in the test; never from the models under test.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.hw.cdrlayout import (
    ALIGN_ORIGIN, cdr_registry, cdr_tokens, derive_cdr_layout, format_cdr_layout,
)
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.hw.cdrwalker import (
    CdrInterpreter, TAIL_LABEL, extract_cdr_fast, extract_cdr_reference, publish_cdr_fast,
    publish_cdr_reference,
)
from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError, LayoutError
from rosfpga_lab.hw.layout import StepKind
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.cdr import deserialize_cdr, serialize_cdr
from rosfpga_lab.msg.ros2 import ros2_registry
from rosfpga_lab.msg.strategies import message
from tests.hw.test_walker import _frame as _record  # 4-byte length + payload, as TCPROS
from tests.hw.test_walker import (
    _wire as _layout_wire, conversion_config, definitions, push_counting_refusals,
)
from tests.support.wiretools import require_cyclonedds

DATA = Path(__file__).resolve().parents[2] / "data"


def _wire(cdr: Any, toks: list) -> list[tuple[int, tuple[int, ...], bytes]]:
    """Tokens as comparable (step, indices, wire bytes), as the TCPROS walker's tests do."""
    return _layout_wire(cdr.layout, toks)


def _pad_tail(payload: bytes, pad: int) -> bytes:
    """The payload as Cyclone DDS's core sends it: padded to ``pad`` more bytes, the options'
    low bits saying how many (DDS-XTypes 1.3 7.6.3.1.2)."""
    return payload[:2] + struct.pack(">H", pad) + payload[4:] + bytes(pad)


@st.composite
def cases(draw: st.DrawFn) -> tuple[MsgRegistry, str, Any, bytes]:
    reg, type_name, stream = draw(definitions())
    r2 = ros2_registry(reg)
    value = draw(message(r2, type_name))
    n = len(value[stream])
    cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n)
    return r2, type_name, cdr, serialize_cdr(r2, type_name, value)


def _outcome(extract: Any, cdr: Any, record: bytes) -> tuple:
    try:
        ex = extract(cdr, record)
    except FrameFieldError as exc:
        return ("refused", type(exc).__name__, exc.field, exc.offset, exc.rule)
    return ("ok", _wire(cdr, ex.tokens), ex.stream.tobytes(), ex.stream_offset)


# -- the walk against the msg layer's CDR codec ---------------------------------------------------

@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases(), st.integers(0, 3))
def test_reference_fast_and_the_cdr_codec_agree_on_every_field(case: Any, pad: int) -> None:
    r2, type_name, cdr, payload = case
    decoded = deserialize_cdr(r2, type_name, payload)
    expected = _wire(cdr, cdr_tokens(cdr, decoded))
    record = _record(payload)
    cyclone = _record(payload + bytes(-len(payload) % 4))   # padded to 4, options 00 00
    for given_record in (record, _record(_pad_tail(payload, pad)), cyclone):
        ref = extract_cdr_reference(cdr, given_record)
        fast = extract_cdr_fast(cdr, given_record)
        assert _wire(cdr, ref.tokens) == expected
        assert _wire(cdr, fast.tokens) == expected
        stream = np.asarray(decoded["stream"], cdr.layout.stream.dtype)
        assert ref.stream.tobytes() == fast.stream.tobytes() == stream.tobytes()
        assert ref.stream_offset == fast.stream_offset
        assert given_record[ref.stream_offset:ref.stream_offset + stream.nbytes] == stream.tobytes()
        # the publisher writes the sample back (passthrough), in both models, unpadded
        assert publish_cdr_fast(cdr, ref.tokens, ref.stream) == record
        assert publish_cdr_reference(cdr, ref.tokens, ref.stream) == record
    # the stream starts where the codec's layout says (alignment counted after the header)
    assert (ref.stream_offset - ALIGN_ORIGIN) % cdr.layout.stream.size == 0 or not stream.size
    assert len(payload) >= cdr.layout.min_body


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cases(), st.data())
def test_reference_and_fast_refuse_damaged_samples_alike(case: Any, data: st.DataObject) -> None:
    _r2, _type_name, cdr, payload = case
    record = bytearray(_record(payload))
    how = data.draw(st.sampled_from(["byte", "length", "cut", "extra"]))
    if how == "byte":
        at = data.draw(st.integers(4, len(record) - 1))
        record[at] = data.draw(st.integers(0, 255))
    elif how == "length":
        n = max(0, len(payload) + data.draw(st.integers(-9, 9)))
        record[:4] = struct.pack("<I", n)
    elif how == "cut":
        record = record[:data.draw(st.integers(1, len(record) - 1))]
    else:
        record += bytes(data.draw(st.integers(1, 9)))
    assert _outcome(extract_cdr_reference, cdr, bytes(record)) == \
        _outcome(extract_cdr_fast, cdr, bytes(record))


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(definitions(), st.data())
def test_a_refused_check_names_its_field_and_the_next_good_sample_comes_out_right(
        defn: Any, data: st.DataObject) -> None:
    reg, type_name, stream = defn
    r2 = ros2_registry(reg)
    good = data.draw(message(r2, type_name))
    ints = [f for f in r2.get(type_name).fields if not f.is_array and f.base_type in
            ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "char",
             "byte")]
    n = len(good[stream])
    bad = dict(good)
    if ints:
        f = ints[0]
        info = np.iinfo(SCALARS[f.base_type].dtype)
        bad[f.name] = info.min if good[f.name] != info.min else info.max
        cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n,
                                checks={f.name: int(good[f.name])})
        label = f.name
    else:
        if r2.get(type_name).fields[[x.name for x in r2.get(type_name).fields].index(stream)] \
                .array_length is not None:
            return
        bad[stream] = list(good[stream]) + [0]
        cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n)
        label = f"{stream} length"
    bad_record = _record(serialize_cdr(r2, type_name, bad))
    good_record = _record(serialize_cdr(r2, type_name, good))
    for extract in (extract_cdr_reference, extract_cdr_fast):
        with pytest.raises(FrameFieldError) as exc:
            extract(cdr, bad_record)
        assert exc.value.field == label and exc.value.rule == "not what the circuit was built for"
    interp = CdrInterpreter(cdr)
    assert push_counting_refusals(interp, bad_record + good_record) == 1
    assert interp.frames == 1 and interp.last is not None
    expected = _wire(cdr, cdr_tokens(cdr, deserialize_cdr(r2, type_name, good_record[4:])))
    assert _wire(cdr, interp.last.tokens) == expected


# -- what CDR adds: the header, the NULs, the alignment ---------------------------------------------

SAMPLES_CONFIG = load_config(DATA / "fpga_samples_dilate.yaml")


def _samples_value(n: int = 64, label: str = "hi", mode: int = 2) -> dict:
    rng = np.random.default_rng(7)
    calib = {"sensor_name": "imu", "offset": [0.5, -1.0, 2.0], "mode": mode}
    return {"header": {"stamp": {"sec": 1700000000, "nanosec": 5}, "frame_id": "array"},
            "calibration": calib, "label": label, "thresholds": [-3, 0, 7, 32767],
            "samples": rng.integers(-2**31, 2**31, n, dtype=np.int32),
            "period": {"sec": 0, "nanosec": 1000},
            "history": [dict(calib, sensor_name="old"), dict(calib, sensor_name="")],
            "valid": True}


def _samples_pipeline(model: str = "fast") -> CdrPipeline:
    return CdrPipeline(SAMPLES_CONFIG, model)


def test_the_cdr_walk_is_the_ros2_form_with_header_alignment_and_nuls() -> None:
    cdr = _samples_pipeline().cdr
    steps = cdr.layout.steps
    labels = [s.label for s in steps]
    assert labels[:7] == ["sample length", "encapsulation header", "header.stamp.sec",
                          "header.stamp.nanosec", "header.frame_id length", "header.frame_id",
                          "header.frame_id NUL"]
    assert "header.seq" not in labels
    # every string is followed by its NUL, every base step appears once, in order
    for s in steps:
        if s.kind is StepKind.STRING:
            assert steps[s.index + 1].kind is StepKind.NUL
    assert [b for b in cdr.base_index if b is not None] == list(range(len(cdr.base.steps)))
    assert cdr.align[labels.index("calibration.offset")] == 8
    assert cdr.align[labels.index("thresholds")] == 2
    assert cdr.align[labels.index("header.frame_id length")] == 4
    text = format_cdr_layout(cdr)
    assert "SUB_BAD_LABEL_LENGTH: 1..33" in text     # limits: label 32 bytes, + its NUL
    # the smallest sample (by the codec) is the walk's minimum
    creg = cdr.registry
    smallest = {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
                "calibration": {"sensor_name": "", "offset": [0.0] * 3, "mode": 2}, "label": "",
                "thresholds": [0] * 4, "samples": [], "period": {"sec": 0, "nanosec": 0},
                "history": [], "valid": False}
    assert len(serialize_cdr(creg, "lab_msgs/Samples", smallest)) == cdr.layout.min_body


def test_a_ros1_only_check_is_refused_for_cdr() -> None:
    reg = MsgRegistry.with_defaults()
    with pytest.raises(LayoutError) as exc:
        derive_cdr_layout(reg, "sensor_msgs/LaserScan", stream="ranges", stream_length=4,
                          checks={"header.seq": 0})
    assert exc.value.key == "checks.header.seq"


@pytest.mark.parametrize("model", ["fast", "reference"])
def test_bad_headers_nuls_and_lengths_are_refused_and_the_next_sample_is_right(model: str) -> None:
    pipe = _samples_pipeline(model)
    creg = pipe.cdr.registry
    good = serialize_cdr(creg, "lab_msgs/Samples", _samples_value())
    expected = _samples_pipeline().process(good)
    frame_id_at = 4 + 8 + 4       # header, sec and nanosec, the length of "array\0"
    cases = {
        "big endian": (b"\x00\x00" + good[2:], "encapsulation header",
                       "not what the circuit was built for"),
        "xcdr2": (b"\x00\x07" + good[2:], "encapsulation header",
                  "not what the circuit was built for"),
        "no nul": (good[:frame_id_at + 5] + b"!" + good[frame_id_at + 6:], "header.frame_id NUL",
                   "no NUL"),
        "zero length": (good[:frame_id_at - 4] + struct.pack("<I", 0) + good[frame_id_at:],
                        "header.frame_id length", "below the minimum"),
        "label too long": (serialize_cdr(creg, "lab_msgs/Samples", _samples_value(label="x" * 33)),
                           "label length", "over the limit"),
        "mode": (serialize_cdr(creg, "lab_msgs/Samples", _samples_value(mode=3)),
                 "calibration.mode", "not what the circuit was built for"),
        "stream length": (serialize_cdr(creg, "lab_msgs/Samples", _samples_value(n=63)),
                          "samples length", "not what the circuit was built for"),
    }
    for name, (bad, field, rule) in cases.items():
        with pytest.raises(FrameFieldError) as exc:
            pipe.process(bad)
        assert (exc.value.field, exc.value.rule) == (field, rule), name
        assert pipe.process(good) == expected, name
    # byte by byte: the circuit resynchronises on the next sample
    interp = CdrInterpreter(pipe.cdr)
    refusals = []
    for byte in b"".join(_record(c[0]) for c in cases.values()) + _record(good):
        try:
            interp.push(byte)
        except FrameFieldError as exc:
            refusals.append(exc.field)
    assert refusals == [c[1] for c in cases.values()] and interp.frames == 1


def test_end_padding_announced_by_the_options_is_skipped() -> None:
    pipe = _samples_pipeline("reference")
    creg = pipe.cdr.registry
    good = serialize_cdr(creg, "lab_msgs/Samples", _samples_value())
    out = pipe.process(good)
    for pad in (1, 2, 3):
        assert pipe.process(_pad_tail(good, pad)) == out
    # padding the options do not announce is not the sample's
    with pytest.raises(FrameLengthError) as exc:
        pipe.process(good + b"\x00")
    assert exc.value.field == "frame length"
    interp = CdrInterpreter(pipe.cdr)
    interp.feed(_record(_pad_tail(good, 3))[:-1])
    with pytest.raises(FrameFieldError) as exc:
        interp.finish()
    assert exc.value.field == TAIL_LABEL


@pytest.mark.parametrize("model", ["reference", "fast"])
def test_unannounced_zero_padding_to_4_is_taken_when_the_options_announce_fewer(model: str) -> None:
    """Issue 20: Cyclone DDS pads an XCDR1 payload to a multiple of 4 (counted from the
    encapsulation header's first byte) with options 00 00; a 398-byte Samples arrives as 400."""
    pipe = _samples_pipeline(model)
    creg = pipe.cdr.registry
    extract = extract_cdr_reference if model == "reference" else extract_cdr_fast
    good = serialize_cdr(creg, "lab_msgs/Samples", _samples_value())
    shorter = serialize_cdr(creg, "lab_msgs/Samples", dict(_samples_value(), history=[]))
    assert (len(good) % 4, len(shorter) % 4) == (2, 1)   # they need 2 and 3 bytes
    out = pipe.process(good)
    out_shorter = pipe.process(shorter)
    for payload, want in ((good, out), (shorter, out_shorter)):
        fill = -len(payload) % 4
        padded = payload + bytes(fill)                      # options 00 00: unannounced
        assert len(padded) % 4 == 0 and padded[2:4] == b"\x00\x00"
        assert pipe.process(padded) == want
        # options announcing fewer bytes do not stop it; announcing more than there are
        # claims the last field's bytes as padding and is refused, as before
        for options in range(1, 4):
            record = _record(padded[:2] + struct.pack(">H", options) + padded[4:])
            if options < fill:
                assert pipe.process(record[4:]) == want
            elif options > fill:
                with pytest.raises(FrameLengthError):
                    extract(pipe.cdr, record)
                assert _outcome(extract_cdr_reference, pipe.cdr, record) == \
                    _outcome(extract_cdr_fast, pipe.cdr, record)
        # announced by the options and also aligning: taken as before
        assert pipe.process(_pad_tail(payload, fill)) == want
        # one byte short of alignment, one zero too many, four more zeros: not padding
        for bad in (payload + bytes(fill - 1) if fill > 1 else None, padded + b"\x00",
                    padded + bytes(4)):
            if bad is None:
                continue
            with pytest.raises(FrameLengthError) as exc:
                extract(pipe.cdr, _record(bad))
            assert exc.value.field == "frame length"
            assert pipe.process(padded) == want
        # padding's value is not looked at (CDR leaves it undefined; Cyclone DDS reads past
        # it): a non-zero byte there is taken like a zero, both models alike
        for k in range(fill):
            odd = bytearray(padded)
            odd[len(payload) + k] = 0x5A
            assert pipe.process(bytes(odd)) == want
            assert _outcome(extract_cdr_reference, pipe.cdr, _record(bytes(odd))) == \
                _outcome(extract_cdr_fast, pipe.cdr, _record(bytes(odd))) == \
                _outcome(extract_cdr_reference, pipe.cdr, _record(padded))
    # byte by byte: padding of non-zero bytes, then two more samples, none refused
    odd = bytearray(good + bytes(2))
    odd[-2] = 1
    interp = CdrInterpreter(pipe.cdr)
    for byte in _record(bytes(odd)) + _record(good + bytes(2)) + _record(shorter + bytes(3)):
        interp.push(byte)
    assert interp.frames == 3
    assert interp.pc == 0 and not interp._buf


def test_the_samples_pipeline_agrees_with_the_codec_and_a_sliding_max() -> None:
    pipe = _samples_pipeline()
    creg = pipe.cdr.registry
    value = _samples_value()
    out = deserialize_cdr(creg, "lab_msgs/Samples", pipe.process(
        serialize_cdr(creg, "lab_msgs/Samples", value)))
    x = value["samples"]
    padded = np.concatenate([[x[0]], x, [x[-1]]])
    want = np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:])
    assert np.array_equal(out["samples"], want)
    assert out["label"] == "hi" and out["header"]["frame_id"] == "array"
    assert [h["sensor_name"] for h in out["history"]] == ["old", ""]


# -- real Cyclone DDS -----------------------------------------------------------------------------

def _cyclone_types() -> dict[str, Any]:
    """rosidl's IDL of the types (tests/support/cdrtypes.py), or skip (fail under CI)."""
    require_cyclonedds()
    from tests.support import cdrtypes

    return {name: getattr(cdrtypes, name) for name in
            ("Time_", "Duration_", "Header_", "Image_", "Calibration_", "Samples_")}


IMAGE_YAML = """
node: {name: /fpga_dilate}
subscriber: {topic: /image_raw, type: sensor_msgs/Image}
publisher: {topic: /image_dilated, type: sensor_msgs/Image}
image: {width: 7, height: 5, encoding: rgba8}
application: {op: OP, ksize: 3}
"""


@pytest.mark.parametrize("op", ["dilate", "erode"])
@pytest.mark.parametrize("model", ["fast", "reference"])
def test_cyclone_dds_images_through_the_cdr_circuit_exactly(op: str, model: str) -> None:
    T = _cyclone_types()
    config = parse_config(IMAGE_YAML.replace("OP", op))
    pipe = CdrPipeline(config, model)
    rng = np.random.default_rng(11)
    pixels = rng.integers(0, 256, (5, 7, 4), np.uint8)
    kernel = np.ones((3, 3), np.uint8)
    want = (cv2.dilate if op == "dilate" else cv2.erode)(pixels, kernel)
    for frame_id in ("camera", "", "a" * 13):
        header = T["Header_"](T["Time_"](-5, 999_999_999), frame_id)
        sample = T["Image_"](header, 5, 7, "rgba8", 0, 28, pixels.tobytes()).serialize()
        expected = T["Image_"](header, 5, 7, "rgba8", 0, 28, want.tobytes()).serialize()
        out = pipe.process(sample)
        assert out == expected
        back = T["Image_"].deserialize(out)
        assert back.header.frame_id == frame_id and bytes(back.data) == want.tobytes()
    # a wrong width is refused by name, and the next sample comes out right
    wrong = T["Image_"](header, 5, 8, "rgba8", 0, 32, bytes(160)).serialize()
    with pytest.raises(FrameFieldError) as exc:
        pipe.process(wrong)
    assert exc.value.field == "width"
    assert pipe.process(sample) == expected


@pytest.mark.parametrize("model", ["fast", "reference"])
def test_cyclone_dds_samples_of_the_labs_own_message_through_the_cdr_circuit(model: str) -> None:
    T = _cyclone_types()
    pipe = _samples_pipeline(model)
    rng = np.random.default_rng(5)
    for labels in (("hi", "imu", "old"), ("", "", ""), ("seven!!", "x", "yz")):
        x = rng.integers(-2**31, 2**31, 64, dtype=np.int32)
        padded = np.concatenate([[x[0]], x, [x[-1]]])
        want = np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:])

        def sample(values: np.ndarray) -> Any:
            calib = T["Calibration_"](labels[1], [0.25, -1.5, 3.0], 2)
            return T["Samples_"](
                T["Header_"](T["Time_"](12, 34), "array"), calib, labels[0], [-1, 2, -3, 4],
                [int(v) for v in values], T["Duration_"](0, 1000),
                [T["Calibration_"](labels[2], [1.0, 2.0, 4.0], 7)] * 2, True)

        out = pipe.process(sample(x).serialize())
        assert out == sample(want).serialize()
        assert list(T["Samples_"].deserialize(out).samples) == want.tolist()


def test_cyclone_dds_bytes_are_the_labs_cdr_bytes() -> None:
    """The samples above are what the lab's codec writes too (so the hypothesis tests, run on
    the codec's bytes, cover Cyclone's)."""
    T = _cyclone_types()
    creg = cdr_registry(SAMPLES_CONFIG.registry())
    value = _samples_value(n=5)
    theirs = T["Samples_"](
        T["Header_"](T["Time_"](1700000000, 5), "array"),
        T["Calibration_"]("imu", [0.5, -1.0, 2.0], 2), "hi", [-3, 0, 7, 32767],
        [int(v) for v in value["samples"]], T["Duration_"](0, 1000),
        [T["Calibration_"]("old", [0.5, -1.0, 2.0], 2), T["Calibration_"]("", [0.5, -1.0, 2.0], 2)],
        True).serialize()
    assert serialize_cdr(creg, "lab_msgs/Samples", value) == theirs


# -- real Cyclone DDS on the wire (no cyclonedds needed: the capture is in data/) -------------------

def test_images_cyclone_dds_sent_over_rtps_through_the_cdr_circuit() -> None:
    """data/rtps_image.pcapng: two 640x480 rgb8 samples a Cyclone DDS writer sent (DATA_FRAG),
    reassembled by the lab's RTPS decoder, through the circuit; the output is the codec's
    bytes of the dilated image (cv2) with every other field as received."""
    from rosfpga_lab.graph.capture_read import udp_datagrams
    from rosfpga_lab.rtps import DataFrag, FragmentAssembler, parse_message

    asm = FragmentAssembler()
    samples = []
    for _t, _src, _dst, data in udp_datagrams(DATA / "rtps_image.pcapng"):
        msg = parse_message(data)
        for sub in msg.submessages:
            if isinstance(sub, DataFrag):
                got = asm.add(msg.header.guid_prefix, sub)
                if got is not None:
                    samples.append(got)
    assert len(samples) == 2
    config = parse_config(IMAGE_YAML.replace("OP", "dilate").replace(
        "width: 7, height: 5, encoding: rgba8", "width: 640, height: 480, encoding: rgb8"))
    pipe = CdrPipeline(config)
    reg = ros2_registry()
    for sample in samples:
        value = deserialize_cdr(reg, "sensor_msgs/Image", sample)
        image = np.asarray(value["data"]).reshape(480, 640, 3)
        want = dict(value, data=cv2.dilate(image, np.ones((3, 3), np.uint8)).tobytes())
        assert pipe.process(sample) == serialize_cdr(reg, "sensor_msgs/Image", want)


def test_messages_without_fields_are_rosidls_one_byte_in_the_walk() -> None:
    reg = MsgRegistry.with_defaults()
    reg.add("h_msgs/E", "std_msgs/Empty e\nstd_msgs/Empty[] es\nfloat64[] stream\nstd_msgs/Empty z")
    cdr = derive_cdr_layout(reg, "h_msgs/E", stream="stream", stream_length=2)
    assert [s.label for s in cdr.layout.steps if s.kind is StepKind.SCALAR] == [
        "e.structure_needs_at_least_one_member", "es[].structure_needs_at_least_one_member",
        "z.structure_needs_at_least_one_member"]
    r2 = ros2_registry(reg)
    value = {"e": {}, "es": [{}, {}, {}], "stream": [1.5, -2.0], "z": {}}
    payload = serialize_cdr(r2, "h_msgs/E", value)
    # 1 byte, 4-byte count, 3 bytes, pad to 8, 4-byte count, 2 float64, 1 byte
    assert len(payload) == 4 + 1 + 3 + 4 + 3 + 1 + 4 + 16 + 1
    for extract in (extract_cdr_reference, extract_cdr_fast):
        ex = extract(cdr, _record(payload))
        assert ex.stream.tolist() == [1.5, -2.0]
        assert publish_cdr_fast(cdr, ex.tokens, ex.stream[::-1].copy()) == _record(
            serialize_cdr(r2, "h_msgs/E", dict(value, stream=[-2.0, 1.5])))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(min_size=1, max_size=120), st.integers(0, 3))
def test_any_bytes_are_walked_or_refused_by_name_and_both_models_agree(junk: bytes, mode: int) -> None:
    cdr = _samples_pipeline().cdr
    good = _record(serialize_cdr(cdr.registry, "lab_msgs/Samples", _samples_value(n=64)))
    record = [junk, good[:8] + junk, good[:40] + junk, _record(b"\x00\x01\x00\x00" + junk)][mode]
    outcome = _outcome(extract_cdr_reference, cdr, record)
    assert outcome == _outcome(extract_cdr_fast, cdr, record)
    # byte by byte after the junk, the next good sample still comes out right
    interp = CdrInterpreter(cdr)
    for byte in record:
        try:
            interp.push(byte)
        except FrameFieldError:
            pass
    frames = interp.frames
    if interp.pc != 0 or interp._buf:   # mid-sample: the junk's sample length still runs
        return
    for byte in good:
        interp.push(byte)
    assert interp.frames == frames + 1


def test_skipped_fields_are_written_as_cdr_defaults_and_another_output_type_by_path(
        tmp_path: Path) -> None:
    r2 = ros2_registry()
    c = parse_config("node: {name: n}\nsubscriber: {topic: /a, type: sensor_msgs/LaserScan}\n"
                     "publisher: {topic: /b}\nstream: {field: ranges, length: 3}\n"
                     "skip: [intensities, header.frame_id, scan_time]\n"
                     "application: {op: dilate, ksize: 3}\n")
    scan = {"header": {"stamp": {"sec": 5, "nanosec": 6}, "frame_id": "laser"},
            "angle_min": -1.0, "angle_max": 1.0, "angle_increment": 0.5, "time_increment": 0.0,
            "scan_time": 0.5, "range_min": 0.1, "range_max": 9.0, "ranges": [3.0, 1.0, 2.0],
            "intensities": [9.0, 9.0, 9.0]}
    # a skipped string is "" on the wire: length 1, its NUL (the alignment after it moves)
    want = serialize_cdr(r2, "sensor_msgs/LaserScan", dict(
        scan, header=dict(scan["header"], frame_id=""), scan_time=0.0, intensities=[],
        ranges=[3.0, 3.0, 2.0]))
    for model in ("fast", "reference"):
        assert CdrPipeline(c, model).process(serialize_cdr(r2, "sensor_msgs/LaserScan", scan)) == want

    config = conversion_config(tmp_path)
    reg2 = ros2_registry(config.registry())
    msg = {"header": {"stamp": {"sec": 3, "nanosec": 4}, "frame_id": "x"}, "name": "nm",
           "values": [1, -5, 3, 0], "gain": 2.5, "inner": {"a": 7, "b": "in"},
           "list": [{"a": 1, "b": "z"}]}
    want = serialize_cdr(reg2, "conv_msgs/Out", {
        "header": msg["header"], "values": [1, 3, 3, 3], "name": "nm", "extra": 0,
        "inner": {"b": "in", "a": 0, "c": 0}, "list": []})
    for model in ("fast", "reference"):
        assert CdrPipeline(config, model).process(serialize_cdr(reg2, "conv_msgs/In", msg)) == want


def test_the_rtl_model_is_refused_with_where_the_cdr_verilog_runs() -> None:
    """``node --ros2 --model rtl`` once ran the Python model quietly: the CDR circuit's Verilog
    runs live in the ROS 2 node's simulator (rtl/server.py), so the Python pipeline refuses
    ``rtl`` and says where it runs."""
    from rosfpga_lab.hw.errors import PipelineConfigError

    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    with pytest.raises(PipelineConfigError, match=r"node CONFIG --ros2 --model rtl"):
        CdrPipeline(config, "rtl")
    with pytest.raises(PipelineConfigError, match="model must be one of fast, reference"):
        CdrPipeline(config, "fastest")
