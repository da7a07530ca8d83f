"""ARCHITECTURE.md says what the code does: its layer table is ``tests/flow/test_layers.py``'s order,
its command table the CLI's sub-commands, and every file it names exists."""

from __future__ import annotations

import argparse
import ast
import importlib
import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "ARCHITECTURE.md"


def _section(title: str) -> str:
    text = DOC.read_text(encoding="utf-8")
    return text.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def _table_rows(section: str) -> list[list[str]]:
    rows = [line for line in section.splitlines() if line.startswith("|")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows[2:]]


def _levels_of_test_layers() -> list[set[str]]:
    """``LEVELS`` as tests/flow/test_layers.py writes it, read from its source (not imported)."""
    tree = ast.parse(Path(__file__).with_name("test_layers.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "LEVELS"
                                                for t in node.targets):
            return [set(ast.literal_eval(level)) for level in node.value.elts]  # type: ignore[attr-defined]
    raise AssertionError("tests/flow/test_layers.py has no LEVELS")


def test_layer_table_is_the_order_test_layers_enforces() -> None:
    rows = _table_rows(_section("Layers"))
    levels = [set(re.findall(r"`([a-z_]+)`", row[1])) for row in rows]
    assert [int(row[0]) for row in rows] == list(range(len(rows)))
    assert levels == _levels_of_test_layers()


def test_command_table_lists_exactly_the_cli_sub_commands() -> None:
    from rosfpga_lab.cli import build_parser

    parser = build_parser()
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    commands = set(actions[0].choices)
    rows = _table_rows(_section("Commands"))
    listed = [re.fullmatch(r"`rosfpga-lab ([a-z]+)`", row[0])[1] for row in rows]  # type: ignore[index]
    assert len(listed) == len(set(listed))
    assert set(listed) == commands
    for row in rows:   # the module named is the one that registers the command
        module = re.match(r"`(cli/[a-z_]+\.py)`", row[2])[1]  # type: ignore[index]
        name = re.fullmatch(r"`rosfpga-lab ([a-z]+)`", row[0])[1]  # type: ignore[index]
        assert f'"{name}"' in (ROOT / "rosfpga_lab" / module).read_text(encoding="utf-8"), row


def test_every_file_it_names_exists() -> None:
    """A path is the repository's (``rosfpga_lab/hw/layout.py``) or the package's
    (``hw/layout.py``, ``rtl/verilog/rfl_morph.v``)."""
    text = DOC.read_text(encoding="utf-8")
    named = set(re.findall(r"`((?:[\w.]+/)+[\w.]+\.(?:py|md|v|ipynb))`", text))
    assert len(named) > 20, "the conventions, the flow and the commands name files"
    missing = sorted(p for p in named if "NN_" not in p and not (ROOT / p).exists()
                     and not (ROOT / "rosfpga_lab" / p).exists())
    assert missing == []


def test_every_notebook_is_in_the_map() -> None:
    rows = _table_rows(_section("Notebooks and the library they drive"))
    listed = {re.fullmatch(r"`(\d\d_\w+)`", row[0])[1] for row in rows}  # type: ignore[index]
    assert listed == {p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")}
    for row in rows:   # each name is a module of the lab, or a name one exports
        for name in re.findall(r"`([a-z_.A-Z]+)`", re.sub(r"\([^)]*\)", "", row[1])):
            module, _, attr = name.rpartition(".")
            found = importlib.util.find_spec(f"rosfpga_lab.{name}") is not None or (
                bool(module) and hasattr(importlib.import_module(f"rosfpga_lab.{module}"), attr))
            assert found, f"{row[0]}: {name} is neither a module nor a name the lab exports"
