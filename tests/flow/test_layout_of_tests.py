"""The tests are laid out like the library (ARCHITECTURE.md "Where the tests live"): a test
file sits in ``tests/<package>/`` for a package of ``rosfpga_lab/`` or in ``tests/flow/``;
helpers in ``tests/support/``; cocotb benches are ``tests/rtl/bench_<verilog module>.py``."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support import REPO, TESTS

PACKAGES = {p.parent.name for p in (REPO / "rosfpga_lab").glob("*/__init__.py")}
#: The folders of tests/ that are not a package's: what they hold.
OTHER = {"flow": "tests", "support": "helpers", "benchmarks": "benchmarks",
         "golden": "golden files", "ros_programs": "real ROS programs"}


def test_every_test_file_sits_in_a_package_folder_or_flow() -> None:
    misplaced = [str(p.relative_to(TESTS)) for p in TESTS.rglob("test_*.py")
                 if "__pycache__" not in p.parts
                 and (len(p.relative_to(TESTS).parts) != 2
                      or p.parent.name not in PACKAGES | {"flow"})]
    assert misplaced == [], "tests/<package>/test_<module>.py or tests/flow/ (ARCHITECTURE.md, where the tests live)"


def test_tests_holds_only_conftest_and_known_folders() -> None:
    assert sorted(p.name for p in TESTS.glob("*.py")) == ["__init__.py", "conftest.py"]
    folders = {p.name for p in TESTS.iterdir() if p.is_dir() and p.name != "__pycache__"
               and not p.name.startswith(".")}
    assert folders <= PACKAGES | set(OTHER), sorted(folders - PACKAGES - set(OTHER))


def test_tests_and_each_folder_of_tests_or_helpers_is_a_package() -> None:
    """Tests import each other and the helpers as ``tests.<folder>.<module>``."""
    folders = {p.parent for p in TESTS.rglob("test_*.py")} | {TESTS, TESTS / "support"}
    assert sorted(str(f.relative_to(TESTS)) for f in folders
                  if not (f / "__init__.py").exists()) == []


def test_rtl_python_files_are_tests_or_benches_named_after_their_module() -> None:
    verilog = "\n".join(p.read_text(encoding="utf-8", errors="replace")
                        for base in (REPO / "rosfpga_lab", TESTS)
                        for p in base.rglob("*.v*") if p.suffix in (".v", ".sv", ".j2"))
    for path in (TESTS / "rtl").glob("*.py"):
        assert path.name.startswith(("test_", "bench_", "__init__")), path.name
        if path.name.startswith("bench_"):
            # bench_<module>.py, or bench_<module>_<what>.py for a second bench of one module
            words = path.stem.removeprefix("bench_").split("_")
            modules = ["_".join(words[:n]) for n in range(len(words), 0, -1)]
            assert any(re.search(rf"\bmodule\s+{m}\b", verilog) for m in modules), \
                f"{path.name}: no module {modules[0]}"


def test_the_heavy_files_run_first_exist() -> None:
    from tests.conftest import HEAVY_FIRST

    assert [name for name in HEAVY_FIRST if not (REPO / name).is_file()] == []
    assert len(set(HEAVY_FIRST)) == len(HEAVY_FIRST)
