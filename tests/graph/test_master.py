"""The embedded master and the safe XML-RPC layer: replies like rosmaster, bad input refused."""

from __future__ import annotations

import socket
import threading
import xmlrpc.client

import pytest

from rosfpga_lab.graph import EmbeddedMaster, OpenBindWarning, Trace, XmlRpcError, call, parse_xmlrpc
from rosfpga_lab.graph.names import resolve
from rosfpga_lab.graph.xmlrpc import XmlRpcServer

API = "http://127.0.0.1:9/"


@pytest.fixture
def master():
    m = EmbeddedMaster(port=0).start()
    yield m
    m.stop()


def proxy(m: EmbeddedMaster) -> xmlrpc.client.ServerProxy:
    return xmlrpc.client.ServerProxy(m.uri)


def test_binds_loopback_and_answers_get_uri(master: EmbeddedMaster) -> None:
    assert master.uri.startswith("http://127.0.0.1:")
    assert proxy(master).getUri("/x") == [1, "", master.uri]


def test_register_lookup_state_like_rosmaster(master: EmbeddedMaster) -> None:
    p = proxy(master)
    assert p.registerSubscriber("/l", "/chatter", "std_msgs/String", API) == [1, "Subscribed to [/chatter]", []]
    assert p.registerPublisher("/t", "/chatter", "std_msgs/String", API) == \
        [1, "Registered [/t] as publisher of [/chatter]", [API]]
    assert p.lookupNode("/x", "/t") == [1, "node api", API]
    assert p.lookupNode("/x", "/nobody") == [-1, "unknown node [/nobody]", ""]
    assert p.getPublishedTopics("/x", "") == [1, "current topics", [["/chatter", "std_msgs/String"]]]
    assert p.getTopicTypes("/x") == [1, "current system state", [["/chatter", "std_msgs/String"]]]
    assert p.getSystemState("/x") == [1, "current system state", [[["/chatter", ["/t"]]], [["/chatter", ["/l"]]], []]]
    assert p.lookupService("/x", "/srv") == [-1, "no provider", ""]
    assert p.unregisterPublisher("/t", "/chatter", API) == [1, "Unregistered [/t] as provider of [/chatter]", 1]
    assert p.unregisterPublisher("/t", "/chatter", API) == [1, "[/t] is not a registered node", 0]
    assert p.getPublishedTopics("/x", "") == [1, "current topics", []]


def test_relative_names_resolve_in_caller_namespace(master: EmbeddedMaster) -> None:
    p = proxy(master)
    p.registerPublisher("/ns/t", "chatter", "std_msgs/String", API)
    assert p.getPublishedTopics("/x", "/ns") == [1, "current topics", [["/ns/chatter", "std_msgs/String"]]]
    assert resolve("~p", "/ns/node") == "/ns/node/p" and resolve("", "/a/b") == "/a/"


BAD_CALLS = [
    ("registerPublisher", (), -1, "missing required caller_id parameter"),
    ("registerPublisher", ("/t",), -1, "bad call arity"),
    ("registerPublisher", ("/t", "/a", "std_msgs/String", API, "extra"), -1, "bad call arity"),
    ("registerPublisher", (5, "/a", "std_msgs/String", API), -1, "caller_id must be a string"),
    ("registerPublisher", ("/t", 7, "std_msgs/String", API), -1, "[topic] must be a non-empty string"),
    ("registerPublisher", ("/t", "/a", "String", API), -1, "not a valid package resource name"),
    ("registerPublisher", ("/t", "/a", "std_msgs/String", "ftp://x"), -1, "[caller_api] is not an RPC URI"),
    ("registerPublisher", ("/t", "/", "std_msgs/String", API), -1, "cannot be the global namespace"),
    ("registerSubscriber", ("/t", "bad name", "std_msgs/String", API), -1, "contains illegal chars"),
    ("setParam", ("/t", "", 1), -1, "[key] must be specified and non-empty"),
    ("getParam", ("/t", ["list"]), -1, "[key] must be a string"),
    ("lookupNode", ("/t", 1.5), -1, "[node] must be a non-empty string"),
]


@pytest.mark.parametrize("method,args,code,text", BAD_CALLS, ids=[f"{b[0]}-{i}" for i, b in enumerate(BAD_CALLS)])
def test_bad_arguments_get_error_triples_and_master_keeps_serving(master, method, args, code, text) -> None:
    reply = getattr(proxy(master), method)(*args)
    assert reply[0] == code and text in reply[1]
    assert proxy(master).getUri("/x")[0] == 1


def test_unknown_method_is_a_fault(master: EmbeddedMaster) -> None:
    with pytest.raises(xmlrpc.client.Fault, match="not supported"):
        proxy(master).noSuchMethod("/x")


def test_parameter_server(master: EmbeddedMaster) -> None:
    p = proxy(master)
    assert p.hasParam("/x", "/run_id")[2] is True
    assert p.setParam("/ns/node", "~gain", 2.5) == [1, "parameter /ns/node/gain set", 0]
    assert p.setParam("/x", "/cfg", {"a": 1, "b": {"c": "s"}})[0] == 1
    assert p.getParam("/x", "/cfg") == [1, "Parameter [/cfg]", {"a": 1, "b": {"c": "s"}}]
    assert p.getParam("/x", "/cfg/b/c")[2] == "s"
    assert p.getParam("/x", "/nope") == [-1, "Parameter [/nope] is not set", 0]
    # rosmaster 1.15.15 looks in the caller's own namespace first (ns_join(caller_id, key))
    assert p.searchParam("/ns/node", "gain") == [1, "Found [/ns/node/gain]", "/ns/node/gain"]
    assert p.searchParam("/ns/node", "gain/x") == [1, "Found [/ns/node/gain/x]", "/ns/node/gain/x"]
    assert p.searchParam("/ns/other", "gain") == [-1, "Cannot find parameter [gain] in an upwards search", ""]
    assert p.searchParam("/ns/node", "~gain") == [0, "Internal failure: invalid key", 0]
    assert p.searchParam("node", "gain") == [0, "Internal failure: namespace must be global", 0]
    assert p.setParam("/x", "/", 5) == \
        [-1, "Error: invalid arguments: cannot set root of parameter tree to non-dictionary", 0]
    assert p.searchParam("/cfg/node", "b") == [1, "Found [/cfg/b]", "/cfg/b"]
    p.setParam("/x", "/ns/gain", 1)
    assert p.searchParam("/ns/sub/node", "gain") == [1, "Found [/ns/gain]", "/ns/gain"]
    assert "/cfg/b/c" in p.getParamNames("/x")[2]
    assert p.deleteParam("/x", "/cfg/b")[0] == 1
    assert p.deleteParam("/x", "/cfg/b") == [-1, "parameter [/cfg/b] is not set", 0]
    assert p.subscribeParam("/x", API, "/cfg") == [1, "Subscribed to parameter [/cfg]", {"a": 1}]


def test_new_node_with_same_name_replaces_old(master: EmbeddedMaster) -> None:
    p = proxy(master)
    p.registerPublisher("/t", "/a", "std_msgs/String", "http://127.0.0.1:1/")
    p.registerPublisher("/t", "/a", "std_msgs/String", "http://127.0.0.1:2/")
    assert p.lookupNode("/x", "/t")[2] == "http://127.0.0.1:2/"
    # rosmaster drops every registration of the old instance, its services included
    p.registerService("/t", "/t/svc", "rosrpc://127.0.0.1:5", "http://127.0.0.1:2/")
    p.registerSubscriber("/t", "/b", "std_msgs/String", "http://127.0.0.1:3/")
    assert p.lookupService("/x", "/t/svc") == [-1, "no provider", ""]
    assert p.getSystemState("/x")[2] == [[], [["/b", ["/t"]]], []]


# ----------------------------------------------------------------------------- XML-RPC safety
def test_a_node_with_an_unusable_uri_does_not_stop_notifications(master: EmbeddedMaster) -> None:
    import time

    from rosfpga_lab.graph import Node

    p = proxy(master)
    # passes rosmaster's is_api check (starts with http://) but has no port to call
    assert p.registerSubscriber("/broken", "/t", "std_msgs/String", "http://noport")[0] == 1
    assert p.registerPublisher("/pub1", "/t", "std_msgs/String", API)[0] == 1
    node = Node("/good", master=master)
    try:
        sub = node.subscribe("/t", "std_msgs/String")
        assert p.registerPublisher("/pub2", "/t", "std_msgs/String", "http://127.0.0.1:8/")[0] == 1
        deadline = time.monotonic() + 5
        while "http://127.0.0.1:8/" not in sub._links and time.monotonic() < deadline:
            time.sleep(0.02)
        assert set(sub._links) == {API, "http://127.0.0.1:8/"}  # publisherUpdate still arrives
        assert any("publisherUpdate to http://noport: ConfigError" in e for e in master.notify_errors)
    finally:
        node.shutdown()


BOMB = b"""<?xml version="1.0"?>
<!DOCTYPE x [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>
<methodCall><methodName>getUri</methodName><params><param><value>&b;</value></param></params></methodCall>"""


def raw_http(port: int, data: bytes) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(data)
        out = b""
        while chunk := s.recv(65536):
            out += chunk
        return out


def post(body: bytes, length: int | None = None) -> bytes:
    n = len(body) if length is None else length
    return b"POST / HTTP/1.0\r\nContent-Type: text/xml\r\nContent-Length: %d\r\n\r\n" % n + body


@pytest.mark.parametrize("request_bytes,expect", [
    (post(BOMB), b"parse error"),                                   # entity expansion refused
    (post(b"<methodCall><methodName>getUri"), b"parse error"),      # truncated XML
    (post(b"<x/>"), b"parse error"),                                # not XML-RPC
    (post(b"", length=100_000_000), b"413"),                        # body over the cap
    (b"GET / HTTP/1.0\r\n\r\n", b"405"),
    (b"POST / HTTP/1.0\r\nContent-Length: abc\r\n\r\n", b"400"),
    (b"POST / HTTP/1.0\r\nBroken header line\r\n\r\n", b"400"),
], ids=["entity-bomb", "truncated", "not-xmlrpc", "too-big", "get", "bad-length", "bad-header"])
def test_hostile_http_is_refused_and_server_keeps_serving(master, request_bytes, expect) -> None:
    reply = raw_http(master.port, request_bytes)
    assert expect in reply
    assert proxy(master).getUri("/x")[0] == 1


def test_parse_xmlrpc_refuses_entities() -> None:
    with pytest.raises(XmlRpcError, match="malformed"):
        parse_xmlrpc(BOMB)


def test_keep_alive_client_and_trace_holds_raw_http() -> None:
    tr = Trace()
    server = XmlRpcServer(lambda m, p: [1, "ok", list(p)], trace=tr, name="/srv")
    server.start()
    try:
        p = xmlrpc.client.ServerProxy(server.uri)  # HTTP/1.1 keep-alive, like rospy
        assert [p.a("/c", 1), p.b("/c", 2)] == [[1, "ok", ["/c", 1]], [1, "ok", ["/c", 2]]]
        assert call(server.uri, "c", "/me", [1, 2], trace=tr, caller="/me") == [1, "ok", ["/me", [1, 2]]]
    finally:
        server.stop()
    evs = tr.events
    assert [e.method for e in evs if e.role == "server"] == ["a", "b", "c"]
    client = [e for e in evs if e.role == "client"][0]
    assert client.raw.startswith(b"POST / HTTP/1.1\r\n") and b"<methodName>c</methodName>" in client.raw
    assert client.raw_reply.startswith(b"HTTP/1.1 200 OK\r\n") and client.result == [1, "ok", ["/me", [1, 2]]]
    # conversation(): the server-side copy of /me's call is dropped, /c (not a recorder) kept
    assert [e.method for e in tr.conversation()] == ["a", "b", "c"]


def test_call_errors_are_typed() -> None:
    with pytest.raises(XmlRpcError, match="failed"):
        call("http://127.0.0.1:1/", "getUri", "/x", timeout=1)


def test_open_bind_warns() -> None:
    with pytest.warns(OpenBindWarning, match="no authentication"):
        m = EmbeddedMaster(host="0.0.0.0", port=0)
    m.start()
    m.stop()


def test_stop_leaves_no_threads() -> None:
    before = set(threading.enumerate())
    m = EmbeddedMaster(port=0).start()
    proxy(m).getUri("/x")
    m.stop()
    assert set(threading.enumerate()) <= before


# ----------------------------------------------------------------------------- fuzzing
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from rosfpga_lab.errors import LabError  # noqa: E402

XMLRPC_PIECES = [b"<?xml version='1.0'?>", b"<methodCall>", b"</methodCall>", b"<methodName>",
                 b"</methodName>", b"<params>", b"<param>", b"<value>", b"<int>", b"12", b"</int>",
                 b"<string>", b"x", b"</string>", b"<array><data>", b"</data></array>", b"<struct>",
                 b"<member><name>a</name>", b"</member>", b"</struct>", b"</value>", b"</param>",
                 b"</params>", b"<base64>", b"!!", b"<double>", b"nan", b"<!ENTITY a 'b'>", b"&a;",
                 b"<boolean>", b"2", b"<nil/>", b"\xff"]


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.binary(max_size=200),
                 st.lists(st.sampled_from(XMLRPC_PIECES), max_size=25).map(b"".join)))
def test_fuzz_xmlrpc_parser_only_lab_errors(data: bytes) -> None:
    try:
        parse_xmlrpc(data)
    except LabError:
        pass


def test_fuzz_server_survives_garbage(master) -> None:
    import random

    rnd = random.Random(7)
    for _ in range(30):
        junk = bytes(rnd.randrange(256) for _ in range(rnd.randrange(1, 300)))
        try:
            raw_http(master.port, junk + b"\r\n\r\n")
        except OSError:
            pass
    assert proxy(master).getUri("/x")[0] == 1
