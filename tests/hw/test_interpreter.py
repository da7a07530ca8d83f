"""The subscriber-side message interpreter: table, decoding, bad frames, resynchronisation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.errors import LabError
from rosfpga_lab.hw import (
    INTERPRETER_TABLE, ByteFIFO, FrameFieldError, FrameLengthError, FrameTruncatedError,
    Interpreter, PipelineError, UnsupportedEncodingError, interpret_fast, interpret_reference,
)
from rosfpga_lab.hw import limits
from tests.hw.test_oracles import image_msg, images, tcpros_frame

IMG = np.arange(2 * 3 * 4, dtype=np.uint8).reshape(2, 3, 4)
GOOD = tcpros_frame(image_msg(IMG, "rgba8", seq=7, stamp=(11, 12), frame_id="camera"))


def run_reference(frame: bytes, **config):
    rx, out = ByteFIFO(name="rx"), ByteFIFO(name="out")
    rx.extend(frame)
    fields = interpret_reference(rx, out, **config)
    return fields, out.to_bytes()


def both(frame: bytes, **config):
    """Run both models; return (fields, pixels) after checking they agree, or both errors."""
    try:
        ref = run_reference(frame, **config)
    except PipelineError as exc:
        ref = exc
    try:
        fields, pixels = interpret_fast(frame, **config)
        fast = (fields, pixels.tobytes())
    except PipelineError as exc:
        fast = exc
    if isinstance(ref, Exception) or isinstance(fast, Exception):
        assert type(ref) is type(fast), (ref, fast)
        assert (ref.field, ref.offset, str(ref)) == (fast.field, fast.offset, str(fast))
        raise ref
    assert ref == fast
    return ref


def test_table_is_a_connected_chain_over_every_image_field():
    states = [t.state for t in INTERPRETER_TABLE]
    assert len(set(states)) == len(states)
    for here, there in zip(INTERPRETER_TABLE, INTERPRETER_TABLE[1:]):
        assert here.next == there.state
    assert INTERPRETER_TABLE[-1].next == INTERPRETER_TABLE[0].state
    assert [t.label for t in INTERPRETER_TABLE] == [
        "frame length", "header.seq", "header.stamp.secs", "header.stamp.nsecs",
        "header.frame_id length", "header.frame_id", "height", "width", "encoding length",
        "encoding", "is_bigendian", "step", "data length", "data"]


def test_table_as_text_for_notebooks():
    from rosfpga_lab.hw import format_table
    lines = format_table().splitlines()
    assert lines[0].split() == ["state", "field", "bytes", "next", "check"]
    assert lines[1].split() == ["FRAME_LEN", "frame", "length", "4", "SEQ", "frame_length"]
    assert lines[-1].split() == ["DATA", "data", "=", "data_length", "FRAME_LEN", "frame_end"]
    assert len(lines) == len(INTERPRETER_TABLE) + 1


def test_decodes_a_frame_written_by_the_message_layer():
    fields, pixels = both(GOOD)
    assert (fields.seq, fields.stamp_secs, fields.stamp_nsecs, fields.frame_id) == (7, 11, 12, "camera")
    assert (fields.height, fields.width, fields.encoding, fields.step) == (2, 3, "rgba8", 12)
    assert fields.data_length == 24 and fields.frame_length == len(GOOD) - 4
    assert fields.data_offset == len(GOOD) - 24
    assert pixels == IMG.tobytes()


def test_byte_by_byte_states_and_pixel_output():
    interp = Interpreter()
    seen = []
    for byte in GOOD:
        seen.append(interp.state)
        interp.push(byte)
    assert interp.frames == 1 and interp.state == "FRAME_LEN"
    assert seen[:4] == ["FRAME_LEN"] * 4 and seen[4] == "SEQ"
    assert seen[-24:] == ["DATA"] * 24
    assert interp.out.to_bytes() == IMG.tobytes()


def test_trace_records_state_and_field_per_byte():
    rows = Interpreter().trace(GOOD, limit=30)
    assert rows[0] == (0, GOOD[0], "FRAME_LEN", "frame length")
    assert rows[4] == (4, 7, "SEQ", "header.seq")
    assert [r[3] for r in rows[20:26]] == ["header.frame_id"] * 6
    assert rows[26][2:] == ("HEIGHT", "height")


def test_two_frames_back_to_back_and_trailing_bytes():
    interp = Interpreter()
    other = tcpros_frame(image_msg(IMG[:1], "rgba8", seq=8))
    interp.feed(GOOD + other)
    assert interp.frames == 2 and interp.fields.seq == 8
    assert interp.out.to_bytes() == IMG.tobytes() + IMG[:1].tobytes()
    with pytest.raises(FrameLengthError, match="1 more bytes"):
        both(GOOD + b"\x00")


@given(images(max_side=6), st.text(max_size=8), st.integers(0, 2**32 - 1), st.integers(0, 2**32 - 1))
@settings(max_examples=80, deadline=None)
def test_reference_equals_fast_on_random_frames(img_enc, frame_id, seq, secs):
    image, encoding = img_enc
    frame = tcpros_frame(image_msg(image, encoding, seq=seq, stamp=(secs, 5), frame_id=frame_id))
    fields, pixels = both(frame)
    assert pixels == image.tobytes()
    assert fields.frame_id == frame_id and fields.seq == seq


@given(images(max_side=4), st.data())
@settings(max_examples=80, deadline=None)
def test_reference_equals_fast_on_corrupted_frames(img_enc, data):
    """Flip, cut or extend a good frame anywhere: both models fail (or pass) identically."""
    image, encoding = img_enc
    frame = bytearray(tcpros_frame(image_msg(image, encoding, frame_id="x")))
    how = data.draw(st.sampled_from(["flip", "cut", "extend"]))
    at = data.draw(st.integers(0, len(frame) - 1))
    if how == "flip":
        frame[at] ^= data.draw(st.integers(1, 255))
    elif how == "cut":
        del frame[at:]
    else:
        frame[at:at] = data.draw(st.binary(min_size=1, max_size=3))
    try:
        both(bytes(frame))
    except PipelineError:
        pass


def bad(**override) -> bytes:
    return tcpros_frame(image_msg(IMG, "rgba8", **override))


@pytest.mark.parametrize("frame, error, field, offset", [
    (bad(height=0, data=b""), FrameFieldError, "height", 20),
    (bad(width=0), FrameFieldError, "width", 24),
    (bad(height=limits.MAX_HEIGHT + 1), FrameFieldError, "height", 20),
    (bad(width=10**9), FrameFieldError, "width", 24),
    (bad(step=13), FrameFieldError, "step", 38),
    (bad(data=IMG.tobytes()[:-1]), FrameFieldError, "data length", 42),
    (tcpros_frame(image_msg(IMG, "yuv422")), UnsupportedEncodingError, "encoding", 32),
    (tcpros_frame(image_msg(IMG, "16UC1")), UnsupportedEncodingError, "encoding", 32),
    (GOOD[:30], FrameTruncatedError, "width", 30),
    (GOOD[:-1], FrameTruncatedError, "data", len(GOOD) - 24),
    (GOOD[:3], FrameTruncatedError, "frame length", 0),
    ((10).to_bytes(4, "little") + bytes(10), FrameLengthError, "frame length", 0),
    ((2**31).to_bytes(4, "little") + GOOD[4:], FrameLengthError, "frame length", 0),
], ids=["height0", "width0", "height-absurd", "width-absurd", "step", "data-length", "yuv422",
        "16UC1", "cut-in-width", "cut-in-data", "cut-in-length", "length-too-small", "length-huge"])
def test_bad_frames_name_the_field_and_offset(frame, error, field, offset):
    with pytest.raises(error) as info:
        both(frame)
    assert info.value.field == field and info.value.offset == offset
    assert isinstance(info.value, LabError) and info.value.stage == "interpreter"
    assert f"field {field!r} at byte {offset}" in str(info.value)


def test_frame_length_that_disagrees_with_the_body():
    body = GOOD[4:]
    with pytest.raises(FrameLengthError, match="announces"):
        both((len(body) + 1).to_bytes(4, "little") + body + b"\x00")
    with pytest.raises(FrameLengthError, match="ends before this field") as info:
        both((40).to_bytes(4, "little") + body[:40])   # ends between is_bigendian and step
    assert (info.value.field, info.value.offset) == ("step", 44)
    with pytest.raises(FrameLengthError, match="ends inside this field") as info:
        both((42).to_bytes(4, "little") + body[:42])
    assert (info.value.field, info.value.offset) == ("step", 44)
    with pytest.raises(FrameLengthError, match="frame length leaves only"):
        both((37).to_bytes(4, "little") + body[:37])   # frame_id would not fit


def test_configured_circuit_refuses_other_sizes_and_encodings():
    with pytest.raises(FrameFieldError, match="built for width 4"):
        both(GOOD, width=4)
    with pytest.raises(FrameFieldError, match="built for height 3"):
        both(GOOD, height=3)
    with pytest.raises(UnsupportedEncodingError, match="built for 'bgra8'"):
        both(GOOD, encoding="bgra8")
    assert both(GOOD, width=3, height=2, encoding="rgba8")[1] == IMG.tobytes()


def test_resynchronises_on_a_byte_stream_after_a_bad_frame():
    """An error mid-stream skips the rest of that frame; the next frame decodes right."""
    interp = Interpreter()
    stream = bad(step=13) + GOOD
    errors = 0
    for byte in stream:
        try:
            interp.push(byte)
        except FrameFieldError as exc:
            errors += 1
            assert exc.field == "step" and interp.state == "SKIP"
    assert errors == 1 and interp.frames == 1 and interp.fields.seq == 7
    assert interp.out.to_bytes() == IMG.tobytes()


def test_finish_reports_a_cut_frame_and_resets():
    interp = Interpreter()
    interp.feed(GOOD[:40])
    with pytest.raises(FrameTruncatedError, match="cut short"):
        interp.finish()
    assert interp.state == "FRAME_LEN" and interp.offset == 0
    interp.feed(GOOD)
    interp.finish()
    assert interp.frames == 1


def test_one_vocabulary_for_states_kinds_and_checks() -> None:
    """The tables use enum names, not free strings: every check has its method, the generator's
    kinds are the interpreter's, and the names still print as the notebooks show them."""
    from rosfpga_lab.hw import GENERATOR_TABLE, INTERPRETER_TABLE, Check, IState, Kind, format_table
    from rosfpga_lab.hw.interpreter import _CHECKS

    assert set(_CHECKS) == set(Check) == {t.check for t in INTERPRETER_TABLE if t.check}
    assert {t.state for t in INTERPRETER_TABLE} | {IState.SKIP} == set(IState)
    by_label = {t.label: t.kind for t in INTERPRETER_TABLE}
    for label, kind, _attr in GENERATOR_TABLE:
        assert isinstance(kind, Kind) and by_label[label] is kind
    assert Kind.STRING == "string" and repr(Kind.STRING) == "string"
    assert "FRAME_ID_LEN  header.frame_id length  4                  FRAME_ID      frame_id_length" \
        in format_table()
