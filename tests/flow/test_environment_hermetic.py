"""The suite passes whatever ``ROS_*`` variables the caller's shell holds (issue 29): many ROS
users export ``ROS_HOSTNAME``, ``ROS_IP``, ``ROS_MASTER_URI`` or ``ROS_NAMESPACE`` in their
``.bashrc``. ``conftest.py`` clears them (and the other variables it names) unless a test sets
them; this test runs a sample of the suite in a shell that holds them."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import CALLER_NAMES, CALLER_PREFIXES

HERE = Path(__file__).resolve().parents[1]

#: What a ROS user's shell plausibly holds; each one changed a result of the sample before
#: conftest cleared it (ROS_HOSTNAME beats the ROS_IP=::1 of graph/test_ipv6.py, the master
#: and namespace change which graph a node joins and what it is called).
USER_SHELL = {
    "ROS_HOSTNAME": "127.0.0.1",
    "ROS_IP": "192.168.1.20",
    "ROS_MASTER_URI": "http://localhost:11311/",
    "ROS_NAMESPACE": "/robot1",
    "ROS_DOMAIN_ID": "7",
}

#: Tests whose results depend on those variables when they leak in.
SAMPLE = [
    "graph/test_ipv6.py",
    "graph/test_master.py",
    "graph/test_node.py",
    "config/test_rosargs.py",
    "component/test_cli.py::test_node_command_runs_reports_and_stops_on_sigint",
]


def test_the_user_shell_covers_what_conftest_clears() -> None:
    assert all(name.startswith(CALLER_PREFIXES) for name in USER_SHELL)
    assert "ROSFPGA_REQUIRE_ROS" not in CALLER_NAMES   # CI's requirements stay in force


def test_inside_a_test_the_callers_ros_variables_are_gone() -> None:
    assert [k for k in os.environ if k.startswith(CALLER_PREFIXES) or k in CALLER_NAMES] == []


def test_a_variable_a_test_sets_is_seen(monkeypatch: pytest.MonkeyPatch) -> None:
    from rosfpga_lab.config.master import master_uri_from_env

    monkeypatch.setenv("ROS_MASTER_URI", "http://127.0.0.2:11311/")
    assert master_uri_from_env() == "http://127.0.0.2:11311/"


def test_a_sample_of_the_suite_passes_in_a_ros_users_shell(tmp_path: Path) -> None:
    env = {**os.environ, **USER_SHELL}
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--durations=1",
         "--rootdir", str(HERE.parent),
         *(str(HERE / test) for test in SAMPLE)],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert " passed" in run.stdout and " failed" not in run.stdout, run.stdout[-2000:]
