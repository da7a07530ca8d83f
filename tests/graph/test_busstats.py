"""``getBusStats`` as rospy and roscpp answer it (issue 23, item 8): a subscriber entry per
publisher link ``[conn_id, bytes, num_msgs, drop_estimate, connected]``, a publisher lists its
open connections only ``[conn_id, bytes, num_sent, connected]``. The shapes are checked against
a real rospy node's answer."""

from __future__ import annotations

import json
import time

from tests.support.realros import run_ros_python
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.graph.xmlrpc import call

MSG = {"data": "hello"}
BODY_BYTES = 4 + len("hello")   # std_msgs/String: uint32 length + the bytes


def wait_until(predicate, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


def links_of(entries: list, topic: str) -> list:
    """The connection entries of ``topic`` in a getBusStats publisher or subscriber list."""
    [links] = [e[-1] for e in entries if e[0] == topic]
    return links


def test_lab_bus_stats_have_rospys_fields_and_drop_closed_connections() -> None:
    with EmbeddedMaster(port=0) as master, Node("/bs_pub", master=master) as p, \
            Node("/bs_sub", master=master) as s:
        pub = p.advertise("/bs", "std_msgs/String")
        sub = s.subscribe("/bs", "std_msgs/String")
        assert pub.wait_for_subscribers(1, 10)
        for _ in range(3):
            pub.publish(MSG)
        assert wait_until(lambda: sub.stats.frames == 3)
        _code, _msg, (spubs, ssubs, _svc) = call(s.uri, "getBusStats", "/t")
        assert not any(t == "/bs" for t, _b, _links in spubs)   # (a node may also publish /rosout)
        [entry] = links_of(ssubs, "/bs")
        conn, nbytes, frames, drops, connected = entry
        assert (nbytes, frames, drops, connected) == (3 * BODY_BYTES, 3, -1, True)
        assert isinstance(conn, int) and conn > 0
        [pentry] = links_of(call(p.uri, "getBusStats", "/t")[2][0], "/bs")
        assert len(pentry) == 4 and pentry[2] == 3 and pentry[3] is True
        s.shutdown()
        # the closed connection leaves the publisher's list, as in rospy and roscpp
        assert wait_until(lambda: links_of(call(p.uri, "getBusStats", "/t")[2][0], "/bs") == [])


ROSPY_STATS = r"""
import json, sys, time, xmlrpc.client
import rospy
from std_msgs.msg import String
rospy.init_node("rospy_bs", anonymous=False, disable_signals=True)
got = []
sub = rospy.Subscriber("/from_lab", String, got.append)
pub = rospy.Publisher("/to_lab", String, queue_size=10)
deadline = time.time() + 20
while len(got) < 2 and time.time() < deadline:
    time.sleep(0.05)
while pub.get_num_connections() < 1 and time.time() < deadline:
    time.sleep(0.05)
for _ in range(2):
    pub.publish(String("hi"))
time.sleep(0.5)
print(json.dumps(xmlrpc.client.ServerProxy(rospy.get_node_uri()).getBusStats("/t")), flush=True)
sys.stdin.readline()   # the test reads the lab's figures while this node is still connected
rospy.signal_shutdown("done")
"""


def test_bus_stats_match_a_real_rospy_nodes_shapes(tmp_path) -> None:
    import subprocess
    import threading

    from rosfpga_lab.graph.realros import ROS_PYTHON, ros_env

    with EmbeddedMaster(port=0) as master, Node("/lab_bs", master=master) as lab:
        run_ros_python("import rospy")   # skips (or fails under CI) without real ROS
        pub = lab.advertise("/from_lab", "std_msgs/String")
        got = []
        lab.subscribe("/to_lab", "std_msgs/String", got.append)
        proc = subprocess.Popen([ROS_PYTHON, "-c", ROSPY_STATS], env=ros_env(master.uri, tmp_path),
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        stop = threading.Event()

        def feed() -> None:
            while not stop.wait(0.2):
                pub.publish(MSG)

        feeder = threading.Thread(target=feed, daemon=True)
        feeder.start()
        try:
            reader = threading.Thread(target=lambda: lines.append(proc.stdout.readline()),
                                      daemon=True)
            lines: list[str] = []
            reader.start()
            reader.join(60)
            stop.set()
            assert lines and lines[0].strip(), proc.stderr.read() if proc.poll() is not None else ""
            assert wait_until(lambda: len(got) == 2)
            lab_stats = call(lab.uri, "getBusStats", "/t")
            _out, err = proc.communicate("\n", timeout=30)
        finally:
            stop.set()
            feeder.join()
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
        assert proc.returncode == 0, err
        out = lines[0]
    code, _msg, (rpubs, rsubs, _rsvc) = json.loads(out.strip().splitlines()[-1])
    assert code == 1
    _c, _m, (lpubs, lsubs, _lsvc) = lab_stats
    # publisher side: [topic, bytes, [[conn_id, bytes, num_sent, connected]]]
    # (rospy also publishes /rosout: compare the topics between the two nodes)
    [rpub] = links_of(rpubs, "/to_lab")
    [lpub] = links_of(lpubs, "/from_lab")
    assert [type(v) for v in rpub] == [type(v) for v in lpub] == [int, int, int, bool]
    # subscriber side: [topic, [[conn_id, bytes, num_msgs, drop_estimate, connected]]]
    [rsub] = links_of(rsubs, "/from_lab")
    [lsub] = links_of(lsubs, "/to_lab")
    assert [type(v) for v in rsub] == [type(v) for v in lsub] == [int, int, int, int, bool]
    assert rsub[3] == lsub[3] == -1 and rsub[4] is lsub[4] is True
    assert lsub[2] == 2 and lsub[1] == 2 * (4 + len("hi"))
