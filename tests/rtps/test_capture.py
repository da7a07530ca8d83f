"""tshark's RTPS dissector reads a capture of the lab's participant talking to Cyclone DDS:
no malformed packet, the submessages the lab sent, and the lab's decoder agrees with tshark
on every datagram. Needs root (dumpcap on loopback), tshark and cyclonedds; in CI
(ROSFPGA_REQUIRE_WIRE=1, as root) it runs."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.config import parse_config
from rosfpga_lab.rtps.participant import discovery_port, user_port
from tests.support.ros2tools import DOMAIN, cyclone, image, qos, wait
from tests.support.wiretools import assert_rtps_agrees_with_tshark, require_capture, tshark_fields

pytestmark = pytest.mark.timeout(120)

CONFIG = """\
node: {name: /fpga_cap}
subscriber: {topic: /cam, type: sensor_msgs/Image}
publisher: {topic: /cam_out, type: sensor_msgs/Image}
image: {width: 320, height: 240, encoding: rgba8}
application: {op: dilate, ksize: 3}
"""


def test_tshark_reads_the_lab_participant_with_no_malformed_packet(tmp_path: Path) -> None:
    dumpcap = require_capture()
    dds = cyclone()
    cap_file = tmp_path / "lab_ros2.pcapng"
    lo, hi = discovery_port(DOMAIN, 0), user_port(DOMAIN, 9)
    cap = subprocess.Popen([dumpcap, "-q", "-i", "lo", "-f", f"udp portrange {lo}-{hi}",
                            "-w", str(cap_file)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        time.sleep(1.0)
        with Ros2Component(parse_config(CONFIG), domain=DOMAIN) as comp:
            dp = dds.DomainParticipant(DOMAIN)
            writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
            reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds))
            assert comp.wait_for_peers(10)
            assert wait(lambda: writer.get_matched_subscriptions() and reader.get_matched_publications())
            pixels = np.random.default_rng(0).integers(0, 256, (240, 320, 4), dtype=np.uint8)
            for k in range(2):                   # 307 kB samples: DATA_FRAG both ways
                writer.write(image(dds, pixels, "rgba8", sec=k))
            got: list = []
            assert wait(lambda: got.extend(reader.take(10)) or len(got) >= 2, 20)
            prefix = comp.node.participant.guid_prefix if comp.node else b""
            time.sleep(0.5)
        time.sleep(0.5)
    finally:
        cap.terminate()
        cap.wait(timeout=10)
    malformed = tshark_fields(cap_file, ["frame.number"], display_filter="_ws.malformed")
    assert malformed == [], f"{len(malformed)} malformed packets"
    rows = tshark_fields(cap_file, ["rtps.sm.id"],
                         display_filter=f"rtps.guidPrefix.src == {prefix.hex(':')}")
    ids = {i for row in rows for i in row[0].split("|")}
    # SPDP/SEDP/user DATA, DATA_FRAG, HEARTBEAT, ACKNACK, INFO_DST, INFO_TS, as the lab sent them
    assert {"0x15", "0x16", "0x07", "0x06", "0x0e", "0x09"} <= ids, ids
    assert assert_rtps_agrees_with_tshark(cap_file) > 100
