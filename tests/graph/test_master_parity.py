"""The lab master against rosmaster 1.15 (issue 23, items 1 and 2): ``system.multicall``, what
roslaunch and rospy need of it, ``getParamNames``, ``paramUpdate``, ``/rosversion`` and the
texts of ``unregisterService``.

Pinned replies were taken from Debian's rosmaster 1.15.15 (``rosmaster --core``); the ``real``
tests ask a live rosmaster the same questions and compare, so a pin that goes stale shows.
"""

from __future__ import annotations

import os
import subprocess
import threading
import time
import xmlrpc.client
from pathlib import Path
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from tests.support.realros import ROS_PYTHON, real_rosmaster, require_ros, ros_env
from rosfpga_lab.graph import EmbeddedMaster
from rosfpga_lab.graph.limits import MAX_XMLRPC_MULTICALL
from rosfpga_lab.graph.master import ROS_COMM_VERSION

MULTICALL = [
    {"methodName": "getParam", "params": ["/r", "/nothing_here"]},
    {"methodName": "nope", "params": []},
    {"methodName": "getUri", "params": []},
    {"methodName": "getUri", "params": ["/a", 1, 2]},
    {"methodName": "setParam", "params": ["/r", "/mc", 7]},
    {"methodName": "getParam", "params": ["/r", "/mc"]},
]
#: rosmaster 1.15.15's answer to MULTICALL
MULTICALL_REPLY = [
    [[-1, "Parameter [/nothing_here] is not set", 0]],
    {"faultCode": 1, "faultString": "<class 'Exception'>:method \"nope\" is not supported"},
    [[-1, "missing required caller_id parameter", ""]],
    [[-1, "Error: bad call arity", ""]],
    [[1, "parameter /mc set", 0]],
    [[1, "Parameter [/mc]", 7]],
]
#: malformed multicalls: the whole call is a fault, with Python's dispatcher's text
BAD_MULTICALLS = [
    (3, "<class 'TypeError'>:object of type 'int' has no len()"),
    ([{"methodName": "getUri"}], "<class 'KeyError'>:'params'"),
    ([{"params": []}], "<class 'KeyError'>:'methodName'"),
]


def params_calls(proxy: xmlrpc.client.ServerProxy) -> list:
    """getParamNames with empty dicts, and unregisterService's texts."""
    proxy.setParam("/x", "/a/b", {})
    proxy.setParam("/x", "/c", {"d": {}, "e": 1})
    names = sorted(n for n in proxy.getParamNames("/x")[2] if n in ("/a", "/a/b", "/c", "/c/d", "/c/e"))
    out: list = [names]
    out.append(proxy.unregisterService("/x", "/nosvc", "rosrpc://a:1"))
    proxy.registerService("/n", "/svc", "rosrpc://a:1", "http://a:2/")
    out.append(proxy.unregisterService("/x", "/svc", "rosrpc://a:1"))
    out.append(proxy.unregisterService("/n", "/svc", "rosrpc://a:3"))
    out.append(proxy.unregisterService("/n", "/other", "rosrpc://a:1"))
    out.append(proxy.unregisterService("/n", "/svc", "rosrpc://a:1"))
    out.append(proxy.lookupService("/n", "/svc"))
    return out


PARAMS_REPLY = [  # rosmaster 1.15.15
    ["/c/e"],
    [1, "[/x] is not a registered node", 0],
    [1, "[/x] is not a registered node", 0],
    [1, "[rosrpc://a:3] is no longer the current service api handle for [/svc]", 0],
    [1, "[rosrpc://a:1] is no longer the current service api handle for [/other]", 0],
    [1, "Unregistered [/n] as provider of [/svc]", 1],
    [-1, "no provider", ""],
]


class ParamListener:
    """A fake node's slave API that records every paramUpdate it gets."""

    def __init__(self) -> None:
        self.updates: list[tuple[str, object]] = []
        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=False)
        self.server.register_function(self.paramUpdate, "paramUpdate")
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def paramUpdate(self, caller_id: str, key: str, value: object) -> list:
        self.updates.append((key, value))
        return [1, "", 0]

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


def wait_counts(listeners, want: list[int], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and [len(lst.updates) for lst in listeners] != want:
        time.sleep(0.02)


def param_update_story(uri: str) -> list[list[tuple[str, object]]]:
    """Subscribe fake nodes to keys, change the tree, return what each was told (in order)."""
    proxy = xmlrpc.client.ServerProxy(uri)
    subs = {"/p/": None, "/p/q": None, "/p/q/r": None, "/gone": None}
    listeners = {k: ParamListener() for k in subs}
    try:
        for i, (key, lst) in enumerate(listeners.items()):
            proxy.subscribeParam(f"/sub{i}", lst.uri, key)
        # one step at a time: the lab coalesces waiting updates of one key, rosmaster sends
        # values it still holds (a later change inside them shows in an earlier update)
        steps = [
            (("/setter", "/p/q/r", 1), [1, 1, 1, 0]),                    # below every /p subscriber
            (("/setter", "/p", {"q": {"s": 2}, "t": 3}), [2, 2, 2, 0]),  # a dict above them
            (("/setter", "/gone", 5), [2, 2, 2, 1]),
            (None, [2, 2, 2, 2]),                                        # delete /gone
            (("/sub1", "/p/q", 9), [3, 2, 2, 2]),  # the setter is not told its own change
        ]
        for args, counts in steps:
            if args is None:
                proxy.deleteParam("/setter", "/gone")
            else:
                proxy.setParam(*args)
            wait_counts(listeners.values(), counts)
        return [sorted(lst.updates, key=repr) for lst in listeners.values()]
    finally:
        for lst in listeners.values():
            lst.close()


PARAM_UPDATES = [  # rosmaster 1.15.15's paramUpdate calls to subscribers of /p/, /p/q, /p/q/r, /gone
    sorted([("/p/q/r/", 1), ("/p/", {"q": {"s": 2}, "t": 3}), ("/p/q/", 9)], key=repr),
    sorted([("/p/q/r/", 1), ("/p/q/", {"s": 2})], key=repr),
    sorted([("/p/q/r/", 1), ("/p/q/r/", {})], key=repr),
    sorted([("/gone/", 5), ("/gone/", {})], key=repr),
]


@pytest.fixture
def lab_master():
    with EmbeddedMaster(port=0) as m:
        yield m


def test_multicall_answers_each_call_like_rosmaster(lab_master) -> None:
    proxy = xmlrpc.client.ServerProxy(lab_master.uri)
    assert proxy.system.multicall(MULTICALL) == MULTICALL_REPLY


@pytest.mark.parametrize("arg, text", BAD_MULTICALLS)
def test_a_malformed_multicall_is_one_fault(lab_master, arg, text) -> None:
    with pytest.raises(xmlrpc.client.Fault) as info:
        xmlrpc.client.ServerProxy(lab_master.uri).system.multicall(arg)
    assert info.value.faultString == text


def test_multicall_is_bounded_and_not_nested(lab_master) -> None:
    proxy = xmlrpc.client.ServerProxy(lab_master.uri)
    one = {"methodName": "getUri", "params": ["/a"]}
    with pytest.raises(xmlrpc.client.Fault, match="MAX_XMLRPC_MULTICALL"):
        proxy.system.multicall([one] * (MAX_XMLRPC_MULTICALL + 1))
    nested = proxy.system.multicall([{"methodName": "system.multicall", "params": [[one]]}])
    assert nested[0]["faultCode"] == 1 and "inside system.multicall" in nested[0]["faultString"]
    assert len(proxy.system.multicall([one] * MAX_XMLRPC_MULTICALL)) == MAX_XMLRPC_MULTICALL


def test_unknown_method_fault_text_is_rosmasters(lab_master) -> None:
    with pytest.raises(xmlrpc.client.Fault) as info:
        xmlrpc.client.ServerProxy(lab_master.uri).nope()
    assert info.value.faultString == "<class 'Exception'>:method \"nope\" is not supported"


def test_param_names_and_unregister_service_texts(lab_master) -> None:
    assert params_calls(xmlrpc.client.ServerProxy(lab_master.uri)) == PARAMS_REPLY


def test_param_updates_carry_the_changed_key(lab_master) -> None:
    assert param_update_story(lab_master.uri) == PARAM_UPDATES


def test_rosversion_and_rosdistro(lab_master) -> None:
    proxy = xmlrpc.client.ServerProxy(lab_master.uri)
    assert proxy.getParam("/x", "/rosversion")[2] == ROS_COMM_VERSION + "\n"
    assert proxy.getParam("/x", "/rosdistro")[2] == "noetic\n"


# ---------------------------------------------------------------- against the real rosmaster
def test_real_rosmaster_gives_the_pinned_replies(tmp_path: Path) -> None:
    with real_rosmaster(tmp_path) as uri:
        proxy = xmlrpc.client.ServerProxy(uri)
        assert proxy.system.multicall(MULTICALL) == MULTICALL_REPLY
        for arg, text in BAD_MULTICALLS[1:]:  # (an int's text differs by Python version)
            with pytest.raises(xmlrpc.client.Fault) as info:
                proxy.system.multicall(arg)
            assert info.value.faultString == text
        assert params_calls(proxy) == PARAMS_REPLY
        assert param_update_story(uri) == PARAM_UPDATES


def test_rosversion_is_the_installed_ros_comm() -> None:
    require_ros()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    out = subprocess.run(["rosversion", "roslaunch"], capture_output=True, text=True, env=env,
                         timeout=30)
    assert out.stdout == ROS_COMM_VERSION + "\n", (
        "the golden replies were pinned against rosmaster " + ROS_COMM_VERSION + "; re-pin them")


def _tool_env(uri: str, home: Path) -> dict[str, str]:
    env = ros_env(uri, home)  # ROS's scripts run "env python3": the system's, where rospy is
    env["PATH"] = f"{os.path.dirname(ROS_PYTHON)}:{env.get('PATH', '')}"
    return env


def test_roslaunch_starts_against_the_lab_master(tmp_path: Path, lab_master) -> None:
    require_ros()
    launch = tmp_path / "t.launch"
    launch.write_text(
        '<launch>\n  <param name="answer" value="42"/>\n'
        '  <node pkg="rostopic" type="rostopic" name="pub1" required="true"\n'
        '        args="pub -1 /zz std_msgs/String hi"/>\n</launch>\n')
    proc = subprocess.run(["roslaunch", str(launch)], env=_tool_env(lab_master.uri, tmp_path),
                          capture_output=True, text=True, timeout=60)
    assert "multicall" not in proc.stdout + proc.stderr, proc.stderr
    assert "started with pid" in proc.stdout, proc.stdout + proc.stderr
    assert lab_master.params.get("/answer") == 42
    assert "/pub1" not in repr(lab_master.getSystemState("/x"))


def test_rostopic_pub_and_echo_leave_nothing_behind(tmp_path: Path, lab_master) -> None:
    require_ros()
    env = _tool_env(lab_master.uri, tmp_path)
    pub = subprocess.Popen(["rostopic", "pub", "-1", "/zz", "std_msgs/String", "hi"], env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and "/zz" not in lab_master.publishers:
            time.sleep(0.05)
        echo = subprocess.run(["rostopic", "echo", "-n1", "/zz"], env=env, capture_output=True,
                              text=True, timeout=30)  # the latched message
        _out, err = pub.communicate(timeout=30)
    finally:
        if pub.poll() is None:
            pub.kill()
            pub.wait()
    assert 'data: "hi"' in echo.stdout, echo.stderr
    assert pub.returncode == 0, err
    assert lab_master.getSystemState("/x")[2] == [[], [], []]
    assert lab_master.nodes == {}


# ---------------------------------------------------------------- item 14: full message_definition
def test_lab_publisher_sends_genpys_full_text(lab_master) -> None:
    """A lab publisher's connection header carries genpy's ``_full_text`` byte for byte,
    comments included (pinned: tests/golden/sensor_msgs_Image.full_text, 2016 bytes)."""
    import socket

    from rosfpga_lab.graph import Node
    from rosfpga_lab.tcpros import decode_header, encode_header

    golden = (Path(__file__).resolve().parents[1] / "golden" / "sensor_msgs_Image.full_text").read_bytes()
    with Node("/full_text_pub", master=lab_master) as node:
        node.advertise("/img", "sensor_msgs/Image")
        with socket.create_connection(("127.0.0.1", node.tcpros_port), timeout=5) as sock:
            sock.sendall(encode_header({"callerid": "/probe", "topic": "/img", "md5sum": "*",
                                        "type": "sensor_msgs/Image"}))
            data = b""
            while len(data) < 4 or len(data) < 4 + int.from_bytes(data[:4], "little"):
                chunk = sock.recv(65536)
                assert chunk, "publisher closed before its header"
                data += chunk
    fields, _used = decode_header(data)
    assert fields["message_definition"].encode() == golden
