"""Real ROS 1 programs beside the lab: which interpreter runs them, their environment, whether they can.

How this works: Debian's ROS 1 Noetic (rospy, genpy, rostopic, rosmaster) runs under the system
interpreter :data:`ROS_PYTHON`, not the lab's virtual environment, so the tests, the bench and
notebook 7 start real ROS programs as subprocesses, with the environment :func:`ros_env` gives
(loopback only, a private ``ROS_HOME`` for their logs). :func:`ros_missing` says in one line why
they cannot run on this machine (None when they can), so every caller skips with the same words.

Scratch folders (``ROS_HOME``, build caches) live in :func:`user_temp_dir`: one folder per user
under the temp dir, made ``0700`` and checked to be that user's own, so a second user of a course
server never trips over the first one's files (a folder that fails the check is not used: the
process gets a fresh private one instead).

Standard library only: anything may import it, including a test run without the lab's extras.
"""

from __future__ import annotations

import functools
import getpass
import os
import shutil
import stat
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

#: The interpreter with Debian's rospy, genpy and message packages.
ROS_PYTHON = "/usr/bin/python3"
#: Modules a real ROS 1 program of the lab imports under :data:`ROS_PYTHON`.
ROS_MODULES = ("rospy", "genpy", "std_msgs.msg", "sensor_msgs.msg", "geometry_msgs.msg")
#: Debian packages that provide them (what to install when :func:`ros_missing` says no).
ROS_PACKAGES = ("python3-rospy", "python3-rosmaster", "python3-rostopic", "python3-sensor-msgs",
                "python3-geometry-msgs")
#: Seconds the import probe may take (a cold disk makes rospy's first import slow).
PROBE_TIMEOUT = 60.0
#: Name of the per-user folder under the temp dir (followed by ``-<uid>``).
USER_DIR_PREFIX = "rosfpga-lab"


def _user_id() -> str:
    getuid = getattr(os, "getuid", None)
    return str(getuid()) if getuid is not None else getpass.getuser()


def _own_private_dir(path: Path) -> bool:
    """True when ``path`` is a real folder (not a link) of this user that nobody else may write."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISDIR(st.st_mode):
        return False
    getuid = getattr(os, "getuid", None)
    if getuid is not None and st.st_uid != getuid():
        return False
    return not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def user_temp_dir(purpose: str) -> Path:
    """A scratch folder for ``purpose`` (e.g. ``"ros-home"``) that belongs to this user only.

    It is ``<tempdir>/rosfpga-lab-<uid>/<purpose>``, created ``0700``; when that per-user folder
    exists but is not this user's own private folder (another user made it, or it is a link),
    a fresh folder private to this process is returned instead.

    Args:
        purpose: one path component naming what the folder holds.

    Raises:
        ValueError: ``purpose`` is empty or not a single path component.
    """
    if not purpose or Path(purpose).name != purpose or purpose in (".", ".."):
        raise ValueError(f"purpose must be one folder name, got {purpose!r}")
    base = Path(tempfile.gettempdir()) / f"{USER_DIR_PREFIX}-{_user_id()}"
    try:
        base.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        pass
    if not _own_private_dir(base):
        return Path(tempfile.mkdtemp(prefix=f"{USER_DIR_PREFIX}-{purpose}-"))
    folder = base / purpose
    folder.mkdir(mode=0o700, exist_ok=True)
    return folder


def ros_env(master_uri: str, home: Path | str | None = None) -> dict[str, str]:
    """Environment for a real ROS program talking to ``master_uri`` over loopback only.

    This process's environment without its ``ROS_*`` and ``PYTHON*`` variables (the lab's
    virtual environment must not leak into the system interpreter), plus ``ROS_MASTER_URI``,
    ``ROS_HOSTNAME=127.0.0.1``, unbuffered output, and ``ROS_HOME`` (where ROS writes its
    logs): ``home``, else this user's :func:`user_temp_dir` ``("ros-home")``.
    """
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "PYTHON"))}
    env.update(
        ROS_MASTER_URI=master_uri,
        ROS_HOSTNAME="127.0.0.1",
        ROS_HOME=str(home if home is not None else user_temp_dir("ros-home")),
        ROSCONSOLE_STDOUT_LINE_BUFFERED="1",
        PYTHONUNBUFFERED="1",
    )
    return env


@functools.lru_cache(maxsize=16)
def import_problem(python: str, modules: tuple[str, ...], hint: str) -> str | None:
    """Why ``python`` cannot import ``modules``, in one line ending with ``hint`` (what to
    install); None when it can. Probed in a subprocess without this process's ``PYTHON*``
    variables, remembered per process."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    try:
        probe = subprocess.run([python, "-c", f"import {', '.join(modules)}"], env=env,
                               capture_output=True, text=True, timeout=PROBE_TIMEOUT)
    except (OSError, subprocess.SubprocessError) as exc:
        return f"{python} cannot run ({exc})"
    if probe.returncode == 0:
        return None
    last = (probe.stderr.strip().splitlines() or ["no error text"])[-1]
    return f"{python} cannot import {', '.join(modules)} ({last}); {hint}"


def ros_missing(tools: Sequence[str] = (), *, modules: Sequence[str] = ROS_MODULES,
                python: str = ROS_PYTHON) -> str | None:
    """Why real ROS 1 programs cannot run here, in one line; None when they can.

    The checks run cheapest first, so the answer does not depend on what else is installed:
    each program of ``tools`` on ``PATH`` (e.g. ``"rostopic"``), then ``python``, then
    ``import``-ing ``modules`` under it (that probe is a subprocess, remembered per process).

    Args:
        tools: programs the caller will run from ``PATH``.
        modules: modules the caller's ROS programs import under ``python``.
        python: the interpreter with Debian's rospy.
    """
    for tool in tools:
        if shutil.which(tool) is None:
            return f"{tool} is not on PATH"
    if not Path(python).exists():
        return f"{python} not found"
    if not modules:
        return None
    return import_problem(python, tuple(modules), f"Debian's packages: {' '.join(ROS_PACKAGES)}")


__all__ = ["PROBE_TIMEOUT", "ROS_MODULES", "ROS_PACKAGES", "ROS_PYTHON", "import_problem", "ros_env",
           "ros_missing", "user_temp_dir"]
