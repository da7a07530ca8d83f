"""One source for exercises and solutions: student notebooks generated from instructor notebooks.

How this works (as nbgrader and the scikit-learn MOOC do): the instructor notebooks in
``notebooks/solutions/`` are the only source. In their code cells the solution sits between
marker lines::

    # BEGIN SOLUTION
    answer = compute_it()
    # END SOLUTION
    check_something(answer)

:func:`student_notebook` replaces each such block by ``# YOUR CODE HERE`` and a ``raise
NotImplementedError(...)`` (same indentation), so a student who runs the cell unchanged gets a
clear message, and drops whole cells tagged ``solution`` (instructor notes). In Markdown cells,
text between ``<!-- BEGIN SOLUTION -->`` and ``<!-- END SOLUTION -->`` becomes
``*Your answer here.*``. Outputs and execution counts are removed from both versions.
:func:`build` writes ``notebooks/NN_*.ipynb`` from ``notebooks/solutions/NN_*.ipynb``;
``check=True`` only reports which would change (the drift test and ``--check`` use it).
Notebooks are written in nbformat's own JSON layout (indent 1, sorted keys), so rebuilding an
unchanged source gives identical bytes.
"""

from __future__ import annotations

import copy
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosfpga_lab.errors import LabError

BEGIN = "# BEGIN SOLUTION"
END = "# END SOLUTION"
MD_BEGIN = "<!-- BEGIN SOLUTION -->"
MD_END = "<!-- END SOLUTION -->"
SOLUTION_TAG = "solution"
PLACEHOLDER = "# YOUR CODE HERE"
RAISE = 'raise NotImplementedError("exercise: replace this line with your code")'
MD_PLACEHOLDER = "*Your answer here.*"
#: Notebooks the build looks at: ``NN_name.ipynb``.
NOTEBOOK_GLOB = "[0-9][0-9]_*.ipynb"


class NotebookBuildError(LabError):
    """A source notebook cannot be turned into a student notebook (the message says where)."""


def cell_source(cell: dict[str, Any]) -> str:
    """A cell's source as one string (notebook files may store a list of lines)."""
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _set_source(cell: dict[str, Any], text: str) -> None:
    cell["source"] = text.splitlines(keepends=True)


def strip_solution(source: str, *, where: str = "") -> str:
    """Replace every ``# BEGIN SOLUTION`` ... ``# END SOLUTION`` block by the placeholder.

    Raises:
        NotebookBuildError: an unmatched or nested marker (``where`` and the line are named).
    """
    out: list[str] = []
    inside: int | None = None
    for n, line in enumerate(source.splitlines(keepends=True), 1):
        stripped = line.strip()
        if stripped == BEGIN:
            if inside is not None:
                raise NotebookBuildError(f"{where} line {n}: {BEGIN} inside another solution "
                                         f"block (opened at line {inside})")
            inside = n
            indent = line[: len(line) - len(line.lstrip())]
            out += [f"{indent}{PLACEHOLDER}\n", f"{indent}{RAISE}\n"]
        elif stripped == END:
            if inside is None:
                raise NotebookBuildError(f"{where} line {n}: {END} without {BEGIN}")
            inside = None
        elif inside is None:
            out.append(line)
    if inside is not None:
        raise NotebookBuildError(f"{where} line {inside}: {BEGIN} is never closed by {END}")
    text = "".join(out)
    return text.rstrip("\n") if not source.endswith("\n") else text


def strip_markdown_solution(source: str, *, where: str = "") -> str:
    """Replace ``<!-- BEGIN SOLUTION -->`` ... ``<!-- END SOLUTION -->`` by the placeholder."""
    pattern = re.compile(re.escape(MD_BEGIN) + r".*?" + re.escape(MD_END), re.S)
    text = pattern.sub(MD_PLACEHOLDER, source)
    if MD_BEGIN in text or MD_END in text:
        raise NotebookBuildError(f"{where}: unmatched {MD_BEGIN} / {MD_END}")
    return text


def strip_outputs(nb: dict[str, Any]) -> dict[str, Any]:
    """Remove outputs, execution counts and run-time cell metadata (in place; returns ``nb``)."""
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "code":
            cell["outputs"] = []
            cell["execution_count"] = None
        meta = cell.get("metadata", {})
        for key in ("execution", "collapsed", "scrolled", "ExecuteTime"):
            meta.pop(key, None)
    return nb


def has_outputs(nb: dict[str, Any]) -> list[int]:
    """Indices of code cells that carry outputs or an execution count."""
    return [i for i, c in enumerate(nb.get("cells", []))
            if c.get("cell_type") == "code" and (c.get("outputs") or c.get("execution_count") is not None)]


#: The note a student notebook with exercises carries after its title cell (the build adds it).
RUN_ALL_NOTE_ID = "run-all-note"
RUN_ALL_NOTE = (
    "> **Run All stops at the first exercise.** Each exercise cell starts as `raise "
    "NotImplementedError(...)`, so *Run > Run All Cells* runs the notebook up to there and stops. "
    "Write your answer in place of that line and run the cell; then go on from the next cell with "
    "*Run > Run Selected Cell and All Below*."
)


def with_run_all_note(cells: list[dict[str, Any]], source: dict[str, Any]) -> list[dict[str, Any]]:
    """``cells`` with :data:`RUN_ALL_NOTE` after the title cell when ``source`` has exercises
    (the student build and nbgrader's source notebooks add it the same way)."""
    if not any(is_exercise_cell(c) for c in source.get("cells", [])):
        return cells
    note = {"cell_type": "markdown", "id": RUN_ALL_NOTE_ID, "metadata": {}, "source": RUN_ALL_NOTE}
    return [*cells[:1], note, *cells[1:]]


def is_exercise_cell(cell: dict[str, Any]) -> bool:
    """True for a code cell of a source notebook holding a solution block."""
    return cell.get("cell_type") == "code" and BEGIN in cell_source(cell)


def student_notebook(nb: dict[str, Any], name: str = "") -> dict[str, Any]:
    """The student version of an instructor notebook (a new dict; ``nb`` is not changed).

    A notebook with exercises gets :data:`RUN_ALL_NOTE` after its title cell.

    Raises:
        NotebookBuildError: unbalanced markers.
    """
    out = copy.deepcopy(nb)
    cells = []
    for i, cell in enumerate(out.get("cells", [])):
        if SOLUTION_TAG in cell.get("metadata", {}).get("tags", []):
            continue
        where = f"{name} cell {i}"
        if cell.get("cell_type") == "code":
            _set_source(cell, strip_solution(cell_source(cell), where=where))
        elif cell.get("cell_type") == "markdown":
            _set_source(cell, strip_markdown_solution(cell_source(cell), where=where))
        cells.append(cell)
    out["cells"] = with_run_all_note(cells, nb)
    out.setdefault("metadata", {})["rosfpga_lab"] = {
        "generated_from": f"solutions/{name}" if name else "solutions",
        "note": "generated by `rosfpga-lab notebooks build`; edit the solutions notebook instead",
    }
    return strip_outputs(out)


def dumps(nb: dict[str, Any]) -> str:
    """Notebook JSON in nbformat's layout (indent 1, sorted keys, UTF-8, final newline)."""
    return json.dumps(nb, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def load(path: str | Path) -> dict[str, Any]:
    """Read a notebook file.

    Raises:
        NotebookBuildError: unreadable or not a notebook.
    """
    p = Path(path)
    try:
        nb = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise NotebookBuildError(f"{p}: cannot read the notebook ({exc})") from None
    if not isinstance(nb, dict) or "cells" not in nb:
        raise NotebookBuildError(f"{p}: not a Jupyter notebook (no 'cells')")
    return nb


@dataclass(frozen=True)
class BuildItem:
    """One student notebook of a build.

    Attributes:
        source: the instructor notebook.
        target: the student notebook.
        changed: the target was (or, with ``check``, would be) written with new content.
        exercises: how many solution blocks were replaced.
    """

    source: Path
    target: Path
    changed: bool
    exercises: int


def orphans(source_dir: str | Path, target_dir: str | Path) -> list[Path]:
    """Student notebooks in ``target_dir`` whose source in ``source_dir`` no longer exists."""
    names = {p.name for p in Path(source_dir).glob(NOTEBOOK_GLOB)}
    return sorted(p for p in Path(target_dir).glob(NOTEBOOK_GLOB) if p.name not in names)


def build(source_dir: str | Path, target_dir: str | Path, *, check: bool = False,
          clean_sources: bool = True) -> list[BuildItem]:
    """Write the student notebooks of every ``NN_*.ipynb`` in ``source_dir`` into ``target_dir``.

    Args:
        source_dir: the instructor notebooks (``notebooks/solutions``).
        target_dir: where the student notebooks go (``notebooks``).
        check: write nothing; only report which targets differ.
        clean_sources: also strip outputs from the source notebooks (unless ``check``), so both
            versions are stored without outputs.

    Returns:
        One :class:`BuildItem` per source, in name order.

    Raises:
        NotebookBuildError: no sources, or a source with unbalanced markers.
    """
    src, dst = Path(source_dir), Path(target_dir)
    sources = sorted(src.glob(NOTEBOOK_GLOB))
    if not sources:
        raise NotebookBuildError(f"no notebooks named NN_*.ipynb in {src} (run from the lab's "
                                 "checkout, or pass --source)")
    items = []
    for path in sources:
        nb = load(path)
        exercises = sum(cell_source(c).count(BEGIN) for c in nb["cells"] if c.get("cell_type") == "code")
        text = dumps(student_notebook(nb, path.name))
        target = dst / path.name
        old = target.read_text(encoding="utf-8") if target.exists() else None
        changed = old != text
        if not check:
            if clean_sources:
                cleaned = dumps(strip_outputs(copy.deepcopy(nb)))
                if cleaned != path.read_text(encoding="utf-8"):
                    path.write_text(cleaned, encoding="utf-8")
            if changed:
                dst.mkdir(parents=True, exist_ok=True)
                target.write_text(text, encoding="utf-8")
        items.append(BuildItem(path, target, changed, exercises))
    return items
