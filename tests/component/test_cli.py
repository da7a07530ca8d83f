"""``rosfpga-lab node``, ``camera``, ``view`` and ``bench``; the camera's image sources."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from rosfpga_lab.cli import main
from rosfpga_lab.component import (
    Camera, ComponentConfigError, FpgaComponent, SourceError, Viewer, open_source, to_rgb,
)
from rosfpga_lab.graph import EmbeddedMaster

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "data" / "fpga_dilate_rgba8.yaml"


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# ------------------------------------------------------------------------------- sources
@pytest.mark.parametrize("encoding,channels", [("rgba8", 4), ("bgra8", 4), ("rgb8", 3),
                                               ("bgr8", 3), ("mono8", 1)])
def test_sources_give_the_size_and_encoding_asked_and_move(encoding, channels) -> None:
    for name in ("synthetic", "grace_hopper"):
        src = open_source(name, 80, 60, encoding, period=10)
        a, b = src.frame(0), src.frame(3)
        assert a.shape == (60, 80, channels) and a.dtype == np.uint8
        assert not np.array_equal(a, b), f"{name} frames should differ"
        assert np.array_equal(src.frame(0), src.frame(10))  # the period
        assert to_rgb(a, encoding).shape == (60, 80, 3)


def test_source_channel_order_follows_the_encoding() -> None:
    rgb = open_source("grace_hopper", 64, 48, "rgb8").frame(2)
    bgr = open_source("grace_hopper", 64, 48, "bgr8").frame(2)
    rgba = open_source("grace_hopper", 64, 48, "rgba8").frame(2)
    assert np.array_equal(rgb, bgr[:, :, ::-1])
    assert np.array_equal(rgba[:, :, :3], rgb) and (rgba[:, :, 3] == 255).all()


def test_file_and_directory_sources(tmp_path) -> None:
    for k, colour in enumerate([(0, 0, 255), (0, 255, 0)]):
        img = np.zeros((30, 40, 3), np.uint8)
        img[:] = colour
        cv2.imwrite(str(tmp_path / f"p{k}.png"), img)
    one = open_source(str(tmp_path / "p0.png"), 20, 10, "rgb8", period=4)
    assert (one.frame(1) == (255, 0, 0)).all()                   # red, in RGB order
    both = open_source(str(tmp_path), 20, 10, "rgb8", period=4)
    assert (both.frame(0) == (255, 0, 0)).all() and (both.frame(3) == (0, 255, 0)).all()


@pytest.mark.parametrize("args,match", [
    (("nope", 10, 10, "rgba8"), "unknown image source"),
    (("synthetic", 10, 10, "yuv422"), "unsupported encoding"),
    (("synthetic", 0, 10, "rgba8"), "width 0"),
])
def test_bad_sources_are_refused(args, match) -> None:
    with pytest.raises(SourceError, match=match):
        open_source(*args)


def test_empty_directory_and_unreadable_file(tmp_path) -> None:
    with pytest.raises(SourceError, match="no .png"):
        open_source(str(tmp_path), 10, 10, "rgba8")
    bad = tmp_path / "x.png"
    bad.write_bytes(b"not a png")
    with pytest.raises(SourceError, match="not an image"):
        open_source(str(bad), 10, 10, "rgba8")


# ------------------------------------------------------------------------------- camera + viewer
def test_camera_rate_and_viewer_saves_pngs(tmp_path) -> None:
    with EmbeddedMaster(port=0) as master:
        viewer = Viewer("/img", save_dir=tmp_path, every=5, master=master)
        cam = Camera("/img", width=64, height=48, encoding="bgr8", rate=50, master=master,
                     source="synthetic")
        try:
            assert cam.publisher.wait_for_subscribers(1, 10)
            t0 = time.monotonic()
            assert cam.run(count=20) == 20
            elapsed = time.monotonic() - t0
            assert viewer.wait_for(20, 10)
        finally:
            cam.stop()
            viewer.stop()
    assert 19 / 50 <= elapsed < 19 / 50 + 5.0          # paced by the schedule (frame k at k / rate), slack for a loaded machine
    assert viewer.received == 20 and not viewer.problems
    assert [p.name for p in viewer.saved] == [f"frame_{k:06d}.png" for k in (0, 5, 10, 15)]
    saved = cv2.imread(str(viewer.saved[1]))             # BGR file == the bgr8 frame 5 sent
    assert np.array_equal(saved, cam.source.frame(5))
    assert viewer.last.header["seq"] == 19 and viewer.last.encoding == "bgr8"
    assert viewer.latency.summary().count == 20


def test_viewer_gives_no_latency_for_a_stamp_that_is_not_wall_clock_time() -> None:
    """A rospy node that leaves header.stamp at 0 (notebook 7 has one): no 55-year latency."""
    from rosfpga_lab.graph import Node

    image = {"header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}, "height": 1,
             "width": 2, "encoding": "mono8", "is_bigendian": 0, "step": 2, "data": b"\x01\x02"}
    with EmbeddedMaster(port=0) as master:
        viewer = Viewer("/img", master=master)
        node = Node("/plain_pub", master=master)
        try:
            pub = node.advertise("/img", "sensor_msgs/Image")
            assert pub.wait_for_subscribers(1, 10)
            pub.publish(image)
            pub.publish({**image, "header": {**image["header"], "stamp": {"secs": int(time.time()),
                                                                           "nsecs": 0}}})
            assert viewer.wait_for(2, 10)
        finally:
            node.shutdown()
            viewer.stop()
    assert viewer.last.latency is not None and 0 <= viewer.last.latency < 5
    assert viewer.latency.summary().count == 1      # the zero stamp left out of the figures


def test_camera_refuses_a_bad_rate() -> None:
    with pytest.raises(SourceError, match="rate"):
        Camera("/img", rate=0)


def test_camera_and_view_commands(tmp_path, capsys) -> None:
    with EmbeddedMaster(port=0) as master:
        results = {}

        def view() -> None:
            results["view"] = main(["view", "/image_raw", "--master-uri", master.uri, "--count",
                                    "10", "--timeout", "20", "--save", str(tmp_path), "--latest"])

        t = threading.Thread(target=view)
        t.start()
        time.sleep(0.5)
        code = main(["camera", "--config", str(CONFIG), "--master-uri", master.uri, "--count",
                     "40", "--rate", "40", "--size", "32x24", "--source", "grace_hopper"])
        t.join(30)
    out = capsys.readouterr().out
    assert code == 0 and results["view"] == 0, out
    assert "publishing grace_hopper 32x24 rgba8 on /image_raw at 40 fps" in out
    assert "sent 40 frames" in out and "received 1" in out  # 10+ frames received
    assert (tmp_path / "latest.png").exists()
    assert cv2.imread(str(tmp_path / "latest.png")).shape == (24, 32, 3)


def test_view_gives_up_with_exit_code_1(capsys) -> None:
    with EmbeddedMaster(port=0) as master:
        code = main(["view", "/nothing", "--master-uri", master.uri, "--count", "1",
                     "--timeout", "0.5"])
    assert code == 1
    assert "only 0 of 1 frames arrived" in capsys.readouterr().err


def test_size_argument_is_checked(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["camera", "--size", "640by480"])
    assert "WIDTHxHEIGHT" in capsys.readouterr().err


@pytest.mark.parametrize("argv,words", [
    (["camera", "--count", "0"], "argument --count: want a number of at least 1, got 0"),
    (["view", "/x", "--every", "0"], "argument --every: want a number of at least 1, got 0"),
    (["view", "/x", "--count", "-1"], "argument --count: want a number of at least 1, got -1"),
    (["view", "/x", "--timeout", "soon"], "argument --timeout: want a number, got 'soon'"),
    (["node", str(CONFIG), "--duration", "-1"], "argument --duration: want a number greater than 0"),
    (["node", str(CONFIG), "--input-queue", "0"], "argument --input-queue: want a number of at least 1"),
    (["node", str(CONFIG), "--status-interval", "-1"], "argument --status-interval: want a number of at least 0"),
    (["demo", "--frames", "0"], "argument --frames: want a number of at least 1, got 0"),
    (["demo", "--scale", "0"], "argument --scale: want a number greater than 0, got 0"),
    (["bench", "--frames", "0"], "argument --frames: want a number of at least 1, got 0"),
    (["bench", "--rounds", "0"], "argument --rounds: want a number of at least 1, got 0"),
])
def test_numbers_out_of_range_are_refused_by_the_parser(argv, words, capsys) -> None:
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert words in capsys.readouterr().err


def test_view_into_an_unwritable_directory_is_a_clear_error(tmp_path, capsys) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with EmbeddedMaster(port=0) as master:
        code = main(["view", "/x", "--save", str(blocker / "out"), "--count", "1", "--timeout", "0.1",
                     "--master-uri", master.uri])
    err = capsys.readouterr().err
    assert code == 1
    assert f"cannot save frames into {blocker / 'out'}" in err and "Traceback" not in err


# ------------------------------------------------------------------------------- node command
def start_node_command(master: EmbeddedMaster, cwd: Path, *options: str) -> subprocess.Popen:
    """``rosfpga-lab node`` on the shipped configuration, once it has subscribed to its input."""
    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "node", str(CONFIG),
                             "--master-uri", master.uri, *options],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd,
                            preexec_fn=interruptible)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and proc.poll() is None:
        subscribers = master.getSystemState("/t")[2][1]
        if any(t == "/image_raw" and "/fpga_dilate" in n for t, n in subscribers):
            return proc
        time.sleep(0.05)
    proc.kill()
    out, err = proc.communicate()
    raise AssertionError(f"the node never subscribed to /image_raw:\n{out}{err}")


def test_node_command_runs_reports_and_stops_on_sigint(tmp_path) -> None:
    with EmbeddedMaster(port=0) as master:
        proc = start_node_command(master, tmp_path, "--status-interval", "0.2")
        try:
            cam = Camera("/image_raw", rate=30, master=master, source="synthetic")
            viewer = Viewer("/image_dilated", master=master, queue_size=20)
            try:
                assert cam.publisher.wait_for_subscribers(1, 10)
                assert viewer.subscriber.wait_for_connection(1, 10)
                for sent in range(1, 16):  # in lock step: the report's counts, not the load, decide
                    cam.publish_one()
                    assert viewer.wait_for(sent, timeout=20), f"frame {sent} never came out"
            finally:
                cam.stop()
                viewer.stop()
            out, err = stop_with(proc, signal.SIGINT)
        finally:
            kill_if_running(proc)
        state = master.getSystemState("/t")[2]
    assert proc.returncode == 0, err
    assert "/image_raw -> dilate (fast model, host timing) -> /image_dilated" in out
    assert "data path: fast model; timing: host" in out
    assert "frames: received 15, processed 15, published 15, refused 0, dropped 0" in out
    assert "cycles per stage (last frame): interpreter 1,228,8" in out
    assert "FIFO high water: rx 1" in out
    assert "latency since capture (input header.stamp -> publish): median" in out
    assert "over 15 frames" in out
    # it unregistered on the way out
    assert not any("/fpga_dilate" in n for _t, n in state[0] + state[1])


def test_node_command_stops_cleanly_on_sigterm(tmp_path) -> None:
    """SIGTERM (what a service manager or a hub sends) ends the node as Ctrl-C does: report
    printed, unregistered, exit 0."""
    with EmbeddedMaster(port=0) as master:
        proc = start_node_command(master, tmp_path, "--quiet")
        out, err = stop_with(proc, signal.SIGTERM)
        state = master.getSystemState("/t")[2]
    assert proc.returncode == 0, err
    assert "frames: received 0, processed 0, published 0" in out
    assert not any("/fpga_dilate" in n for _t, n in state[0] + state[1])


def test_node_command_without_a_master_says_what_to_do(capsys) -> None:
    """It waits for the master as rospy nodes do (issue 23, item 8), saying so once;
    --duration bounds the wait."""
    uri = f"http://127.0.0.1:{free_port()}/"
    assert main(["node", str(CONFIG), "--master-uri", uri, "--duration", "1.2"]) == 1
    err = capsys.readouterr().err
    assert err.count(f"no ROS master answers at {uri} yet; waiting for it") == 1
    assert "--embedded-master" in err and "no ROS master answered" in err


def test_node_command_embedded_master_and_duration(capsys) -> None:
    uri = f"http://127.0.0.1:{free_port()}/"
    t0 = time.monotonic()
    assert main(["node", str(CONFIG), "--master-uri", uri, "--embedded-master",
                 "--duration", "1", "-q"]) == 0
    assert time.monotonic() - t0 < 10
    out = capsys.readouterr()
    assert "started the embedded master at " + uri in out.err
    assert "frames: received 0" in out.out


def test_node_command_follows_ros_master_uri_like_every_ros_node(monkeypatch, capsys) -> None:
    with EmbeddedMaster(port=0) as master:
        monkeypatch.setenv("ROS_MASTER_URI", master.uri)   # the config says :11311
        assert main(["node", str(CONFIG), "--duration", "0.3", "-q"]) == 0
    assert f"master {master.uri}" in capsys.readouterr().out


def test_node_command_bad_config(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("node: {name: /x}\n")
    assert main(["node", str(bad)]) == 1
    assert "bad.yaml" in capsys.readouterr().err


def test_component_refuses_non_image_topics() -> None:
    """The loader refuses this already; the component checks again for hand-built configs."""
    import dataclasses

    from rosfpga_lab.config import TopicConfig, load_config

    cfg = dataclasses.replace(load_config(CONFIG), subscriber=TopicConfig("/a", "std_msgs/String"))
    with pytest.raises(ComponentConfigError, match="sensor_msgs/Image only"):
        FpgaComponent(cfg)


# ------------------------------------------------------------------------------- bench (smoke)
def test_bench_runs_and_checks_outputs(capsys) -> None:
    """Not a timing test: the bench runs end to end and the component's outputs are right."""
    code = main(["bench", "--config", str(ROOT / "data" / "fpga_passthrough_rgb8.yaml"),
                 "--middles", "direct,component", "--frames", "20", "--rate-frames", "10",
                 "--rate", "50", "--rounds", "1", "-q"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "model's output equals OpenCV's: yes" in out
    rows = [line for line in out.splitlines() if line.startswith("| FPGA component")]
    assert len(rows) == 1 and "10/10 at 50/s" in rows[0]
    checked = rows[0].rstrip(" |").rsplit("|", 1)[1].strip()
    good, total = (int(v) for v in checked.split("/"))
    assert total > 0 and good == total
    assert main(["bench", "--middles", "nonsense"]) == 2



def test_camera_and_view_without_a_master_say_what_to_do(capsys) -> None:
    uri = f"http://127.0.0.1:{free_port()}/"
    assert main(["camera", "--master-uri", uri, "--count", "1"]) == 1
    assert main(["view", "/x", "--master-uri", uri, "--count", "1"]) == 1
    err = capsys.readouterr().err
    assert err.count(f"no ROS master answers at {uri}") == 2 and "rosfpga-lab master" in err


def test_node_ros2_with_the_rtl_model_and_no_verilog_says_why(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--ros2 --model rtl`` runs the generated CDR top (tests/component/test_ros2_rtl.py); an
    application in the user's C++ has no Verilog: it stops before any socket, saying so."""
    scan = Path(__file__).resolve().parents[2] / "data" / "fpga_laserscan_min_cdr.yaml"
    text = scan.read_text().replace("application: {op: erode, ksize: 5}",
                                    "application: {op: custom, source: mine.cpp}")
    (tmp_path / "mine.cpp").write_text("// the user's application\n")
    (tmp_path / "custom_scan.yaml").write_text(text)
    assert main(["node", str(tmp_path / "custom_scan.yaml"), "--ros2", "--model", "rtl",
                 "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert "rosfpga-lab node: error:" in err and "(--model rtl)" in err, err
    assert "custom_scan.yaml: application.op is custom" in err and "Traceback" not in err
