"""``rosfpga-lab demo`` as a test: the teacher's headless check, and the checker's own teeth."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.proctools import interruptible, kill_if_running, stop_with
from rosfpga_lab.cli import main
from rosfpga_lab.component import ComponentConfigError, run_demo

DATA = Path(__file__).resolve().parents[2] / "data"


def test_demo_command_passes_bit_exact(tmp_path, capsys) -> None:
    png = tmp_path / "demo.png"
    # a queue as deep as the run: a loaded machine may be slower than the camera, and this test
    # checks the summary's counts, not the machine (drops are test_a_slow_circuit_drops_...)
    code = main(["demo", "--frames", "45", "--input-queue", "45", "--output", str(png),
                 "--scale", "0.5"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "bit-exact: 45/45" in out
    assert "frames: sent 45, received 45" in out
    assert "fps:" in out and "latency camera -> component -> checker: median" in out
    figure = cv2.imread(str(png))
    assert figure is not None and figure.shape[1] > 3 * 320 and figure.shape[0] > 240


def test_demo_as_a_separate_process_exits_zero(tmp_path) -> None:
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "demo", "--frames", "10",
                           "--source", "synthetic", "--no-figure", "--input-queue", "10"],
                          capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "bit-exact: 10/10" in proc.stdout


def test_demo_with_another_config_erode_mono8(tmp_path) -> None:
    result = run_demo(DATA / "fpga_erode_mono8.yaml", frames=10, rate=60, source="synthetic",
                      png=tmp_path / "erode.png", input_queue=10)
    assert result.ok, "\n".join(result.lines())
    assert result.check.bit_exact == 10 and result.component.cycles["application"] > 0
    assert (tmp_path / "erode.png").exists()


def test_checker_catches_a_wrong_circuit(tmp_path) -> None:
    """Negative control: checked against erode, the dilating component must fail every frame."""
    result = run_demo(frames=5, rate=60, source="synthetic", png=tmp_path / "bad.png",
                      oracle_op="erode", input_queue=5)
    assert not result.ok
    assert result.received == 5 and result.check.bit_exact == 0
    assert all("differ from OpenCV's cv2.erode" in m for m in result.check.mismatches)
    assert "bit-exact: 0/5" in "\n".join(result.lines())
    src, got, want = result.check.first_bad
    assert not np.array_equal(got, want)


def test_demo_rejects_bad_arguments(capsys) -> None:
    with pytest.raises(SystemExit) as info:
        main(["demo", "--frames", "0"])
    assert info.value.code == 2
    assert main(["demo", "--source", "/no/such/picture.png", "--frames", "1", "--no-figure"]) == 1
    assert "unknown image source" in capsys.readouterr().err
    assert main(["demo", "--frames", "1", "--output", "demo.jpg"]) == 1
    assert "the figure is a PNG: give a file name ending in .png, not demo.jpg" in capsys.readouterr().err


def test_demo_with_the_reference_model_checks_every_frame() -> None:
    result = run_demo(DATA / "fpga_passthrough_rgb8.yaml", frames=3, rate=30, source="synthetic",
                      png=None, model="reference")
    assert result.ok, "\n".join(result.lines())
    assert result.component.dropped == 0 and result.check.bit_exact == 3
    assert "circuit: passthrough on 160x120 rgb8" in result.lines()[0]


def test_a_slow_circuit_drops_frames_and_the_demo_counts_them() -> None:
    """The reference model (some 40 ms a 160x120 frame here, so at 30 frames/s it kept up on an
    idle machine) behind a one-frame queue, a camera at 200 frames/s: the queue keeps the newest
    frame and drops the rest, as a ROS queue does. The verdict holds (every output bit-exact,
    every frame accounted for), the summary says why, and the demo ends once every frame is
    accounted for, not at its 30 s time-out (it waited for the dropped frames' outputs)."""
    from dataclasses import replace

    start = time.monotonic()
    result = run_demo(DATA / "fpga_passthrough_rgb8.yaml", frames=8, rate=200, source="synthetic",
                      png=None, model="reference", input_queue=1)
    assert time.monotonic() - start < 15
    dropped = result.component.dropped
    lines = "\n".join(result.lines())
    assert dropped > 0 and result.received + dropped == result.sent == 8, lines
    assert result.ok and result.lost == 0, lines
    assert f"bit-exact: {result.received}/{result.received}" in lines
    assert f"dropped {dropped} of 8: the circuit model was slower than the camera" in lines
    vanished = replace(result, received=result.received - 1)   # an output that never came
    assert vanished.lost == 1 and not vanished.ok
    assert "lost 1 of 8: sent, never came back, and not dropped by the component" in \
        "\n".join(vanished.lines())


def test_demo_input_queue_is_checked(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["demo", "--input-queue", "0"])
    assert "argument --input-queue: want a number of at least 1, got 0" in capsys.readouterr().err
    with pytest.raises(ComponentConfigError, match="input_queue must be at least 1, not 0"):
        run_demo(frames=1, png=None, input_queue=0)


def test_demo_rig_runs_in_the_background_for_a_live_view() -> None:
    import threading

    from rosfpga_lab.component import DemoRig

    before = {t.ident for t in threading.enumerate()}
    seen = []
    with DemoRig(DATA / "fpga_erode_mono8.yaml", rate=50, source="synthetic") as rig:
        rig.component.add_observer(lambda rec: seen.append((rec.ok, rec.output_image.shape)))
        rig.start_camera()
        assert rig.checker.wait_for(10, 10)
        assert rig.checker.report.bit_exact == rig.checker.report.received >= 10
    assert seen[:3] == [(True, (240, 320, 1))] * 3
    time.sleep(0.1)
    assert [t.name for t in threading.enumerate() if t.ident not in before and t.is_alive()] == []


def test_demo_interrupted_says_so_and_exits_130(tmp_path) -> None:
    import signal

    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "demo", "--frames", "1000",
                             "--source", "synthetic", "--no-figure", "-v"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                            preexec_fn=interruptible)
    try:
        for line in proc.stdout:                     # wait until the camera runs
            if line.startswith("camera:"):
                break
        _out, err = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 130
    assert "rosfpga-lab demo: interrupted" in err and "Traceback" not in err


def test_demo_view_serves_a_live_page_while_it_runs(tmp_path) -> None:
    """``demo --view``: the printed URL serves the page, a frame image and counters on
    loopback while the demo runs, and nothing after it ended."""
    import json
    import re
    import urllib.error
    import urllib.request

    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "demo", "--view", "--frames", "45",
                             "--rate", "15", "--source", "synthetic", "--no-figure"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
    try:
        first = proc.stdout.readline()
        found = re.match(r"live view: (http://127\.0\.0\.1:\d+/) ", first)
        assert found, first
        url = found[1]
        with urllib.request.urlopen(url, timeout=5) as resp:
            page = resp.read().decode()
        assert "<img id=\"input\"" in page and "<img id=\"output\"" in page
        assert not re.search(r"(src|href)=\"https?://", page), "the page loads nothing from elsewhere"
        deadline = time.monotonic() + 20
        stats = {}
        while time.monotonic() < deadline:
            with urllib.request.urlopen(url + "stats.json", timeout=5) as resp:
                stats = json.loads(resp.read())
            if stats["frame"] > 0:
                break
            time.sleep(0.2)
        assert stats["frame"] > 0 and stats["sent"] > 0, stats
        with urllib.request.urlopen(url + "frame/output.jpg", timeout=5) as resp:
            jpeg = resp.read()
        picture = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert picture is not None and picture.shape[:2] == (480, 640)
        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(url + "etc/passwd", timeout=5)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, out
    assert "bit-exact: 45/45" in out
    with pytest.raises(OSError):   # the page stopped with the demo
        urllib.request.urlopen(url, timeout=2)
