"""``rosfpga-lab notebooks html``: executed notebooks as pages whose widgets need no JavaScript."""

from __future__ import annotations

import re
from pathlib import Path

import nbformat
import pytest

from rosfpga_lab.cli import main
from rosfpga_lab.widgets import WidgetError
from rosfpga_lab.widgets.export import export_html

VIEWER_CELL = '''
from rosfpga_lab import msg
from rosfpga_lab.widgets import message_viewer
body = msg.serialize(msg.default_registry(), "std_msgs/String", {"data": "hi<&>"})
message_viewer("std_msgs/String", body)
'''


def notebook(path: Path, *cells: str) -> Path:
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in cells]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(nb, path)
    return path


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_html_command_runs_the_notebook_and_shows_widgets_statically(tmp_path: Path, capsys) -> None:
    src = notebook(tmp_path / "viewer.ipynb", "import os\nprint(os.getcwd())", VIEWER_CELL)
    assert main(["notebooks", "html", str(src), "--output-dir", str(tmp_path / "site")]) == 0
    assert f"{tmp_path / 'site' / 'viewer.html'}: from {src}" in capsys.readouterr().out
    page = (tmp_path / "site" / "viewer.html").read_text(encoding="utf-8")
    assert str(tmp_path) in page                                   # ran in the notebook's directory
    assert '<script type="application/vnd.jupyter.widget-view+json">' not in page
    bare = re.sub(r"<(script|style)\b.*?</\1>", "", page, flags=re.S | re.I)
    assert "std_msgs/String" in bare and "hi&lt;&amp;&gt;" in bare   # the byte viewer's table
    assert nbformat.read(src, as_version=4).cells[0].outputs == []  # the source is left alone


def test_export_without_running_and_the_errors(tmp_path: Path) -> None:
    src = notebook(tmp_path / "plain.ipynb", "'a stored cell'")
    done = export_html(src, tmp_path / "out", execute=False)
    assert done.html == tmp_path / "out" / "plain.html" and done.errors == 0
    assert "a stored cell" in done.html.read_text(encoding="utf-8")
    with pytest.raises(WidgetError, match="cannot read the notebook"):
        export_html(tmp_path / "missing.ipynb", tmp_path / "out")
    (tmp_path / "file").write_text("")
    with pytest.raises(WidgetError, match="cannot write"):
        export_html(src, tmp_path / "file" / "sub", execute=False)


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_failing_cell_is_named_or_kept_with_allow_errors(tmp_path: Path, capsys) -> None:
    src = notebook(tmp_path / "student.ipynb", "raise NotImplementedError('exercise: your code')", "2")
    assert main(["notebooks", "html", str(src), "--output-dir", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "a cell failed: NotImplementedError: exercise: your code" in err and "\x1b[" not in err
    assert main(["notebooks", "html", str(src), "--output-dir", str(tmp_path), "--allow-errors"]) == 0
    assert "1 cell(s) with errors" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_pages_load_no_cdn_script_and_do_not_ask_to_click(tmp_path: Path) -> None:
    """A course page works offline and says nothing about clicking: nothing in it is clickable."""
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell(
                    'The bytes of every arrow. <span class="rfl-live-only">Click an arrow to see its '
                    "bytes.</span> Math stays text: $x^2$."),
                nbformat.v4.new_code_cell(VIEWER_CELL)]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    src = tmp_path / "page.ipynb"
    nbformat.write(nb, src)
    assert main(["notebooks", "html", str(src), "--output-dir", str(tmp_path / "site")]) == 0
    page = (tmp_path / "site" / "page.html").read_text(encoding="utf-8")
    assert not re.findall(r"<script[^>]*\bsrc=[\"']?https?://", page, flags=re.I), "a CDN script"
    assert "unpkg.com" not in page and "cdnjs" not in page and "cdn.jsdelivr" not in page
    assert "widget-state+json" not in page
    text = re.sub(r"<(script|style)\b.*?</\1>", "", page, flags=re.S | re.I)
    assert "click" not in text.lower()
    assert "The bytes of every arrow." in page and "std_msgs/String" in page
