"""Hostile and broken peers over loopback (issue 10): every server keeps serving the others.

Each test is a regression test of one defect: it fails on the code before the fix. All of
them are bounded in sockets and time and talk to 127.0.0.1 only.
"""

from __future__ import annotations

import logging
import socket
import subprocess
import sys
import textwrap
import threading
import time
import xmlrpc.client

import pytest

from rosfpga_lab.graph import EmbeddedMaster, Node, Trace, XmlRpcError, XmlRpcServer, call
from rosfpga_lab.graph.limits import MAX_HTTP_HEAD, MAX_PUBLISHERS_PER_TOPIC, MAX_XMLRPC_DEPTH

from tests.graph.test_node import master, nodes, wait_until  # noqa: F401  (the graph tests' fixtures)

pytestmark = pytest.mark.timeout(90)


def http_post(port: int, body: bytes, extra_head: bytes = b"", timeout: float = 10.0) -> bytes:
    """One raw HTTP POST to 127.0.0.1:port; the whole reply (until the server closes)."""
    head = (b"POST / HTTP/1.0\r\nContent-Type: text/xml\r\n" + extra_head +
            b"Content-Length: %d\r\n\r\n" % len(body))
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(head + body)
        out = bytearray()
        while chunk := s.recv(65536):
            out += chunk
    return bytes(out)


def xml_call(method: str, *values: str) -> bytes:
    """A methodCall whose parameters are given as raw ``<value>`` contents."""
    params = "".join(f"<param><value>{v}</value></param>" for v in values)
    return (f"<?xml version='1.0'?><methodCall><methodName>{method}</methodName>"
            f"<params>{params}</params></methodCall>").encode()


def reply_value(reply: bytes):
    body = reply.split(b"\r\n\r\n", 1)[1]
    return xmlrpc.client.loads(body)[0][0]


# ------------------------------------------------------------------ 2: accept loops
FD_SCRIPT = textwrap.dedent("""
    import errno, logging, resource, socket, sys, time
    logging.basicConfig(level=logging.WARNING, stream=sys.stdout, format="%(name)s %(message)s")
    from rosfpga_lab.graph import EmbeddedMaster, Node, call
    master = EmbeddedMaster(port=0).start()
    victim = Node("/victim", master=master)
    pub = victim.advertise("/t", "std_msgs/String", latch=True)
    pub.publish({"data": "alive"})
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (FD_LIMIT, hard))
    held = []
    ports = [victim.tcpros_port, victim._xmlrpc.port]
    try:
        while len(held) < 4 * FD_LIMIT:
            held.append(socket.create_connection(("127.0.0.1", ports[len(held) % 2]), timeout=2))
    except OSError as exc:
        assert exc.errno in (errno.EMFILE, errno.ENFILE), exc
    # every descriptor is taken: each freed one goes to a new connection the servers cannot
    # accept (EMFILE in their accept threads)
    for i in range(20):
        held.pop(0).close()
        try:
            held.append(socket.create_connection(("127.0.0.1", ports[i % 2]), timeout=2))
        except OSError:
            pass
        time.sleep(0.05)
    time.sleep(1.0)
    for s in held:
        s.close()
    held.clear()
    print("RELEASED", flush=True)
    t0 = time.monotonic()
    reply = call(victim.uri, "getPid", "/probe", timeout=5)
    assert reply[0] == 1, reply
    listener = Node("/listener", master=master)
    sub = listener.subscribe("/t", "std_msgs/String")
    value, _ = sub.wait_for_message(10)
    assert value == {"data": "alive"}, value
    print(f"SERVED AGAIN after {time.monotonic() - t0:.2f} s", flush=True)
    listener.shutdown(); victim.shutdown(); master.stop()
""")


def test_accept_loops_survive_descriptor_exhaustion() -> None:
    """~250 held sockets exhaust a lowered RLIMIT_NOFILE; both accept loops come back."""
    script = FD_SCRIPT.replace("FD_LIMIT", "256")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=80)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-3000:]
    for server in ("XML-RPC server /victim", "TCPROS server of /victim"):  # both hit EMFILE
        assert f"{server}: accept() failed ([Errno 24] Too many open files" in out, out[-3000:]
    assert "SERVED AGAIN" in out, out[-3000:]


# ------------------------------------------------------------------ 3: traces in bytes
def test_trace_is_bounded_in_bytes_not_events() -> None:
    tr = Trace(max_bytes=4 << 20, excerpt_bytes=4096)
    big = b"x" * (8 << 20)
    for i in range(20):
        ev = tr.record("xmlrpc", "/m", role="server", method="setParam",
                       args=["/c", "/k", big.decode()], raw=big, raw_reply=b"ok", size=len(big) + 2)
        assert len(ev.raw) == 4096 and len(ev.args[2]) < 1024 and "8388608 chars" in ev.args[2]
    held = sum(len(e.raw) + len(e.raw_reply) + len(repr(e.args)) for e in tr.events)
    assert len(tr) == 20 and held < 200_000 and tr.bytes_held <= tr.max_bytes
    many = Trace(max_bytes=1 << 20, excerpt_bytes=64 << 10)
    for i in range(100):
        many.record("xmlrpc", "/m", raw=b"y" * (60 << 10), size=60 << 10)
    assert many.dropped > 0 and many.bytes_held <= 1 << 20 and len(many) < 100


def test_big_request_bodies_leave_only_excerpts_in_the_trace(master) -> None:
    big = "z" * (4 << 20)
    for i in range(5):
        reply = http_post(master.port, xml_call("setParam", "<string>/a</string>",
                                                f"<string>/big{i}</string>", f"<string>{big}</string>"))
        assert reply_value(reply)[0] == 1
    reply = http_post(master.port, b"<not xml" + b"!" * (4 << 20))  # refused bodies too
    assert b"parse error" in reply
    held = sum(len(e.raw) + len(e.raw_reply) + len(repr(e.args)) + len(repr(e.result))
               for e in master.trace.events)
    assert held < 2 << 20, held
    last = [e for e in master.trace.events if e.method == "setParam"][-1]
    assert last.size > 4 << 20 and last.raw.startswith(b"POST / HTTP/1.0")


# ------------------------------------------------------------------ 4: publisher links capped
def test_publisher_update_with_thousands_of_uris_is_capped(nodes, caplog) -> None:
    sub_node = nodes("/many")
    sub = sub_node.subscribe("/crowd", "std_msgs/String")
    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()  # nothing listens there: each link fails fast and retries with back-off
    uris = [f"http://127.0.0.1:{port}/{i}" for i in range(2000)]
    with caplog.at_level(logging.WARNING, logger="rosfpga_lab.graph"):
        reply = call(sub_node.uri, "publisherUpdate", "/master", "/crowd", uris)
    assert reply[0] == 1
    assert len(sub._links) == MAX_PUBLISHERS_PER_TOPIC
    links = [t for t in threading.enumerate() if t.name == "rosfpga-sub-link-/crowd"]
    assert len(links) <= MAX_PUBLISHERS_PER_TOPIC
    assert any("2000 publishers listed for /crowd" in r.getMessage() for r in caplog.records)


# ------------------------------------------------------------------ 6: slow sockets
def test_dripping_sockets_do_not_lock_out_xmlrpc_callers(master) -> None:
    """150 connections that sent one byte each (over the cap of 128): calls still go through."""
    held = []
    try:
        for _ in range(150):
            s = socket.create_connection(("127.0.0.1", master.port), timeout=5)
            s.sendall(b"P")
            held.append(s)
        time.sleep(0.3)
        for i in range(10):
            reply = call(master.uri, "getPid", f"/legit{i}", timeout=3)
            assert reply[0] == 1
        assert master._server.evicted >= 22
    finally:
        for s in held:
            s.close()


def test_whole_request_deadline_closes_a_dripping_socket() -> None:
    server = XmlRpcServer(lambda m, p: 1)
    server.request_timeout = 0.5
    server.start()
    try:
        with socket.create_connection(("127.0.0.1", server.port), timeout=5) as s:
            t0 = time.monotonic()
            reply = b""
            try:
                for byte in b"POST / HTTP/1.0\r\nContent-Length: 10\r\n\r\n0123456789":
                    s.sendall(bytes([byte]))  # one byte each 0.1 s: every recv is quick
                    time.sleep(0.1)
                    if time.monotonic() - t0 > 3:
                        break
            except OSError:
                pass
            s.settimeout(2)
            try:
                reply = s.recv(4096)
            except OSError:
                pass
        assert time.monotonic() - t0 < 2.5  # closed soon after 0.5 s, not after 30 s of idling
        assert reply == b"" or b"408" in reply.split(b"\r\n", 1)[0] or b"400" in reply
    finally:
        server.stop()


def test_idle_tcpros_sockets_do_not_lock_out_subscribers(nodes) -> None:
    """80 silent connections on the TCPROS port (cap: 64 in handshake): a subscriber gets in."""
    a, b = nodes("/held"), nodes("/newcomer")
    pub = a.advertise("/h", "std_msgs/String", latch=True)
    pub.publish({"data": "in"})
    idle = []
    try:
        for _ in range(80):
            idle.append(socket.create_connection(("127.0.0.1", a.tcpros_port), timeout=5))
        time.sleep(0.2)
        sub = b.subscribe("/h", "std_msgs/String")
        assert sub.wait_for_connection(1, 2.0), sub.stats.errors
        assert wait_until(lambda: sub.last is not None, 2.0) and sub.last[0] == {"data": "in"}
        assert a.refused_connections >= 16
    finally:
        for s in idle:
            s.close()


# ------------------------------------------------------------------ 7: master notifier
def test_silent_nodes_do_not_delay_other_notifications(master, nodes) -> None:
    silent = []
    try:
        for i in range(3):  # three nodes whose slave API accepts and never answers
            lst = socket.socket()
            lst.bind(("127.0.0.1", 0))
            lst.listen(64)
            silent.append(lst)
            api = f"http://127.0.0.1:{lst.getsockname()[1]}/"
            for t in range(5):
                assert call(master.uri, "registerSubscriber", f"/silent{i}", f"/busy{t}",
                            "std_msgs/String", api)[0] == 1
        for t in range(5):  # 15 notifications to silent nodes: 75 s for one serial notifier
            for k in range(3):
                call(master.uri, "registerPublisher", f"/talker{k}", f"/busy{t}",
                     "std_msgs/String", f"http://127.0.0.1:9/{k}")
        listener, talker = nodes("/listener"), nodes("/talker")
        sub = listener.subscribe("/legit", "std_msgs/String")
        t0 = time.monotonic()
        talker.advertise("/legit", "std_msgs/String")
        assert sub.wait_for_connection(1, 3.0), f"not connected after {time.monotonic() - t0:.1f} s"
        # coalesced: at most one waiting publisherUpdate per silent node and topic
        assert master._pending_count <= 15
    finally:
        for lst in silent:
            lst.close()


# ------------------------------------------------------------------ 10: parameter server
def test_parameter_server_refuses_values_it_could_not_return(master) -> None:
    big = http_post(master.port, xml_call("setParam", "<string>/c</string>", "<string>/big</string>",
                                          "<int>4294967296</int>"))
    assert reply_value(big)[0] == -1 and "32-bit" in reply_value(big)[1]
    nil = http_post(master.port, xml_call("setParam", "<string>/c</string>", "<string>/n</string>",
                                          "<nil/>"))
    assert reply_value(nil)[:2] == [-1, "ERROR: parameter [value] must be specified"]
    nested_nil = http_post(master.port, xml_call(
        "setParam", "<string>/c</string>", "<string>/nn</string>",
        "<struct><member><name>a</name><value><nil/></value></member></struct>"))
    assert reply_value(nested_nil)[0] == -1
    levels = 100_000
    deep = "<array><data><value>" * levels + "<int>1</int>" + "</value></data></array>" * levels
    reply = http_post(master.port, xml_call("setParam", "<string>/c</string>", "<string>/deep</string>", deep))
    assert f"deeper than {MAX_XMLRPC_DEPTH}" in reply.decode(errors="replace")
    ok = "<array><data><value>" * 10 + "<int>1</int>" + "</value></data></array>" * 10
    assert reply_value(http_post(master.port, xml_call(
        "setParam", "<string>/c</string>", "<string>/ok</string>", ok)))[0] == 1
    code, _, tree = call(master.uri, "getParam", "/c", "/")
    assert code == 1 and "big" not in tree and "n" not in tree and "deep" not in tree
    assert "ok" in tree
    with pytest.raises(XmlRpcError, match="32-bit"):
        call(master.uri, "setParam", "/c", "/client_big", 2**31)  # no silent clamping


# ------------------------------------------------------------------ 12: HTTP head cap
def test_http_head_over_the_cap_is_refused_even_in_one_chunk(master) -> None:
    pad = b"X-Pad: " + b"p" * (20 << 10) + b"\r\n"
    assert len(pad) > MAX_HTTP_HEAD
    reply = http_post(master.port, xml_call("getPid", "<string>/c</string>"), extra_head=pad)
    assert reply.startswith(b"HTTP/1.1 400") and b"HTTP head longer" in reply
    small = http_post(master.port, xml_call("getPid", "<string>/c</string>"), extra_head=b"X-Pad: p\r\n")
    assert small.startswith(b"HTTP/1.1 200")


# ------------------------------------------------------------------ 13: registrations logged
def test_master_logs_registrations_with_peer(master, nodes, caplog) -> None:
    with caplog.at_level(logging.INFO, logger="rosfpga_lab.graph.master"):
        n = nodes("/logged")
        pub = n.advertise("/lt", "std_msgs/String")
        n.subscribe("/ls", "std_msgs/String")
        spoof = call(master.uri, "unregisterPublisher", "/logged", "/lt", "http://127.0.0.1:1/")
        pub.unregister()
    lines = [r.getMessage() for r in caplog.records if r.name == "rosfpga_lab.graph.master"]
    assert spoof[2] == 0
    assert any(l.startswith(f"+PUB [/lt] /logged {n.uri} (from 127.0.0.1:") for l in lines), lines
    assert any(l.startswith(f"+SUB [/ls] /logged {n.uri} (from 127.0.0.1:") for l in lines), lines
    assert any(l.startswith("-PUB [/lt] /logged http://127.0.0.1:1/") and "refused" in l
               for l in lines), lines
    assert any(l.startswith(f"-PUB [/lt] /logged {n.uri} (from 127.0.0.1:") for l in lines), lines
