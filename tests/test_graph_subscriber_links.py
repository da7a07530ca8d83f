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
