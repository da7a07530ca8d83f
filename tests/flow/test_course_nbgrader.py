"""Exercises graded by real nbgrader: the student versions it makes, and the scores it gives.

* ``nbgrader generate_assignment`` on the course source that ``rosfpga-lab notebooks nbgrader``
  derives from ``notebooks/solutions/`` gives, cell for cell, the student notebooks of
  ``rosfpga-lab notebooks build`` (each exercise cell split into its answer and its check).
* Released, fetched, submitted and collected through an nbgrader exchange (one student; the
  others' files are put in place, to keep the test short), then ``nbgrader autograde`` scores notebook 2 (three exercises, one point each): the solution 3,
  the untouched student copy 0, a half-done copy (one right, one wrong, one untouched) 1, and
  the wrong answer's findings from its check appear in the graded notebook.

nbgrader comes with the ``[course]`` extra; without it these tests skip with a reason, and with
``ROSFPGA_REQUIRE_COURSE=1`` (CI) they fail instead.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.realros import skip_or_fail
from rosfpga_lab.checks import grading, nbbuild

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = ROOT / "notebooks" / "solutions"
GRADED = "02_tcpros"
BIN = Path(sys.executable).parent

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]


@pytest.fixture(scope="module")
def nbgrader_cmd() -> list[str]:
    try:
        import nbgrader  # noqa: F401
    except ImportError:
        skip_or_fail("nbgrader not installed (pip install -e '.[course]')", "ROSFPGA_REQUIRE_COURSE")
    return [sys.executable, "-m", "nbgrader"]


def run(cmd: list[str], cwd: Path) -> str:
    # nbgrader runs alembic as a program: the environment's bin/ goes first on PATH.
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}")
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, f"{' '.join(cmd)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc.stdout + proc.stderr


def cells(path: Path) -> list[dict]:
    return json.loads(path.read_text(encoding="utf-8"))["cells"]


def test_split_exercise_keeps_answer_and_check_apart() -> None:
    answer, check = grading.split_exercise(
        "from x import check\n\n# BEGIN SOLUTION\nv = 1\n# END SOLUTION\ncheck(v)\n")
    assert answer == "from x import check\n\n# BEGIN SOLUTION\nv = 1\n# END SOLUTION"
    assert check == "check(v)"
    with pytest.raises(nbbuild.NotebookBuildError):
        grading.split_exercise("v = 1\n")


def test_every_exercise_gets_one_graded_check() -> None:
    for path in sorted(SOLUTIONS.glob(nbbuild.NOTEBOOK_GLOB)):
        nb = nbbuild.load(path)
        exercises = [c for c in nb["cells"] if nbbuild.is_exercise_cell(c)]
        derived = grading.nbgrader_notebook(nb, path.name)
        tests = [c for c in derived["cells"] if c["metadata"].get("nbgrader", {}).get("grade")]
        assert len(tests) == len(exercises), path.name
        for exercise, test in zip(exercises, tests):
            meta = test["metadata"]["nbgrader"]
            assert meta["points"] == grading.POINTS_PER_CHECK and meta["locked"] and not meta["solution"]
            after_end = nbbuild.cell_source(exercise).rsplit(nbbuild.END, 1)[1].strip()
            assert nbbuild.cell_source(test) == after_end and after_end.startswith("check_")
        ids = [c.get("id") for c in derived["cells"]]
        assert len(ids) == len(set(ids)), f"{path.name}: duplicate cell ids"


def test_exercise_without_a_check_is_refused() -> None:
    nb = {"cells": [{"cell_type": "code", "id": "x1", "metadata": {}, "outputs": [],
                     "execution_count": None, "source": "# BEGIN SOLUTION\nv = 1\n# END SOLUTION\n"}]}
    with pytest.raises(nbbuild.NotebookBuildError, match="nothing after"):
        grading.nbgrader_notebook(nb, "09_x.ipynb")


def test_generate_assignment_equals_the_lab_build(nbgrader_cmd: list[str], tmp_path: Path) -> None:
    course = tmp_path / "course"
    grading.write_course_source(SOLUTIONS, course, assignment="all")
    run(nbgrader_cmd + ["generate_assignment", "all", "--force"], course)
    for path in sorted(SOLUTIONS.glob(nbbuild.NOTEBOOK_GLOB)):
        lab = nbbuild.student_notebook(nbbuild.load(path), path.name)["cells"]
        released = cells(course / "release" / "all" / path.name)
        joined: list[tuple[str, str]] = []
        for cell in released:
            meta = cell["metadata"].get("nbgrader", {})
            text = nbbuild.cell_source(cell)
            if meta.get("grade") and not meta.get("solution"):
                kind, answer = joined.pop()
                joined.append((kind, f"{answer}\n{text}"))   # the check, back under its answer
            else:
                joined.append((cell["cell_type"], text))
        expected = [(c["cell_type"], nbbuild.cell_source(c).rstrip("\n")) for c in lab]
        assert [(k, t.rstrip("\n")) for k, t in joined] == expected, path.name


def _answer_sources(path: Path) -> dict[str, str]:
    return {c["metadata"]["nbgrader"]["grade_id"]: nbbuild.cell_source(c) for c in cells(path)
            if c["metadata"].get("nbgrader", {}).get("solution")}


def test_autograde_scores_solution_untouched_and_half_done(nbgrader_cmd: list[str],
                                                           tmp_path: Path) -> None:
    course = tmp_path / "course"
    run([str(BIN / "rosfpga-lab"), "notebooks", "nbgrader", str(course), GRADED,
         "--source", str(SOLUTIONS)], tmp_path)
    run(nbgrader_cmd + ["generate_assignment", GRADED, "--force"], course)
    source = course / "source" / GRADED / f"{GRADED}.ipynb"
    release = course / "release" / GRADED / f"{GRADED}.ipynb"
    solved = _answer_sources(source)
    ids = sorted(solved)
    assert len(ids) == 3

    release_nb = json.loads(release.read_text(encoding="utf-8"))
    half = json.loads(release.read_text(encoding="utf-8"))
    for cell in half["cells"]:
        gid = cell["metadata"].get("nbgrader", {}).get("grade_id")
        text = nbbuild.cell_source(cell)
        if gid == ids[0]:
            cell["source"] = solved[gid]                                   # right
        elif gid in solved and "check_md5" in text:                        # wrong: md5 of the name
            assert nbbuild.RAISE in text
            cell["source"] = text.replace(
                nbbuild.RAISE, 'md5 = hashlib.md5(b"geometry_msgs/Pose").hexdigest()')
    assert sum(nbbuild.RAISE in nbbuild.cell_source(c) for c in half["cells"]) == 1
    full = json.loads(release.read_text(encoding="utf-8"))
    for cell in full["cells"]:
        gid = cell["metadata"].get("nbgrader", {}).get("grade_id")
        if gid in solved:
            cell["source"] = solved[gid]
    # release, fetch, submit and collect through an exchange, as on a course server
    exchange = tmp_path / "exchange"
    exchange.mkdir(mode=0o777)
    where = [f"--Exchange.root={exchange}", "--CourseDirectory.course_id=test-course"]
    run(nbgrader_cmd + ["release_assignment", GRADED] + where, course)
    students = {"solved": full, "untouched": release_nb, "half": half}
    home = tmp_path / "half"                   # one student goes through the exchange ...
    home.mkdir()
    run(nbgrader_cmd + ["fetch_assignment", GRADED] + where, home)
    fetched = home / GRADED / f"{GRADED}.ipynb"
    assert fetched.read_text(encoding="utf-8") == release.read_text(encoding="utf-8")
    fetched.write_text(json.dumps(half), encoding="utf-8")
    run(nbgrader_cmd + ["submit", GRADED, "--student=half"] + where, home)
    for student in ("solved", "untouched"):    # ... two hand theirs in by other means
        target = course / "submitted" / student / GRADED / f"{GRADED}.ipynb"
        target.parent.mkdir(parents=True)
        target.write_text(json.dumps(students[student]), encoding="utf-8")
    (tmp_path / "students.csv").write_text("id\n" + "\n".join(students) + "\n")
    run(nbgrader_cmd + ["db", "student", "import", str(tmp_path / "students.csv")], course)
    run(nbgrader_cmd + ["collect", GRADED] + where, course)
    run(nbgrader_cmd + ["autograde", GRADED, "--force"], course)
    run(nbgrader_cmd + ["export", "--to", str(tmp_path / "grades.csv")], course)

    with open(tmp_path / "grades.csv", newline="", encoding="utf-8") as f:
        scores = {row["student_id"]: (float(row["score"]), float(row["max_score"]))
                  for row in csv.DictReader(f)}
    print(scores)
    assert scores["solved"] == (3.0, 3.0)
    assert scores["untouched"] == (0.0, 3.0)
    assert scores["half"] == (1.0, 3.0)

    graded = cells(course / "autograded" / "half" / GRADED / f"{GRADED}.ipynb")
    outputs = json.dumps([c.get("outputs", []) for c in graded])
    assert "not right yet" in outputs and "md5" in outputs            # the wrong answer's findings
    assert "correct" in outputs                                       # the right answer's line
    assert "NotImplementedError" in outputs                           # the untouched one

    run(nbgrader_cmd + ["generate_feedback", GRADED, "--student=half", "--force"], course)
    page = (course / "feedback" / "half" / GRADED / f"{GRADED}.html").read_text(encoding="utf-8")
    assert "not right yet" in page and "Score: 1.0 / 3.0" in page     # what the student gets back


# The orders the help and course/README.md show: options first (the usage line), options between
# the course and the notebooks (course/README.md), options last.
CLI_ORDERS = [
    ["--source", "{src}", "{course}", "02_tcpros", "04_fifo_to_axi_stream"],
    ["{course}", "--source", "{src}", "02_tcpros", "04_fifo_to_axi_stream"],
    ["{course}", "02_tcpros", "--source", "{src}", "04_fifo_to_axi_stream"],
    ["{course}", "02_tcpros", "04_fifo_to_axi_stream", "--source", "{src}"],
]


@pytest.mark.parametrize("order", CLI_ORDERS, ids=["options-first", "readme", "between", "last"])
def test_nbgrader_command_takes_options_between_positionals(order: list[str], tmp_path: Path) -> None:
    from rosfpga_lab.cli import main

    course = tmp_path / "course"
    argv = [a.format(src=SOLUTIONS, course=course) for a in order]
    assert main(["notebooks", "nbgrader", *argv]) == 0
    written = sorted(p.relative_to(course).as_posix() for p in course.glob("source/*/*.ipynb"))
    assert written == ["source/02_tcpros/02_tcpros.ipynb",
                       "source/04_fifo_to_axi_stream/04_fifo_to_axi_stream.ipynb"]


def _readme_grading_block() -> str:
    text = (ROOT / "course" / "README.md").read_text(encoding="utf-8")
    section = text.split("**Grading with nbgrader.**", 1)[1]
    return section.split("```bash\n", 1)[1].split("```", 1)[0]


def test_readme_grading_commands_run_as_written_in_a_new_shell(nbgrader_cmd: list[str],
                                                               tmp_path: Path) -> None:
    """course/README.md's commands, one script in a fresh /bin/sh whose PATH has no environment on it
    (a teacher's new shell, script or cron job): only the install places are swapped for this
    machine's. Before the fix nbgrader failed there: it runs ``alembic`` by name."""
    block = _readme_grading_block()
    assert "/opt/rosfpga-lab/venv/bin/nbgrader generate_assignment" in block
    script = (block.replace("/opt/rosfpga-lab/venv/bin", str(BIN))
              .replace("/path/to/checkout", str(ROOT)))
    etc = tmp_path / "etc"       # what course/setup.sh writes to /etc/jupyter/nbgrader_config.py
    etc.mkdir()
    exchange = tmp_path / "exchange"
    exchange.mkdir()
    (etc / "nbgrader_config.py").write_text(
        f'c = get_config()\nc.CourseDirectory.course_id = "test-course"\n'
        f'c.Exchange.root = "{exchange}"\n', encoding="utf-8")
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "JUPYTER_CONFIG_PATH": str(etc),
           "TMPDIR": os.environ.get("TMPDIR", "/tmp"), "LANG": "C.UTF-8"}
    if os.environ.get("PYTHONPATH"):      # a worktree run: the lab under test, not the installed one
        env["PYTHONPATH"] = os.environ["PYTHONPATH"]
    assert shutil.which("alembic", path=env["PATH"]) is None
    teacher, collect = script.split(f"{BIN}/nbgrader collect", 1)
    student = tmp_path / "student"      # between release and collect, a student hands one in
    student.mkdir()
    student_script = (f"cd {student}\n{BIN}/nbgrader fetch_assignment 02_tcpros\n"
                      f"{BIN}/nbgrader submit 02_tcpros\n")
    for part in (teacher, student_script, f"cd ~/course\n{BIN}/nbgrader collect{collect}"):
        proc = subprocess.run(["/bin/sh", "-e", "-c", part], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=240)
        assert proc.returncode == 0, f"{part}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    course = tmp_path / "course"
    assert (course / "release" / "02_tcpros" / "02_tcpros.ipynb").is_file()
    assert (exchange / "test-course" / "outbound" / "02_tcpros" / "02_tcpros.ipynb").is_file()
    with open(course / "grades.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [(r["assignment"], float(r["score"]), float(r["max_score"])) for r in rows] == [
        ("02_tcpros", 0.0, 3.0)]                            # the untouched copy, graded


def test_environment_tools_on_path_adds_only_what_is_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    if shutil.which("alembic", path=str(BIN)) is None:
        skip_or_fail("alembic not installed (pip install -e '.[course]')", "ROSFPGA_REQUIRE_COURSE")
    monkeypatch.setenv("PATH", "/usr/bin:/bin")
    assert grading.environment_tools_on_path() == str(BIN)
    assert os.environ["PATH"] == f"{BIN}{os.pathsep}/usr/bin:/bin"
    assert grading.environment_tools_on_path() is None          # found now: PATH stays
    assert os.environ["PATH"] == f"{BIN}{os.pathsep}/usr/bin:/bin"


def test_validate_fails_on_an_unanswered_assignment(nbgrader_cmd: list[str], tmp_path: Path) -> None:
    """nbgrader's Validate said "Success" for an unanswered student notebook (it carries no
    graded cells; the student lab hides the button, tests/flow/test_lab_student_view.py). The version
    students fetch on the course server has the checks as graded cells: there it fails."""
    course = tmp_path / "course"
    grading.write_course_source(SOLUTIONS, course, [GRADED])
    run(nbgrader_cmd + ["generate_assignment", GRADED, "--force"], course)
    released = course / "release" / GRADED / f"{GRADED}.ipynb"
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}")
    proc = subprocess.run(nbgrader_cmd + ["validate", str(released)], cwd=course, env=env,
                          capture_output=True, text=True, timeout=240)
    out = proc.stdout + proc.stderr
    assert "Success" not in out and "VALIDATION FAILED" in out, out[-2000:]
