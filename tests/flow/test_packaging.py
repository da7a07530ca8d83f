"""The promised layout, the dependency lists and the command line's entry points."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _requirement_names(lines: list[str]) -> dict[str, str]:
    out = {}
    for line in lines:
        line = line.split("#", 1)[0].strip()
        if line:
            name = re.split(r"[<>=!~ ;\[]", line, maxsplit=1)[0].lower()
            out[name] = line.replace(" ", "")
    return out


def test_layout_promised_to_users_exists() -> None:
    for name in ("notebooks", "rosfpga_lab", "data", "tests"):
        assert (ROOT / name).is_dir(), name
    for name in ("environment.txt", "README.md", "pyproject.toml", ".ci/run", "lab.sh"):
        assert (ROOT / name).is_file(), name


def test_environment_txt_matches_pyproject_dependencies() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    from_pyproject = _requirement_names(project["dependencies"])
    from_env = _requirement_names((ROOT / "environment.txt").read_text().splitlines())
    assert from_env == from_pyproject
    for name in ("jupyterlab", "numpy", "opencv-python-headless", "matplotlib", "ipywidgets"):
        assert ">=" in from_env[name], f"{name} needs a lower bound"


def test_readme_dependency_table_names_every_dependency() -> None:
    readme = (ROOT / "README.md").read_text()
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    for name in _requirement_names(project["dependencies"]):
        assert f"`{name}`" in readme, f"README's dependency table does not explain {name}"


def test_cli_help_lists_subcommands_and_module_entry_point_works() -> None:
    out = subprocess.run([sys.executable, "-m", "rosfpga_lab", "--help"], capture_output=True,
                         text=True, check=True).stdout
    assert "usage: rosfpga-lab" in out
    assert "msg" in out


def test_every_subcommand_has_help() -> None:
    from rosfpga_lab.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    assert sub.choices, "no sub-commands registered"
    for name, subparser in sub.choices.items():
        text = subparser.format_help()
        assert text.startswith("usage: rosfpga-lab " + name), name
        assert subparser.description, f"sub-command {name} has no description"


def test_every_data_file_of_the_package_is_installed() -> None:
    """A non-editable install (the course server's) ships every file the library reads: each
    file under rosfpga_lab/ matches pyproject's package-data globs. The .srv files were missing,
    and every lab node failed on the course server ("service type 'roscpp/GetLoggers' is not
    shipped")."""
    from fnmatch import fnmatch

    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["*"]
    code = {".py", ".pyc"}
    left_out = [str(p.relative_to(ROOT)) for p in (ROOT / "rosfpga_lab").rglob("*")
                if p.is_file() and p.suffix not in code and "__pycache__" not in p.parts
                and p.name != "README.md" and not any(fnmatch(p.name, g) for g in globs)]
    assert left_out == [], f"add their patterns to [tool.setuptools.package-data]: {left_out}"


def test_the_bare_machine_hides_what_lab_sh_test_does_not_install() -> None:
    """.ci/bare-machine (CI's second run) is a student's machine: .ci/venv-extras.py finds the
    extras `./lab.sh test` installs in lab.sh ([test], then [ros2]) and lists for hiding every
    installed distribution that only pyproject's other extras bring ([synth]'s PyPI Yosys,
    SymbiYosys, Yices and nextpnr ran the proofs and place and route a second time), never one
    the installed extras need."""
    from importlib.metadata import PackageNotFoundError, distribution

    done = subprocess.run([sys.executable, "-I", str(ROOT / ".ci" / "venv-extras.py"), str(ROOT)],
                          capture_output=True, text=True, check=True, timeout=120)
    lines = done.stdout.splitlines()
    assert lines[:2] == ["extras ros2 test", "hidden course synth"], lines[:2]
    hidden = {line.split()[1].lower() for line in lines if line.startswith("dist ")}
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    kept = set(_requirement_names(extras["test"] + extras["ros2"]))
    assert not hidden & kept, hidden & kept
    for name in _requirement_names(extras["synth"] + extras["course"]):
        try:
            distribution(name)
        except PackageNotFoundError:
            continue
        assert name in hidden, f"{name} (an extra ./lab.sh test does not install) is not hidden"
    files = [Path(line.split(" ", 1)[1]) for line in lines if line.startswith("file ")]
    assert all(f.is_relative_to(Path(sys.prefix).resolve()) for f in files), files[:3]
