"""The README stays short and its links lead somewhere: at most 250 lines of at most 110
characters; every relative link of the README, ARCHITECTURE.md, docs/, course/ and data/
pages names a file that exists; the Quick start is what lab.sh says it does. The library
reference is the package docstrings: every package has one, every file a docstring names
exists, and docs/ holds only guides."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", ROOT / "ARCHITECTURE.md", ROOT / "course" / "README.md",
         ROOT / "data" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_readme_is_short_with_short_lines() -> None:
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 250
    assert [n for n, line in enumerate(lines, 1) if len(line) > 110] == []


def test_relative_links_lead_to_files() -> None:
    broken = []
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text(encoding="utf-8")):
            if "://" not in target and not (page.parent / target).exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
    assert broken == []


def test_every_docs_page_is_in_the_index() -> None:
    index = (ROOT / "docs" / "README.md").read_text(encoding="utf-8")
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} - {"README.md"}
    assert {name for name in pages if f"]({name})" not in index} == set()


def test_quick_start_commands_are_lab_sh_s() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = readme.split("## Quick start", 1)[1].split("```bash\n", 1)[1].split("```", 1)[0]
    commands = [line.split("#", 1)[0].strip() for line in block.splitlines()]
    assert commands == ["./lab.sh", "./lab.sh test"]
    usage = (ROOT / "lab.sh").read_text(encoding="utf-8")
    assert "#   ./lab.sh          set up" in usage and "#   ./lab.sh test     set up" in usage


def test_the_notebook_table_names_every_notebook_and_real_packages() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## The notebooks", 1)[1].split("\n## ", 1)[0]
    rows = [line.strip("|").split("|") for line in section.splitlines() if line.startswith("| `")]
    assert {row[0].strip(" `") for row in rows} == {
        p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")}
    packages = {p.name for p in (ROOT / "rosfpga_lab").iterdir() if (p / "__init__.py").exists()}
    for row in rows:
        drives = set(re.findall(r"`([a-z_]+)`", row[2]))
        assert drives and drives <= packages, row


PACKAGES = sorted(p.parent for p in (ROOT / "rosfpga_lab").glob("*/__init__.py"))


def _docstring_paths(path: Path) -> list[str]:
    """The file paths a module's docstring names in backquotes (``a/b.ext`` or ``b/``...)."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    return re.findall(r"``([\w./-]+/[\w.-]+\.(?:py|md|yaml|v|vh|sv|cpp|json|pcapng|bin|png))``", doc)


def test_every_package_has_its_reference_docstring() -> None:
    """The library reference is the package docstrings: none is missing or a one-liner."""
    thin = [p.name for p in PACKAGES
            if len((ast.get_docstring(ast.parse((p / "__init__.py").read_text())) or "")
                   .splitlines()) < 5]
    assert thin == []


def test_files_the_docstrings_name_exist() -> None:
    """Every file a package's or module's docstring names is there: relative to the repository,
    to the package or to the module's own folder."""
    broken = []
    for module in sorted((ROOT / "rosfpga_lab").rglob("*.py")):
        package = ROOT / "rosfpga_lab" / module.relative_to(ROOT / "rosfpga_lab").parts[0]
        for name in _docstring_paths(module):
            if not any((base / name).exists() for base in (ROOT, package, module.parent)):
                broken.append(f"{module.relative_to(ROOT)}: {name}")
    assert broken == []


def test_docs_keeps_only_guides() -> None:
    """docs/ is no second library reference: every page there says it is a guide, and the
    index says why each one is not a docstring."""
    for page in sorted((ROOT / "docs").glob("*.md")):
        if page.name != "README.md":
            assert page.read_text(encoding="utf-8").startswith("# Guide"), page.name


def test_constants_the_guides_name_are_defined() -> None:
    """A guide names a limit's constant instead of restating its value: each such name is
    defined at the top level of a module of the library or the tests (environment variables,
    which the code reads by their quoted name, are not constants)."""
    sources = [p.read_text(encoding="utf-8")
               for p in [*(ROOT / "rosfpga_lab").rglob("*.py"), *(ROOT / "tests").rglob("*.py")]]
    defined = {name for text in sources
               for name in re.findall(r"^([A-Z][A-Z0-9_]+)\b[^=\n]*=", text, re.M)}
    quoted = {name for text in sources for name in re.findall(r"[\"']([A-Z][A-Z0-9_]+)[\"']", text)}
    named = {(page.name, name) for page in (ROOT / "docs").glob("*.md")
             for name in re.findall(r"`(?:[a-z_.]+\.)?([A-Z][A-Z0-9_]{3,})`",
                                    page.read_text(encoding="utf-8"))}
    assert sorted(pair for pair in named if pair[1] not in defined | quoted) == []
