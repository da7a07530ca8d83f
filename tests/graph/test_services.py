"""ROS 1 services in the lab (issue 23, item 6): the sans-IO codec, a node's service port and
client, the logger services and ``/rosout`` on every lab node; then Debian's ``rosservice``,
``rosout`` and a rospy client against lab nodes, on the lab master and on rosmaster.
"""

from __future__ import annotations

import logging
import os
import socket
import subprocess
import time
from pathlib import Path

import pytest

from tests.support.realros import ROS_PYTHON, real_rosmaster, require_ros, ros_env, run_ros_python
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.limits import MAX_SERVICE_CONNECTIONS
from rosfpga_lab.graph.service import ServiceError
from rosfpga_lab.msg.srv import service_registry, srv_spec
from rosfpga_lab.tcpros import FrameError, encode_header, decode_header
from rosfpga_lab.tcpros.service import (
    ServiceAccepted,
    ServiceClientConnection,
    ServiceRejected,
    ServiceRequest,
    ServiceResponse,
    ServiceServerConnection,
    ServiceSpec,
    encode_response,
)

# genpy's md5 sums (roscpp.srv, Debian's Noetic)
GOLDEN_SRV_MD5 = {"roscpp/GetLoggers": "32e97e85527d4678a8f9279894bb64b0",
                  "roscpp/SetLoggerLevel": "51da076440d78ca1684d36c868df61ea",
                  "roscpp/Empty": "d41d8cd98f00b204e9800998ecf8427e"}
SPEC = ServiceSpec("/n/svc", "roscpp/SetLoggerLevel", GOLDEN_SRV_MD5["roscpp/SetLoggerLevel"],
                   "roscpp/SetLoggerLevelRequest", "roscpp/SetLoggerLevelResponse")


def lookup(name: str) -> ServiceSpec | None:
    return SPEC if name == SPEC.service else None


def feed_bytewise(machine, data: bytes) -> list:
    out = []
    for i in range(len(data)):
        out += machine.receive_data(data[i:i + 1])
    return out


@pytest.mark.parametrize("name", sorted(GOLDEN_SRV_MD5))
def test_service_md5_is_genmsgs(name: str) -> None:
    assert srv_spec(name).md5sum == GOLDEN_SRV_MD5[name]


@pytest.mark.parametrize("bytewise", [False, True])
def test_server_codec_header_then_requests(bytewise: bool) -> None:
    client = ServiceClientConnection("/c", "/n/svc", SPEC.md5sum, persistent=True)
    stream = client.request_header + client.request(b"abc") + client.request(b"") + b"\x05\x00"
    server = ServiceServerConnection("/n", lookup)
    events = feed_bytewise(server, stream) if bytewise else server.receive_data(stream)
    accepted = [e for e in events if isinstance(e, ServiceAccepted)]
    assert len(accepted) == 1 and accepted[0].persistent and not accepted[0].probe
    assert decode_header(accepted[0].reply)[0] == {
        "callerid": "/n", "md5sum": SPEC.md5sum, "request_type": SPEC.request_type,
        "response_type": SPEC.response_type, "type": SPEC.type_name}
    assert [e.body for e in events if isinstance(e, ServiceRequest)] == [b"abc", b""]


def test_server_refuses_wrong_md5_unknown_service_and_answers_probes() -> None:
    bad = ServiceServerConnection("/n", lookup).receive_data(
        encode_header({"callerid": "/c", "md5sum": "0" * 32, "service": "/n/svc"}))
    assert isinstance(bad[-1], ServiceRejected) and "md5sums do not match" in bad[-1].error
    assert decode_header(bad[-1].reply)[0]["error"] == bad[-1].error
    none = ServiceServerConnection("/n", lookup).receive_data(
        encode_header({"callerid": "/c", "md5sum": "*", "service": "/other"}))
    assert isinstance(none[-1], ServiceRejected) and "/other" in none[-1].error
    probe = ServiceServerConnection("/n", lookup).receive_data(
        encode_header({"callerid": "/c", "md5sum": "*", "service": "/n/svc", "probe": "1"}))
    assert isinstance(probe[-1], ServiceAccepted) and probe[-1].probe
    # rospy's rules (test_service_server_header_rules_are_rospys checks them against rospy)
    kept = ServiceServerConnection("/n", lookup).receive_data(
        encode_header({"callerid": "/c", "md5sum": "*", "service": "/n/svc", "persistent": "True"}))
    assert isinstance(kept[-1], ServiceAccepted) and kept[-1].persistent
    anonymous = ServiceServerConnection("/n", lookup).receive_data(
        encode_header({"md5sum": "*", "service": "/n/svc"}))
    assert isinstance(anonymous[-1], ServiceRejected)
    assert anonymous[-1].error == "Missing required 'callerid' field"


def test_request_and_response_bodies_are_bounded() -> None:
    server = ServiceServerConnection("/n", lookup, max_frame=10)
    server.receive_data(encode_header({"callerid": "/c", "md5sum": "*", "service": "/n/svc"}))
    with pytest.raises(FrameError):
        server.receive_data((11).to_bytes(4, "little"))
    client = ServiceClientConnection("/c", "/n/svc", "*", max_frame=10)
    client.receive_data(encode_header({"callerid": "/n", "md5sum": SPEC.md5sum}))
    with pytest.raises(FrameError):
        client.receive_data(b"\x01" + (11).to_bytes(4, "little"))


@pytest.mark.parametrize("bytewise", [False, True])
def test_client_codec_reads_ok_and_error_responses(bytewise: bool) -> None:
    client = ServiceClientConnection("/c", "/n/svc", SPEC.md5sum)
    stream = (encode_header({"callerid": "/n", "md5sum": SPEC.md5sum}) + encode_response(True, b"xy")
              + encode_response(False, "boom"))
    events = feed_bytewise(client, stream) if bytewise else client.receive_data(stream)
    assert [(e.ok, e.body) for e in events if isinstance(e, ServiceResponse)] == [(True, b"xy"),
                                                                                   (False, b"boom")]
    refused = ServiceClientConnection("/c", "/n/svc", SPEC.md5sum)
    events = refused.receive_data(encode_header({"error": "no such service"}))
    assert isinstance(events[-1], ServiceRejected) and events[-1].error == "no such service"


# ---------------------------------------------------------------- lab nodes on sockets
@pytest.fixture
def master():
    with EmbeddedMaster(port=0) as m:
        yield m


def test_node_serves_and_calls_and_unregisters(master) -> None:
    with Node("/srv_a", master=master) as a, Node("/srv_b", master=master) as b:
        seen = []

        def handler(req: dict) -> dict:
            seen.append(req)
            if req["level"] == "boom":
                raise ValueError("boom asked")
            return {}

        name = a.advertise_service("~echo", "roscpp/SetLoggerLevel", handler)
        assert name == "/srv_a/echo"
        assert b.call_service("/srv_a/echo", "roscpp/SetLoggerLevel", {"logger": "x", "level": "y"}) == {}
        assert seen == [{"logger": "x", "level": "y"}]
        with pytest.raises(ServiceError, match="error processing request: boom asked"):
            b.call_service("/srv_a/echo", "roscpp/SetLoggerLevel", {"logger": "x", "level": "boom"})
        with pytest.raises(ServiceError, match="no provider"):
            b.call_service("/nobody", "roscpp/Empty")
        with pytest.raises(ServiceError, match="md5sums do not match"):
            b.call_service("/srv_a/echo", "roscpp/Empty")
    assert master.services == {} and master.nodes == {}


def test_every_node_has_logger_services_and_rosout(master) -> None:
    with Node("/log_a", master=master) as a, Node("/log_b", master=master) as b:
        a.advertise("/t", "std_msgs/String")
        assert a.logging_ready.wait(5)
        services = dict(master.getSystemState("/x")[2][2])
        assert services == {"/log_a/get_loggers": ["/log_a"], "/log_a/set_logger_level": ["/log_a"]}
        names = {lg["name"] for lg in b.call_service("/log_a/get_loggers", "roscpp/GetLoggers")["loggers"]}
        assert "rosfpga_lab" in names
        lab_logger = logging.getLogger("rosfpga_lab.test_services")
        before = lab_logger.level
        try:
            b.call_service("/log_a/set_logger_level", "roscpp/SetLoggerLevel",
                           {"logger": "rosfpga_lab.test_services", "level": "DEBUG"})
            assert lab_logger.level == logging.DEBUG
            with pytest.raises(ServiceError, match="level \\[loud\\]"):
                b.call_service("/log_a/set_logger_level", "roscpp/SetLoggerLevel",
                               {"logger": "rosfpga_lab", "level": "loud"})
            got: list[dict] = []
            b.subscribe("/rosout", "rosgraph_msgs/Log", got.append)
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and not any(g["msg"] == "to rosout" for g in got):
                lab_logger.warning("to rosout")
                time.sleep(0.1)
            mine = [g for g in got if g["name"] == "/log_a" and g["msg"] == "to rosout"]
            assert mine and mine[0]["level"] == 4 and mine[0]["topics"] == ["/t"]
        finally:
            lab_logger.setLevel(before)


def test_service_connections_are_bounded(master) -> None:
    with Node("/bounded", master=master) as a:
        a.advertise_service("~e", "roscpp/Empty", lambda req: {})
        port = a._service_port
        assert port is not None
        idle = [socket.create_connection(("127.0.0.1", port.port)) for _ in range(MAX_SERVICE_CONNECTIONS + 5)]
        try:
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and port.evicted < 5:
                time.sleep(0.05)
            assert port.evicted >= 5
            with Node("/caller", master=master) as b:
                assert b.call_service("/bounded/e", "roscpp/Empty") == {}
        finally:
            for s in idle:
                s.close()


# ---------------------------------------------------------------- real ROS tools
def _tool_env(uri: str, home: Path) -> dict[str, str]:
    env = ros_env(uri, home)
    env["PATH"] = f"{os.path.dirname(ROS_PYTHON)}:{env.get('PATH', '')}"
    return env


@pytest.fixture(params=["embedded", "rosmaster"])
def any_master_uri(request, tmp_path):
    if request.param == "rosmaster":
        with real_rosmaster(tmp_path) as uri:
            yield uri
    else:
        require_ros()
        with EmbeddedMaster(port=0) as m:
            yield m.uri


def test_rosservice_lists_and_calls_a_lab_node(any_master_uri, tmp_path: Path) -> None:
    env = _tool_env(any_master_uri, tmp_path)

    def rosservice(*args: str, rc: int = 0) -> str:
        proc = subprocess.run(["rosservice", *args], env=env, capture_output=True, text=True, timeout=30)
        assert proc.returncode == rc, proc.stdout + proc.stderr
        return proc.stdout + proc.stderr

    with Node("/lab_svc", any_master_uri) as node:
        node.advertise("/t", "std_msgs/String")
        assert node.logging_ready.wait(10)
        assert {"/lab_svc/get_loggers", "/lab_svc/set_logger_level"} <= set(rosservice("list").split())
        assert rosservice("type", "/lab_svc/get_loggers").strip() == "roscpp/GetLoggers"
        assert 'name: "rosfpga_lab"' in rosservice("call", "/lab_svc/get_loggers")
        lab_logger = logging.getLogger("rosfpga_lab.test_rosservice")
        rosservice("call", "/lab_svc/set_logger_level", "rosfpga_lab.test_rosservice", "error")
        assert lab_logger.level == logging.ERROR
        assert "does not exist" in rosservice("call", "/lab_svc/set_logger_level", "nope", "info", rc=2)
    assert "/lab_svc" not in rosservice("list")


def test_lab_client_calls_a_rospy_service(tmp_path: Path) -> None:
    with real_rosmaster(tmp_path) as uri:
        code = ("import rospy, sys\nrospy.init_node('py_srv')\nprint('READY', flush=True)\n"
                "rospy.sleep(20)\n")
        proc = subprocess.Popen([ROS_PYTHON, "-c", code], env=ros_env(uri, tmp_path),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            assert proc.stdout is not None and proc.stdout.readline().strip() == b"READY"
            with Node("/lab_client", uri) as node:
                deadline = time.monotonic() + 20
                while True:
                    try:
                        reply = node.call_service("/py_srv/get_loggers", "roscpp/GetLoggers")
                        break
                    except ServiceError:
                        if time.monotonic() > deadline:
                            raise
                        time.sleep(0.2)
                assert {lg["name"] for lg in reply["loggers"]} >= {"rospy"}
        finally:
            proc.kill()
            proc.wait()


def test_rosout_agg_shows_lab_messages(any_master_uri, tmp_path: Path) -> None:
    require_ros()
    rosout = "/usr/lib/rosout/rosout"
    if not os.path.exists(rosout):
        pytest.fail("Debian's rosout is not installed (.ci/run installs the 'rosout' package)")
    env = _tool_env(any_master_uri, tmp_path)
    agg = subprocess.Popen([rosout], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        with Node("/lab_talker", any_master_uri) as node, Node("/lab_watch", any_master_uri) as watch:
            node.advertise("/t", "std_msgs/String")
            got: list[dict] = []
            watch.subscribe("/rosout_agg", "rosgraph_msgs/Log", got.append)
            deadline = time.monotonic() + 20
            def arrived() -> bool:  # (other lab records may come too: this process's loggers)
                return any(g["name"] == "/lab_talker" and g["msg"] == "via rosout_agg" for g in got)

            while time.monotonic() < deadline and not arrived():
                logging.getLogger("rosfpga_lab.test_agg").warning("via rosout_agg")
                time.sleep(0.2)
            assert arrived(), got[:3]
    finally:
        agg.terminate()
        agg.wait(10)


__all__ = ["run_ros_python", "service_registry"]


def test_the_component_answers_rosservice_and_reaches_rosout_agg(tmp_path: Path) -> None:
    """The FPGA component is a lab node like the others: ``rosservice call /<component>/get_loggers``
    answers, and its logger's records reach ``/rosout_agg`` through Debian's rosout."""
    require_ros()
    from rosfpga_lab.component import FpgaComponent

    config = Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml"
    with EmbeddedMaster(port=0) as m:
        env = _tool_env(m.uri, tmp_path)
        comp = FpgaComponent.from_config(config, master=m).start()
        agg = subprocess.Popen(["/usr/lib/rosout/rosout"], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
        try:
            name = comp.name
            assert comp.node is not None and comp.node.logging_ready.wait(10)
            out = subprocess.run(["rosservice", "call", f"{name}/get_loggers"], env=env,
                                 capture_output=True, text=True, timeout=30)
            assert out.returncode == 0 and 'name: "rosfpga_lab"' in out.stdout, out.stderr
            with Node("/agg_watch", m.uri) as watch:
                got: list[dict] = []
                watch.subscribe("/rosout_agg", "rosgraph_msgs/Log", got.append)
                deadline = time.monotonic() + 20
                while time.monotonic() < deadline and not any(g["name"] == name for g in got):
                    logging.getLogger("rosfpga_lab.component").warning("component says hi")
                    time.sleep(0.2)
                assert any(g["name"] == name and g["msg"] == "component says hi" for g in got)
        finally:
            agg.terminate()
            agg.wait(10)
            comp.stop()


def test_random_bytes_only_raise_protocol_errors() -> None:
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from rosfpga_lab.tcpros import ProtocolError

    @settings(max_examples=200, deadline=None)
    @given(st.binary(max_size=300), st.booleans())
    def run(data: bytes, server_side: bool) -> None:
        machine = (ServiceServerConnection("/n", lookup, max_frame=1000, max_header=200) if server_side
                   else ServiceClientConnection("/c", "/n/svc", "*", max_frame=1000, max_header=200))
        try:
            machine.receive_data(data)
            machine.receive_eof()
        except ProtocolError:
            pass

    run()


def test_a_publisher_update_during_subscribe_is_kept(master, monkeypatch) -> None:
    """The first subscription also registers /rosout and the logger services; a publisherUpdate
    that arrives meanwhile brings a newer list than registerSubscriber's: it is kept."""
    with Node("/late_pub", master=master) as pub_node, Node("/early_sub", master=master) as sub_node:
        original = sub_node._start_logging

        def publisher_appears() -> None:
            pub_node.advertise("/race", "std_msgs/String")   # the master's update comes now
            deadline = time.monotonic() + 5
            while time.monotonic() < deadline and not sub_node._updates.get("/race"):
                time.sleep(0.01)
            original()

        monkeypatch.setattr(sub_node, "_start_logging", publisher_appears)
        sub = sub_node.subscribe("/race", "std_msgs/String")
        assert [uri for uri, _ in sub.publisher_links()] == [pub_node.uri]


# ---------------------------------------------------------------- the server's header rules, against rospy
def _recv_exact(sock: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            return data
        data += chunk
    return data


def _read_reply_header(sock: socket.socket) -> dict[str, str]:
    size = _recv_exact(sock, 4)
    body = _recv_exact(sock, int.from_bytes(size, "little")) if len(size) == 4 else b""
    return decode_header(size + body)[0] if body else {}


def server_header_story(rosrpc: str, service: str) -> list:
    """What a service server does with ``persistent=true`` (two calls on one connection) and
    with headers missing a required field (its refusal text, or '' when it accepts)."""
    host, port = rosrpc.removeprefix("rosrpc://").rstrip("/").rsplit(":", 1)
    md5 = GOLDEN_SRV_MD5["roscpp/GetLoggers"]
    out: list = []
    with socket.create_connection((host, int(port)), timeout=5) as sock:
        sock.sendall(encode_header({"callerid": "/story", "md5sum": md5, "service": service,
                                    "persistent": "true"}))
        out.append("error" in _read_reply_header(sock))
        for _ in range(2):
            try:
                sock.sendall((0).to_bytes(4, "little"))  # GetLoggers' request is empty
                ok_and_size = _recv_exact(sock, 5)
            except OSError:
                ok_and_size = b""
            out.append(ok_and_size[:1])
            if len(ok_and_size) == 5:
                _recv_exact(sock, int.from_bytes(ok_and_size[1:], "little"))
    full = {"callerid": "/story", "md5sum": md5, "service": service}
    for missing in ("md5sum", "callerid"):
        with socket.create_connection((host, int(port)), timeout=5) as sock:
            sock.sendall(encode_header({k: v for k, v in full.items() if k != missing}))
            out.append(_read_reply_header(sock).get("error", ""))
    return out


def test_service_server_header_rules_are_rospys(tmp_path: Path) -> None:
    """``persistent=true`` keeps the connection (rospy: ``'1'``/``'true'``; before, the lab
    closed after one call) and a header without md5sum or callerid is refused with rospy's text
    (before, a missing callerid was accepted and a missing md5sum called a mismatch)."""
    want = [False, b"\x01", b"\x01", "Missing required 'md5sum' field",
            "Missing required 'callerid' field"]
    with real_rosmaster(tmp_path) as uri:
        code = ("import rospy\nrospy.init_node('py_srv')\nprint('READY', flush=True)\n"
                "rospy.sleep(20)\n")
        proc = subprocess.Popen([ROS_PYTHON, "-c", code], env=ros_env(uri, tmp_path),
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        try:
            assert proc.stdout is not None and proc.stdout.readline().strip() == b"READY"
            import xmlrpc.client
            master = xmlrpc.client.ServerProxy(uri)
            deadline = time.monotonic() + 20
            while (found := master.lookupService("/t", "/py_srv/get_loggers"))[0] != 1:
                assert time.monotonic() < deadline, found
                time.sleep(0.1)
            assert server_header_story(found[2], "/py_srv/get_loggers") == want
        finally:
            proc.kill()
            proc.wait()
        with Node("/lab_srv", uri) as node:
            node.advertise("/t", "std_msgs/String")  # a node serves its logger services once it has a topic
            assert node.logging_ready.wait(5)
            found = xmlrpc.client.ServerProxy(uri).lookupService("/t", "/lab_srv/get_loggers")
            assert found[0] == 1, found
            assert server_header_story(found[2], "/lab_srv/get_loggers") == want
