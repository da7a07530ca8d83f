"""The lab's nodes and master against real ROS 1 Noetic (Debian's rosmaster, rospy, roscpp, rostopic).

Every case runs twice: with Debian's ``rosmaster`` and with the lab's embedded master. The
real programs are ``ros_programs/wire_rospy_node.py`` and ``wire_roscpp_node.cpp``; each
writes the bytes it sent or re-serialized on receipt to a file, and the tests compare every
byte with what the lab sent or received. Everything is bounded by time-outs and talks over
loopback only. Skipped with a reason without ROS; a failure under CI (ROSFPGA_REQUIRE_ROS=1).
"""

from __future__ import annotations

import struct
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import (
    ROS_PROGRAMS,
    ROS_PYTHON,
    build_roscpp_program,
    finish,
    real_rosmaster,
    require_ros,
    ros_env,
    stop_process,
    wait_line,
)
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.msg import Time, default_registry, deserialize, serialize
from rosfpga_lab.tcpros import decode_header

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.timeout(120)]

TYPES = {"String": "std_msgs/String", "Image": "sensor_msgs/Image", "Int32": "std_msgs/Int32"}
COUNT = {"String": 5, "Image": 3}
REG = default_registry()


@pytest.fixture(params=["rosmaster", "embedded"])
def master_uri(request, tmp_path):
    require_ros()
    if request.param == "rosmaster":
        with real_rosmaster(tmp_path) as uri:
            yield uri
    else:
        with EmbeddedMaster(port=0) as m:
            yield m.uri


@pytest.fixture
def lab_nodes():
    made: list[Node] = []

    def make(name: str, uri: str) -> Node:
        n = Node(name, master_uri=uri)
        made.append(n)
        return n

    yield make
    for n in made:
        n.shutdown()


@pytest.fixture
def programs(tmp_path):
    procs: list[subprocess.Popen] = []

    def start(client: str, mode: str, kind: str, topic: str, count: int, uri: str,
              timeout: float = 30.0) -> tuple[subprocess.Popen, Path]:
        out = tmp_path / f"{client}-{mode}-{len(procs)}.bin"
        if client == "rospy":
            cmd = [ROS_PYTHON, str(ROS_PROGRAMS / "wire_rospy_node.py")]
        else:
            cmd = [str(build_roscpp_program(ROS_PROGRAMS / "wire_roscpp_node.cpp"))]
        cmd += [mode, kind, topic, str(count), str(out), str(timeout)]
        proc = subprocess.Popen(cmd, env=ros_env(uri, tmp_path), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE)
        procs.append(proc)
        wait_line(proc, b"READY", 30)
        return proc, out

    yield start
    for p in procs:
        stop_process(p)
        for stream in (p.stdout, p.stderr):
            if stream:
                stream.close()


def records(path: Path) -> list[bytes]:
    data = path.read_bytes()
    out, pos = [], 0
    while pos < len(data):
        (n,) = struct.unpack_from("<I", data, pos)
        out.append(data[pos + 4:pos + 4 + n])
        pos += 4 + n
    return out


def wait_until(pred, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.02)
    return pred()


def lab_body(kind: str, k: int) -> bytes:
    if kind == "String":
        return serialize(REG, "std_msgs/String", {"data": f"lab {k} \u00e9"})
    rng = np.random.default_rng(k)
    return serialize(REG, "sensor_msgs/Image", {
        "header": {"seq": k, "stamp": Time(1700000000 + k, 123), "frame_id": "lab"},
        "height": 480, "width": 640, "encoding": "rgba8", "is_bigendian": 0, "step": 2560,
        "data": rng.integers(0, 256, 640 * 480 * 4, dtype=np.uint8)})


# ------------------------------------------------------------------------- data, both ways
@pytest.mark.parametrize("kind", ["String", "Image"])
@pytest.mark.parametrize("client", ["rospy", "roscpp"])
def test_lab_publisher_to_real_subscriber(master_uri, lab_nodes, programs, client, kind) -> None:
    node = lab_nodes("/lab_talker", master_uri)
    pub = node.advertise("/wire", TYPES[kind], queue_size=0)
    proc, out = programs(client, "sub", kind, "/wire", COUNT[kind], master_uri)
    assert pub.wait_for_subscribers(1, 20), "real subscriber never connected"
    sent = [lab_body(kind, k) for k in range(COUNT[kind])]
    for body in sent:
        pub.publish_body(body)
    finish(proc)
    assert records(out) == sent  # every byte, re-serialized by genpy / roscpp
    # the real subscriber's connection header, as the lab publisher saw it
    hdr = next(e for e in node.trace.events if e.kind == "tcpros_header" and e.role == "in")
    fields = decode_header(hdr.raw)[0]
    expected = {"callerid", "md5sum", "tcp_nodelay", "topic", "type"}
    if client == "rospy":
        expected.add("message_definition")  # rospy sends it, roscpp does not
    assert set(fields) == expected
    assert fields["md5sum"] == REG.md5(TYPES[kind]) and fields["callerid"] == f"/wire_{client}_sub"


@pytest.mark.parametrize("kind", ["String", "Image"])
@pytest.mark.parametrize("client", ["rospy", "roscpp"])
def test_real_publisher_to_lab_subscriber(master_uri, lab_nodes, programs, client, kind) -> None:
    node = lab_nodes("/lab_listener", master_uri)
    got: list[bytes] = []
    sub = node.subscribe("/wire", TYPES[kind], lambda body, info: got.append(bytes(body)),
                         raw=True, queue_size=0)
    proc, out = programs(client, "pub", kind, "/wire", COUNT[kind], master_uri)
    finish(proc)
    assert wait_until(lambda: len(got) >= COUNT[kind], 10), sub.stats
    assert got == records(out)  # every byte as the real publisher serialized it
    value = deserialize(REG, TYPES[kind], got[-1])
    if kind == "Image":
        assert (value["width"], value["height"], value["encoding"]) == (640, 480, "rgba8")
        k = COUNT[kind] - 1
        i = np.arange(640 * 480 * 4)
        assert np.array_equal(value["data"], ((i * 7 + k * 13) & 0xFF).astype(np.uint8))
    else:
        assert value == {"data": f"msg {COUNT[kind] - 1} \u00e9"}
    hdr = next(e for e in node.trace.events if e.kind == "tcpros_header" and e.role == "in")
    assert set(decode_header(hdr.raw)[0]) == {"callerid", "latching", "md5sum", "message_definition",
                                              "topic", "type"}


# ------------------------------------------------------------------------- faults
def test_publisher_killed_mid_stream_and_restarted(master_uri, lab_nodes, programs) -> None:
    node = lab_nodes("/lab_listener", master_uri)
    got: list[bytes] = []
    sub = node.subscribe("/wire", "std_msgs/String", lambda b, i: got.append(bytes(b)), raw=True,
                         queue_size=0)
    first, out1 = programs("rospy", "pub", "String", "/wire", 0, master_uri)
    assert wait_until(lambda: len(got) >= 3, 20), sub.stats
    first.kill()
    first.wait(10)
    assert wait_until(lambda: sub.get_num_connections() == 0, 10)
    n = len(got)
    assert got == records(out1)[:n]
    second, out2 = programs("rospy", "pub", "String", "/wire", 0, master_uri)
    assert wait_until(lambda: len(got) >= n + 3, 30), sub.stats
    stop_process(second)
    later = records(out2)
    assert got[n:] == later[:len(got) - n]
    assert deserialize(REG, "std_msgs/String", got[n]) == {"data": "msg 0 \u00e9"}


@pytest.mark.parametrize("client", ["rospy", "roscpp"])
def test_md5_mismatch_real_subscriber_is_refused(master_uri, lab_nodes, programs, client) -> None:
    node = lab_nodes("/lab_talker", master_uri)
    pub = node.advertise("/wire", "std_msgs/String")
    proc, out = programs(client, "sub", "Int32", "/wire", 1, master_uri, timeout=4)
    assert wait_until(lambda: any(e.kind == "tcpros_header" and e.result for e in node.trace.events), 15)
    pub.publish({"data": "not for you"})
    finish(proc)
    assert records(out) == []
    refusal = next(e for e in node.trace.events if e.kind == "tcpros_header" and e.result)
    assert decode_header(refusal.raw)[0] == {"error": (
        f"Client [/wire_{client}_sub] wants topic /wire to have datatype/md5sum "
        f"[std_msgs/Int32/{REG.md5('std_msgs/Int32')}], but our version has "
        f"[std_msgs/String/{REG.md5('std_msgs/String')}]. Dropping connection.")}
    assert pub.get_num_connections() == 0


@pytest.mark.parametrize("client,text", [
    ("rospy", "topic types do not match: [std_msgs/Int32] vs. [std_msgs/String]"),
    ("roscpp", "Client [/lab_listener] wants topic /wire to have datatype/md5sum [std_msgs/Int32/"
               "da5909fbe378aeaf85e547e830cc1bb7], but our version has [std_msgs/String/"
               "992ce8a1687cec8c8bd883ec73ca41d1]. Dropping connection."),
])
def test_md5_mismatch_seen_by_lab_subscriber(master_uri, lab_nodes, programs, client, text) -> None:
    node = lab_nodes("/lab_listener", master_uri)
    sub = node.subscribe("/wire", "std_msgs/Int32")
    proc, _ = programs(client, "pub", "String", "/wire", 1, master_uri, timeout=5)
    assert wait_until(lambda: sub.stats.errors, 15)
    assert f"publisher refused the connection: {text}" in sub.stats.errors[0]
    assert "not retrying" in sub.stats.errors[0]
    stop_process(proc)


# ------------------------------------------------------------------------- rostopic
def test_rostopic_against_embedded_master_and_lab_nodes(tmp_path, lab_nodes) -> None:
    require_ros()
    with EmbeddedMaster(port=0) as m:
        talker = lab_nodes("/lab_talker", m.uri)
        listener = lab_nodes("/lab_listener", m.uri)
        pub = talker.advertise("/chatter", "std_msgs/String")
        listener.subscribe("/chatter", "std_msgs/String")
        env = ros_env(m.uri, tmp_path)

        def rostopic(*args: str) -> str:
            proc = subprocess.run(["rostopic", *args], env=env, capture_output=True, timeout=30)
            assert proc.returncode == 0, proc.stderr.decode()
            return proc.stdout.decode()

        assert "/chatter" in rostopic("list").split()
        assert rostopic("type", "/chatter").strip() == "std_msgs/String"
        info = rostopic("info", "/chatter")
        assert "Type: std_msgs/String" in info
        assert f"* /lab_talker ({talker.uri})" in info
        assert f"* /lab_listener ({listener.uri})" in info
        stop = threading.Event()

        def keep_publishing() -> None:
            while not stop.wait(0.05):
                pub.publish({"data": "hello from the lab"})

        t = threading.Thread(target=keep_publishing, daemon=True)
        t.start()
        try:
            echo = rostopic("echo", "-n", "2", "/chatter")
        finally:
            stop.set()
            t.join(5)
        assert echo.count('data: "hello from the lab"') == 2 and echo.count("---") == 2


# ------------------------------------------------------------------------- the master, call by call
API = "http://127.0.0.1:9/"
MASTER_CALLS = [
    ("registerSubscriber", "/l", "/chatter", "std_msgs/String", API),
    ("registerPublisher", "/t", "/chatter", "std_msgs/String", API),
    ("registerPublisher", "/ns/t", "rel", "std_msgs/String", API),
    ("getSystemState", "/x"), ("getPublishedTopics", "/x", ""), ("getPublishedTopics", "/x", "/ns"),
    ("getTopicTypes", "/x"), ("lookupNode", "/x", "/t"), ("lookupNode", "/x", "/nobody"),
    ("unregisterPublisher", "/t", "/chatter", API), ("unregisterPublisher", "/t", "/chatter", API),
    ("unregisterPublisher", "/zz", "/chatter", API), ("unregisterSubscriber", "/l", "/chatter", API),
    ("lookupService", "/x", "/srv"), ("hasParam", "/x", "/p"), ("setParam", "/ns/n", "~p", 3),
    ("getParam", "/x", "/ns/n/p"), ("setParam", "/x", "/d", {"a": 1, "b": {"c": 2.5}}),
    ("getParam", "/x", "/d"), ("getParam", "/x", "/d/b"), ("searchParam", "/d/x/y", "b"),
    ("searchParam", "/x", "nope"), ("deleteParam", "/x", "/d/b"), ("deleteParam", "/x", "/d/b"),
    ("getParam", "/x", "/nope"), ("hasParam", "/x", "/d"), ("getParamNames", "/x"),
    ("subscribeParam", "/x", API, "/d"), ("unsubscribeParam", "/x", API, "/d"),
    ("unsubscribeParam", "/x", API, "/d"), ("getUri", "/x"),
    ("registerPublisher", "/t"), ("registerPublisher",), ("registerPublisher", 5, "/a", "std_msgs/String", API),
    ("registerPublisher", "/t", "/a", "String", API), ("registerPublisher", "/t", 3, "std_msgs/String", API),
    ("registerPublisher", "/t", "/a b", "std_msgs/String", API), ("registerPublisher", "/t", "/", "std_msgs/String", API),
    ("registerPublisher", "/t", "/a", "std_msgs/String", "bad"), ("setParam", "/x", "", 1),
    ("lookupNode", "/x", 1.5), ("getPublishedTopics", "/x", 3), ("getPid", 3), ("searchParam", "/x", 3),
    ("getTopicTypes", 3), ("getSystemState", 3), ("hasParam", "/x", ""), ("getParam", "/x", ""),
    ("lookupService", "/x", ""), ("subscribeParam", "/x", "nope", "/d"),
    ("unregisterSubscriber", "/l", "x y", API),
    # searchParam starts in the caller's own namespace; a '~' key or a relative caller is code 0
    ("setParam", "/x", "/a/b/node/q", 1), ("searchParam", "/a/b/node", "q"),
    ("searchParam", "/a/b/node", "q/z"), ("searchParam", "/a/b/other", "q"),
    ("setParam", "/x", "/top", 1), ("searchParam", "/a/b/node", "top/"),
    ("searchParam", "/a/b/node", "~q"), ("searchParam", "node", "top"), ("setParam", "/x", "/", 5),
    # a node that registers again from a new API (a restart) loses its old services too
    ("registerService", "/rs", "/rs/svc", "rosrpc://127.0.0.1:1", "http://127.0.0.1:2/"),
    ("registerPublisher", "/rs", "/rs/t", "std_msgs/String", "http://127.0.0.1:3/"),
    ("lookupService", "/x", "/rs/svc"), ("getSystemState", "/x"),
    ("unregisterService", "/rs", "/rs/svc", "rosrpc://127.0.0.1:1"),
]
ROSCORE_PARAMS = {"/run_id", "/rosdistro", "/rosversion"}  # set by roscore (roslaunch), not rosmaster --core


def master_replies(uri: str) -> list[str]:
    import xmlrpc.client

    proxy = xmlrpc.client.ServerProxy(uri)
    out = []
    for method, *args in MASTER_CALLS:
        reply = getattr(proxy, method)(*args)
        if method == "getParamNames":
            reply[2] = [n for n in reply[2] if n not in ROSCORE_PARAMS]
        out.append(repr(reply).replace(uri, "MASTER_URI"))
    return out


def test_master_api_replies_match_rosmaster(tmp_path) -> None:
    with real_rosmaster(tmp_path) as uri:
        real = master_replies(uri)
    with EmbeddedMaster(port=0) as m:
        lab = master_replies(m.uri)
    for call_, want, got in zip(MASTER_CALLS, real, lab):
        assert got == want, f"{call_}: rosmaster {want} vs lab {got}"
