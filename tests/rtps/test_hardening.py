"""A hostile participant against the lab's running ROS 2 component, while Cyclone DDS peers use
it: spoofed SPDP floods, garbage, ACKNACK storms with the real reader's GUID, absurd fragment
counts. The frames keep coming through exact, and every table stays within its limit."""

from __future__ import annotations

import os
import random
import socket
import threading
import time

import cv2
import numpy as np
import pytest

from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.config import parse_config
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.limits import MAX_NOTES, MAX_PENDING_BYTES, MAX_REMOTE_PARTICIPANTS
from rosfpga_lab.rtps.participant import SPDP_READER, SPDP_WRITER
from tests.support.ros2tools import DOMAIN, cyclone, image, qos, wait

pytestmark = pytest.mark.timeout(60)

CONFIG = """\
node: {name: /fpga_hard}
subscriber: {topic: /cam, type: sensor_msgs/Image}
publisher: {topic: /cam_out, type: sensor_msgs/Image}
image: {width: 32, height: 16, encoding: rgba8}
application: {op: dilate, ksize: 3}
"""


def test_hostile_participant_cannot_crash_stall_or_bloat_the_node() -> None:
    dds = cyclone()
    domain = (DOMAIN + 13) % 233
    with Ros2Component(parse_config(CONFIG), domain=domain) as comp:
        dp = dds.DomainParticipant(domain)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds))
        assert comp.wait_for_peers(10)
        assert wait(lambda: writer.get_matched_subscriptions() and reader.get_matched_publications())
        part = comp.node.participant if comp.node else None
        assert part is not None
        cyclone_prefix = next(iter(part.participants))
        reader_key = next(iter(part.local[comp._pub.writer_id].proxies)) if comp._pub else None
        assert reader_key is not None
        stop = threading.Event()
        sent = [0]

        def attack() -> None:
            rng = random.Random(5)
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            meta, user = part.meta, part.user
            k = 0
            while not stop.is_set() and k < 20000:
                k += 1
                prefix = bytes(rng.randrange(256) for _ in range(12))
                kind = k % 5
                if kind == 0:     # SPDP flood from new participants, pointing at a dead port
                    payload = b.spdp_payload(prefix, b.Locator("127.0.0.1", 9), b.Locator("127.0.0.1", 9),
                                             300.0, "evil", b"", domain)
                    dg = b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)
                    dst = meta
                elif kind == 1:   # spoofed SPDP claiming Cyclone's GUID
                    payload = b.spdp_payload(cyclone_prefix, b.Locator("127.0.0.1", 9),
                                             b.Locator("127.0.0.1", 9), 0.1, "evil", b"", domain)
                    dg = b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)
                    dst = meta
                elif kind == 2:   # ACKNACK storm in the name of the real reader
                    dg = b.header(reader_key[0]) + b.acknack(reader_key[1], comp._pub.writer_id, 1,
                                                             range(1, 200), 1000 + k)
                    dst = user
                elif kind == 3:   # absurd fragments in the name of Cyclone's writer
                    dg = b.header(cyclone_prefix) + b.data_frag(
                        0, 0x103, 10_000 + k, 1, 1, 60_000_000, os.urandom(64), 65535)
                    dst = user
                else:             # garbage
                    dg = b"RTPS\x02\x03" + os.urandom(rng.randrange(0, 300))
                    dst = user
                s.sendto(dg, dst)
                sent[0] += 1
                if k % 200 == 0:
                    time.sleep(0.001)
            s.close()

        t = threading.Thread(target=attack, daemon=True)
        t.start()
        pics = [np.random.default_rng(k).integers(0, 256, (16, 32, 4), dtype=np.uint8) for k in range(5)]
        for k, px in enumerate(pics):
            writer.write(image(dds, px, "rgba8", sec=k))
            time.sleep(0.05)
        got: list = []
        ok = wait(lambda: got.extend(reader.take(10)) or len(got) >= 5, 20)
        stop.set()
        t.join(10)
        assert ok, (len(got), comp.counts, comp.notes()[:10])
        assert sent[0] > 1000
        for k, s in enumerate(got[:5]):
            out = np.frombuffer(bytes(s.data), np.uint8).reshape(16, 32, 4)
            assert s.header.stamp.sec == k
            assert np.array_equal(out, cv2.dilate(pics[k], np.ones((3, 3), np.uint8)))
        assert len(part.participants) <= MAX_REMOTE_PARTICIPANTS
        assert cyclone_prefix in part.participants           # the spoof did not replace it
        assert part.assembler.held <= MAX_PENDING_BYTES
        assert len(part.notes) <= MAX_NOTES + 1 and len(part.counts) <= MAX_NOTES + 1
