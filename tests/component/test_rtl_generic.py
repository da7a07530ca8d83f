"""``--model rtl`` and ``--timing fpga`` for a generated circuit (issue 28 item 3): the LaserScan
component with its generated top (the ``rtl/`` ``rosfpga-lab generate`` writes) simulated by the
fast harness on the data path.

* ``rosfpga-lab node data/fpga_laserscan_min.yaml --model rtl`` between a lab publisher and a
  lab subscriber on loopback: every output body equals the Python model's output for one input,
  byte for byte, and the refused scan (359 beams) is counted under the walk's status name;
* ``timing="fpga"`` on the fast model: the circuit time the stats give is the RTL's own span of
  the same frame (first byte in to last out, measured by the harness) at ``clock_mhz``, and
  each output is held at least that long;
* the configurations ``--model rtl`` cannot run are refused with a typed error that names them.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.realros import require_rtl
from rosfpga_lab.component import FpgaComponent
from rosfpga_lab.component.errors import ComponentConfigError
from rosfpga_lab.config import load_config
from rosfpga_lab.graph import EmbeddedMaster, Node, call
from rosfpga_lab.hw.msgpipeline import MessagePipeline
from rosfpga_lab.msg import deserialize, serialize
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.sim import design_from_config
from tests.component.test_message import Collector, scan, sliding

DATA = Path(__file__).resolve().parents[2] / "data"
SCAN = DATA / "fpga_laserscan_min.yaml"


def _frame(reg, msg: dict) -> bytes:
    body = serialize(reg, "sensor_msgs/LaserScan", msg)
    return len(body).to_bytes(4, "little") + body


@pytest.mark.rtl
def test_laserscan_node_command_with_the_generated_verilog_is_exact(tmp_path) -> None:
    require_rtl("verilator")
    config = load_config(SCAN)
    reg = config.registry()
    pipe = MessagePipeline.from_config(config)
    good = [scan(k) for k in range(6)]
    with EmbeddedMaster(port=0) as master:
        node = subprocess.Popen(
            [sys.executable, "-m", "rosfpga_lab", "node", str(SCAN), "--master-uri", master.uri,
             "--model", "rtl", "--input-queue", "16", "--output-queue", "16",
             "--status-interval", "0"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
            preexec_fn=interruptible)
        src = Node("/scanner", master=master, registry=reg)
        out = Collector(master, "/scan_min", "sensor_msgs/LaserScan", reg)
        try:
            pub = src.advertise("/scan", "sensor_msgs/LaserScan", queue_size=0)
            deadline = time.monotonic() + 120          # the first run compiles the circuit
            while time.monotonic() < deadline and node.poll() is None:
                subscribers = call(master.uri, "getSystemState", "/t")[2][1]
                if any(t == "/scan_min" and len(n) for t, n in subscribers) and \
                        pub.wait_for_subscribers(1, 0.1):
                    break
                time.sleep(0.1)
            else:
                raise AssertionError(f"the node never came up: {node.communicate(timeout=10)}")
            sent = [good[0], scan(9, n=359), *good[1:]]   # the second: 359 beams, refused
            for msg in sent:
                pub.publish(msg)
                time.sleep(0.02)
            assert out.wait(len(good), 30), node.poll()
            stdout, stderr = stop_with(node, signal.SIGINT)
        finally:
            out.node.shutdown()
            src.shutdown()
            kill_if_running(node)
    assert node.returncode == 0, stderr
    assert len(out.bodies) == len(good)
    for msg, body in zip(good, out.bodies):
        assert body == pipe.process(_frame(reg, msg)).output_frame[4:]      # every byte
        got = np.asarray(deserialize(reg, "sensor_msgs/LaserScan", body)["ranges"])
        assert got.tobytes() == sliding(msg["ranges"], 5, np.min).tobytes()  # numpy's minimum
    assert "(rtl model, host timing)" in stdout
    assert f"published {len(good)}, refused 1" in stdout, stdout
    assert "SUB_BAD_RANGES_LENGTH" in stdout, stdout


@pytest.mark.rtl
@pytest.mark.parametrize("model", ["fast", "rtl"])
def test_fpga_timing_of_a_generated_circuit_is_the_rtl_span_at_its_clock(model) -> None:
    """The fast model's clocks (the walk's cycle model) and the simulated Verilog's agree."""
    require_rtl("verilator")
    from rosfpga_lab.rtl.server import RtlServer

    config = replace(load_config(SCAN), clock_mhz=1.0)    # 1 MHz: a few ms a scan
    reg = config.registry()
    frame = _frame(reg, scan(3))
    with RtlServer(config) as server:
        span = server.process(frame).span                  # the Verilog's clocks, measured
    assert span > len(frame)
    with EmbeddedMaster(port=0) as master:
        comp = FpgaComponent(config, master=master, timing="fpga", output_queue=8,
                             model=model).start()
        src = Node("/scanner", master=master, registry=reg)
        pub = src.advertise("/scan", "sensor_msgs/LaserScan", queue_size=0)
        out = Collector(master, "/scan_min", "sensor_msgs/LaserScan", reg)
        try:
            assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
            pub.publish_body(frame[4:])
            assert out.wait(1, 10)
            st = comp.stats
        finally:
            out.node.shutdown()
            src.shutdown()
            comp.stop()
    assert st.circuit_time_s == pytest.approx(span / 1e6, rel=1e-9), st.report()
    assert st.latency.count == 1 and min(comp.latency_samples()) >= span / 1e6
    assert "timing: fpga" in st.report()


def test_model_rtl_refuses_a_cdr_configuration_and_a_custom_application(tmp_path) -> None:
    cdr = load_config(DATA / "fpga_laserscan_min_cdr.yaml")
    with pytest.raises(ComponentConfigError, match=r"fpga_laserscan_min_cdr.yaml has wire: cdr.*"
                                                   r"--ros2 --model rtl.*wire: tcpros"):
        FpgaComponent(cdr, model="rtl")
    text = SCAN.read_text().replace("application: {op: erode, ksize: 5}",
                                    "application: {op: custom, source: mine.cpp}")
    (tmp_path / "mine.cpp").write_text("// the user's application\n")
    (tmp_path / "custom_scan.yaml").write_text(text)
    custom = load_config(tmp_path / "custom_scan.yaml")
    with pytest.raises(RtlError, match="custom_scan.yaml: application.op is custom.*fast"):
        design_from_config(custom)


@pytest.mark.rtl
def test_rtl_sim_of_generated_tops_is_exact_and_fails_on_a_wrong_byte(
        tmp_path, capsys: pytest.CaptureFixture[str]) -> None:
    """``rosfpga-lab rtl sim CONFIG`` runs the generated top on generate's test frames (TCPROS
    frames or CDR records) and compares with the models; a byte off is a FAIL naming it."""
    from rosfpga_lab.cli import main
    from rosfpga_lab.hls import sample_frames

    sim = require_rtl("iverilog")
    for name in ("fpga_laserscan_min", "fpga_samples_dilate_cdr"):
        assert main(["rtl", "sim", str(DATA / f"{name}.yaml"), "--simulator", sim,
                     "--bp", "300", "--gap", "100"]) == 0
        out = capsys.readouterr().out
        assert "PASS: the output equals the Python models' output" in out, out
        assert out.count(": SUB_OK") == 2 and "clocks" in out, out
    assert "frame at byte 386: SUB_BAD_ENCAPSULATION" in out      # the walk's own status names
    frames, expected = sample_frames(load_config(SCAN))
    wrong = bytearray(expected)
    wrong[100] ^= 1
    (tmp_path / "wrong.bin").write_bytes(bytes(wrong))
    assert main(["rtl", "sim", str(SCAN), "--simulator", sim, "--expected",
                 str(tmp_path / "wrong.bin")]) == 1
    assert "FAIL: the output differs from the expected bytes at byte 100" in capsys.readouterr().out


def test_rtl_sim_of_a_custom_application_is_a_clear_error(tmp_path, capsys) -> None:
    from rosfpga_lab.cli import main

    text = SCAN.read_text().replace("application: {op: erode, ksize: 5}",
                                    "application: {op: custom, source: mine.cpp}")
    (tmp_path / "mine.cpp").write_text("// the user's application\n")
    (tmp_path / "custom_scan.yaml").write_text(text)
    assert main(["rtl", "sim", str(tmp_path / "custom_scan.yaml")]) == 1
    err = capsys.readouterr().err
    assert "rosfpga-lab rtl: error:" in err and "custom_scan.yaml: application.op is custom" in err
    assert "Traceback" not in err


@pytest.mark.rtl
def test_rtl_demo_runs_a_generated_top_with_its_waveform(tmp_path) -> None:
    """``rtl.demo.run_demo`` (notebook 08's run) on the lab_msgs/Samples example: generate's
    three test frames through the generated top with gaps and backpressure, the output the
    models', the refused one by the walk's name, and a readable dump of the streams."""
    from rosfpga_lab.rtl.demo import run_demo
    from rosfpga_lab.rtl.project import model_output
    from rosfpga_lab.hls import sample_frames
    from rosfpga_lab.rtl.vcd import read_vcd

    sim = require_rtl("iverilog")
    config = load_config(DATA / "fpga_samples_dilate.yaml")
    result = run_demo(tmp_path / "demo.vcd", simulator=sim, config=config)
    assert result.output == model_output(config, sample_frames(config)[0])
    assert [name for _, name in result.status] == ["SUB_OK", "SUB_BAD_SAMPLES_LENGTH", "SUB_OK"]
    wave = read_vcd(tmp_path / "demo.vcd", clock="clk", signals=["m_tvalid", "m_tready"])
    handshakes = int(np.sum(wave.values("m_tvalid") & wave.values("m_tready")))
    assert handshakes == len(result.output)
