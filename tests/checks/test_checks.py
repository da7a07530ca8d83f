"""The exercise checks: right answers pass, typical wrong answers get the specific finding.

Right answers here are written independently of the code under test (struct by hand, literal
values known from real ROS), and every wrong answer is one a student plausibly gives.
"""

from __future__ import annotations

import struct

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab import checks as C
from rosfpga_lab.errors import LabError
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.msg import default_registry, field_layout, serialize
from rosfpga_lab.msg import strategies as msg_st


def problems_of(fn, *args, **kwargs) -> str:
    with pytest.raises(C.ExerciseError) as info:
        fn(*args, **kwargs)
    assert isinstance(info.value, LabError)
    return str(info.value)


def pack_str(text: str | bytes) -> bytes:
    raw = text.encode() if isinstance(text, str) else text
    return struct.pack("<I", len(raw)) + raw


# ------------------------------------------------------------------------------ core
def test_exercise_error_renders_without_traceback():
    err = C.ExerciseError("9.9 (demo)", ["first", "second"])
    lines = err._render_traceback_()
    assert "Exercise 9.9 (demo): not right yet" in lines[0]
    assert any("- first" in line for line in lines) and len(lines) == 3


def test_placeholder_answers_are_refused():
    assert "replace it with your answer" in problems_of(C.check_tdata, ..., (1, 2, 3, 4))
    assert "replace it with your answer" in problems_of(C.check_data_offset, None, b"")


def test_check_result_says_correct():
    res = C.check_tdata(0x04030201, (1, 2, 3, 4))
    assert res.ok and "correct" in str(res) and "correct" in res._repr_html_()


def test_describe_byte_difference_names_field_and_decodes():
    fields = [C.ByteField(0, 4, "a", "uint32"), C.ByteField(4, 2, "b", "bytes")]
    want = struct.pack("<I", 7) + b"hi"
    got = struct.pack("<I", 5) + b"hi"
    assert C.describe_byte_difference(got, want, fields) == [
        "byte 0 (field a, uint32 at bytes 0..3) is 5, expected 7"]
    assert C.describe_byte_difference(want, want, fields) == []
    short = C.describe_byte_difference(want[:5], want, fields)
    assert short == ["your bytes end after 5 bytes, expected 6 (missing from field b on)"]
    assert "1 byte(s) too many" in C.describe_byte_difference(want + b"!", want, fields)[0]
    swapped = C.describe_byte_difference(struct.pack(">I", 7) + b"hi", want, fields)
    assert swapped == ["byte 0 (field a, uint32 at bytes 0..3) is 117440512, expected 7: its bytes "
                       "are in big-endian order; ROS is little-endian (struct format '<')"]


# ------------------------------------------------------------------------------ notebook 1
RIGHT_CALLS = [("/listener", "/master", "registerSubscriber"), ("/talker", "/master", "registerPublisher"),
               ("/master", "/listener", "publisherUpdate"), ("/listener", "/talker", "requestTopic")]


def test_call_order_right():
    assert C.check_call_order(RIGHT_CALLS).ok


def test_call_order_wrong_answers():
    to_master = RIGHT_CALLS[:3] + [("/listener", "/master", "requestTopic")]
    assert "requestTopic goes /listener -> /talker, you wrote /listener -> /master" in \
        problems_of(C.check_call_order, to_master)
    assert "publisherUpdate is missing" in problems_of(C.check_call_order, RIGHT_CALLS[:2] + RIGHT_CALLS[3:])
    swapped = [RIGHT_CALLS[1], RIGHT_CALLS[0]] + RIGHT_CALLS[2:]
    assert "entry 0 is registerPublisher, expected registerSubscriber" in problems_of(C.check_call_order, swapped)
    assert "(caller, callee, method) tuple" in problems_of(C.check_call_order, ["registerSubscriber"])


def test_talker_contact_right_and_wrong():
    with EmbeddedMaster(port=0) as master:
        talker = Node("/talker", master=master)
        try:
            xmlrpc_port = int(talker.uri.rstrip("/").rsplit(":", 1)[1])
            assert C.check_talker_contact(talker.uri, talker.tcpros_port, talker=talker).ok
            msg = problems_of(C.check_talker_contact, master.uri, xmlrpc_port, talker=talker,
                              master_uri=master.uri)
            assert "talker_uri is the master's URI" in msg
            assert f"tcpros_port {xmlrpc_port} is the port of the talker's XML-RPC server" in msg
            msg = problems_of(C.check_talker_contact, [1, "ok", talker.uri],
                              ["TCPROS", "127.0.0.1", talker.tcpros_port], talker=talker)
            assert "whole [code, statusMessage, value] reply" in msg and "take the port (index 2)" in msg
            assert "give an int" in problems_of(C.check_talker_contact, talker.uri,
                                                str(talker.tcpros_port), talker=talker)
        finally:
            talker.shutdown()


def test_a_whole_reply_passed_as_uri_is_named():
    """Exercise 1.2's likeliest mistake: lookupNode's whole reply handed to call() as the URI
    ended in a raw TypeError from urllib; split_uri now raises its documented ConfigError."""
    from rosfpga_lab.errors import LabError
    from rosfpga_lab.graph.xmlrpc import call, split_uri

    reply = [1, "node api", "http://127.0.0.1:9/"]
    with pytest.raises(LabError, match=r"whole \[code, statusMessage, value\].*reply\[2\]"):
        call(reply, "requestTopic", "/student", "/chatter", [["TCPROS"]])   # before any socket
    with pytest.raises(LabError, match="not int 5"):
        split_uri(5)
    with pytest.raises(LabError, match="not NoneType"):
        split_uri(None)


HTTP = b"POST / HTTP/1.1\r\nContent-Length: 5\r\n\r\nhello"


def test_http_body():
    assert C.check_http_body(HTTP, 38, 5).ok      # 17 + 19 + 2 bytes of head
    assert "points at the blank line" in problems_of(C.check_http_body, HTTP, 34, 5)
    assert "off by 2" in problems_of(C.check_http_body, HTTP, 36, 5)
    assert "is the whole request" in problems_of(C.check_http_body, HTTP, 38, len(HTTP))
    assert "body_start should be int" in problems_of(C.check_http_body, HTTP, "38", 5)
    assert "not an HTTP message" in problems_of(C.check_http_body, b"hello", 0, 5)


# ------------------------------------------------------------------------------ notebook 2
FIELDS = {"callerid": "/s", "md5sum": "*", "topic": "/t", "type": "*"}


def by_hand(fields, order=sorted, fmt="<I") -> bytes:
    body = b"".join(struct.pack(fmt, len(f)) + f for f in (f"{k}={v}".encode() for k, v in order(fields.items())))
    return struct.pack(fmt, len(body)) + body


def test_connection_header_right():
    assert C.check_connection_header(by_hand(FIELDS), FIELDS).ok


def test_connection_header_wrong_answers():
    unsorted = {"type": "*", "topic": "/t", "md5sum": "*", "callerid": "/s"}
    unsorted_msg = problems_of(C.check_connection_header, by_hand(unsorted, order=list), unsorted)
    assert "the protocol accepts any order" in unsorted_msg
    assert "rospy and roscpp write them sorted by key" in unsorted_msg
    assert "total length at the start is missing" in problems_of(C.check_connection_header, by_hand(FIELDS)[4:], FIELDS)
    assert "big-endian" in problems_of(C.check_connection_header, by_hand(FIELDS, fmt=">I"), FIELDS)
    bad = bytearray(by_hand(FIELDS))
    bad[4] = 12  # the first field 'callerid=/s' is 11 bytes
    assert "byte 4 (field length of field 'callerid=...', uint32 at bytes 4..7) is 12, expected 11" in \
        problems_of(C.check_connection_header, bytes(bad), FIELDS)
    assert "should be bytes" in problems_of(C.check_connection_header, "callerid=/s", FIELDS)


POSE_MD5 = "e45d45a5a1ce597b249e23fb30fc871f"   # geometry_msgs/Pose, from genpy


def test_md5_right_and_wrong():
    import hashlib

    assert C.check_md5("geometry_msgs/Pose", POSE_MD5).ok
    raw = hashlib.md5(b"Point position\nQuaternion orientation\n").hexdigest()
    assert "nested types must be replaced" in problems_of(C.check_md5, "geometry_msgs/Pose", raw)
    full = hashlib.md5(b"geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation").hexdigest()
    assert "full type names" in problems_of(C.check_md5, "geometry_msgs/Pose", full)
    assert ".hexdigest()" in problems_of(C.check_md5, "geometry_msgs/Pose", hashlib.md5(b""))
    assert "32 lower-case hex digits" in problems_of(C.check_md5, "geometry_msgs/Pose", "E45D")
    newline = hashlib.md5(b"4a842b65f413084dc2b10fb484ea7f17 position\n"
                          b"a779879fadf0160734f906b8c19c7004 orientation\n").hexdigest()
    assert "must not end with a newline" in problems_of(C.check_md5, "geometry_msgs/Pose", newline)


STREAM = struct.pack("<I", 5) + b"hello" + struct.pack("<I", 0) + struct.pack("<I", 2) + b"ok"


def test_frame_split():
    assert C.check_frame_split([b"hello", b"", b"ok"], STREAM).ok
    assert "an empty body (length 0) is a frame too" in problems_of(C.check_frame_split, [b"hello", b"ok"], STREAM)
    with_prefix = [STREAM[:9], b"", b"ok"]
    assert "body 0 still starts with its 4-byte length prefix" in problems_of(C.check_frame_split, with_prefix, STREAM)
    assert "list of bytes" in problems_of(C.check_frame_split, STREAM, STREAM)


# ------------------------------------------------------------------------------ notebook 3
def image_body(frame_id="camera", width=2, height=1, encoding="mono8", data=b"\x01\x02") -> bytes:
    return (struct.pack("<III", 3, 10, 20) + pack_str(frame_id) + struct.pack("<II", height, width)
            + pack_str(encoding) + struct.pack("<BI", 0, width) + pack_str(data))


def image_msg(frame_id="camera"):
    return {"header": {"seq": 3, "stamp": {"secs": 10, "nsecs": 20}, "frame_id": frame_id},
            "height": 1, "width": 2, "encoding": "mono8", "is_bigendian": 0, "step": 2, "data": b"\x01\x02"}


def test_data_offset():
    frame = pack_str(image_body())
    right = 4 + 12 + 4 + 6 + 8 + 4 + 5 + 1 + 4 + 4
    assert C.check_data_offset(right, frame).ok
    assert "the uint32 length of 'data' starts" in problems_of(C.check_data_offset, right - 4, frame)
    assert "inside field header.frame_id" in problems_of(C.check_data_offset, 22, frame)


def test_data_offset_names_both_mistakes_that_give_want_minus_4():
    frame = pack_str(image_body())
    right = 4 + 12 + 4 + 6 + 8 + 4 + 5 + 1 + 4 + 4
    msg = problems_of(C.check_data_offset, right - 4, frame)
    # counted from the message body (no frame length) and stopped at data's length: both give it
    assert "start of the message body" in msg and "uint32 length of 'data'" in msg
    assert "both the frame's 4-byte length and the 4-byte length of 'data'" in \
        problems_of(C.check_data_offset, right - 8, frame)
    assert "still None" in problems_of(C.check_data_offset, None, frame)
    assert "still Ellipsis" in problems_of(C.check_data_offset, ..., frame)


def test_extract_frame_length_forgotten_is_not_called_a_swap():
    """Every field read 4 bytes early (the frame's length left out): width then holds the
    height, which the check used to call a swap of two right variables."""
    frame = pack_str(image_body("left_camera", width=9, height=5, encoding="bgr8"))
    u32 = lambda off: struct.unpack_from("<I", frame, off)[0]  # noqa: E731
    height_at = 4 + 12 + 4 + len("left_camera")
    early = {"height": u32(height_at - 4), "width": u32(height_at), "encoding": "bgr8", "step": 9}
    assert early["width"] == 5                                  # the height's value ...
    msg = problems_of(C.check_extract, early, frame)
    assert "read 4 bytes too early" in msg and "frame's 4-byte length" in msg
    assert "that is the height" not in msg                      # ... but no swap
    swapped = {"height": 9, "width": 5, "encoding": "bgr8", "step": 9}
    assert "that is the height; in sensor_msgs/Image height comes before width" in \
        problems_of(C.check_extract, swapped, frame)
    assert "still None" in problems_of(C.check_extract, None, frame)


def test_extract_from_27_names_the_shift_of_height_and_width_whatever_step_is():
    """Issue 32: ``height, width = unpack_from("<II", mystery, 27)`` (the frame length left out),
    the walk then going on from there, was told "that is the height; height comes before
    width": the shift was named only when every wrong number had it."""
    import numpy as np

    from rosfpga_lab import hw

    mystery = hw.image_frame(np.zeros((5, 9, 3), np.uint8), "bgr8", seq=42, frame_id="left_camera")
    pos = 27                                   # 4 + 8 + 4 + 11: the frame's length forgotten
    height, width = struct.unpack_from("<II", mystery, pos)
    pos += 8
    (n,) = struct.unpack_from("<I", mystery, pos)
    encoding = mystery[pos + 4:pos + 4 + n].decode(errors="replace")
    pos += 4 + n + 1
    (step,) = struct.unpack_from("<I", mystery, pos)
    assert width == 5 and step != 27                    # the height's value, a wrong step
    msg = problems_of(C.check_extract, {"width": width, "height": height, "encoding": encoding,
                                        "step": step}, mystery)
    assert "height and width read 4 bytes too early" in msg and "frame's 4-byte length" in msg
    assert "that is the height" not in msg
    assert f"step is {step}, expected 27" in msg
    # the same with encoding and step right: the shift alone
    msg = problems_of(C.check_extract, {"width": width, "height": height, "encoding": "bgr8",
                                        "step": 27}, mystery)
    assert "height and width read 4 bytes too early" in msg and "step" not in msg


def test_marshal_right_and_the_brief_example():
    assert C.check_marshal(image_body("cam_one"), image_msg("cam_one")).ok
    bad = bytearray(image_body("cam_one"))
    bad[12] = 5   # header.frame_id length says 5, the string has 7 bytes
    assert "byte 12 (field header.frame_id length, uint32 at bytes 12..15) is 5, expected 7" in \
        problems_of(C.check_marshal, bytes(bad), image_msg("cam_one"))
    assert "whole TCPROS frame" in problems_of(C.check_marshal, pack_str(image_body()), image_msg())
    swapped = image_body(width=1, height=2)   # width and height exchanged
    assert "field height" in problems_of(C.check_marshal, swapped, image_msg())


def test_extract():
    frame = pack_str(image_body(width=2, height=1))
    assert C.check_extract({"width": 2, "height": 1, "encoding": "mono8", "step": 2}, frame).ok
    msg = problems_of(C.check_extract, {"width": 1, "height": 2, "encoding": b"mono8", "step": 2}, frame)
    assert "width is 1, expected 2: that is the height" in msg
    assert "encoding is bytes" in msg
    assert "keys missing: step" in problems_of(C.check_extract, {"width": 2, "height": 1, "encoding": "mono8"}, frame)


# ------------------------------------------------------------------------------ notebook 4
def test_tdata():
    assert C.check_tdata(0x44332211, (0x11, 0x22, 0x33, 0x44)).ok
    assert "puts byte 0 (0x11) in the high bits" in problems_of(C.check_tdata, 0x11223344, (0x11, 0x22, 0x33, 0x44))
    assert "bits 15..8 hold 0x00, expected 0x22 (byte 1, G)" in \
        problems_of(C.check_tdata, 0x44330011, (0x11, 0x22, 0x33, 0x44))


def test_tdata_wrong_types_get_no_misleading_example():
    """A str answer got "(an int, e.g. 0x11223344)": the example was the big-endian wrong answer."""
    pixel = (0x11, 0x22, 0x33, 0x44)
    msg = problems_of(C.check_tdata, "0x44332211", pixel)
    assert "should be int, you gave str" in msg and "int(text, 16)" in msg
    assert "0x11223344" not in msg and "11223344" not in msg.replace("'0x44332211'", "")
    assert "0x11223344" not in problems_of(C.check_tdata, 1.5, pixel)
    assert "still None" in problems_of(C.check_tdata, None, pixel)


def test_markers():
    tuser = [i == 0 for i in range(6)]
    tlast = [i % 3 == 2 for i in range(6)]
    assert C.check_markers(tuser, tlast, 3, 2).ok
    every_row = [i % 3 == 0 for i in range(6)]
    assert "beat 3 (pixel x=0, y=1) has tuser=1; only the frame's first beat" in \
        problems_of(C.check_markers, every_row, tlast, 3, 2)
    at_start = [i % 3 == 0 for i in range(6)]
    msg = problems_of(C.check_markers, tuser, at_start, 3, 2)
    assert "beat 0 (pixel x=0, y=0) has tlast=1" in msg and "beat 2 (pixel x=2, y=0) has tlast=0" in msg
    assert "has 5 entries" in problems_of(C.check_markers, tuser[:5], tlast, 3, 2)


def good_fifo2axi(data, rows, cols, bpp):
    out, pos = [], 0
    for y in range(rows):
        for x in range(cols):
            word = int.from_bytes(data[pos:pos + bpp], "little")
            pos += bpp
            out.append((word, (1 << bpp) - 1, x == 0 and y == 0, x == cols - 1))
    return out


def test_fifo2axi():
    assert C.check_fifo2axi(good_fifo2axi).ok
    keep_all = lambda *a: [(d, 0b1111, u, la) for d, _k, u, la in good_fifo2axi(*a)]  # noqa: E731
    msg = problems_of(C.check_fifo2axi, keep_all)
    assert "on mono8 2x3, beat 0" in msg and "tkeep: one bit per byte lane used: 0b0001" in msg
    big_endian = lambda d, r, c, b: [(int.from_bytes(d[i * b:(i + 1) * b], "big"), (1 << b) - 1, i == 0,
                                      i % c == c - 1) for i in range(r * c)]  # noqa: E731
    assert "tdata: byte j of the pixel goes to bits 8j+7..8j" in problems_of(C.check_fifo2axi, big_endian)
    assert "raised ZeroDivisionError" in problems_of(C.check_fifo2axi, lambda *a: 1 / 0)
    assert "pass your function itself" in problems_of(C.check_fifo2axi, 42)


# ------------------------------------------------------------------------------ notebook 5
def good_dilate(image):
    out = np.zeros_like(image)
    rows, cols = image.shape[:2]
    for y in range(rows):
        for x in range(cols):
            out[y, x] = image[max(0, y - 1):y + 2, max(0, x - 1):x + 2].reshape(-1, image.shape[2]).max(axis=0)
    return out


def test_dilate():
    assert C.check_dilate(good_dilate).ok
    assert C.check_dilate(lambda im: cv2.dilate(im, np.ones((3, 3), np.uint8))).ok   # 2-D result reshaped

    def rolled(im):
        out = im.copy()
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                out = np.maximum(out, np.roll(np.roll(im, dy, 0), dx, 1))
        return out

    assert "all of them are on the border" in problems_of(C.check_dilate, rolled)

    def interior(im):
        return good_dilate(im)[1:-1, 1:-1]

    assert "dilate keeps the image size" in problems_of(C.check_dilate, interior)

    def anchored(im):   # window rows y..y+2, columns x..x+2 instead of centred
        pad = np.zeros((im.shape[0] + 2, im.shape[1] + 2, im.shape[2]), np.uint8)
        pad[:-2, :-2] = im
        out = np.zeros_like(im)
        for dy in range(3):
            for dx in range(3):
                out = np.maximum(out, pad[dy:dy + im.shape[0], dx:dx + im.shape[1]])
        return out

    assert "looks shifted" in problems_of(C.check_dilate, anchored)
    assert "keep uint8" in problems_of(C.check_dilate, lambda im: good_dilate(im).astype(np.int32))


def test_dilate_returning_none_says_so():
    """5.1 returning None said "your output has shape ()"."""
    def forgot_return(image):
        out = image.copy()  # noqa: F841 - the mistake: no return
    msg = problems_of(C.check_dilate, forgot_return)
    assert "returned None: did you forget 'return out'" in msg and "shape ()" not in msg
    assert "still None" in problems_of(C.check_dilate, None)


def test_frame_timing_frame_time_instead_of_the_filters_is_named_and_rounded():
    """5.2: the byte-wide stages' 12.28846 ms (the frame's time) in the filter's variable got
    "frame_ms is 12.288459999999999, expected 3.0832" and no hint."""
    msg = problems_of(C.check_frame_timing, 308_321, 1_228_846 / 100e6 * 1e3, "byte-wide stages")
    assert "filter_ms is 12.2885: that is about the byte-wide stages' time" in msg
    assert "12.288459999" not in msg
    msg = problems_of(C.check_frame_timing, 308_321, 1 / 3, "byte-wide stages")
    assert "filter_ms is 0.333333, expected 3.0832" in msg
    assert "still None" in problems_of(C.check_frame_timing, 308_321, None, "byte-wide stages")


def test_frame_timing():
    assert C.check_frame_timing(308_321, 3.08321, "byte-wide stages").ok
    assert C.check_frame_timing(308_321, 3.08321, "the walkers").ok     # notebook 5 names them
    assert C.check_frame_timing(308_321, 3.08321, "subscriber and publisher").ok
    assert "bottleneck 'dilate'" in problems_of(C.check_frame_timing, 308_321, 3.08321, "dilate")
    msg = problems_of(C.check_frame_timing, 307_200, 3.072, "filter")
    assert "one clock per pixel" in msg and "bottleneck 'filter'" in msg
    assert "counts bytes" in problems_of(C.check_frame_timing, 1_228_800, 12.288, "byte-wide stages")
    assert "in microseconds" in problems_of(C.check_frame_timing, 308_321, 3083.21, "byte-wide stages")
    assert "in seconds: multiply by 1000" in problems_of(C.check_frame_timing, 308_321, 0.00308321, "fifo")


# ------------------------------------------------------------------------------ notebook 6
GOOD_CONFIG = """\
node: {name: /fpga_erode}
subscriber: {topic: /camera/image_mono, type: sensor_msgs/Image}
publisher: {topic: /camera/image_eroded, type: sensor_msgs/Image}
image: {width: 320, height: 240, encoding: mono8}
application: {op: erode, ksize: 5}
"""


def test_node_config():
    assert C.check_node_config(GOOD_CONFIG).ok
    no_ksize = GOOD_CONFIG.replace(", ksize: 5", "")
    assert "application.ksize is 3, expected 5 (the default: the key ksize is missing from the text)" \
        in problems_of(C.check_node_config, no_ksize)
    # an explicit 3 is a wrong value, not a missing key
    explicit = problems_of(C.check_node_config, GOOD_CONFIG.replace("ksize: 5", "ksize: 3"))
    assert "application.ksize is 3, expected 5" in explicit and "missing" not in explicit
    swapped = GOOD_CONFIG.replace("width: 320, height: 240", "width: 240, height: 320")
    msg = problems_of(C.check_node_config, swapped)
    assert "image.width is 240, expected 320" in msg and "image.height is 320, expected 240" in msg
    assert "does not load: config_text:4" in problems_of(C.check_node_config, GOOD_CONFIG.replace("mono8", "gray"))


SNIPPET = """\
/* block
   comment */
#pragma HLS PIPELINE

int x = 1;  // trailing
// only a comment
"""


def test_sloc():
    assert C.check_sloc(2, SNIPPET).ok
    assert "that is every line" in problems_of(C.check_sloc, 6, SNIPPET)
    assert "still counts comment-only lines" in problems_of(C.check_sloc, 5, SNIPPET)
    assert "leaves out the #pragma HLS lines; they count" in problems_of(C.check_sloc, 1, SNIPPET)
    assert "too many: is a line inside a /* ... */ comment counted?" in problems_of(C.check_sloc, 3, SNIPPET)
    assert "too few: a line with code before a // comment counts" in problems_of(C.check_sloc, 0, SNIPPET)


def test_marshal_explains_a_shift_instead_of_listing_every_byte_after_it():
    four_byte_flag = (struct.pack("<III", 3, 10, 20) + pack_str("camera") + struct.pack("<II", 1, 2)
                      + pack_str("mono8") + struct.pack("<II", 0, 2) + pack_str(b"\x01\x02"))
    msg = problems_of(C.check_marshal, four_byte_flag, image_msg())
    assert "something before byte 40 is 3 byte(s) too long (the field before is is_bigendian, uint8: 1 byte)" in msg
    assert msg.count("\n  - ") == 2, "one finding and one explanation, not every later byte"
    assert "big-endian" not in msg
    pixels = bytes(range(1, 9))
    msg8 = {**image_msg(), "height": 2, "width": 4, "step": 4, "data": pixels}
    right = image_body(width=4, height=2, data=pixels)
    no_length = right[:-12] + pixels     # data without its uint32 length
    assert "field data length (uint32, 4 byte(s) at 44..47) is missing" in \
        problems_of(C.check_marshal, no_length, msg8)


def test_numpy_scalars_count_as_numbers_but_bools_do_not():
    assert C.check_tdata(np.uint32(0x04030201), (1, 2, 3, 4)).ok
    assert C.check_frame_timing(np.int64(308_321), np.float32(3.08321), "byte-wide stages").ok
    assert "should be int, you gave bool" in problems_of(C.check_data_offset, True, b"")


@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_a_corrupted_byte_is_named_by_the_field_that_holds_it(data):
    reg = default_registry()
    type_name = data.draw(st.sampled_from(["std_msgs/Header", "geometry_msgs/Pose", "sensor_msgs/Image"]))
    body = serialize(reg, type_name, data.draw(msg_st.message(reg, type_name, max_len=6)))
    i = data.draw(st.integers(0, len(body) - 1))
    bad = bytearray(body)
    bad[i] ^= data.draw(st.integers(1, 255))
    owner = next(s for s in field_layout(reg, type_name, body) if s.offset <= i < s.end)
    name = f"{owner.path} length" if owner.role == "length" else owner.path
    findings = C.describe_byte_difference(bytes(bad), body, C.message_fields(type_name, body))
    assert findings and findings[0].startswith(f"byte {i} (field {name}"), findings


NOTEBOOK_6_SNIPPET = """\
/* Copy one frame.
   Pixels arrive in raster order. */
#include "ros_node.h"

void copy(pixel_stream& in, pixel_stream& out) {
#pragma HLS INTERFACE axis port=in
    // one pixel per clock
    for (int i = 0; i < ROWS * COLS; i++) {
#pragma HLS PIPELINE II=1
        out << in.read();   // pass it on
    }
}
"""


def test_sloc_notebook_6_slips_get_their_own_diagnosis():
    # counted by hand: #include, void, #pragma, for, #pragma, out, }, } = 8
    assert C.check_sloc(8, NOTEBOOK_6_SNIPPET).ok
    no_pragmas = problems_of(C.check_sloc, 6, NOTEBOOK_6_SNIPPET)
    assert "leaves out the #pragma HLS lines; they count" in no_pragmas and no_pragmas.endswith(".")
    no_directives = problems_of(C.check_sloc, 5, NOTEBOOK_6_SNIPPET)
    assert "leaves out the preprocessor lines" in no_directives
    too_few = problems_of(C.check_sloc, 4, NOTEBOOK_6_SNIPPET)
    assert "comment counts. Count the lines" in too_few and too_few.endswith(".")


def test_marshal_native_alignment_is_named_not_big_endian():
    """Exercise 3.2 written with struct's native mode: '@BI' pads is_bigendian to 4 bytes."""
    msg = image_msg()
    body = (struct.pack("<III", 3, 10, 20) + pack_str("camera") + struct.pack("<II", 1, 2)
            + pack_str("mono8") + struct.pack("@BI", 0, 2) + pack_str(b"\x01\x02"))
    assert struct.calcsize("@BI") == 8  # the padding this test is about
    found = problems_of(C.check_marshal, body, msg)
    assert "big-endian" not in found
    assert "3 zero byte(s) follow is_bigendian" in found and "native mode" in found
    assert "start every format with '<'" in found
    # a real big-endian step is still called big-endian
    swapped = image_body()[:-10] + struct.pack(">I", 2) + pack_str(b"\x01\x02")
    assert "big-endian" in problems_of(C.check_marshal, swapped, msg)


def test_notebook_3_exercise_3_1_frame_is_not_the_printed_one():
    """03 printed ``data_offset=52`` (now "pixels from byte 52") for ``frame`` two cells above
    Exercise 3.1, so that number passed; the exercise asks about a frame nothing prints."""
    from pathlib import Path

    from rosfpga_lab import tcpros
    from rosfpga_lab.checks import nbbuild

    path = Path(__file__).resolve().parents[2] / "notebooks" / "solutions" / "03_message_conversion.ipynb"
    cells = nbbuild.load(path)["cells"]
    source = next(nbbuild.cell_source(c) for c in cells if "check_data_offset(" in nbbuild.cell_source(c))
    reg = default_registry()

    def image_frame(pixels, encoding, *, seq=0, frame_id=""):   # the notebook's, written again
        rows, cols = pixels.shape[:2]
        return tcpros.encode_frame(serialize(reg, "sensor_msgs/Image", {
            "header": {"seq": seq, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": frame_id},
            "height": rows, "width": cols, "encoding": encoding, "is_bigendian": 0,
            "step": pixels[0].size, "data": pixels.tobytes()}))

    scope = {"image_frame": image_frame, "np": np}
    exec(source.split(nbbuild.BEGIN)[0], scope)                   # the exercise's set-up lines
    printed_body = image_frame(np.zeros((3, 4, 4), np.uint8), "rgba8", frame_id="camera")[4:]
    data_at = next(s.offset for s in field_layout(reg, "sensor_msgs/Image", printed_body)
                   if s.path == "data")                             # its uint32 length first
    printed = 4 + data_at + 4                                       # what the notebook prints: 52
    assert "exercise_frame)" in source and printed == 52
    assert "not right yet" in problems_of(C.check_data_offset, printed, scope["exercise_frame"])
