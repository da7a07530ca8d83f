"""data/README.md maps data/: every file there is named in it, and every name in its tables is
there (a capture or result without its script, or a script without its file, shows)."""

from __future__ import annotations

import re
from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "data"


def _named(first_column: bool = True) -> set[str]:
    """The names in backquotes in the map's tables (in their first column only, by default)."""
    text = (DATA / "README.md").read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    cells = [row.split("|")[1] if first_column else row for row in rows]
    return {name for cell in cells for name in re.findall(r"`([\w./-]+\.\w+|[\w/]+/)`", cell)}


def test_every_file_of_data_is_in_the_map() -> None:
    named = _named(first_column=False)
    files = {p.name for p in DATA.iterdir() if p.is_file() and p.name != "README.md"}
    folders = {f"{p.relative_to(DATA)}/" for p in (DATA / "msg").iterdir() if p.is_dir()}
    missing = sorted(name for name in files | {f"msg/{f.split('/')[1]}/" for f in folders}
                     if name not in named)
    assert missing == [], f"add these to data/README.md: {missing}"


def test_every_file_the_map_names_is_there() -> None:
    absent = sorted(n for n in _named() if not (DATA / n).exists())
    assert absent == []


def test_every_capture_names_the_script_that_made_it() -> None:
    text = (DATA / "README.md").read_text(encoding="utf-8")
    for script in DATA.glob("*.py"):
        assert f"`{script.name}`" in text, script.name
        doc = script.read_text(encoding="utf-8")
        made = re.findall(r"data/([\w.]+\.(?:pcapng|bin|json|vcd|txt))", doc.split('"""', 2)[1])
        assert made, f"{script.name}'s docstring names no file it makes"
        for name in made:
            row = next(line for line in text.splitlines() if f"`{name}`" in line)
            assert f"`{script.name}`" in row, (name, script.name)
