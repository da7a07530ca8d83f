"""Helpers the tests share (not tests): ``from tests.support.realros import require_ros``."""

from pathlib import Path

#: The repository's root, ``tests/`` and ``data/``: a test may reach files through these rather
#: than through how deep it sits.
REPO = Path(__file__).resolve().parents[2]
TESTS = REPO / "tests"
DATA = REPO / "data"
