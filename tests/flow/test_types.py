"""The library type-checks: mypy on ``rosfpga_lab/`` with the settings in pyproject.toml; and no
Python file of the project names something undefined (pyflakes: a misspelt or left-over name in
a test that only runs where the real tools are would otherwise first fail in CI)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_mypy_finds_no_errors_in_the_library() -> None:
    from mypy import api  # in the [test] extra: a missing mypy is a failure, not a skip

    stdout, stderr, status = api.run(["--config-file", str(ROOT / "pyproject.toml"),
                                      "--cache-dir", str(ROOT / ".mypy_cache"),
                                      str(ROOT / "rosfpga_lab")])
    assert status == 0, f"mypy found errors:\n{stdout}{stderr}"
    assert "Success: no issues found" in stdout


#: The project's Python outside ``.venv`` and the generated student notebooks.
PYTHON_DIRS = ("rosfpga_lab", "tests", "data", "course", "ros", "tools", ".ci")
#: Names a program's host defines before running it: JupyterHub's config loader.
INJECTED = {"course/jupyterhub_config.py": {"get_config"}}


def test_no_python_file_names_an_undefined_name() -> None:
    from pyflakes import api, messages  # in the [test] extra
    from pyflakes.reporter import Reporter

    found: list[str] = []

    class Collect(Reporter):
        def __init__(self) -> None:
            super().__init__(None, None)

        def unexpectedError(self, filename: str, msg: str) -> None:
            found.append(f"{filename}: {msg}")

        def syntaxError(self, filename: str, msg: str, lineno: int, offset: int,
                        text: str) -> None:
            found.append(f"{filename}:{lineno}: {msg}")

        def flake(self, message: messages.Message) -> None:
            if not isinstance(message, (messages.UndefinedName, messages.UndefinedLocal,
                                        messages.UndefinedExport)):
                return
            where = Path(message.filename).resolve().relative_to(ROOT).as_posix()
            if message.message_args[0] not in INJECTED.get(where, ()):
                found.append(str(message))

    paths = [str(ROOT / d) for d in PYTHON_DIRS if (ROOT / d).is_dir()]
    assert api.checkRecursive(paths, Collect()) >= 0
    assert found == [], "\n".join(found)
