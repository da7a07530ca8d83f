"""Shared fixtures. Real-ROS helpers live in ``realros.py`` beside this file."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from realros import real_rosmaster, require_cxx, require_ros  # noqa: E402


@pytest.fixture(autouse=True, scope="session")
def dev_null_stays_writable() -> Iterator[None]:
    """No test may change /dev/null: an ``iverilog -o /dev/null`` run as root once made it 0755
    for the whole machine (apt, and the course server's students, could no longer write it)."""
    before = os.stat(os.devnull).st_mode
    yield
    after = os.stat(os.devnull).st_mode
    assert after == before, (f"a test changed {os.devnull}'s mode from {before:o} to {after:o} "
                             f"(restore it: chmod 666 {os.devnull})")


@pytest.fixture
def real_ros() -> None:
    """Skip (or fail under CI) unless real ROS 1 Noetic is installed."""
    require_ros()


@pytest.fixture
def cxx() -> None:
    """Skip (or fail under CI) unless g++ is installed."""
    require_cxx()


@pytest.fixture
def rosmaster_uri(tmp_path: Path) -> Iterator[str]:
    """URI of a real ``rosmaster --core`` on a free loopback port, stopped afterwards."""
    with real_rosmaster(tmp_path) as uri:
        yield uri
