"""Every notebook runs headless, top to bottom, in a fresh kernel, offline.

* The instructor versions (``notebooks/solutions/``) run with every exercise filled in: no cell
  may fail, and every exercise cell must show its check's "correct" line.
* The student versions run top to bottom too, with each exercise cell expected to raise exactly
  the placeholder's ``NotImplementedError`` (that is what a student who runs it unchanged sees)
  and every other cell expected to succeed. So the teaching cells, the exercise set-up and the
  clean-up cells all work without the solutions, and no later cell depends on an answer.

Notebooks run in their own directory, as JupyterLab runs them. Notebook 7 also drives real ROS 1
(``rostopic``, a rospy node) when it is installed, and explains itself when it is not; notebook 6
compiles the generated C++ when g++ is there.
"""

from __future__ import annotations

import time
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError

from rosfpga_lab.checks import nbbuild

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
SOLUTIONS = NOTEBOOKS / "solutions"
#: Seconds one cell may take (the slowest, notebook 7's real-ROS cell, needs about 10).
CELL_TIMEOUT = 180

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]


def client_for(path: Path) -> tuple[NotebookClient, nbformat.NotebookNode]:
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=CELL_TIMEOUT, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    return client, nb


def text_of(cell: nbformat.NotebookNode) -> str:
    parts = []
    for out in cell.get("outputs", []):
        if out.get("output_type") == "stream":
            parts.append(out.get("text", ""))
        elif out.get("output_type") in ("execute_result", "display_data"):
            parts.append(out.get("data", {}).get("text/plain", ""))
        elif out.get("output_type") == "error":
            parts.append(f"{out.get('ename')}: {out.get('evalue')}")
    return "\n".join(parts)


@pytest.mark.parametrize("path", sorted(SOLUTIONS.glob(nbbuild.NOTEBOOK_GLOB)), ids=lambda p: p.stem)
def test_solution_notebook_runs_and_every_check_passes(path: Path):
    client, nb = client_for(path)
    start = time.monotonic()
    client.execute()
    print(f"{path.name}: {time.monotonic() - start:.1f} s")
    for index, cell in enumerate(nb.cells):
        if nbbuild.is_exercise_cell(cell):
            shown = text_of(cell)
            assert "\u2714 Exercise" in shown and "correct" in shown, \
                f"{path.name} cell {index}: the check did not report success: {shown[:300]}"


STUDENT_NOTEBOOKS = [p for p in sorted(NOTEBOOKS.glob(nbbuild.NOTEBOOK_GLOB))
                     if nbbuild.PLACEHOLDER in p.read_text(encoding="utf-8")]


@pytest.mark.parametrize("path", STUDENT_NOTEBOOKS, ids=lambda p: p.stem)
def test_student_notebook_runs_with_only_the_placeholders_failing(path: Path):
    client, nb = client_for(path)
    placeholders = 0
    with client.setup_kernel():
        for index, cell in enumerate(nb.cells):
            if cell.cell_type != "code":
                continue
            if nbbuild.PLACEHOLDER in cell.source:
                with pytest.raises(CellExecutionError) as info:
                    client.execute_cell(cell, index)
                assert info.value.ename == "NotImplementedError", \
                    f"{path.name} cell {index}: expected the placeholder's error, got {info.value.ename}"
                assert "replace this line with your code" in info.value.evalue
                placeholders += 1
            else:
                client.execute_cell(cell, index)
    assert placeholders >= 2
