"""Every lab node registers again after a master restart and says so once (issue 23, item 18):
a library ``Node`` (what the camera, the checker and a notebook's graph are built on) against
the lab's master restarted in this process, and against Debian's rosmaster restarted.
"""

from __future__ import annotations

import logging
import subprocess
import time
from pathlib import Path

import pytest

from tests.support.realros import free_port, require_ros, ros_env, stop_process, wait_for_master
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.xmlrpc import call


def wait_for(pred, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.05)
    return pred()


def restarted_lines(caplog: pytest.LogCaptureFixture, name: str) -> list[str]:
    return [r.getMessage() for r in caplog.records
            if r.getMessage().startswith(f"{name}: the master") and "registered again" in r.getMessage()]


def test_library_nodes_register_again_after_a_restart(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger="rosfpga_lab")
    port = free_port()
    first = EmbeddedMaster(port=port).start()
    try:
        talker = Node("/restart_talker", master_uri=first.uri)
        listener = Node("/restart_listener", master_uri=first.uri)
        pub = talker.advertise("/restart_t", "std_msgs/String")
        sub = listener.subscribe("/restart_t", "std_msgs/String")
        assert talker.logging_ready.wait(5) and listener.logging_ready.wait(5)
        first.stop()
        second = EmbeddedMaster(port=port).start()
        try:
            assert wait_for(lambda: "/restart_talker" in second.publishers.get("/restart_t", {})
                            and "/restart_listener" in second.subscribers.get("/restart_t", {})
                            and "/restart_talker/get_loggers" in second.services)
            time.sleep(2.5)   # more checks pass: the node is known now, nothing more is said
            assert len(restarted_lines(caplog, "/restart_talker")) == 1
            assert len(restarted_lines(caplog, "/restart_listener")) == 1
            pub.publish({"data": "after"})
            assert sub.wait_for_message(5)[0] == {"data": "after"}
            talker.shutdown()
            listener.shutdown()
            assert second.nodes == {}
        finally:
            second.stop()
    finally:
        first.stop()


def test_a_node_registers_again_with_a_restarted_rosmaster(tmp_path: Path,
                                                         caplog: pytest.LogCaptureFixture) -> None:
    require_ros()
    caplog.set_level(logging.WARNING, logger="rosfpga_lab")
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"

    def rosmaster() -> subprocess.Popen:
        proc = subprocess.Popen(["rosmaster", "--core", "-p", str(port), "-w", "2"],
                                env=ros_env(uri, tmp_path), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        wait_for_master(uri)
        return proc

    proc = rosmaster()
    try:
        with Node("/restart_cam", master_uri=uri) as node:
            node.advertise("/image_raw", "sensor_msgs/Image")
            assert node.logging_ready.wait(10)
            stop_process(proc)
            proc = rosmaster()

            def known() -> bool:
                state = call(uri, "getSystemState", "/probe")[2]
                return ["/image_raw", ["/restart_cam"]] in state[0]

            assert wait_for(known, 15)
            assert len(restarted_lines(caplog, "/restart_cam")) == 1
    finally:
        stop_process(proc)
