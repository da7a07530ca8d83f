"""A subscriber keeps a live publisher link until it fails (issue 23, item 19).

A spoofed ``publisherUpdate`` with an empty publisher list (the ROSPenTo attack) made a lab
subscriber close its only link and go silent; rospy keeps receiving. Now a connected link that
the list no longer names is kept until its connection ends, which is what a publisher that
really unregisters does; then it is not retried.
"""

from __future__ import annotations

import threading
import time

import pytest

from rosfpga_lab.graph import EmbeddedMaster, Node, call

pytestmark = pytest.mark.timeout(60)


def test_spoofed_empty_publisher_update_keeps_the_live_link_until_the_publisher_unregisters() -> None:
    with EmbeddedMaster(port=0) as m:
        talker, listener = Node("/talker", master=m), Node("/listener", master=m)
        stop = threading.Event()
        try:
            pub = talker.advertise("/chatter", "std_msgs/String")
            got: list[str] = []
            sub = listener.subscribe("/chatter", "std_msgs/String", lambda v: got.append(v["data"]))
            assert sub.wait_for_connection(1, 10)

            def loop() -> None:
                while not stop.wait(0.02):
                    pub.publish({"data": "hi"})

            threading.Thread(target=loop, daemon=True).start()
            sub.wait_for_message(10)
            # the attacker's call, as any host that reaches the listener's XML-RPC port can make it
            assert call(listener.uri, "publisherUpdate", "/master", "/chatter", [])[0] == 1
            time.sleep(0.3)
            before = len(got)
            sub.wait_for_message(5)
            time.sleep(0.3)
            assert len(got) > before + 3          # still receiving
            assert sub.get_num_connections() == 1 and sub.publisher_links() == [(talker.uri, True)]
            # the publisher really unregisters: it closes the connection, the link ends, no retry
            stop.set()
            pub.unregister()
            deadline = time.monotonic() + 10
            while sub.publisher_links() and time.monotonic() < deadline:
                time.sleep(0.05)
            assert sub.publisher_links() == [] and sub.get_num_connections() == 0
        finally:
            stop.set()
            talker.shutdown()
            listener.shutdown()


ROSPY_LISTENER = r'''
import sys, time, rospy
from std_msgs.msg import String
got = []
rospy.init_node("rospy_listener", disable_signals=True)
rospy.Subscriber("/chatter", String, lambda m: got.append(time.monotonic()))
print("READY", flush=True)
sys.stdin.readline()              # the test has sent the spoofed publisherUpdate
t = time.monotonic()
time.sleep(1.0)
print("AFTER", sum(1 for g in got if g > t), flush=True)
rospy.signal_shutdown("done")
'''


@pytest.mark.ros
def test_rospy_and_the_lab_both_keep_receiving_after_the_spoof(tmp_path) -> None:
    """The same attack on a rospy subscriber and a lab subscriber: both keep receiving."""
    import subprocess

    from tests.support.realros import ROS_PYTHON, require_ros, ros_env, stop_process

    require_ros()
    with EmbeddedMaster(port=0) as m:
        talker, listener = Node("/talker", master=m), Node("/listener", master=m)
        stop = threading.Event()
        rospy_node = subprocess.Popen([ROS_PYTHON, "-c", ROSPY_LISTENER], env=ros_env(m.uri, tmp_path),
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            pub = talker.advertise("/chatter", "std_msgs/String")
            got: list[float] = []
            sub = listener.subscribe("/chatter", "std_msgs/String", lambda v: got.append(time.monotonic()))
            assert rospy_node.stdout.readline().strip() == "READY"
            deadline = time.monotonic() + 20
            while pub.get_num_connections() < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert pub.get_num_connections() == 2

            def loop() -> None:
                while not stop.wait(0.02):
                    pub.publish({"data": "hi"})

            threading.Thread(target=loop, daemon=True).start()
            rospy_uri = call(m.uri, "lookupNode", "/test", "/rospy_listener")[2]
            for uri in (rospy_uri, listener.uri):
                assert call(uri, "publisherUpdate", "/master", "/chatter", [])[0] == 1
            t = time.monotonic()
            rospy_node.stdin.write("go\n")
            rospy_node.stdin.flush()
            words = rospy_node.stdout.readline().split()
            assert words[0] == "AFTER" and int(words[1]) > 10            # rospy kept receiving
            assert sum(1 for g in got if g > t) > 10 and sub.get_num_connections() == 1   # so does the lab
        finally:
            stop.set()
            stop_process(rospy_node)
            talker.shutdown()
            listener.shutdown()
