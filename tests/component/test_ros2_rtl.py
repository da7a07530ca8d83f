"""``model="rtl"`` on ROS 2 (issue 28 item 3): the generated CDR top of
``data/fpga_laserscan_min_cdr.yaml`` simulated by Verilator's fast harness on the live node's data
path, between real Cyclone DDS peers (PyPI ``cyclonedds``) on loopback.

Every output is compared with numpy (a 5-beam minimum over ``ranges``) and with the CDR model
(``hw.CdrPipeline`` on the payload as Cyclone serializes it), never with the RTL's own output;
with ``timing="fpga"`` the clocks each sample was held for are the generated walk's
(``hls.program.frame_clocks``, first byte in to last out). Skips without cyclonedds or
Verilator; fails under ROSFPGA_REQUIRE_WIRE / ROSFPGA_REQUIRE_RTL (CI).
"""

from __future__ import annotations

import signal
import struct
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.config import load_config
from rosfpga_lab.hls.generic import spec_from_config
from rosfpga_lab.hls.program import frame_clocks
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from tests.support.generictools import window_oracle
from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.realros import require_rtl
from tests.support.ros2tools import DOMAIN, cyclone, qos, wait

pytestmark = [pytest.mark.timeout(120), pytest.mark.rtl]

SCAN_CDR = Path(__file__).resolve().parents[2] / "data" / "fpga_laserscan_min_cdr.yaml"
#: Values a float32 minimum must get right: signed zeros, infinities, NaN.
SPECIALS = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1.0, 2.5, 29.5], np.float32)


def _scans(T: Any, n: int, bad_at: int | None = None) -> list[Any]:
    """``n`` Cyclone LaserScan samples of 360 beams (the configuration's stream length); the one
    at ``bad_at`` claims range_max 1000.5, over the configuration's bound (refused)."""
    rng = np.random.default_rng(28)
    out = []
    for k in range(n):
        ranges = rng.choice(SPECIALS, 360) if k % 2 else rng.uniform(0.1, 30, 360)
        header = T.Header_(T.Time_(100 + k, k), "laser" if k % 2 else "l" * 64)
        out.append(T.LaserScan_(header, -1.5, 1.5, 0.01, 0.0, 0.1, 0.05,
                                1000.5 if k == bad_at else 30.0,
                                [float(r) for r in np.asarray(ranges, np.float32)],
                                [float(i) for i in range(k * 7 % 12)]))
    return out


def _f32(values: Any) -> bytes:
    return np.asarray(values, np.float32).tobytes()


def _assert_exact(T: Any, sent: Any, got: Any, pipe: CdrPipeline) -> None:
    """``got`` (what the reader took) is ``sent`` with its ranges eroded over 5 beams (numpy) and
    equals the CDR model's output for ``sent``, field for field, bit for bit."""
    assert _f32(got.ranges) == window_oracle(_f32(sent.ranges), "<f4", 5, "erode")
    want = T.LaserScan_.deserialize(pipe.process(sent.serialize()))
    for name in ("angle_min", "angle_max", "angle_increment", "time_increment", "scan_time",
                 "range_min", "range_max"):
        assert _f32(getattr(got, name)) == _f32(getattr(want, name)), name
    assert _f32(got.ranges) == _f32(want.ranges)
    assert _f32(got.intensities) == _f32(want.intensities) == _f32(sent.intensities)
    assert got.header == want.header == sent.header


def _record(payload: bytes) -> bytes:
    return struct.pack("<I", len(payload)) + payload


@pytest.mark.parametrize("model", ["rtl", "fast"])
def test_ros2_node_with_the_generated_cdr_verilog_serves_cyclone_exactly(
        model: str, caplog: pytest.LogCaptureFixture) -> None:
    """Five scans from a Cyclone writer (the third refused: range_max over its bound, logged by
    the walk's status name or the model's field) through the component to a Cyclone reader; with
    timing fpga at 1 MHz each output waits its clocks."""
    if model == "rtl":
        require_rtl("verilator")
    dds = cyclone()
    from tests.support import cdrtypes as T

    domain = (DOMAIN + (53 if model == "rtl" else 59)) % 233
    config = replace(load_config(SCAN_CDR), clock_mhz=1.0)     # 1 MHz: a few ms a scan
    sent = _scans(T, 5, bad_at=2)
    got: list = []
    with Ros2Component(config, domain=domain, model=model, timing="fpga") as comp:
        dp = dds.DomainParticipant(domain)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/scan", T.LaserScan_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/scan_min", T.LaserScan_), qos=qos(dds))
        assert comp.wait_for_peers(10), comp.notes()
        assert wait(lambda: writer.get_matched_subscriptions() and reader.get_matched_publications())
        for msg in sent:
            writer.write(msg)
        assert comp.wait_for(len(sent), 30), (comp.counts, comp.notes())
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= 4, 20), len(got)
        assert comp.counts == {"seen": 5, "published": 4, "refused": 1}
        clocks, latencies = list(comp.clocks), list(comp.latencies)
        assert (comp._rtl is not None) == (model == "rtl")      # the Verilog ran, or not
    refusals = [r.getMessage() for r in caplog.records if "refused sample" in r.getMessage()]
    assert len(refusals) == 1 and "range_max" in refusals[0], refusals
    if model == "rtl":
        assert "(SUB_BAD_RANGE_MAX): bad range_max" in refusals[0], refusals
    good = [m for k, m in enumerate(sent) if k != 2]
    pipe = CdrPipeline(load_config(SCAN_CDR))
    for msg, out in zip(good, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    program = spec_from_config(config).program
    walk = [frame_clocks(program, _record(m.serialize())).total for m in good]
    assert clocks == walk

    assert all(lat >= c / 1e6 * 0.999 for lat, c in zip(latencies, clocks, strict=True))


def test_node_command_ros2_model_rtl_serves_cyclone_peers(tmp_path: Path) -> None:
    """``rosfpga-lab node data/fpga_laserscan_min_cdr.yaml --ros2 --model rtl``: a reliable
    Cyclone writer's scans come out of the simulated Verilog exact, to a Cyclone reader; Ctrl-C
    stops it with a summary that counts them."""
    require_rtl("verilator")
    dds = cyclone()
    from tests.support import cdrtypes as T

    domain = (DOMAIN + 61) % 233
    import os

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    node = subprocess.Popen(
        [sys.executable, "-m", "rosfpga_lab", "node", str(SCAN_CDR), "--ros2", "--model", "rtl",
         "--domain", str(domain), "--duration", "90", "--status-interval", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
        preexec_fn=interruptible)
    sent = _scans(T, 3)
    got: list = []
    try:
        dp = dds.DomainParticipant(domain)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/scan", T.LaserScan_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/scan_min", T.LaserScan_), qos=qos(dds))
        # the first run compiles the circuit (seconds) before the node joins the graph
        assert wait(lambda: (writer.get_matched_subscriptions()
                             and reader.get_matched_publications()) or node.poll() is not None,
                    60) and node.poll() is None, node.communicate(timeout=10)
        for msg in sent:
            writer.write(msg)
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= 3, 30), len(got)
        stdout, stderr = stop_with(node, signal.SIGINT)
    finally:
        kill_if_running(node)
    assert node.returncode == 0, stderr
    assert "(rtl CDR circuit model, host timing)" in stdout, stdout
    assert "3 samples seen, 3 published, 0 refused" in stdout, stdout
    pipe = CdrPipeline(load_config(SCAN_CDR))
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
