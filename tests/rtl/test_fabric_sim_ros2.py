"""``rosfpga-lab fabric sim data/fpga_laserscan_min_cdr.yaml`` (issue 31 item 3) against a real
DDS peer: the whole network-attached top (LiteEth GMII, RTPS, the generated CDR circuit) in
Verilator, bridged by the shim to UDP ports on 127.0.0.1, and a PyPI Cyclone DDS participant
configured as rmw_cyclonedds_cpp is for a loopback graph (the lab's ``cyclone_loopback_uri``,
with MaxMessageSize one frame's payload: the circuit reassembles no IP fragments) that
publishes sensor_msgs/LaserScan on rt/scan and subscribes to rt/scan_min, both with ROS 2's
default QoS (RELIABLE, KEEP_LAST 10, VOLATILE).

Discovery is the circuit's own (its SPDP, SEDP and answers from its ROMs; the bridge only sets
its one peer's ports from the peer's SPDP and pulses send_sedp). Every output is compared with
numpy (a 5-beam minimum over ``ranges``) and with the lab's CDR model, never with the circuit's
own output. The scans go out 0.3 s apart (a scanner's rate): back to back at line rate, the
circuit's 2 KB receive buffer overflows (counted), see the report in item 3's notes. Domain 230
for the model's ports (a build per domain; cached after the first, some 15-50 s).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rosfpga_lab.component.fabricsim import fabric_peer_uri
from rosfpga_lab.config import load_config
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.rtl.discrom import render_rom
from rosfpga_lab.rtl.fabricsim import build_fabric_sim
from tests.component.test_ros2_rtl import SCAN_CDR, _assert_exact, _scans
from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.ros2tools import cyclone, qos, wait
from tests.support.rtltools import require_verilator

pytestmark = [pytest.mark.rtl, pytest.mark.timeout(300)]

DOMAIN = 230
SCANS = 3


def _start_cli(tmp_path: Path) -> tuple[subprocess.Popen, list[str]]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.Popen(
        [sys.executable, "-m", "rosfpga_lab", "fabric", "sim", str(SCAN_CDR), "--shim",
         "--domain", str(DOMAIN), "--seconds", "60"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
        preexec_fn=interruptible)
    lines: list[str] = []

    def pump() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line)

    threading.Thread(target=pump, daemon=True).start()
    return proc, lines


def test_cyclone_talks_to_the_simulated_fabric_and_gets_exact_scans(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    require_verilator()
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", fabric_peer_uri())
    from tests.support import cdrtypes as T

    config = load_config(SCAN_CDR)
    start = time.monotonic()
    build = build_fabric_sim(config, render_rom(config, domain=DOMAIN))   # the CLI's, cached
    print(f"build {build.seconds:.1f} s (0: cached), {time.monotonic() - start:.1f} s")
    proc, lines = _start_cli(tmp_path)
    got: list = []
    sent = _scans(T, SCANS)
    try:
        assert wait(lambda: any(x.startswith("ready:") for x in lines) or proc.poll() is not None,
                    60) and proc.poll() is None, "".join(lines)
        t0 = time.monotonic()
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/scan", T.LaserScan_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/scan_min", T.LaserScan_), qos=qos(dds))
        assert wait(lambda: writer.get_matched_subscriptions()
                    and reader.get_matched_publications(), 15), "".join(lines)
        matched = time.monotonic() - t0
        for msg in sent:
            writer.write(msg)
            time.sleep(0.3)
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= SCANS, 15), \
            (len(got), "".join(lines))
        print(f"matched after {matched:.2f} s, {SCANS} scans back after "
              f"{time.monotonic() - t0:.2f} s")
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, "".join(lines)
    print(stdout)
    pipe = CdrPipeline(config)
    for msg, out in zip(sent, got, strict=True):
        _assert_exact(T, msg, out, pipe)
    counters = dict(kv.rsplit(" ", 1) for kv in
                    next(x for x in stdout.splitlines() if x.startswith("circuit: "))
                    [len("circuit: "):].split(", "))
    assert (counters["samples"], counters["rx_error"], counters["rx_overflow"],
            counters["tx_overflow"]) == (str(SCANS), "0", "0", "0"), stdout
    assert "bridge: peers learned: 1;" in stdout, stdout
