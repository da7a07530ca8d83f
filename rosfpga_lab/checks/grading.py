"""Exercises graded with nbgrader: an nbgrader course's source notebooks, derived from the solutions.

How this works: nbgrader grades a notebook by its cells' ``metadata.nbgrader``: an *autograded
answer* cell (``solution: true``) holds the student's code, and an *autograder test* cell
(``grade: true`` with ``points``, locked) passes when it runs without an error. The lab's
exercise cells hold both in one cell: the answer between ``# BEGIN SOLUTION`` and
``# END SOLUTION``, then the check call (``check_tdata(tdata, pixel)``) that raises
:class:`~rosfpga_lab.checks.ExerciseError` with its findings when the answer is wrong.
:func:`nbgrader_notebook` splits each such cell after its last ``# END SOLUTION``: the answer
part keeps the cell's id and becomes the answer cell, the check lines become a test cell worth
:data:`POINTS_PER_CHECK` (id ``<id>-check``). Nothing is added to ``notebooks/solutions/`` by
hand: the metadata is derived here on every build, so it can never drift from the sources.

:func:`configure` points nbgrader's own ``ClearSolutions`` preprocessor at the lab's
placeholders (:mod:`rosfpga_lab.checks.nbbuild`), so ``nbgrader generate_assignment`` writes
the same student cells as ``rosfpga-lab notebooks build`` (the answer and check cells joined
again give the lab's exercise cell); ``tests/flow/test_course_nbgrader.py`` holds them equal. One
mechanism makes the committed student notebooks (the lab's build, which every student has);
nbgrader, on the course server only, is configured to agree with it. In Markdown, nbgrader
replaces whole lines, so there the two agree when ``<!-- BEGIN SOLUTION -->`` and
``<!-- END SOLUTION -->`` stand on lines of their own.

A passing check returns a :class:`~rosfpga_lab.checks.CheckResult`, shown as display data
(not as the cell's value, which nbgrader would read as partial credit); a failing one raises,
so its findings stand in the graded notebook and in nbgrader's feedback.
"""

from __future__ import annotations

import copy
import os
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosfpga_lab.checks.nbbuild import (
    BEGIN,
    END,
    MD_BEGIN,
    MD_PLACEHOLDER,
    NOTEBOOK_GLOB,
    PLACEHOLDER,
    RAISE,
    SOLUTION_TAG,
    NotebookBuildError,
    cell_source,
    dumps,
    is_exercise_cell,
    load,
    strip_outputs,
    with_run_all_note,
)

#: Points of one check cell (one exercise).
POINTS_PER_CHECK = 1
#: nbgrader's cell-metadata schema this module writes.
NBGRADER_SCHEMA = 3
#: Suffix of a check cell's id and grade id: ``<exercise cell id>-check``.
CHECK_SUFFIX = "-check"


def split_exercise(source: str) -> tuple[str, str]:
    """Split an exercise cell's code after its last ``# END SOLUTION`` line.

    Returns:
        ``(answer, check)``: the lines up to and including the last ``# END SOLUTION``, and
        the lines after it (``""`` when there are none); ``answer + "\\n" + check`` is the
        cell again (up to trailing newlines).

    Raises:
        NotebookBuildError: no ``# END SOLUTION`` line.
    """
    lines = source.splitlines(keepends=True)
    ends = [i for i, line in enumerate(lines) if line.strip() == END]
    if not ends:
        raise NotebookBuildError(f"no {END} line in an exercise cell")
    cut = ends[-1] + 1
    answer = "".join(lines[:cut]).rstrip("\n")
    check = "".join(lines[cut:]).rstrip("\n")
    return answer, check


def _nbgrader_meta(grade_id: str, *, solution: bool, grade: bool, locked: bool,
                   points: int | None = None) -> dict[str, Any]:
    meta: dict[str, Any] = {"grade": grade, "grade_id": grade_id, "locked": locked,
                            "schema_version": NBGRADER_SCHEMA, "solution": solution}
    if points is not None:
        meta["points"] = points
    return meta


def nbgrader_notebook(nb: dict[str, Any], name: str) -> dict[str, Any]:
    """The nbgrader source version of an instructor notebook (a new dict).

    Exercise cells become an answer cell and a check cell (see the module's docstring); cells
    tagged ``solution`` are left out (as the student build drops them); Markdown cells with
    ``<!-- BEGIN SOLUTION -->`` become answer cells, whose markers nbgrader replaces too.
    Outputs are removed.

    Args:
        nb: the instructor notebook (``notebooks/solutions/NN_name.ipynb``, loaded).
        name: its file name; the stem prefixes every ``grade_id``.

    Raises:
        NotebookBuildError: an exercise cell without a check after its solution, or without id.
    """
    stem = Path(name).stem
    out = copy.deepcopy(nb)
    cells: list[dict[str, Any]] = []
    for i, cell in enumerate(out.get("cells", [])):
        meta = cell.setdefault("metadata", {})
        if SOLUTION_TAG in meta.get("tags", []):
            continue
        cell_id = cell.get("id")
        if is_exercise_cell(cell):
            if not cell_id:
                raise NotebookBuildError(f"{name} cell {i}: an exercise cell needs a cell id "
                                         "(nbformat 4.5)")
            answer, check = split_exercise(cell_source(cell))
            if not check.strip():
                raise NotebookBuildError(f"{name} cell {i} ({cell_id}): nothing after {END}; "
                                         "an exercise cell ends with the call of its check")
            cell["source"] = answer.splitlines(keepends=True)
            meta["nbgrader"] = _nbgrader_meta(f"{stem}-{cell_id}", solution=True, grade=False,
                                              locked=False)
            test = {"cell_type": "code", "execution_count": None, "id": f"{cell_id}{CHECK_SUFFIX}",
                    "metadata": {"nbgrader": _nbgrader_meta(
                        f"{stem}-{cell_id}{CHECK_SUFFIX}", solution=False, grade=True,
                        locked=True, points=POINTS_PER_CHECK)},
                    "outputs": [], "source": check.splitlines(keepends=True)}
            cells += [cell, test]
            continue
        if cell.get("cell_type") == "markdown" and MD_BEGIN in cell_source(cell):
            meta["nbgrader"] = _nbgrader_meta(f"{stem}-{cell_id or i}", solution=True,
                                              grade=False, locked=False)
        cells.append(cell)
    out["cells"] = with_run_all_note(cells, nb)   # as the student build has it
    return strip_outputs(out)


def check_cell_count(nb: dict[str, Any]) -> int:
    """How many autograded test cells a notebook holds (``metadata.nbgrader.grade``)."""
    return sum(1 for c in nb.get("cells", []) if c.get("metadata", {}).get("nbgrader", {}).get("grade"))


#: The ``nbgrader_config.py`` :func:`write_course_source` puts into a new course directory.
NBGRADER_CONFIG = """\
# nbgrader's settings for a rosfpga_lab course (written by `rosfpga-lab notebooks nbgrader`).
# configure() makes nbgrader's student versions match `rosfpga-lab notebooks build`.
from rosfpga_lab.checks.grading import configure

c = get_config()  # noqa: F821 (nbgrader defines it)
configure(c)   # also finds nbgrader's alembic when the environment is not activated
"""


@dataclass(frozen=True)
class Assignment:
    """One assignment of an nbgrader course written by :func:`write_course_source`.

    Attributes:
        name: the assignment's name (the notebook's stem, e.g. ``02_tcpros``).
        notebook: the written source notebook.
        checks: how many autograded check cells it holds.
        points: the most points a submission can score.
    """

    name: str
    notebook: Path
    checks: int
    points: int


def write_course_source(source_dir: str | Path, course_dir: str | Path,
                        names: list[str] | None = None, *,
                        assignment: str | None = None) -> list[Assignment]:
    """Write ``course_dir/source/<assignment>/<stem>.ipynb`` for each instructor notebook.

    Each notebook is its own assignment, named after its stem, unless ``assignment`` names one
    for all of them. Existing files are overwritten (they are derived; edit
    ``notebooks/solutions/`` instead). Also writes ``course_dir/nbgrader_config.py`` (see
    :data:`NBGRADER_CONFIG`) when there is none.

    Args:
        source_dir: the instructor notebooks (``notebooks/solutions``).
        course_dir: the nbgrader course directory (``CourseDirectory.root``).
        names: only these stems or file names (default: every ``NN_*.ipynb``).
        assignment: one assignment for all the notebooks (default: one per notebook).

    Raises:
        NotebookBuildError: no such notebook, or one that cannot be converted.
    """
    src = Path(source_dir)
    paths = sorted(src.glob(NOTEBOOK_GLOB))
    if names:
        wanted = {Path(n).stem for n in names}
        unknown = wanted - {p.stem for p in paths}
        if unknown:
            raise NotebookBuildError(f"no instructor notebook {', '.join(sorted(unknown))} in {src}")
        paths = [p for p in paths if p.stem in wanted]
    if not paths:
        raise NotebookBuildError(f"no notebooks named NN_*.ipynb in {src}")
    done = []
    for path in paths:
        nb = nbgrader_notebook(load(path), path.name)
        name = assignment or path.stem
        target = Path(course_dir) / "source" / name / path.name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(dumps(nb), encoding="utf-8")
        checks = check_cell_count(nb)
        done.append(Assignment(name, target, checks, checks * POINTS_PER_CHECK))
    config = Path(course_dir) / "nbgrader_config.py"
    if not config.exists():
        config.write_text(NBGRADER_CONFIG, encoding="utf-8")
    return done


def configure(c: Any) -> None:
    """Set nbgrader's options so its student versions match ``rosfpga-lab notebooks build``.

    Call it from an ``nbgrader_config.py``: ``from rosfpga_lab.checks.grading import
    configure; configure(get_config())``.
    """
    environment_tools_on_path()
    c.ClearSolutions.code_stub = {"python": f"{PLACEHOLDER}\n{RAISE}"}
    c.ClearSolutions.text_stub = MD_PLACEHOLDER
    c.ClearSolutions.begin_solution_delimeter = BEGIN.removeprefix("# ")
    c.ClearSolutions.end_solution_delimeter = END.removeprefix("# ")


def environment_tools_on_path() -> str | None:
    """Put the running environment's ``bin/`` first on ``PATH`` when nbgrader's tools are not there.

    nbgrader runs ``alembic`` (its database migrations) as a program found on ``PATH``. A
    teacher's script or cron job that runs ``/opt/rosfpga-lab/venv/bin/nbgrader`` without
    activating the environment has no ``alembic`` on ``PATH``, and nbgrader fails with
    ``FileNotFoundError: 'alembic'``. Called from ``nbgrader_config.py`` (:func:`configure`), so
    every nbgrader command of a course finds the ``alembic`` installed beside it.

    Returns:
        The directory added, or ``None`` when ``alembic`` was already found (``PATH`` unchanged).
    """
    here = os.path.dirname(sys.executable)
    if shutil.which("alembic") is not None or shutil.which("alembic", path=here) is None:
        return None
    os.environ["PATH"] = here + os.pathsep + os.environ.get("PATH", "")
    return here
