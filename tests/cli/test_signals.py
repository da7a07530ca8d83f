"""Every lab command that registers with a master unregisters on SIGINT and SIGTERM (issue 23,
items 3, 8, 9): ``topic pub/hz/echo``, ``camera``, ``view`` and ``node``, stopped by SIGTERM (what
``timeout``, ``kill``, systemd and container stops send) and by SIGINT when started with SIGINT
ignored (a shell's background job, ``cmd &``), on the lab's master and on Debian's rosmaster.
The signal tests find the command's node as the one that appears on the master.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.realros import real_rosmaster
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.xmlrpc import call

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "data" / "fpga_dilate_rgba8.yaml"

TOOLS = {
    "pub": ["topic", "pub", "/sig_chatter", "std_msgs/String", "data: hi"],
    "hz": ["topic", "hz", "/sig_chatter"],
    "echo": ["topic", "echo", "/sig_chatter"],
    "camera": ["camera", "--size", "16x8", "--rate", "5", "--topic", "/sig_image"],
    "view": ["view", "/sig_image"],
    "node": ["node", str(CONFIG), "-q"],
}


def ignore_sigint() -> None:
    """What a shell does to a background job (``cmd &``): SIGINT ignored, inherited by exec."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def nodes_of(uri: str, *, beside_rosout: bool = False) -> set[str]:
    """Nodes the master lists; with ``beside_rosout`` only those with a topic other than
    ``/rosout`` (every lab node advertises ``/rosout`` first, before its own topics)."""
    pubs, subs, _srvs = call(uri, "getSystemState", "/t")[2]
    return {n for t, names in pubs + subs for n in names if not (beside_rosout and t == "/rosout")}


def wait_for_entry(uri: str, kind: int, entry: list, timeout: float = 10.0) -> list:
    """getSystemState's publishers (0) or subscribers (1) once ``entry`` is among them (or at
    the time-out)."""
    deadline = time.monotonic() + timeout
    while True:
        entries = call(uri, "getSystemState", "/t")[2][kind]
        if entry in entries or time.monotonic() > deadline:
            return entries
        time.sleep(0.05)


def start_registered(uri: str, argv: list[str], name: str = "", *, background: bool,
                     env: dict[str, str] | None = None, expect: str = "") -> tuple[subprocess.Popen, str]:
    """Start ``rosfpga-lab ARGV`` (with ``__name:=NAME`` when a name is given) and wait until the
    master lists a new node (``expect``, else ``/NAME``, else any new one); return the process
    and that node's name. The master comes from ROS_MASTER_URI only, so the signal tests do not
    depend on the ROS command line."""
    before = nodes_of(uri)
    expect = expect or (f"/{name}" if name else "")
    proc = subprocess.Popen(
        [sys.executable, "-m", "rosfpga_lab", *argv, *([f"__name:={name}"] if name else [])],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "ROS_MASTER_URI": uri, **(env or {})},
        preexec_fn=ignore_sigint if background else interruptible)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and proc.poll() is None:
        new = nodes_of(uri, beside_rosout=True) - before
        if (expect in new) if expect else new:
            return proc, expect or sorted(new)[0]
        time.sleep(0.05)
    kill_if_running(proc)
    out, err = proc.communicate()
    raise AssertionError(f"{argv} never registered as {expect or 'a new node'}:\n{out}{err}")


def stop_and_check(uri: str, proc: subprocess.Popen, node: str, sig: int) -> None:
    out, err = stop_with(proc, sig)
    assert proc.returncode == 0, f"rc {proc.returncode}\n{out}\n{err}"
    assert node not in nodes_of(uri), f"{node} stayed registered:\n{err}"


@pytest.fixture
def lab_master():
    with EmbeddedMaster(port=0) as master, \
            Node("/sig_source", master=master) as source:
        source.advertise("/sig_chatter", "std_msgs/String", latch=True).publish({"data": "x"})
        yield master.uri


@pytest.mark.parametrize("how", ["sigterm", "sigint_ignored_at_start"])
@pytest.mark.parametrize("tool", list(TOOLS))
def test_each_tool_unregisters_on_the_lab_master(lab_master, tool, how) -> None:
    background = how != "sigterm"
    proc, node = start_registered(lab_master, TOOLS[tool], background=background)
    stop_and_check(lab_master, proc, node, signal.SIGINT if background else signal.SIGTERM)


@pytest.mark.parametrize("tool", ["pub", "camera", "node"])
def test_tools_unregister_on_sigterm_on_real_rosmaster(tmp_path, tool) -> None:
    with real_rosmaster(tmp_path) as uri:
        proc, node = start_registered(uri, TOOLS[tool], background=True)
        stop_and_check(uri, proc, node, signal.SIGTERM)


def test_node_command_waits_for_a_master_that_comes_later(tmp_path) -> None:
    """A launch order race: the component starts first, says once that it waits, and registers
    as soon as the master answers (rospy and roscpp do the same); before, it exited with 1."""
    from tests.support.realros import free_port

    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    log = tmp_path / "stderr"       # (a file, read while the node runs: it said it waits)
    with log.open("w") as stderr:
        proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "node", str(CONFIG), "-q",
                                 "--master-uri", uri], stdout=subprocess.PIPE,
                                stderr=stderr, text=True, preexec_fn=interruptible)
    try:
        # the master comes only once the node said it waits (a fixed sleep lost the race on a
        # loaded machine, where the node's start-up alone took longer)
        deadline = time.monotonic() + 60
        while ("waiting for it and trying again" not in log.read_text()
               and proc.poll() is None and time.monotonic() < deadline):
            time.sleep(0.05)
        assert proc.poll() is None, (proc.communicate(), log.read_text())
        with EmbeddedMaster(port=port) as master:
            deadline = time.monotonic() + 20
            while "/fpga_dilate" not in nodes_of(master.uri) and time.monotonic() < deadline:
                time.sleep(0.05)
            assert "/fpga_dilate" in nodes_of(master.uri)
            stop_with(proc, signal.SIGTERM)
    finally:
        kill_if_running(proc)
    err = log.read_text()
    assert proc.returncode == 0, err
    assert err.count("waiting for it and trying again") == 1, err
    assert f"the ROS master at {uri} answers now" in err


def test_node_command_exits_0_after_rosnode_kill(lab_master) -> None:
    """A slave-API shutdown (rosnode kill) ends the component normally, as rospy nodes
    (exit status 0; it was 1)."""
    proc, _node = start_registered(lab_master, TOOLS["node"], "killed", background=False)
    try:
        node_uri = call(lab_master, "lookupNode", "/t", "/killed")[2]
        assert call(node_uri, "shutdown", "/rosnode", "kill")[0] == 1
        out, err = proc.communicate(timeout=20)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, err
    assert "shut down from outside (remote shutdown by /rosnode: kill" in err
    assert "/killed" not in nodes_of(lab_master)


def test_node_command_takes_remaps_name_and_namespace(lab_master, tmp_path) -> None:
    """``node CONFIG image_raw:=/cam/image __name:=foo __log:=...`` under ROS_NAMESPACE (what
    roslaunch runs for ``<node ns="ns1" name="foo"><remap .../></node>``); before: argparse
    refused it with rc 2, and a relative config name ignored ROS_NAMESPACE."""
    cfg = tmp_path / "rel.yaml"
    cfg.write_text(CONFIG.read_text().replace("name: /fpga_dilate", "name: fpga_dilate")
                   .replace("topic: /image_dilated", "topic: image_dilated"))
    argv = ["node", str(cfg), "-q", "/image_raw:=/cam/image", f"__log:={tmp_path}/foo.log"]
    proc, _node = start_registered(lab_master, argv, "foo", background=False,
                            env={"ROS_NAMESPACE": "ns1"}, expect="/ns1/foo")
    try:
        subs = wait_for_entry(lab_master, 1, ["/cam/image", ["/ns1/foo"]])
        pubs = wait_for_entry(lab_master, 0, ["/ns1/image_dilated", ["/ns1/foo"]])
    finally:
        out, err = stop_with(proc, signal.SIGINT)
    assert ["/cam/image", ["/ns1/foo"]] in subs, subs
    assert ["/ns1/image_dilated", ["/ns1/foo"]] in pubs, pubs
    assert proc.returncode == 0, err


@pytest.mark.parametrize("argv,expect,topic,kind", [
    (["camera", "--size", "16x8", "--rate", "5", "--topic", "image", "image:=cam/raw"],
     "/ns2/cam", "/ns2/cam/raw", 0),
    (["view", "image", "image:=/elsewhere"], "/ns2/cam", "/elsewhere", 1),
    (["topic", "hz", "chatter"], "/ns2/cam", "/ns2/chatter", 1),
])
def test_camera_view_and_topic_take_names_from_the_ros_command_line(lab_master, argv, expect,
                                                                    topic, kind) -> None:
    """Relative names land in ROS_NAMESPACE, remappings apply, __name names the node (before:
    argparse refused the ROS words)."""
    proc, _node = start_registered(lab_master, argv, "cam", background=False,
                                   env={"ROS_NAMESPACE": "ns2"}, expect=expect)
    try:
        entries = wait_for_entry(lab_master, kind, [topic, [expect]])
    finally:
        stop_with(proc, signal.SIGTERM)
    assert [topic, [expect]] in entries, entries


def test_stop_signals_hold_a_signal_while_registering_and_restore_the_old_handlers() -> None:
    from rosfpga_lab.cli._signals import StopSignals, deliver_held

    before = signal.getsignal(signal.SIGTERM)
    with StopSignals() as stop:
        with stop.holding(deliver=False):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)            # the handler ran here, and raised nothing
        assert stop.fired == signal.SIGTERM
        with pytest.raises(KeyboardInterrupt):
            deliver_held()
        deliver_held()                  # delivered once only
    assert signal.getsignal(signal.SIGTERM) == before
    with pytest.raises(KeyboardInterrupt), StopSignals() as stop:
        with stop.holding():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
        raise AssertionError("holding() should have raised at its end")
