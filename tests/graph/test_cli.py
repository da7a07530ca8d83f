"""``rosfpga-lab master`` and ``rosfpga-lab topic`` end to end, as subprocesses."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time

import pytest

from tests.support.realros import free_port, stop_process, wait_for_master
from rosfpga_lab.graph import MAX_XMLRPC_BODY, MAX_XMLRPC_REPLY, EmbeddedMaster, Node, call
from rosfpga_lab.graph.tools import RateMeter, format_message, parse_message_value
from rosfpga_lab.msg import Time, default_registry

pytestmark = pytest.mark.timeout(90)


def cli(*args: str, timeout: float = 30) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    return subprocess.run([sys.executable, "-m", "rosfpga_lab", *args], capture_output=True,
                          text=True, timeout=timeout, env=env)


@pytest.fixture
def graph():
    with EmbeddedMaster(port=0) as m:
        talker = Node("/talker", master=m)
        listener = Node("/listener", master=m)
        pub = talker.advertise("/chatter", "std_msgs/String")
        sub = listener.subscribe("/chatter", "std_msgs/String")
        stop = threading.Event()

        def loop() -> None:
            while not stop.wait(0.05):
                pub.publish({"data": "hi"})

        t = threading.Thread(target=loop, daemon=True)
        t.start()
        yield m, talker, listener, sub
        stop.set()
        t.join(5)
        talker.shutdown()
        listener.shutdown()


def test_master_cli_serves_and_stops() -> None:
    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "master", "--port", str(port)],
                            stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.strip() == f"ROS master running; export ROS_MASTER_URI=http://127.0.0.1:{port}/"
        wait_for_master(f"http://127.0.0.1:{port}/", timeout=10)
        node = Node("/probe", master_uri=f"http://127.0.0.1:{port}/")
        node.advertise("/x", "std_msgs/String")
        assert node.logging_ready.wait(5)
        out = cli("topic", "--master-uri", f"http://127.0.0.1:{port}/", "list")
        assert out.stdout.split() == ["/rosout", "/x"]   # every node logs on /rosout, as in ROS
        node.shutdown()
    finally:
        stop_process(proc)
        proc.stdout.close()  # type: ignore[union-attr]


def test_topic_list_info(graph) -> None:
    m, talker, listener, _ = graph
    out = cli("topic", "--master-uri", m.uri, "list", "-v")
    assert out.returncode == 0, out.stderr
    assert " * /chatter [std_msgs/String] 1 publisher" in out.stdout
    assert " * /chatter [std_msgs/String] 1 subscriber" in out.stdout
    info = cli("topic", "--master-uri", m.uri, "info", "/chatter").stdout
    assert info.startswith("Type: std_msgs/String\n")
    assert f" * /talker ({talker.uri})" in info and f" * /listener ({listener.uri})" in info


def test_topic_echo_and_hz(graph) -> None:
    m = graph[0]
    out = cli("topic", "--master-uri", m.uri, "echo", "-n", "2", "--timeout", "20", "/chatter")
    assert out.returncode == 0, out.stderr
    assert out.stdout == 'data: "hi"\n---\n' * 2
    hexed = cli("topic", "--master-uri", m.uri, "echo", "-n", "1", "--hex", "/chatter").stdout
    assert hexed.split()[0] == "020000006869"
    hz = cli("topic", "--master-uri", m.uri, "hz", "--duration", "2.5", "/chatter").stdout
    rates = [float(line.split(":")[1]) for line in hz.splitlines() if line.startswith("average rate")]
    assert rates and all(5 < r < 40 for r in rates), hz


def test_topic_pub_reaches_a_lab_subscriber() -> None:
    with EmbeddedMaster(port=0) as m:
        node = Node("/listener", master=m)
        try:
            sub = node.subscribe("/cmd", "std_msgs/String")
            out = cli("topic", "--master-uri", m.uri, "pub", "-1", "/cmd", "std_msgs/String", "data: go")
            assert out.returncode == 0, out.stderr
            assert sub.last is not None and sub.last[0] == {"data": "go"}
        finally:
            node.shutdown()


@pytest.mark.parametrize("action", [["list"], ["info", "/x"], ["echo", "/x"],
                                    ["pub", "-1", "/x", "std_msgs/String", "hi"],
                                    ["hz", "--duration", "1", "/x"]], ids=lambda a: a[0])
def test_topic_without_a_master_stops_with_a_hint(action: list[str]) -> None:
    dead = f"http://127.0.0.1:{free_port()}/"
    out = cli("topic", "--master-uri", dead, *action)
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr.startswith(f"rosfpga-lab topic: error: cannot reach the ROS master at {dead}")
    assert "Start one with `rosfpga-lab master`" in out.stderr and "Traceback" not in out.stderr


def test_topic_default_master_is_roscores(monkeypatch) -> None:
    from rosfpga_lab.graph.tools import pick_master_uri

    monkeypatch.delenv("ROS_MASTER_URI", raising=False)
    assert pick_master_uri(None) == "http://127.0.0.1:11311/"  # never a private embedded master
    monkeypatch.setenv("ROS_MASTER_URI", "http://127.0.0.1:5/")
    assert pick_master_uri(None) == "http://127.0.0.1:5/"
    assert pick_master_uri("http://10.0.0.1:7/") == "http://10.0.0.1:7/"


def test_topic_names_resolve_like_rostopic(graph) -> None:
    m = graph[0]
    info = cli("topic", "--master-uri", m.uri, "info", "chatter")
    assert info.returncode == 0 and info.stdout.startswith("Type: std_msgs/String\n"), info.stderr


def test_topic_errors_are_clear() -> None:
    with EmbeddedMaster(port=0) as m:
        out = cli("topic", "--master-uri", m.uri, "info", "/nope")
        assert out.returncode == 1 and "topic /nope is unknown" in out.stderr


def test_format_and_parse_helpers() -> None:
    reg = default_registry()
    v = parse_message_value(reg, "sensor_msgs/Image", ["{header: {frame_id: cam}, width: 2, encoding: rgba8}"])
    assert v["header"]["frame_id"] == "cam" and v["width"] == 2 and v["height"] == 0
    v["header"]["stamp"] = Time(3, 4)
    text = format_message(v)
    assert "header: \n  seq: 0\n  stamp: \n    secs: 3\n    nsecs:         4\n  frame_id: \"cam\"" in text
    assert parse_message_value(reg, "std_msgs/String", ["hello"]) == {"data": "hello"}
    with pytest.raises(Exception, match="no field 'nope'"):
        parse_message_value(reg, "std_msgs/String", ["{nope: 1}"])
    meter = RateMeter()
    for t in (0.0, 0.1, 0.2, 0.3):
        meter.tick(t)
    assert meter.report().startswith("average rate: 10.000")


def test_master_cli_trace_prints_calls() -> None:
    import xmlrpc.client

    port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "master", "--port", str(port), "--trace"],
                            stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout is not None
        proc.stdout.readline()
        uri = f"http://127.0.0.1:{port}/"
        wait_for_master(uri, timeout=10)
        xmlrpc.client.ServerProxy(uri).lookupNode("/probe", "/nobody")
        lines = [proc.stdout.readline().strip() for _ in range(2)]
        assert "/probe -> lookupNode('/nobody',) = -1" in lines, lines
    finally:
        stop_process(proc)
        proc.stdout.close()  # type: ignore[union-attr]


def test_master_cli_bad_ports_are_clear() -> None:
    with EmbeddedMaster(port=0) as m:  # the port is taken
        out = cli("master", "--port", str(m.port), timeout=20)
    assert out.returncode == 1 and "Traceback" not in out.stderr
    assert "Address already in use" in out.stderr and "pick another --port" in out.stderr
    out = cli("master", "--port", "99999")
    assert out.returncode == 2 and "'99999' is not a TCP port (0..65535)" in out.stderr


def test_out_of_range_ports_are_lab_errors() -> None:
    from rosfpga_lab.graph import XmlRpcError, XmlRpcServer

    with pytest.raises(XmlRpcError, match="cannot bind XML-RPC server to 127.0.0.1:70000"):
        XmlRpcServer(lambda m, p: 0, port=70000).start()
    with EmbeddedMaster(port=0) as m, pytest.raises(XmlRpcError, match="cannot bind TCPROS port"):
        Node("/n", master=m, tcpros_port=70000)


# ---- behaviour as rostopic's (issue 10, defect 9) ---------------------------------------------
def popen_cli(*args: str) -> subprocess.Popen:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    return subprocess.Popen([sys.executable, "-m", "rosfpga_lab", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def tool_node(m: EmbeddedMaster, topic: str, timeout: float = 20.0) -> str:
    """Name of the topic tool's node once the master lists it on ``topic``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        pubs, subs, _ = call(m.uri, "getSystemState", "/test")[2]
        for t, nodes in pubs + subs:
            for n in nodes:
                if t == topic and n.startswith("/rosfpga_lab_topic_"):
                    return n
        time.sleep(0.05)
    raise AssertionError(f"no topic tool registered on {topic}")


def test_topic_echo_waits_for_a_topic_not_yet_published() -> None:
    """rostopic echo prints a warning and waits; it used to exit with "unknown to the master"."""
    with EmbeddedMaster(port=0) as m:
        proc = popen_cli("topic", "--master-uri", m.uri, "echo", "-n", "1", "/later")
        try:
            assert proc.stderr is not None
            line = proc.stderr.readline()
            assert line == "WARNING: topic [/later] does not appear to be published yet\n"
            time.sleep(0.5)
            assert proc.poll() is None, "echo gave up instead of waiting"
            node = Node("/late_talker", master=m)
            try:
                node.advertise("/later", "std_msgs/String", latch=True).publish({"data": "now"})
                out, err = proc.communicate(timeout=20)
            finally:
                node.shutdown()
            assert proc.returncode == 0, err
            assert out == 'data: "now"\n---\n'
        finally:
            stop_process(proc)


def test_topic_hz_says_no_new_messages_when_they_stop() -> None:
    with EmbeddedMaster(port=0) as m:
        node = Node("/burst", master=m)
        try:
            pub = node.advertise("/burst", "std_msgs/String")
            proc = popen_cli("topic", "--master-uri", m.uri, "hz", "--duration", "5", "/burst")
            assert pub.wait_for_subscribers(1, 20)
            for _ in range(30):   # 1.5 s at 20 Hz, then silence
                pub.publish({"data": "x"})
                time.sleep(0.05)
            out, err = proc.communicate(timeout=30)
        finally:
            node.shutdown()
    assert proc.returncode == 0, err
    lines = out.splitlines()
    last_rate = max(i for i, line in enumerate(lines) if line.startswith("average rate"))
    after = [line for line in lines[last_rate + 2:]]
    assert after and set(after) == {"no new messages"}, out   # not the old rate, again and again


@pytest.mark.parametrize("action", [["echo", "/chatter"], ["hz", "/chatter"],
                                    ["pub", "-l", "/latched", "std_msgs/String", "data: x"]],
                         ids=lambda a: a[0])
def test_topic_tools_exit_after_a_remote_shutdown(graph, action: list[str]) -> None:
    """A slave-API ``shutdown`` ends rostopic with its reason; the lab's tools ran on."""
    m = graph[0]
    proc = popen_cli("topic", "--master-uri", m.uri, *action)
    try:
        name = tool_node(m, action[1] if action[0] != "pub" else action[2])
        api = call(m.uri, "lookupNode", "/test", name)[2]
        assert call(api, "shutdown", "/killer", "go away")[0] == 1
        out, err = proc.communicate(timeout=15)
    finally:
        stop_process(proc)
    assert proc.returncode == 0, err
    assert "shutdown request: remote shutdown by /killer: go away" in err
    assert "Traceback" not in err


def test_topic_pub_shut_down_before_its_first_publish_exits_as_stopped_remotely(
        monkeypatch, capsys) -> None:
    """The race the [pub] case above lost under load: the shutdown landed between advertise and
    the first publish, which found its publisher closed; the tool said "publisher of /latched is
    closed; advertise again" and exited 1. Made certain here: the first publish waits for the
    remote shutdown to close it."""
    from rosfpga_lab.cli import main
    from rosfpga_lab.graph.publisher import Publisher

    publish = Publisher.publish

    def shut_down_first(self, value) -> None:
        api = call(m.uri, "lookupNode", "/test", tool_node(m, "/latched"))[2]
        assert call(api, "shutdown", "/killer", "go away")[0] == 1
        deadline = time.monotonic() + 10
        while not self.closed and time.monotonic() < deadline:
            time.sleep(0.01)
        assert self.closed
        publish(self, value)

    monkeypatch.setattr(Publisher, "publish", shut_down_first)
    with EmbeddedMaster(port=0) as m:
        assert main(["topic", "--master-uri", m.uri, "pub", "-l", "/latched", "std_msgs/String",
                     "data: x"]) == 0
    err = capsys.readouterr().err
    assert "shutdown request: remote shutdown by /killer: go away" in err
    assert "closed" not in err


def test_topic_tools_handle_a_large_graph() -> None:
    """900 topics with long names: getSystemState is over 8 MiB. rostopic lists them; the lab's
    tools said "cannot reach the ROS master"."""
    long = "x" * 5000
    with EmbeddedMaster(port=0) as m:
        for i in range(900):
            call(m.uri, "registerPublisher", f"/node_{i}_{long}", f"/topic_{i}_{long}",
                 "std_msgs/String", f"http://127.0.0.1:{1000 + i}/")
        import xmlrpc.client

        reply = xmlrpc.client.dumps((call(m.uri, "getSystemState", "/test"),), methodresponse=True)
        assert len(reply) > MAX_XMLRPC_BODY
        out = cli("topic", "--master-uri", m.uri, "list", timeout=60)
    assert out.returncode == 0, out.stderr
    assert len(out.stdout.split()) == 900 and f"/topic_7_{long}" in out.stdout.split()


def test_a_reply_over_the_cap_is_named_not_called_unreachable() -> None:
    """A master whose reply is over the client's cap answered: say so, with the sizes."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    server.settimeout(30)
    huge = MAX_XMLRPC_REPLY + 1

    def serve() -> None:
        for _ in range(2):
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                conn.recv(65536)
                conn.sendall(f"HTTP/1.1 200 OK\r\nContent-Length: {huge}\r\n\r\n".encode())

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    try:
        out = cli("topic", "--master-uri", f"http://127.0.0.1:{server.getsockname()[1]}/", "list")
    finally:
        server.close()
        t.join(5)
    assert out.returncode == 1 and "Traceback" not in out.stderr
    assert "cannot reach" not in out.stderr
    assert "answered getUri, but the reply is too large" in out.stderr
    assert f"HTTP body of {huge} bytes, over the limit of {MAX_XMLRPC_REPLY}" in out.stderr


def test_one_rate_meter_windowed_stale_overall_and_bounded() -> None:
    """graph.rate.RateMeter is the meter of rostopic hz, the live view and the component's fps."""
    from rosfpga_lab.component.stats import fps_meter
    from rosfpga_lab.widgets import RateMeter as WidgetRateMeter

    assert WidgetRateMeter is RateMeter
    m = RateMeter(samples=5, window_s=1.0, stale_s=0.5, clock=lambda: 0.0)
    for k in range(11):              # 10 Hz from 0 to 1 s, then 2 Hz from 1.5 s to 2.5 s
        m.tick(k / 10)
    for t in (1.5, 2.0, 2.5):
        m.tick(t)
    assert len(m.times) == 5 and m.count == 14
    assert m.rate(now=2.5) == pytest.approx(2.0)       # 1.5, 2.0, 2.5 in the last second
    assert m.rate(now=3.1) == 0.0                      # stale: nothing for 0.6 s
    assert m.overall_rate() == pytest.approx(13 / 2.5)  # all arrivals, though only 5 are kept
    report = m.report()
    assert report is not None and "window: 5" in report
    assert m.report() is None                          # nothing new since: "no new messages"
    m.tick(2.6)
    assert m.report() is not None
    f = fps_meter()
    assert (f.window_s, f.stale_s) == (2.0, 1.0)


def test_two_tools_started_in_the_same_millisecond_get_different_names(monkeypatch) -> None:
    """CI saw two `topic pub` tools register one name (the millisecond alone made it unique), so
    the master shut one down. Names are rospy's anonymous form, base_PID_MS."""
    from rosfpga_lab.graph import names

    monkeypatch.setattr(names.time, "time", lambda: 1764000000.1234)
    monkeypatch.setattr(names.os, "getpid", lambda: 4242)
    first = names.anonymous_name("/rosfpga_lab_topic_pub")
    monkeypatch.setattr(names.os, "getpid", lambda: 4243)
    second = names.anonymous_name("/rosfpga_lab_topic_pub")
    assert (first, second) == ("/rosfpga_lab_topic_pub_4242_1764000000123",
                               "/rosfpga_lab_topic_pub_4243_1764000000123")


def test_two_topic_pub_tools_at_once_both_stay_registered() -> None:
    with EmbeddedMaster(port=0) as m:
        procs = [popen_cli("topic", "--master-uri", m.uri, "pub", f"/twin{k}", "std_msgs/String",
                           "{data: x}") for k in range(2)]
        try:
            first, second = tool_node(m, "/twin0"), tool_node(m, "/twin1")
            assert first != second
            time.sleep(0.5)          # a duplicate name would have shut the first one down by now
            assert all(p.poll() is None for p in procs), [p.stderr.read() for p in procs if p.poll() is not None]
        finally:
            for p in procs:
                stop_process(p)
