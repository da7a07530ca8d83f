"""One source for exercises and solutions: the student notebooks are generated, never edited.

Checks that the committed student notebooks equal what ``rosfpga-lab notebooks build`` makes
from ``notebooks/solutions/``, that both sets are stored without outputs, that the course has
the expected notebooks and exercises, and the generator's own rules (markers, tags, errors).
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from rosfpga_lab.checks import nbbuild
from rosfpga_lab.cli import main

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "notebooks"
SOLUTIONS = NOTEBOOKS / "solutions"
EXPECTED = ["00_overview", "01_xmlrpc_handshake", "02_tcpros", "03_message_conversion",
            "04_fifo_to_axi_stream", "05_application", "06_design_flow", "07_workshop_demo",
            "08_rtl", "09_ros2_wire", "10_your_own_message",
            "11_ros2_live", "12_fabric_sample"]


def notebook_paths(folder: Path) -> list[Path]:
    return sorted(folder.glob(nbbuild.NOTEBOOK_GLOB))


def test_the_course_has_its_notebooks_in_both_versions():
    assert [p.stem for p in notebook_paths(SOLUTIONS)] == EXPECTED
    assert [p.stem for p in notebook_paths(NOTEBOOKS)] == EXPECTED


def test_committed_student_notebooks_equal_the_generated_ones():
    items = nbbuild.build(SOLUTIONS, NOTEBOOKS, check=True)
    stale = [str(i.target.relative_to(ROOT)) for i in items if i.changed]
    assert not stale, f"run 'rosfpga-lab notebooks build': {stale} differ from notebooks/solutions"


@pytest.mark.parametrize("path", notebook_paths(NOTEBOOKS) + notebook_paths(SOLUTIONS),
                         ids=lambda p: str(p.relative_to(NOTEBOOKS)))
def test_stored_without_outputs_in_canonical_form(path: Path):
    nb = nbbuild.load(path)
    assert nbbuild.has_outputs(nb) == []
    assert path.read_text(encoding="utf-8") == nbbuild.dumps(nb), "not in nbformat's JSON layout"
    assert nb["nbformat"] == 4 and nb["metadata"]["kernelspec"]["name"] == "python3"


@pytest.mark.parametrize("name", EXPECTED)
def test_exercises_each_have_a_check_and_no_solution_leaks(name: str):
    source = nbbuild.load(SOLUTIONS / f"{name}.ipynb")
    student = nbbuild.load(NOTEBOOKS / f"{name}.ipynb")
    blocks = [c for c in source["cells"] if nbbuild.is_exercise_cell(c)]
    if name in ("00_overview", "07_workshop_demo"):
        assert blocks == []
        return
    assert len(blocks) >= 2, "notebooks 1 to 6 end with exercises"
    for cell in blocks:
        after = nbbuild.cell_source(cell).split(nbbuild.END, 1)[1]
        assert re.search(r"\bcheck_\w+\(", after), "each exercise is checked by rosfpga_lab.checks"
    text = json.dumps(student)
    assert nbbuild.BEGIN not in text and nbbuild.END not in text
    assert text.count(nbbuild.PLACEHOLDER) == len(blocks)
    for cell in blocks:
        solution = nbbuild.cell_source(cell).split(nbbuild.BEGIN, 1)[1].split(nbbuild.END, 1)[0]
        for line in solution.splitlines():
            if len(line.strip()) > 25:
                assert line not in text, f"solution line leaked into the student notebook: {line!r}"


@pytest.mark.parametrize("path", notebook_paths(SOLUTIONS), ids=lambda p: p.stem)
def test_notebooks_stay_offline_and_on_loopback(path: Path):
    code = "\n".join(nbbuild.cell_source(c) for c in nbbuild.load(path)["cells"]
                     if c["cell_type"] == "code")
    for url in re.findall(r"https?://[^\s\"')]+", code):
        assert url.startswith(("http://127.0.0.1", "http://localhost")), url
    assert "0.0.0.0" not in code
    assert "pip install" not in code


# ------------------------------------------------------------------------------ the generator
def test_strip_solution_keeps_indentation_and_the_rest():
    src = ("x = 1\n"
           "def f():\n"
           "    # BEGIN SOLUTION\n"
           "    return 42\n"
           "    # END SOLUTION\n"
           "check(f)")
    assert nbbuild.strip_solution(src) == ("x = 1\n"
                                           "def f():\n"
                                           f"    {nbbuild.PLACEHOLDER}\n"
                                           f"    {nbbuild.RAISE}\n"
                                           "check(f)")


@pytest.mark.parametrize("src, words", [
    ("# BEGIN SOLUTION\nx = 1\n", "line 1: # BEGIN SOLUTION is never closed"),
    ("x = 1\n# END SOLUTION\n", "line 2: # END SOLUTION without # BEGIN SOLUTION"),
    ("# BEGIN SOLUTION\n# BEGIN SOLUTION\n# END SOLUTION\n", "line 2: # BEGIN SOLUTION inside"),
])
def test_unbalanced_markers_are_refused_with_the_line(src: str, words: str):
    with pytest.raises(nbbuild.NotebookBuildError, match=re.escape(words)):
        nbbuild.strip_solution(src, where="nb.ipynb cell 3")


def make_notebook(cells: list[dict]) -> dict:
    return {"cells": cells, "metadata": {"kernelspec": {"name": "python3"}}, "nbformat": 4,
            "nbformat_minor": 5}


def code(src: str, **meta) -> dict:
    return {"cell_type": "code", "id": "a", "metadata": meta, "source": src,
            "outputs": [{"output_type": "stream", "name": "stdout", "text": "hi"}], "execution_count": 3}


def test_student_notebook_drops_tagged_cells_markdown_answers_and_outputs():
    nb = make_notebook([
        code("print(1)"),
        code("secret = 1", tags=["solution"]),
        {"cell_type": "markdown", "id": "m", "metadata": {},
         "source": "Why? <!-- BEGIN SOLUTION -->Because.<!-- END SOLUTION -->"},
    ])
    student = nbbuild.student_notebook(nb, "01_x.ipynb")
    assert [nbbuild.cell_source(c) for c in student["cells"]] == ["print(1)", f"Why? {nbbuild.MD_PLACEHOLDER}"]
    assert nbbuild.has_outputs(student) == []
    assert student["metadata"]["rosfpga_lab"]["generated_from"] == "solutions/01_x.ipynb"
    assert nbbuild.has_outputs(nb) == [0, 1], "the source notebook is not changed"


def test_build_writes_check_detects_drift_and_cli_exit_codes(tmp_path: Path, capsys):
    src = tmp_path / "solutions"
    src.mkdir()
    (src / "01_demo.ipynb").write_text(nbbuild.dumps(make_notebook(
        [code("# BEGIN SOLUTION\nanswer = 42\n# END SOLUTION\ncheck(answer)")])), encoding="utf-8")
    assert main(["notebooks", "build", "--source", str(src), "--check"]) == 1
    assert "out of date" in capsys.readouterr().out
    assert main(["notebooks", "build", "--source", str(src)]) == 0
    target = tmp_path / "01_demo.ipynb"
    first = target.read_text(encoding="utf-8")
    assert "answer = 42" not in first and nbbuild.PLACEHOLDER in first
    assert nbbuild.has_outputs(nbbuild.load(src / "01_demo.ipynb")) == [], "sources are cleaned too"
    assert main(["notebooks", "build", "--source", str(src), "--check"]) == 0
    assert main(["notebooks", "build", "--source", str(src)]) == 0
    assert target.read_text(encoding="utf-8") == first, "rebuilding is deterministic"
    target.write_text(first.replace("check(answer)", "check(answer)  # edited by hand"), encoding="utf-8")
    assert main(["notebooks", "build", "--source", str(src), "--check"]) == 1
    assert main(["notebooks", "build", "--source", str(src)]) == 0
    (tmp_path / "02_renamed.ipynb").write_text(first, encoding="utf-8")   # its source is gone
    capsys.readouterr()
    assert main(["notebooks", "build", "--source", str(src), "--check"]) == 1
    assert "02_renamed.ipynb: no source" in capsys.readouterr().out


def test_build_without_sources_says_where_it_looked(tmp_path: Path, capsys):
    assert main(["notebooks", "build", "--source", str(tmp_path / "nowhere")]) == 1
    assert "no notebooks named NN_*.ipynb" in capsys.readouterr().err


def test_the_real_sources_build_into_an_empty_directory(tmp_path: Path):
    shutil.copytree(SOLUTIONS, tmp_path / "solutions")
    items = nbbuild.build(tmp_path / "solutions", tmp_path)
    assert [i.exercises for i in items] == [0, 3, 3, 3, 3, 2, 2, 0, 3, 2, 3, 3, 2]
    for item in items:
        assert item.target.read_text(encoding="utf-8") == (NOTEBOOKS / item.target.name).read_text(encoding="utf-8")


def test_student_notebooks_with_exercises_say_run_all_stops_at_the_first() -> None:
    """A student who presses Run All sees, near the top, why it stops at the first exercise."""
    from rosfpga_lab.checks import nbbuild

    root = Path(__file__).resolve().parents[2] / "notebooks"
    for path in sorted(root.glob(nbbuild.NOTEBOOK_GLOB)):
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        has_exercises = any(nbbuild.PLACEHOLDER in "".join(c["source"]) for c in cells)
        notes = [i for i, c in enumerate(cells) if c.get("id") == nbbuild.RUN_ALL_NOTE_ID]
        if has_exercises:
            assert notes == [1], path.name
            assert "Run All stops at the first exercise" in "".join(cells[1]["source"])
        else:
            assert notes == [], path.name
