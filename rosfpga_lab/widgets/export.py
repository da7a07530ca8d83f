"""Executed notebooks as self-contained HTML that shows every widget without JavaScript.

``jupyter nbconvert --execute --to html`` stores the widget state and writes pages that fetch
the widget JavaScript from a CDN: offline, or on a page without scripts, every widget is an
empty box. :func:`export_html` runs a notebook in a fresh kernel (in its own directory, as
JupyterLab does) and writes HTML with :data:`STATIC_EXPORT_PRIORITY`, so each widget shows the
static form it carries (byte tables, images, beat tables, the sequence diagram).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.widgets._common import STATIC_EXPORT_PRIORITY, WidgetError

#: Seconds one cell may run before the export gives up.
CELL_TIMEOUT = 300


@dataclass(frozen=True)
class Exported:
    """One written page: ``html`` from ``notebook``, ``seconds`` spent, ``errors`` cells that failed."""

    notebook: Path
    html: Path
    seconds: float
    errors: int


def export_html(notebook: str | Path, output_dir: str | Path, *, execute: bool = True,
                allow_errors: bool = False, timeout: int = CELL_TIMEOUT) -> Exported:
    """Run ``notebook`` (unless ``execute`` is False) and write ``output_dir/<name>.html``.

    Args:
        notebook: the ``.ipynb`` file (it is not modified).
        output_dir: where the page goes (created if missing).
        execute: run every cell in a fresh kernel first; False exports the stored outputs.
        allow_errors: keep going after a failing cell (a student notebook's placeholders);
            the page then shows the error.
        timeout: seconds one cell may take.

    Returns:
        What was written.

    Raises:
        WidgetError: the notebook cannot be read, a cell fails (without ``allow_errors``) or
            the page cannot be written.
    """
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError
    from nbconvert import HTMLExporter
    from traitlets.config import Config

    path = Path(notebook)
    try:
        nb = nbformat.read(path, as_version=4)
    except (OSError, ValueError) as exc:
        raise WidgetError(f"{path}: cannot read the notebook: {exc}") from None
    start = time.monotonic()
    if execute:
        client = NotebookClient(nb, timeout=timeout, kernel_name="python3", allow_errors=allow_errors,
                                resources={"metadata": {"path": str(path.parent.resolve())}})
        try:
            client.execute()
        except CellExecutionError as exc:
            raise WidgetError(f"{path}: a cell failed: {exc.ename}: {exc.evalue} (a student "
                              "notebook stops at its first exercise; allow errors to export it "
                              "anyway)") from None
    errors = sum(1 for c in nb.cells if c.cell_type == "code"
                 for o in c.get("outputs", []) if o.get("output_type") == "error")
    config = Config({"NbConvertBase": {"display_data_priority": STATIC_EXPORT_PRIORITY}})
    page, _ = HTMLExporter(config=config).from_notebook_node(nb)
    out = Path(output_dir) / f"{path.stem}.html"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(page, encoding="utf-8")
    except OSError as exc:
        raise WidgetError(f"cannot write {out}: {exc.strerror}") from None
    return Exported(path, out, time.monotonic() - start, errors)
