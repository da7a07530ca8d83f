"""``rosfpga-lab msg``: show, md5, list and layout, including error exits."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from rosfpga_lab.cli import main


def run(capsys: pytest.CaptureFixture, *argv: str) -> tuple[int, str, str]:
    code = main(["msg", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_md5_lines(capsys: pytest.CaptureFixture) -> None:
    code, out, err = run(capsys, "md5", "sensor_msgs/Image", "std_msgs/Header", "String")
    assert code == 0 and err == ""
    assert out == ("sensor_msgs/Image 060021388200f6f0f447d0fcd9c64743\n"
                   "std_msgs/Header 2176decaecbce78abc3b96ef049fabed\n"
                   "String 992ce8a1687cec8c8bd883ec73ca41d1\n")


def test_md5_unknown_type_exits_1(capsys: pytest.CaptureFixture) -> None:
    code, out, err = run(capsys, "md5", "std_msgs/String", "nav_msgs/Odometry")
    assert code == 1
    assert out == "std_msgs/String 992ce8a1687cec8c8bd883ec73ca41d1\n"
    assert "unknown message type 'nav_msgs/Odometry'" in err and "--msg-path" in err


def test_msg_path(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    pkg = tmp_path / "ws" / "my_msgs" / "msg"
    pkg.mkdir(parents=True)
    (pkg / "Frame.msg").write_text("# a camera frame\nHeader header\nuint8[] data  # pixels\n")
    code, out, _ = run(capsys, "md5", "--msg-path", str(tmp_path / "ws"), "my_msgs/Frame")
    assert code == 0
    # same fields as genmsg would hash: "<Header md5> header\nuint8[] data"
    import hashlib
    expected = hashlib.md5(b"2176decaecbce78abc3b96ef049fabed header\nuint8[] data").hexdigest()
    assert out == f"my_msgs/Frame {expected}\n"
    code, out, _ = run(capsys, "show", "--msg-path", str(pkg.parent), "my_msgs/Frame")
    assert code == 0 and "# a camera frame\nHeader header\nuint8[] data  # pixels\n" in out


def test_malformed_msg_path_file(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    pkg = tmp_path / "p" / "msg"
    pkg.mkdir(parents=True)
    (pkg / "Bad.msg").write_text("int32 a\nint32[ b\n")
    code, _, err = run(capsys, "md5", "--msg-path", str(tmp_path), "p/Bad")
    assert code == 1 and f"{pkg / 'Bad.msg'}:2:" in err


def test_show(capsys: pytest.CaptureFixture) -> None:
    code, out, _ = run(capsys, "show", "sensor_msgs/Image")
    assert code == 0
    assert "# md5: 060021388200f6f0f447d0fcd9c64743" in out
    assert "std_msgs/Header header\n  uint32 seq\n  time stamp\n  string frame_id\nuint32 height\n" in out
    assert "MSG: std_msgs/Header" in out
    code, out, _ = run(capsys, "show", "--no-full-text", "sensor_msgs/NavSatStatus")
    assert "int8 STATUS_NO_FIX=-1\n" in out and "MSG:" not in out and "full text" not in out


def test_show_unknown(capsys: pytest.CaptureFixture) -> None:
    code, _, err = run(capsys, "show", "Nope")
    assert code == 1 and "unknown message type 'Nope'" in err


def test_list(capsys: pytest.CaptureFixture) -> None:
    code, out, _ = run(capsys, "list", "sensor_msgs")
    assert code == 0 and len(out.splitlines()) == 27 and "sensor_msgs/Image\n" in out
    code, out, _ = run(capsys, "list")
    assert len(out.splitlines()) == 92   # std 32, sensor 27, geometry 29, rosgraph_msgs 3, roscpp 1
    code, _, err = run(capsys, "list", "nav_msgs")
    assert code == 1 and "no package 'nav_msgs'" in err


def test_layout(capsys: pytest.CaptureFixture, tmp_path: Path) -> None:
    code, out, _ = run(capsys, "layout", "std_msgs/String", "--hex", "02000000 6869")
    assert code == 0
    assert out.splitlines()[1:] == ["     0     4  length  uint32  data  2",
                                    "     4     2  value   string  data  'hi'"]
    framed = tmp_path / "frame.bin"
    framed.write_bytes(b"\x06\x00\x00\x00\x02\x00\x00\x00hi")
    code, out2, _ = run(capsys, "layout", "std_msgs/String", "--file", str(framed), "--skip", "4")
    assert code == 0 and out2 == out
    code, out, err = run(capsys, "layout", "std_msgs/String", "--hex", "0900000061")
    assert code == 1 and "error" in out and "declares 9 byte(s)" in err
    code, _, err = run(capsys, "layout", "std_msgs/String", "--hex", "zz")
    assert code == 1 and "--hex" in err


def test_module_entry_point() -> None:
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "msg", "md5", "geometry_msgs/Pose"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "geometry_msgs/Pose e45d45a5a1ce597b249e23fb30fc871f\n"


def test_bench_script_prints_a_table() -> None:
    from rosfpga_lab.msg import bench

    table = bench.run(repeat=1)
    assert "Image 640x480 rgba8" in table and "PoseArray 1000 poses" in table
    assert "1228848" in table  # body size of the 640x480 rgba8 image with frame_id 'camera'
