"""The library's real-ROS helpers (rosfpga_lab.graph.realros): the probe, the environment, and
per-user scratch folders (a second user of a course server must not trip over the first one's)."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from rosfpga_lab.graph import realros

MODULE_FILE = Path(realros.__file__)
OTHER_UID = 65534   # "nobody" on Debian


def test_a_missing_tool_is_the_reason_whatever_else_is_installed(monkeypatch: pytest.MonkeyPatch):
    """Notebook 7 on a student's machine: no rostopic on PATH and a system Python without rospy.
    The reason must be the missing program, the same on every machine (cheapest check first)."""
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent))
    assert realros.ros_missing(tools=["rostopic"], python=sys.executable) == "rostopic is not on PATH"
    assert realros.ros_missing(tools=["rostopic"], python="/nonexistent/python3") == \
        "rostopic is not on PATH"


def test_the_interpreter_and_its_modules_are_probed(tmp_path: Path):
    assert realros.ros_missing(python=str(tmp_path / "python3")) == f"{tmp_path / 'python3'} not found"
    reason = realros.ros_missing(python=sys.executable, modules=["json", "no_such_module_rosfpga"])
    assert reason is not None and "cannot import json, no_such_module_rosfpga" in reason
    assert "ModuleNotFoundError" in reason and "python3-rospy" in reason
    assert realros.ros_missing(python=sys.executable, modules=["json"]) is None


def test_ros_env_is_loopback_and_keeps_no_lab_python_variables(monkeypatch: pytest.MonkeyPatch,
                                                               tmp_path: Path):
    monkeypatch.setenv("PYTHONPATH", "/lab/only")
    monkeypatch.setenv("ROS_IP", "10.1.2.3")
    env = realros.ros_env("http://127.0.0.1:1234/", tmp_path)
    assert env["ROS_MASTER_URI"] == "http://127.0.0.1:1234/" and env["ROS_HOSTNAME"] == "127.0.0.1"
    assert env["ROS_HOME"] == str(tmp_path)
    assert "PYTHONPATH" not in env and "ROS_IP" not in env


def test_scratch_folders_are_per_user_and_private(monkeypatch: pytest.MonkeyPatch, tmp_path: Path):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    home = realros.user_temp_dir("ros-home")
    assert home == tmp_path / f"rosfpga-lab-{os.getuid()}" / "ros-home"
    assert realros.ros_env("http://127.0.0.1:1/")["ROS_HOME"] == str(home)
    for folder in (home, home.parent):
        st = folder.stat()
        assert st.st_uid == os.getuid() and stat.S_IMODE(st.st_mode) == 0o700
    assert realros.user_temp_dir("ros-home") == home   # the same folder every time
    with pytest.raises(ValueError):
        realros.user_temp_dir("../elsewhere")


def test_a_planted_link_is_not_followed(monkeypatch: pytest.MonkeyPatch, tmp_path: Path):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    target = tmp_path / "someone-elses"
    target.mkdir()
    (tmp_path / f"rosfpga-lab-{os.getuid()}").symlink_to(target)
    home = realros.user_temp_dir("ros-home")
    assert target not in home.parents and home.is_dir()
    assert stat.S_IMODE(home.stat().st_mode) == 0o700 and not list(target.iterdir())


def _needs_root_and_setpriv() -> None:
    if os.geteuid() != 0:
        pytest.skip("needs root to act as a second user (CI runs as root)")
    if shutil.which("setpriv") is None or not Path("/usr/bin/python3").exists():
        pytest.skip("needs setpriv (util-linux) and /usr/bin/python3 to run as a second user")


def test_a_folder_made_by_another_user_is_not_used(monkeypatch: pytest.MonkeyPatch, tmp_path: Path):
    _needs_root_and_setpriv()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    theirs = tmp_path / f"rosfpga-lab-{os.getuid()}"
    theirs.mkdir(mode=0o777)
    os.chown(theirs, OTHER_UID, OTHER_UID)
    home = realros.user_temp_dir("ros-home")
    assert theirs not in home.parents and home.stat().st_uid == 0


def test_two_users_of_one_machine_each_get_a_writable_ros_home():
    """The course-server case: root (the first user) ran the lab, then user 'nobody' runs it.
    With one fixed ROS_HOME under the temp dir, the second user could not write its logs."""
    _needs_root_and_setpriv()
    shared_tmp = Path(tempfile.mkdtemp(prefix="rosfpga-two-users-"))
    try:
        shared_tmp.chmod(0o1777)   # like /tmp
        script = (
            "import importlib.util, os, sys, tempfile\n"
            f"tempfile.tempdir = {str(shared_tmp)!r}\n"
            f"spec = importlib.util.spec_from_file_location('realros', {str(MODULE_FILE)!r})\n"
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
            "home = m.ros_env('http://127.0.0.1:1/')['ROS_HOME']\n"
            "open(os.path.join(home, 'log-of-' + str(os.getuid())), 'w').write('ok')\n"
            "print(home)\n")
        homes = []
        for user in ([], ["setpriv", "--reuid", str(OTHER_UID), "--regid", str(OTHER_UID),
                          "--clear-groups"]):
            done = subprocess.run([*user, "/usr/bin/python3", "-c", script], capture_output=True,
                                  text=True, timeout=60, cwd="/")
            assert done.returncode == 0, done.stderr
            homes.append(done.stdout.strip())
        assert homes[0] != homes[1]
        assert Path(homes[1], f"log-of-{OTHER_UID}").read_text() == "ok"
    finally:
        shutil.rmtree(shared_tmp, ignore_errors=True)
