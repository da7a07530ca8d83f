"""Helpers for tests that check the lab against real ROS 1 Noetic (Debian's packages).

Debian's rospy, genpy and rosmaster run under the system interpreter ``/usr/bin/python3``, not
the lab's virtual environment, so every real ROS program is started as a subprocess; the
interpreter, the environment and the "is it installed" probe come from the library
(:mod:`rosfpga_lab.graph.realros`, shared with the bench and notebook 7). On a
machine without ROS, those tests skip with a one-line reason; with ``ROSFPGA_REQUIRE_ROS=1``
(set by ``.ci/run`` under CI) the same situation is a failure, so CI can never skip them.

Everything here talks to loopback addresses only and cleans up what it starts.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

from rosfpga_lab.graph.realros import ROS_PYTHON, import_problem, ros_env, ros_missing, user_temp_dir

HERE = Path(__file__).resolve().parents[1]
ROS_PROGRAMS = HERE / "ros_programs"
ROSCPP_LIBS = [
    "-lroscpp", "-lrosconsole", "-lroscpp_serialization", "-lrostime",
    "-lxmlrpcpp", "-lcpp_common", "-lboost_system",
]


def _required(variable: str) -> bool:
    return os.environ.get(variable, "") not in ("", "0", "false", "no")


def skip_or_fail(reason: str, variable: str) -> None:
    """Skip with ``reason``, or fail when ``variable`` says the tool is mandatory (CI)."""
    if _required(variable):
        pytest.fail(f"{reason} (and {variable}=1 says it must be there)", pytrace=False)
    pytest.skip(reason)


@functools.cache
def ros_missing_reason() -> str | None:
    """Why real ROS 1 cannot be used here, or None when it can (the library's probe, plus rosmaster)."""
    reason = ros_missing(tools=("rosmaster",))
    return None if reason is None else f"real ROS 1 not installed: {reason}"


def require_ros() -> None:
    """Skip (or fail under CI) unless real ROS 1 is usable."""
    reason = ros_missing_reason()
    if reason:
        skip_or_fail(reason, "ROSFPGA_REQUIRE_ROS")


@functools.cache
def ros2_missing_reason() -> str | None:
    """Why real ROS 2 Jazzy (rclpy on Fast DDS, the ``[ros2]`` extra's PyPI wheels) cannot be
    used here, or None when it can. Probed in a subprocess of this Python: rclpy is never
    imported into the test process."""
    reason = import_problem(sys.executable, ("rclpy", "sensor_msgs.msg"),
                            "pip install -e '.[ros2]'; wheels for Linux x86_64 only")
    return None if reason is None else f"real ROS 2 (rclpy) not usable: {reason}"


def require_ros2() -> None:
    """Skip (or fail under CI: ROSFPGA_REQUIRE_ROS2=1) unless rclpy imports in this Python."""
    reason = ros2_missing_reason()
    if reason:
        skip_or_fail(reason, "ROSFPGA_REQUIRE_ROS2")


@functools.cache
def cxx_missing_reason() -> str | None:
    """Why no C++ compiler can be used here, or None when g++ is there."""
    return None if shutil.which("g++") else "no C++ compiler (g++) on this machine"


def require_cxx() -> None:
    """Skip (or fail under CI) unless g++ is usable."""
    reason = cxx_missing_reason()
    if reason:
        skip_or_fail(reason, "ROSFPGA_REQUIRE_CXX")


def require_rtl(simulator: str | None = None) -> str:
    """Skip (or fail under CI: ROSFPGA_REQUIRE_RTL=1) unless a Verilog simulator is usable.

    Args:
        simulator: ``"iverilog"`` or ``"verilator"``; None: the first installed.

    Returns:
        The simulator's name.
    """
    from rosfpga_lab.rtl import find_simulator, simulator_missing_reason

    reason = simulator_missing_reason(simulator)
    if reason:
        skip_or_fail(reason, "ROSFPGA_REQUIRE_RTL")
    return find_simulator(simulator)


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_for_master(uri: str, timeout: float = 20.0) -> None:
    """Block until the master at ``uri`` answers getUri, or raise TimeoutError."""
    deadline = time.monotonic() + timeout
    last: Exception | None = None
    while time.monotonic() < deadline:
        try:
            code, _msg, _val = xmlrpc.client.ServerProxy(uri).getUri("/rosfpga_lab_test")
            if code == 1:
                return
        except (OSError, xmlrpc.client.Error) as exc:
            last = exc
        time.sleep(0.1)
    raise TimeoutError(f"master at {uri} did not answer within {timeout} s: {last}")


def stop_process(proc: subprocess.Popen, timeout: float = 5.0) -> None:
    """Terminate ``proc`` (SIGTERM, then SIGKILL) and reap it."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout)


def wait_line(proc: subprocess.Popen, word: bytes, timeout: float) -> None:
    """Block until ``proc`` prints the line ``word`` on stdout; stop it and fail otherwise."""
    found = threading.Event()

    def reader() -> None:
        for line in proc.stdout:  # type: ignore[union-attr]
            if line.strip() == word:
                found.set()
                return

    threading.Thread(target=reader, daemon=True).start()
    if not found.wait(timeout):
        stop_process(proc)
        tail = proc.stderr.read().decode(errors="replace")[-2000:] if proc.stderr else ""
        raise AssertionError(f"{proc.args[0]} never printed {word!r}: {tail}")


def finish(proc: subprocess.Popen, timeout: float = 60.0) -> None:
    """Wait for ``proc`` to exit by itself with status 0; stop it and fail otherwise."""
    try:
        rc = proc.wait(timeout)
    except subprocess.TimeoutExpired:
        stop_process(proc)
        raise AssertionError(f"{proc.args} did not finish in {timeout} s") from None
    tail = proc.stderr.read().decode(errors="replace")[-3000:] if proc.stderr else ""
    assert rc == 0, tail


@contextlib.contextmanager
def real_rosmaster(tmp_path: Path) -> Iterator[str]:
    """Run Debian's ``rosmaster --core`` on a free loopback port; yield its URI."""
    require_ros()
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    log = open(tmp_path / f"rosmaster-{port}.log", "wb")
    proc = subprocess.Popen(
        ["rosmaster", "--core", "-p", str(port), "-w", "2"],
        env=ros_env(uri, tmp_path), stdout=log, stderr=subprocess.STDOUT,
    )
    try:
        wait_for_master(uri)
        yield uri
    finally:
        stop_process(proc)
        log.close()


def run_ros_python(code: str, *, env: dict[str, str] | None = None, timeout: float = 60.0,
                   input: bytes | None = None) -> subprocess.CompletedProcess:
    """Run ``code`` under the system Python with Debian's rospy/genpy; raise on failure."""
    require_ros()
    proc = subprocess.run(
        [ROS_PYTHON, "-c", code], input=input, capture_output=True, timeout=timeout,
        env=env if env is not None else {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")},
    )
    if proc.returncode != 0:
        raise AssertionError(
            f"system-Python ROS helper failed ({proc.returncode}):\n{proc.stderr.decode(errors='replace')}"
        )
    return proc


def build_roscpp_program(source: Path) -> Path:
    """Compile a roscpp test program (cached by source hash); return the binary's path."""
    require_ros()
    require_cxx()
    text = source.read_bytes()
    digest = hashlib.sha256(text).hexdigest()[:16]
    cache = user_temp_dir("roscpp-cache")   # per user: another user's binaries are not ours
    binary = cache / f"{source.stem}-{digest}"
    if not binary.exists():
        tmp = binary.with_name(f"{binary.name}.{os.getpid()}.tmp")
        proc = subprocess.run(
            ["g++", "-O1", "-std=c++17", "-o", str(tmp), str(source), *ROSCPP_LIBS],
            capture_output=True, text=True, timeout=300,
        )
        if proc.returncode != 0:
            raise AssertionError(f"building {source.name} failed:\n{proc.stderr}")
        tmp.replace(binary)
    return binary


# ---- real ROS 2 Python packages (the ros-jazzy-* wheels from PyPI) ------------------------------

def ros2_share() -> Path:
    """Where the ROS 2 wheels install their share/ folders (``<prefix>/share/PKG/msg/*.json``)."""
    import sysconfig

    return Path(sysconfig.get_path("data")) / "share"


@functools.cache
def ros2_python_missing_reason() -> str | None:
    """Why the real ROS 2 Python packages cannot be used here, or None when they can."""
    import importlib.util

    if importlib.util.find_spec("rosidl_generator_type_description") is None:
        return ("real ROS 2 Python packages not installed (rosidl_generator_type_description from "
                "the ros-jazzy-* wheels; there are none for macOS)")
    probe = ros2_share() / "std_msgs" / "msg" / "Header.json"
    if not probe.is_file():
        return f"real ROS 2 type descriptions not installed (no {probe})"
    return None


def require_ros2_python() -> None:
    """Skip (or fail under CI: ROSFPGA_REQUIRE_ROS2=1) unless the ROS 2 Python packages are usable."""
    reason = ros2_python_missing_reason()
    if reason:
        skip_or_fail(reason, "ROSFPGA_REQUIRE_ROS2")


__all__ = [
    "ROS_PYTHON", "ROS_PROGRAMS", "build_roscpp_program", "cxx_missing_reason", "finish", "free_port",
    "real_rosmaster", "require_cxx", "require_ros", "require_ros2", "require_ros2_python",
    "ros2_missing_reason", "ros2_python_missing_reason", "ros2_share", "ros_env", "ros_missing_reason",
    "run_ros_python", "skip_or_fail", "stop_process", "wait_for_master", "wait_line",
]
