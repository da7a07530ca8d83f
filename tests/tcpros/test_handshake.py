"""The handshake machines: the table drives them; they check what rospy/roscpp check."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.errors import LabError
from rosfpga_lab.tcpros import (
    STATES,
    TRANSITIONS,
    Closed,
    Connected,
    Frame,
    HandshakeRejected,
    HandshakeTimeout,
    HeaderFormatError,
    HeaderReceived,
    IncompleteError,
    PublisherHandshake,
    Rejected,
    RemoteError,
    StateError,
    SubscriberHandshake,
    TopicSpec,
    decode_header,
    encode_frame,
    encode_header,
)

MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"
SPEC = TopicSpec("/chatter", "std_msgs/String", MD5, "string data\n", latching=False)
BODY = bytes.fromhex("0c00000068656c6c6f2077c3b6726c64")


def lookup(topic: str) -> TopicSpec | None:
    return SPEC if topic == "/chatter" else None


def sub(**kw) -> SubscriberHandshake:
    args = dict(callerid="/listener", topic="/chatter", md5sum=MD5, type_name="std_msgs/String")
    args.update(kw)
    return SubscriberHandshake(**args)


def pub() -> PublisherHandshake:
    return PublisherHandshake(callerid="/talker", lookup=lookup, peer="127.0.0.1:5")


def test_table_is_consistent() -> None:
    for t in TRANSITIONS:
        assert t.source in STATES[t.role] and t.target in STATES[t.role]
    keys = [(t.role, t.source, t.trigger) for t in TRANSITIONS]
    assert len(keys) == len(set(keys)), "the table must be deterministic"


def test_roscpp_style_subscriber_header_fields() -> None:
    s = sub(tcp_nodelay=True)
    fields = decode_header(s.initiate())[0]
    # roscpp's TransportPublisherLink::initialize sends exactly these five
    assert fields == {"callerid": "/listener", "md5sum": MD5, "tcp_nodelay": "1",
                      "topic": "/chatter", "type": "std_msgs/String"}
    assert s.state == "AWAIT_HEADER"


def test_happy_path_both_roles_byte_by_byte() -> None:
    s, p = sub(message_definition="string data\n"), pub()
    request = s.initiate()
    events = []
    for b in request:
        events += p.receive_data(bytes([b]))
    assert isinstance(events[0], HeaderReceived) and isinstance(events[1], Connected)
    reply = events[1].reply
    assert p.state == "STREAMING"
    assert decode_header(reply)[0] == {
        "callerid": "/talker", "latching": "0", "md5sum": MD5,
        "message_definition": "string data\n", "topic": "/chatter", "type": "std_msgs/String"}
    wire = reply + p.send(BODY) + p.send(b"")
    got = []
    for b in wire:
        got += s.receive_data(bytes([b]))
    kinds = [type(e) for e in got]
    assert kinds == [HeaderReceived, Connected, Frame, Frame]
    assert [bytes(e.body) for e in got if isinstance(e, Frame)] == [BODY, b""]
    assert [e.offset for e in got if isinstance(e, Frame)] == [len(reply), len(reply) + 20]
    assert s.receive_eof() == [Closed(2)]
    assert s.state == "CLOSED"
    assert [t.trigger for t in s.history] == ["connect", "header_ok", "frame", "frame", "eof"]


def test_header_and_frames_in_one_chunk() -> None:
    s = sub()
    s.initiate()
    reply = encode_header(PublisherHandshake(callerid="/t", lookup=lookup).reply_fields(SPEC))
    events = s.receive_data(reply + encode_frame(BODY) + encode_frame(BODY) + b"\x01")
    assert [type(e) for e in events] == [HeaderReceived, Connected, Frame, Frame]
    with pytest.raises(IncompleteError, match="length prefix"):
        s.receive_eof()


def test_latching_and_wildcard() -> None:
    p = PublisherHandshake(callerid="/t", lookup=lambda t: TopicSpec(t, "std_msgs/String", MD5, "", True))
    ev = p.receive_data(encode_header({"callerid": "/echo", "md5sum": "*", "topic": "/x", "type": "*"}))
    assert isinstance(ev[-1], Connected) and ev[-1].latching
    s = sub(md5sum="*", type_name="*")
    s.initiate()
    ev = s.receive_data(ev[-1].reply)
    assert isinstance(ev[-1], Connected) and ev[-1].latching


# Publisher side: each bad request gets an error= header with roscpp's text, machine REJECTED.
REJECTS = [
    ("missing topic", {"callerid": "/l", "md5sum": MD5, "type": "std_msgs/String"},
     "Header from subscriber did not have the required element: topic"),
    ("missing md5sum", {"callerid": "/l", "topic": "/chatter", "type": "std_msgs/String"},
     "Header from subscriber did not have the required elements: md5sum, topic, callerid"),
    ("missing callerid", {"md5sum": MD5, "topic": "/chatter", "type": "std_msgs/String"},
     "Header from subscriber did not have the required elements: md5sum, topic, callerid"),
    ("unknown topic", {"callerid": "/l", "md5sum": MD5, "topic": "/nope", "type": "std_msgs/String"},
     "received a connection for a nonexistent topic [/nope] from [127.0.0.1:5] [/l]."),
    ("md5 mismatch", {"callerid": "/l", "md5sum": "da5909fbe378aeaf85e547e830cc1bb7", "topic": "/chatter",
                      "type": "std_msgs/Int32"},
     "Client [/l] wants topic /chatter to have datatype/md5sum [std_msgs/Int32/da5909fbe378aeaf85e547e830cc1bb7], "
     "but our version has [std_msgs/String/992ce8a1687cec8c8bd883ec73ca41d1]. Dropping connection."),
]


@pytest.mark.parametrize("name,fields,text", REJECTS, ids=[r[0] for r in REJECTS])
def test_publisher_rejects_with_error_header(name: str, fields: dict, text: str) -> None:
    p = pub()
    events = p.receive_data(encode_header(fields))
    assert isinstance(events[-1], Rejected)
    assert isinstance(events[-1].error, HandshakeRejected)
    assert decode_header(events[-1].reply)[0] == {"error": text}
    assert p.state == "REJECTED"
    with pytest.raises(StateError):
        p.send(BODY)


@pytest.mark.parametrize("data", [
    b"\x08\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00",       # zero-length field
    b"\x0c\x00\x00\x00\x08\x00\x00\x00callerid",              # no '='
    b"\x0c\x00\x00\x00\x08\x00\x00\x00topic=\xff\xfe",        # not UTF-8
    b"\xff\xff\xff\x7f",                                      # length over the cap
])
def test_publisher_rejects_malformed(data: bytes) -> None:
    p = pub()
    (event,) = p.receive_data(data)
    assert isinstance(event, Rejected) and isinstance(event.error, HeaderFormatError)
    assert "error" in decode_header(event.reply)[0]


def test_publisher_timeout_and_eof() -> None:
    p = pub()
    p.receive_data(b"\x10\x00")
    (event,) = p.timeout()
    assert isinstance(event.error, HandshakeTimeout) and p.state == "REJECTED"
    p2 = pub()
    assert p2.receive_eof() == [Closed(0)] and p2.state == "CLOSED"


def test_subscriber_reports_remote_error() -> None:
    s = sub()
    s.initiate()
    with pytest.raises(RemoteError, match="publisher refused the connection: Client") as info:
        s.receive_data(encode_header({"error": "Client [/l] wants topic ... Dropping connection."}))
    assert info.value.local is False
    assert s.state == "FAILED"


@pytest.mark.parametrize("missing", ["md5sum", "type"])
def test_subscriber_requires_fields(missing: str) -> None:
    s = sub()
    s.initiate()
    fields = {"callerid": "/t", "md5sum": MD5, "type": "std_msgs/String", "topic": "/chatter"}
    del fields[missing]
    with pytest.raises(HandshakeRejected, match=f"required element: {missing}"):
        s.receive_data(encode_header(fields))


def test_subscriber_md5_mismatch() -> None:
    s = sub()
    s.initiate()
    with pytest.raises(HandshakeRejected, match="does not match ours"):
        s.receive_data(encode_header({"md5sum": "0" * 32, "type": "std_msgs/Int32"}))
    assert s.state == "FAILED"


def test_subscriber_eof_and_timeout() -> None:
    s = sub()
    s.initiate()
    s.receive_data(b"\x20\x00\x00\x00abc")
    with pytest.raises(IncompleteError):
        s.receive_eof()
    s2 = sub()
    s2.initiate()
    with pytest.raises(HandshakeTimeout):
        s2.timeout()
    assert s2.state == "FAILED"


def test_state_errors() -> None:
    s = sub()
    with pytest.raises(StateError, match="in state IDLE"):
        s.receive_data(b"x")
    s.initiate()
    with pytest.raises(StateError):
        s.initiate()


@settings(max_examples=150, deadline=None)
@given(data=st.binary(max_size=300), chunk=st.integers(1, 64))
def test_fuzz_machines_only_lab_errors(data: bytes, chunk: int) -> None:
    s, p = sub(), pub()
    s.initiate()
    for i in range(0, len(data), chunk):
        piece = data[i:i + chunk]
        p.receive_data(piece)  # never raises: rejections are events
        try:
            s.receive_data(piece)
        except LabError:
            break
    try:
        s.receive_eof()
    except LabError:
        pass
    p.receive_eof()


def test_frames_before_bad_length_are_delivered_as_partial_events() -> None:
    from rosfpga_lab.tcpros import FrameError

    s = SubscriberHandshake(callerid="/l", topic="/chatter", md5sum=MD5, type_name="std_msgs/String",
                            max_frame=100)
    s.initiate()
    reply = encode_header(PublisherHandshake(callerid="/t", lookup=lookup).reply_fields(SPEC))
    with pytest.raises(FrameError) as info:
        s.receive_data(reply + encode_frame(BODY) + b"\xff\xff\xff\xff")
    kinds = [type(e) for e in info.value.partial]
    assert kinds == [HeaderReceived, Connected, Frame]
    assert bytes(info.value.partial[-1].body) == BODY
    assert s.state == "FAILED" and [t.trigger for t in s.history][-2:] == ["frame", "frame_bad"]


def test_subscriber_receives_a_body_in_place() -> None:
    s = sub()
    assert s.body_buffer() is None  # not connected yet
    s.initiate()
    with pytest.raises(StateError, match="AWAIT_HEADER"):
        s.receive_into(1)
    reply = encode_header(PublisherHandshake(callerid="/t", lookup=lookup).reply_fields(SPEC))
    big = bytes(range(256)) * 10
    wire = encode_frame(big)
    events = s.receive_data(reply + wire[:100])
    assert [type(e) for e in events] == [HeaderReceived, Connected]
    view = s.body_buffer()
    assert len(view) == len(big) - 96
    view[:1000] = wire[100:1100]
    assert s.receive_into(1000) == []
    view = s.body_buffer()
    view[:] = wire[1100:]
    (frame,) = s.receive_into(len(view))
    assert bytes(frame.body) == big and frame.index == 0 and frame.offset == len(reply)
    assert s.body_buffer() is None  # between frames: back to receive_data
    (second,) = s.receive_data(encode_frame(BODY))
    assert bytes(second.body) == BODY and second.index == 1 and second.offset == len(reply) + len(wire)
    assert [t.trigger for t in s.history] == ["connect", "header_ok", "frame", "frame"]


def test_history_stays_short_over_a_long_stream() -> None:
    """A million frames leave a handshake history of a few entries (repeats are counted)."""
    s, p = sub(), pub()
    p.receive_data(s.initiate())
    reply = p.reply_fields(p.spec)
    from rosfpga_lab.tcpros import encode_header, encode_frame

    s.receive_data(encode_header(reply))
    chunk = encode_frame(BODY) * 1000
    for _ in range(1000):
        assert len(s.receive_data(chunk)) == 1000
        p.send(BODY)
    assert len(s.history) <= 8 and len(p.history) <= 8
    assert s.repeats["frame"] == 1_000_000 - 3 and p.repeats["send"] == 1000 - 3
    assert [t.trigger for t in s.history] == ["connect", "header_ok", "frame", "frame", "frame"]


def test_one_builder_per_header_field_set() -> None:
    """The request and reply field sets are built once (tcpros) and used by graph and hls."""
    from pathlib import Path

    from rosfpga_lab.config import load_config
    from rosfpga_lab.hls import publisher_header_fields, subscriber_header_fields
    from rosfpga_lab.msg import default_registry
    from rosfpga_lab.tcpros import publisher_reply_fields, subscriber_request_fields

    reg = default_registry()
    config = load_config(Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml")
    t = "sensor_msgs/Image"
    assert list(subscriber_header_fields(config)) == [
        "callerid", "md5sum", "message_definition", "tcp_nodelay", "topic", "type"]
    assert subscriber_header_fields(config)["md5sum"] == "060021388200f6f0f447d0fcd9c64743"
    assert publisher_header_fields(config) == {
        "callerid": config.node.global_name, "latching": "0", "md5sum": reg.md5(t),
        "message_definition": reg.full_text(t), "topic": config.publisher.topic, "type": t}
    sub = SubscriberHandshake(callerid="/s", topic="/x", md5sum="*", type_name="*", tcp_nodelay=True)
    assert sub.fields == subscriber_request_fields(callerid="/s", topic="/x", md5sum="*",
                                                   type_name="*", tcp_nodelay=True)
    assert "message_definition" not in sub.fields and sub.fields["tcp_nodelay"] == "1"
    pub = PublisherHandshake(callerid="/t", lookup=lambda _t: SPEC)
    assert pub.reply_fields(SPEC) == publisher_reply_fields("/t", SPEC)
