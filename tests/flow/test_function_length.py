"""A function of the lab over ``LIMIT`` lines is several ideas, to be cut at its seams, unless a
comment right above its ``def`` (or its decorators) starting ``# long:`` says why its length is
honest (a flat table, one dispatch of a state machine, closures sharing one state); a function
that stood here and is not yet cut is a named exception with its reason. The length is the
``def`` line to the last line, docstring included, as ``ast`` gives it."""

from __future__ import annotations

import ast
import functools
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "rosfpga_lab"
LIMIT = 80
MARKER = "# long:"
#: ``path:qualified name`` -> why it is over the limit without a marker. An entry goes when its
#: function is cut or marked (``test_every_exception_is_still_long_and_unmarked`` says which).
EXCEPTIONS: dict[str, str] = {}


def _comment_above(lines: list[str], first: int) -> list[str]:
    """The comment lines right above line ``first`` (1-based), nearest last."""
    out: list[str] = []
    i = first - 2
    while i >= 0 and lines[i].strip().startswith("#"):
        out.insert(0, lines[i].strip())
        i -= 1
    return out


def functions(source: str) -> dict[str, tuple[int, bool]]:
    """Qualified name -> (lines, whether a ``# long:`` comment stands above it) of every
    function and method in ``source``."""
    lines = source.splitlines()
    found: dict[str, tuple[int, bool]] = {}

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + child.name
                first = min([child.lineno] + [d.lineno for d in child.decorator_list])
                marked = any(c.startswith(MARKER) for c in _comment_above(lines, first))
                assert child.end_lineno is not None
                found[name] = (child.end_lineno - child.lineno + 1, marked)
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return found


@functools.cache   # read once for the three tests
def _the_labs_functions() -> dict[str, tuple[int, bool]]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        for name, info in functions(path.read_text(encoding="utf-8")).items():
            out[f"{rel}:{name}"] = info
    return out


def test_the_finder_sees_length_and_marker() -> None:
    body = "".join(f"    x{i} = {i}\n" for i in range(LIMIT))
    source = ("class A:\n    # long: a flat table\n    @staticmethod\n    def table() -> None:\n"
              + body.replace("    ", "        ") + "\n"
              "def plain() -> None:\n" + body + "\n"
              "# a comment, not the marker\ndef short() -> None:\n    pass\n")
    found = functions(source)
    assert found["A.table"] == (LIMIT + 1, True)
    assert found["plain"] == (LIMIT + 1, False)
    assert found["short"] == (2, False)


def test_every_long_function_says_why() -> None:
    found = _the_labs_functions()
    assert len(found) > 1000   # the whole package read
    unmarked = sorted(name for name, (n, marked) in found.items()
                      if n > LIMIT and not marked and name not in EXCEPTIONS)
    assert unmarked == [], (f"over {LIMIT} lines: cut at the seams, or write '{MARKER} why' "
                            f"right above the def: {unmarked}")


def test_every_marker_stands_above_a_long_function() -> None:
    found = _the_labs_functions()
    stale = sorted(name for name, (n, marked) in found.items() if marked and n <= LIMIT)
    assert stale == [], f"{LIMIT} lines or fewer now: take the '{MARKER}' comment away: {stale}"


def test_every_exception_is_still_long_and_unmarked() -> None:
    found = _the_labs_functions()
    done = sorted(name for name in EXCEPTIONS
                  if name not in found or found[name][0] <= LIMIT or found[name][1])
    assert done == [], f"cut, marked or gone: take them out of EXCEPTIONS: {done}"
