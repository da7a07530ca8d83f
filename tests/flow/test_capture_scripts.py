"""The capture scripts in data/ rerun: fresh captures of real ROS 1 and of Cyclone DDS.

They need root (dumpcap on loopback), tshark, and real ROS 1 + g++ or cyclonedds; without them
they skip with a reason, and in CI (ROSFPGA_REQUIRE_WIRE=1, as root) they run.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.graph.capture_read import DATA_DIR, trace_from_capture
from rosfpga_lab.msg import default_registry, deserialize
from tests.support.wiretools import assert_rtps_agrees_with_tshark, require_capture, require_cyclonedds

pytestmark = [pytest.mark.slow, pytest.mark.timeout(240)]


def test_ros1_capture_script_reruns(tmp_path: Path, real_ros: None, cxx: None) -> None:
    require_capture()
    out = tmp_path / "ros1.pcapng"
    run = subprocess.run([sys.executable, str(DATA_DIR / "capture_ros1_image.py"), "--out", str(out)],
                         capture_output=True, text=True, timeout=200)
    assert run.returncode == 0, run.stderr[-2000:]
    conv = trace_from_capture(out).conversation()
    methods = {e.method for e in conv if e.kind == "xmlrpc"}
    assert {"registerPublisher", "registerSubscriber", "publisherUpdate", "requestTopic"} <= methods
    frames = [e for e in conv if e.kind == "tcpros_frame"]
    assert len(frames) == 4
    for k, e in enumerate(frames):
        img = deserialize(default_registry(), "sensor_msgs/Image", e.raw[4:])
        expected = (np.arange(64 * 48 * 3) * 3 + k * 40) % 256
        assert np.array_equal(img["data"], expected.astype(np.uint8))


def test_rtps_capture_script_reruns(tmp_path: Path) -> None:
    require_capture()
    require_cyclonedds()
    out = tmp_path / "rtps.pcapng"
    run = subprocess.run([sys.executable, str(DATA_DIR / "capture_rtps_image.py"), "--out", str(out)],
                         capture_output=True, text=True, timeout=200)
    assert run.returncode == 0, run.stderr[-2000:]
    assert assert_rtps_agrees_with_tshark(out) > 0


def test_cyclone_sedp_dispose_capture_script_reruns(tmp_path: Path) -> None:
    require_cyclonedds()
    from tests.support.ros2tools import DOMAIN

    out = tmp_path / "dispose.pcapng"
    run = subprocess.run([sys.executable, str(DATA_DIR / "capture_cyclone_sedp_dispose.py"),
                          "--domain", str((DOMAIN + 3) % 233), "-o", str(out)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr[-2000:]
    from rosfpga_lab.graph.capture_read import udp_datagrams
    from rosfpga_lab.rtps import Data, parse_message

    last = parse_message(udp_datagrams(out)[-1][3]).submessages
    assert any(isinstance(s, Data) and s.key and s.inline_qos for s in last)
