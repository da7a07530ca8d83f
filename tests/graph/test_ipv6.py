"""IPv6 literals are bound as asked, never widened (issue 23, item 10): ``master --host ::1``
listens on ::1 only; lab nodes with ``ROS_IP=::1`` listen on IPv6, and rostopic reaches them
there; ``topic echo --timeout`` says that it timed out. Loopback only."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import warnings

import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.realros import require_ros
from rosfpga_lab.cli import main
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.names import OpenBindWarning, bind_address, uri_host
from rosfpga_lab.graph.realros import ros_env
from rosfpga_lab.graph.xmlrpc import call, split_uri


def ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_STREAM) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


needs_ipv6 = pytest.mark.skipif(not ipv6_loopback(), reason="this machine has no IPv6 loopback")


def refused(host: str, port: int) -> bool:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.settimeout(2)
        return s.connect_ex((host, port)) != 0


def test_bind_address_keeps_what_was_asked() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", OpenBindWarning)   # no warning: nothing widened
        assert bind_address("::1") == "::1"
        assert bind_address("[::1]") == "::1"
        assert bind_address("127.0.0.2") == "127.0.0.2"
    with pytest.warns(OpenBindWarning):
        assert bind_address("::") == "::"
    assert uri_host("::1") == "[::1]" and uri_host("127.0.0.1") == "127.0.0.1"


@needs_ipv6
def test_master_command_host_ipv6_loopback_binds_only_that() -> None:
    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "master", "--host", "::1",
                             "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=interruptible)
    try:
        line = proc.stdout.readline()   # type: ignore[union-attr]
        uri = line.strip().rsplit("=", 1)[-1]
        assert uri.startswith("http://[::1]:"), line
        _host, port, _ = split_uri(uri)
        assert call(uri, "getUri", "/t")[2] == uri
        assert refused("127.0.0.1", port), "the master answers on IPv4 too"
        _out, err = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert "warning" not in err, err


@needs_ipv6
def test_lab_nodes_with_ros_ip_ipv6_listen_on_ipv6(monkeypatch) -> None:
    monkeypatch.setenv("ROS_IPV6", "on")
    monkeypatch.setenv("ROS_IP", "::1")
    with EmbeddedMaster(host="::1", port=0) as master, Node("/v6_pub", master=master) as pub_node, \
            Node("/v6_sub", master=master) as sub_node:
        assert pub_node.uri.startswith("http://[::1]:")
        assert refused("127.0.0.1", pub_node.tcpros_port)
        pub = pub_node.advertise("/v6", "std_msgs/String", latch=True)
        pub.publish({"data": "over ipv6"})
        sub = sub_node.subscribe("/v6", "std_msgs/String")
        value, info = sub.wait_for_message(timeout=10)
        assert value["data"] == "over ipv6"
        assert info.publisher == "/v6_pub"


@needs_ipv6
def test_rostopic_echo_reaches_a_lab_publisher_over_ipv6(tmp_path) -> None:
    require_ros()
    with EmbeddedMaster(host="::1", port=0) as master:
        env = {**os.environ, "ROS_MASTER_URI": master.uri, "ROS_IPV6": "on", "ROS_IP": "::1"}
        pub = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "topic", "pub", "/v6",
                                "std_msgs/String", "data: hi"], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            renv = ros_env(master.uri, tmp_path)
            renv.pop("ROS_HOSTNAME")
            renv.update(ROS_IPV6="on", ROS_IP="::1")
            echo = subprocess.run(["rostopic", "echo", "-n1", "/v6"], env=renv,
                                  capture_output=True, text=True, timeout=30)
        finally:
            stop_with(pub, signal.SIGTERM)
    assert echo.stdout == 'data: "hi"\n---\n', echo.stderr


def test_topic_echo_timeout_says_it_timed_out(capsys) -> None:
    with EmbeddedMaster(port=0) as master, Node("/silent", master=master) as node:
        node.advertise("/quiet", "std_msgs/String")   # published, but nothing sent
        code = main(["topic", "--master-uri", master.uri, "echo", "/quiet", "-n", "1",
                     "--timeout", "1"])
    assert code == 1
    assert "topic echo: timed out after 1 s: 0 of 1 message(s) arrived on /quiet" in \
        capsys.readouterr().err
