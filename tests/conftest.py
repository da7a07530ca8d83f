"""Shared fixtures. The helpers live in the package ``tests/support/`` (real ROS:
``tests/support/realros.py``)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.realros import real_rosmaster, require_cxx, require_ros  # noqa: E402

#: What a caller's shell may hold that changes what the lab, or a program a test starts, does:
#: ROS 1 (``ROS_MASTER_URI``, ``ROS_HOSTNAME``, ``ROS_IP``, ``ROS_NAMESPACE``, ``ROS_IPV6``, ...)
#: and ROS 2 (``ROS_DOMAIN_ID``, the RMW and DDS vendors' settings) variables, the RTL harness's
#: and benches' ``RFL_*`` files and switches, and the lab's own switches that are not CI's
#: ``ROSFPGA_REQUIRE_*`` (those say what a run must have; CI sets them on purpose).
#: ``XDG_CACHE_HOME`` stays: it says where the user keeps caches (RTL builds), not what they hold.
CALLER_PREFIXES = ("ROS_", "RMW_", "CYCLONEDDS_", "FASTRTPS_", "FASTDDS_", "ROSCONSOLE_", "RFL_")
CALLER_NAMES = ("ROSFPGA_HIDE_CYCLONE", "ROSFPGA_LAB_PYTHON")


#: The test files that take minutes where the real tools are (CI's ``--durations``: proofs, the
#: board's place and route, synthesis, Verilator builds), heaviest first. They run first, so that
#: under ``./lab.sh test``'s two workers (``--dist loadfile --no-loadscope-reorder``: files in this
#: order) no long file starts last while the other worker has nothing left.
HEAVY_FIRST = (
    "tests/rtl/test_formal.py",
    "tests/rtl/test_fabric_bitstream.py",
    "tests/rtl/test_harness.py",
    "tests/rtl/test_synth.py",
    "tests/rtl/test_sim.py",
    "tests/hls/test_generic_project.py",
    "tests/rtl/test_timing.py",
    "tests/flow/test_course_nbgrader.py",
    "tests/rtl/test_fabric_udp.py",
    "tests/flow/test_browser_notebooks.py",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Put :data:`HEAVY_FIRST`'s files first, in its order; every other test keeps its place."""
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    root = Path(str(config.rootpath))
    items.sort(key=lambda item: rank.get(Path(str(item.path)).relative_to(root).as_posix(),
                                         len(rank)))


def _caller_variables() -> list[str]:
    return sorted(k for k in os.environ if k.startswith(CALLER_PREFIXES) or k in CALLER_NAMES)


@pytest.fixture(autouse=True, scope="session")
def no_caller_ros_environment_for_the_session() -> Iterator[None]:
    """The suite runs as in a clean shell: the caller's ``ROS_*`` (and :data:`CALLER_PREFIXES`)
    variables are gone for the whole session, so module and session fixtures do not see them
    either; they are restored at the end."""
    with pytest.MonkeyPatch.context() as patch:
        for name in _caller_variables():
            patch.delenv(name)
        yield


@pytest.fixture(autouse=True)
def no_caller_ros_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test starts without those variables too (a test, or a fixture it asks for, sets
    what it needs with ``monkeypatch.setenv`` or a subprocess's ``env=``; ``monkeypatch`` undoes
    it after the test)."""
    for name in _caller_variables():
        monkeypatch.delenv(name)


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
