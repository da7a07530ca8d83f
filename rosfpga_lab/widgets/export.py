"""Executed notebooks as self-contained HTML that shows every widget without JavaScript.

``jupyter nbconvert --execute --to html`` stores the widget state and writes pages that fetch
the widget JavaScript from a CDN: offline, or on a page without scripts, every widget is an
empty box. :func:`export_html` runs a notebook in a fresh kernel (in its own directory, as
JupyterLab does) and writes HTML with :data:`STATIC_EXPORT_PRIORITY`, so each widget shows the
static form it carries (byte tables, images, beat tables, the sequence diagram).

The page loads nothing from the internet: the widget state is left out (the static forms stand
in for it) and a template drops nbconvert's CDN scripts (RequireJS, MathJax, Mermaid and the
widget manager). Text that only holds in a live notebook ("click an arrow") is marked in the
notebooks' Markdown as ``<span class="rfl-live-only">...</span>`` and left out of the page.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.widgets._common import STATIC_EXPORT_PRIORITY, WidgetError
from rosfpga_lab.widgets.limits import CELL_TIMEOUT

#: Markdown marked with this class speaks of the live notebook only; pages leave it out.
LIVE_ONLY_CLASS = "rfl-live-only"
_LIVE_ONLY = re.compile(rf'<span class="{LIVE_ONLY_CLASS}">.*?</span>[ \t]*', re.S)
#: The lab template without the blocks that load scripts from a CDN.
OFFLINE_TEMPLATE = """{%- extends 'lab/index.html.j2' -%}
{%- block html_head_js_requirejs -%}{%- endblock html_head_js_requirejs -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
"""


def drop_live_only(markdown: str) -> str:
    """``markdown`` without the ``rfl-live-only`` spans (what a page without a kernel leaves out)."""
    return _LIVE_ONLY.sub("", markdown)


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
    nb.metadata.pop("widgets", None)   # the static forms stand in for the live widgets
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            cell.source = drop_live_only(cell.source)
    import jinja2

    config = Config({"NbConvertBase": {"display_data_priority": STATIC_EXPORT_PRIORITY}})
    exporter = HTMLExporter(config=config, template_file="rosfpga_offline.html.j2",
                            extra_loaders=[jinja2.DictLoader({"rosfpga_offline.html.j2": OFFLINE_TEMPLATE})])
    page, _ = exporter.from_notebook_node(nb)
    out = Path(output_dir) / f"{path.stem}.html"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(page, encoding="utf-8")
    except OSError as exc:
        raise WidgetError(f"cannot write {out}: {exc.strerror}") from None
    return Exported(path, out, time.monotonic() - start, errors)
