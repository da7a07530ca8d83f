"""Captures in: the shipped capture of real rosmaster, rospy and roscpp, read by the lab."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.graph import GraphError
from rosfpga_lab.graph.capture import write_capture
from rosfpga_lab.graph.capture_read import tcp_streams, trace_from_capture
from rosfpga_lab.msg import default_registry, deserialize
from tests.support.wiretools import tshark_fields

CAPTURE = Path(__file__).resolve().parents[2] / "data" / "ros1_image.pcapng"
IMAGE_MD5 = "060021388200f6f0f447d0fcd9c64743"  # DESIGN.md; genpy's sensor_msgs/Image._md5sum
FRAMES = 4   # data/capture_ros1_image.py


def test_every_stream_is_complete() -> None:
    streams = tcp_streams(CAPTURE)
    assert len(streams) == 6
    assert all(s.complete[True] and s.complete[False] for s in streams)


def test_the_conversation_of_real_ros() -> None:
    tr = trace_from_capture(CAPTURE)
    conv = tr.conversation()
    calls = [(e.src, e.dst, e.method) for e in conv if e.kind == "xmlrpc"]
    assert ("/rospy_camera", "/master", "registerPublisher") in calls
    assert ("/roscpp_viewer", "/master", "registerSubscriber") in calls
    assert ("/master", "/roscpp_viewer", "publisherUpdate") in calls
    assert ("/roscpp_viewer", "/rospy_camera", "requestTopic") in calls
    headers = [e for e in conv if e.kind == "tcpros_header"]
    assert [(e.src, e.args["md5sum"]) for e in headers] == [
        ("/roscpp_viewer", IMAGE_MD5), ("/rospy_camera", IMAGE_MD5)]
    assert "message_definition" in headers[1].args   # rospy's reply carries the full text


def test_frames_decode_to_the_published_images() -> None:
    tr = trace_from_capture(CAPTURE)
    frames = [e for e in tr.conversation() if e.kind == "tcpros_frame"]
    assert len(frames) == FRAMES
    reg = default_registry()
    for k, e in enumerate(frames):
        assert e.size == len(e.raw)            # kept whole
        img = deserialize(reg, "sensor_msgs/Image", e.raw[4:])
        assert (img["width"], img["height"], img["encoding"]) == (64, 48, "rgb8")
        assert tuple(img["header"]["stamp"]) == (1_700_000_000 + k, 1000 * k)
        assert img["header"]["seq"] == k + 1    # rospy numbers the messages it publishes
        expected = (np.arange(64 * 48 * 3) * 3 + k * 40) % 256
        assert np.array_equal(img["data"], expected.astype(np.uint8))


def test_frame_lengths_agree_with_tshark() -> None:
    rows = tshark_fields(CAPTURE, ["tcpros.message.length"], display_filter="tcpros.message",
                         options=["-2", "--enable-heuristic", "tcpros_tcp"])
    ours = [e.size - 4 for e in trace_from_capture(CAPTURE).events if e.kind == "tcpros_frame"]
    assert [int(r[0]) for r in rows] == ours


def test_rewritten_capture_reads_back_the_same(tmp_path: Path) -> None:
    tr = trace_from_capture(CAPTURE)
    out = tmp_path / "again.pcapng"
    write_capture(out, tr)
    again = trace_from_capture(out)

    def view(t):  # what both captures must agree on
        return [(e.kind, e.src, e.dst, e.method, bytes(e.raw), bytes(e.raw_reply))
                for e in t.conversation() if e.kind in ("xmlrpc", "tcpros_header", "tcpros_frame")]
    assert view(again) == view(tr)
    assert tshark_fields(out, ["frame.number"], display_filter="tcp.analysis.flags") == []


def test_widgets_accept_the_capture() -> None:
    from rosfpga_lab import widgets as W

    diagram = W.SequenceDiagram(CAPTURE)
    assert {"/master", "/rospy_camera", "/roscpp_viewer"} <= set(diagram.participants)
    frame = next(e for e in diagram.events if e.kind == "tcpros_frame")
    assert frame.type_name == "sensor_msgs/Image"
    assert [s.path for s in frame.byte_spans()][:3] == ["frame length", "header.seq",
                                                        "header.stamp.secs"]


def test_not_a_capture_is_a_typed_error(tmp_path: Path) -> None:
    bad = tmp_path / "x.pcapng"
    bad.write_bytes(b"not a capture at all")
    with pytest.raises(GraphError, match="cannot read the capture"):
        trace_from_capture(bad)


def test_byte_viewer_accepts_the_capture() -> None:
    from rosfpga_lab import widgets as W

    viewer = W.capture_viewer(CAPTURE, 2, kind="tcpros_frame")
    span = viewer.select("width")
    assert (span.value, span.type) == (64, "uint32")
    assert viewer.select("header.seq").value == 3     # the third frame rospy sent
    header = W.capture_viewer(CAPTURE, 0, kind="tcpros_header")
    assert any("md5sum" in s.path for s in header.bytemap.spans)
    with pytest.raises(W.WidgetError, match="index 9"):
        W.capture_viewer(CAPTURE, 9, kind="tcpros_frame")
