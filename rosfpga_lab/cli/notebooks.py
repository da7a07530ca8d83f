"""``rosfpga-lab notebooks build|nbgrader|html``: student notebooks from the solutions, an nbgrader
course's source, offline HTML pages.

``notebooks html notebooks/solutions/*.ipynb --output-dir site`` runs each notebook in a fresh
kernel (in its own directory) and writes ``site/NN_*.html``. Every widget shows its static form
(``rosfpga_lab.widgets``): the pages need no JavaScript and no network, and sentences about
clicking (marked ``<span class="rfl-live-only">`` in the notebooks) are left out. (``jupyter
nbconvert --execute --to html`` leaves every widget an empty box offline: it fetches the widgets'
JavaScript from the network.) ``--no-execute`` exports stored outputs; ``--allow-errors`` exports
student notebooks, which stop at each exercise.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any


class _IntermixedParser(argparse.ArgumentParser):
    """A sub-command parser that takes options between positionals.

    ``notebooks nbgrader COURSE_DIR --source DIR NOTEBOOK``: plain argparse fills the
    ``NOTEBOOK`` list (``nargs="*"``) with nothing right after ``COURSE_DIR`` and then rejects
    ``NOTEBOOK`` as an unrecognized argument; intermixed parsing collects every positional first.
    """

    _intermixing = False

    def parse_known_args(self, args: Sequence[str] | None = None,  # type: ignore[override]
                         namespace: Any = None) -> tuple[Any, list[str]]:
        if self._intermixing:   # parse_known_intermixed_args calls this method itself
            return super().parse_known_args(args, namespace)
        self._intermixing = True
        try:
            return self.parse_known_intermixed_args(args, namespace)
        finally:
            self._intermixing = False


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``notebooks`` sub-command."""
    parser = subparsers.add_parser(
        "notebooks",
        help="build the student notebooks from the instructor notebooks (solutions)",
        description="The instructor notebooks in notebooks/solutions/ are the one source of the "
        "course. 'build' writes notebooks/NN_*.ipynb from them, replacing each "
        "'# BEGIN SOLUTION' ... '# END SOLUTION' block by '# YOUR CODE HERE' and dropping cells "
        "tagged 'solution'; outputs are stripped from both. 'build --check' writes nothing and "
        "fails when a student notebook is out of date. 'html' runs notebooks and writes pages "
        "that show every widget without JavaScript (for offline reading or a course website).",
    )
    sub = parser.add_subparsers(dest="action", metavar="ACTION", parser_class=_IntermixedParser)
    build = sub.add_parser("build", help="write (or with --check: verify) the student notebooks",
                           description="Generate the student notebooks from the solutions.")
    build.add_argument("--source", type=Path, default=Path("notebooks/solutions"), metavar="DIR",
                       help="instructor notebooks (default: notebooks/solutions)")
    build.add_argument("--output", type=Path, default=None, metavar="DIR",
                       help="where the student notebooks go (default: the parent of --source)")
    build.add_argument("--check", action="store_true",
                       help="write nothing; exit 1 if any student notebook differs from what "
                       "the build would write")
    build.set_defaults(func=run)
    grading = sub.add_parser(
        "nbgrader", help="write an nbgrader course's source notebooks (exercises graded by the checks)",
        description="Write COURSE_DIR/source/<assignment>/NN_name.ipynb from the instructor "
        "notebooks, with nbgrader's cell metadata derived from them: each exercise cell becomes "
        "an autograded answer cell (the part up to '# END SOLUTION') and a locked autograder "
        "test cell (the check call after it, worth one point). Also writes "
        "COURSE_DIR/nbgrader_config.py when missing. Then, in COURSE_DIR: nbgrader "
        "generate_assignment NAME, release_assignment, collect, autograde (course/README.md). "
        "Needs no nbgrader itself; the course server has it (pip install -e '.[course]'). "
        "Options may stand anywhere, e.g. rosfpga-lab notebooks nbgrader ~/course --source "
        "notebooks/solutions 02_tcpros.")
    grading.add_argument("course_dir", type=Path, metavar="COURSE_DIR",
                         help="the nbgrader course directory (created if missing)")
    grading.add_argument("notebooks", nargs="*", metavar="NOTEBOOK",
                         help="only these notebooks, by stem or file name (default: all)")
    grading.add_argument("--source", type=Path, default=Path("notebooks/solutions"), metavar="DIR",
                         help="instructor notebooks (default: notebooks/solutions)")
    grading.add_argument("--assignment", default=None, metavar="NAME",
                         help="one assignment holding all the notebooks (default: one assignment "
                         "per notebook, named after it)")
    grading.set_defaults(func=run_nbgrader)
    html = sub.add_parser(
        "html", help="run notebooks and write self-contained HTML pages (widgets in static form)",
        description="Run each notebook top to bottom in a fresh kernel (in its own directory) and "
        "write DIR/<name>.html. Unlike 'jupyter nbconvert --execute --to html', whose widgets "
        "need JavaScript from the internet, every widget shows its static form: byte tables, "
        "images, beat tables, the sequence diagram. Example: rosfpga-lab notebooks html "
        "notebooks/solutions/*.ipynb --output-dir site")
    html.add_argument("notebooks", type=Path, nargs="+", metavar="NOTEBOOK", help="the .ipynb files")
    html.add_argument("--output-dir", type=Path, default=Path("html"), metavar="DIR",
                      help="where the pages go (default: html)")
    html.add_argument("--no-execute", action="store_true",
                      help="export the outputs stored in the files instead of running them")
    html.add_argument("--allow-errors", action="store_true",
                      help="keep going past failing cells (student notebooks stop at each exercise)")
    html.set_defaults(func=run_html)
    parser.set_defaults(func=lambda _args: (parser.print_help(), 2)[1])


def run(args: argparse.Namespace) -> int:
    """Build or check; print one line per notebook."""
    from rosfpga_lab.checks.nbbuild import build, orphans

    output = args.output if args.output is not None else args.source.parent
    items = build(args.source, output, check=args.check)
    stale = [i for i in items if i.changed]
    for item in items:
        state = ("out of date" if args.check else "written") if item.changed else "up to date"
        print(f"{item.target}: {state} ({item.exercises} exercise block(s))")
    lost = orphans(args.source, output)
    for path in lost:
        print(f"{path}: no source in {args.source} (renamed or removed? delete it by hand)")
    if args.check and (stale or lost):
        print(f"{len(stale) + len(lost)} student notebook(s) do not match their solutions source; "
              "run 'rosfpga-lab notebooks build'")
        return 1
    return 0


def run_nbgrader(args: argparse.Namespace) -> int:
    """Write the nbgrader course source; print one line per notebook."""
    from rosfpga_lab.checks.grading import write_course_source

    for item in write_course_source(args.source, args.course_dir, args.notebooks,
                                    assignment=args.assignment):
        print(f"{item.notebook}: assignment {item.name}, {item.checks} graded check(s), "
              f"{item.points} point(s)")
    return 0


def run_html(args: argparse.Namespace) -> int:
    """Export each notebook; print one line per page."""
    from rosfpga_lab.widgets.export import export_html

    for notebook in args.notebooks:
        done = export_html(notebook, args.output_dir, execute=not args.no_execute,
                           allow_errors=args.allow_errors)
        errors = f", {done.errors} cell(s) with errors" if done.errors else ""
        print(f"{done.html}: from {notebook} in {done.seconds:.1f} s{errors}", flush=True)
    return 0
