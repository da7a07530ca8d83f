"""Browser test: notebooks 0 to 7 run in JupyterLab in Chromium at 1,000 px wide, and every
output (every widget, picture, diagram and table) fits the notebook without horizontal scroll.

Measured in the DOM: for each output area, the right edge of its widest element against the
output area's own right edge, and the notebook's scroller has nothing to scroll sideways.
The widths are printed (``pytest -s``) and written to ``widths.json`` beside screenshots of the
widgets (``ROSFPGA_SCREENSHOT_DIR=dir`` keeps copies). Also: no "get news?" toast covers the
outputs with the lab's JupyterLab settings, and ``rosfpga-lab demo --view``'s page renders.

Like tests/flow/test_browser_byteviewer.py: Debian's Chromium through Playwright, loopback only,
temporary directories; skips without Chromium (a failure with ``ROSFPGA_REQUIRE_BROWSER=1``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.flow.test_browser_byteviewer import TOKEN, Lab, lab_session

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = ROOT / "notebooks" / "solutions"
NOTEBOOKS = sorted(p.name for p in SOLUTIONS.glob("[0-9][0-9]_*.ipynb"))
#: The notebook's width: the browser window is this wide and the side panels are closed.
NOTEBOOK_WIDTH = 1000
#: Seconds a whole notebook may take in the browser (notebook 7 runs cameras and real ROS).
RUN_TIMEOUT = 240
#: All cells rendered (no windowing), so every output can be measured.
SETTINGS = {"@jupyterlab/notebook-extension:tracker": {"windowingMode": "none"}}

MEASURE = """() => {
  const nb = window.jupyterapp.shell.currentWidget;
  const scroller = nb.content.node;
  const out = [];
  nb.content.widgets.forEach((cell, index) => {
    if (cell.model.type !== 'code') return;
    for (const area of cell.node.querySelectorAll('.jp-OutputArea-output')) {
      const box = area.getBoundingClientRect();
      let right = box.right, widest = null;
      for (const el of area.querySelectorAll('*')) {
        const r = el.getBoundingClientRect();
        if (r.width === 0 || r.height === 0) continue;
        if (r.right > right + 0.5) { right = r.right; widest = el.tagName.toLowerCase() + '.' + el.className; }
      }
      // the widget's own width: its widest drawn piece (blocks that merely span the area do not count)
      let content = 0;
      for (const el of area.querySelectorAll('img, svg, canvas, table, button, input, select, .rfl-bv-grid, summary, code'))
        if (!el.closest('svg') || el.tagName.toLowerCase() === 'svg')
          content = Math.max(content, el.getBoundingClientRect().right - box.left);
      const kinds = [];
      if (area.querySelector('.rfl-svgpane')) kinds.push('sequence diagram');
      if (area.querySelector('.rfl-bv')) kinds.push('byte viewer');
      if (area.querySelector('.rfl-clickimage')) kinds.push('image widget');
      if (area.querySelector('.widget-image')) kinds.push('live view');
      if (area.querySelector('.widget-inline-hbox progress, .widget-progress')) kinds.push('progress');
      if (area.querySelector('svg .rfl-state')) kinds.push('state diagram');
      if (area.querySelector('details pre')) kinds.push('code files');
      if (area.querySelector('.jupyter-widgets') && !kinds.length) kinds.push('widget');
      if (area.querySelector('img') && !kinds.length) kinds.push('picture');
      if (!kinds.length) kinds.push(area.querySelector('table') ? 'table' : 'text');
      out.push({cell: index, kind: kinds.join(', '), available: Math.round(box.width),
                content: Math.round(content), overflow: Math.round(right - box.right),
                scroll: area.scrollWidth - area.clientWidth, widest});
    }
  });
  return {outputs: out, notebook: Math.round(scroller.getBoundingClientRect().width),
          page_scroll: document.documentElement.scrollWidth - document.documentElement.clientWidth,
          notebook_scroll: scroller.scrollWidth - scroller.clientWidth};
}"""

DONE = """(n) => {
  const nb = window.jupyterapp.shell.currentWidget;
  const kernel = nb.sessionContext.session && nb.sessionContext.session.kernel;
  const code = nb.content.widgets.filter(c => c.model.type === 'code');
  return kernel && kernel.status === 'idle' && code.length === n
         && code.every(c => c.model.executionCount !== null);
}"""


@pytest.fixture(scope="module")
def narrow_lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Lab]:
    with lab_session(tmp_path_factory.mktemp("jupyterlab-1000"), NOTEBOOK_WIDTH, 1100, SETTINGS) as lab:
        yield lab


def _keep(path: Path) -> None:
    keep = os.environ.get("ROSFPGA_SCREENSHOT_DIR")
    if keep:
        shutil.copy(path, Path(keep) / path.name)


def _open(lab: Lab, name: str) -> object:
    shutil.copy(SOLUTIONS / name, lab.root / name)
    page = lab.browser.new_page()
    page.set_default_timeout(60_000)
    page.on("pageerror", lambda exc: lab.errors.append(f"{name}: {exc}"))
    page.goto(f"{lab.base}lab/tree/{name}?reset&token={TOKEN}")
    page.wait_for_function("window.jupyterapp && window.jupyterapp.shell.currentWidget"
                           " && window.jupyterapp.shell.currentWidget.sessionContext"
                           " && window.jupyterapp.shell.currentWidget.sessionContext.session"
                           " && window.jupyterapp.shell.currentWidget.sessionContext.session.kernel")
    page.evaluate("window.jupyterapp.shell.collapseLeft(); window.jupyterapp.shell.collapseRight();")
    return page


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.timeout(RUN_TIMEOUT * len(NOTEBOOKS) + 120)
def test_every_output_of_every_notebook_fits_a_1000px_notebook(narrow_lab: Lab, tmp_path: Path) -> None:
    report: dict[str, object] = {}
    problems: list[str] = []
    for name in NOTEBOOKS:
        code_cells = sum(1 for c in json.loads((SOLUTIONS / name).read_text())["cells"]
                         if c["cell_type"] == "code")
        page = _open(narrow_lab, name)
        page.evaluate("window.jupyterapp.shell.currentWidget.sessionContext.ready")
        start = time.monotonic()
        page.evaluate("window.jupyterapp.commands.execute('notebook:run-all-cells')")
        page.wait_for_function(DONE, arg=code_cells, timeout=RUN_TIMEOUT * 1000, polling=500)
        page.wait_for_timeout(1500)   # widget views and pictures settle
        page.wait_for_function("[...document.querySelectorAll('.jp-OutputArea-output img')]"
                               ".every(i => i.complete)")
        seconds = time.monotonic() - start
        measured = page.evaluate(MEASURE)
        measured["seconds"] = round(seconds, 1)
        report[name] = measured
        assert measured["notebook"] <= NOTEBOOK_WIDTH, measured["notebook"]
        assert page.locator(".jp-OutputArea-output").count() > 0
        # no toast (JupyterLab's "get news?" question) over the outputs
        toasts = page.locator(".Toastify__toast").all_text_contents()
        if toasts:
            problems.append(f"{name}: a toast covers the page: {toasts}")
        for o in measured["outputs"]:
            if o["overflow"] > 1 or o["scroll"] > 1:
                problems.append(f"{name} cell {o['cell']} ({o['kind']}): {o['overflow']} px past the "
                                f"output area ({o['available']} px), scroll {o['scroll']} px, widest {o['widest']}")
        if measured["notebook_scroll"] > 1 or measured["page_scroll"] > 1:
            problems.append(f"{name}: the notebook scrolls sideways by {measured['notebook_scroll']} px")
        tracebacks = page.locator(".jp-RenderedText[data-mime-type='application/vnd.jupyter.error']")
        assert tracebacks.count() == 0, f"{name}: {tracebacks.first.text_content()[:400]}"
        _screenshots(page, name, tmp_path)
        page.evaluate("window.jupyterapp.commands.execute('kernelmenu:shutdown')")
        page.close()
    (tmp_path / "widths.json").write_text(json.dumps(report, indent=1))
    _keep(tmp_path / "widths.json")
    for name, m in report.items():
        print(f"\n{name}: {m['seconds']} s, notebook {m['notebook']} px")
        for o in m["outputs"]:
            if o["kind"] not in ("text",):
                print(f"  cell {o['cell']:>2} {o['kind']:<28} content {o['content']:>4} px of "
                      f"{o['available']} px, overflow {max(o['overflow'], 0)} px")
    assert problems == [], "\n".join(problems)
    assert narrow_lab.errors == []


def _screenshots(page: object, name: str, tmp_path: Path) -> None:
    """One picture per kind of widget (its first one), for a person to look at: the widget's
    top, as far as the window shows it."""
    stem = name.split(".")[0]
    wanted = {"sequence": ".rfl-svgpane", "images": ".jp-OutputArea-output:has(.rfl-clickimage)",
              "images-last": ".jp-OutputArea-output:has(.rfl-clickimage) >> nth=-1",
              "live": ".jp-OutputArea-output:has(.widget-image)", "states": ".jp-OutputArea-output:has(svg .rfl-state)",
              "code": ".jp-OutputArea-output:has(details pre)", "bytes": ".rfl-bv",
              "beats": ".jp-OutputArea-output:has(.widget-html-content svg)"}
    for kind, selector in wanted.items():
        element = page.locator(selector) if "nth=" in selector else page.locator(selector).first
        if element.count() == 0 or (kind == "images-last" and page.locator(selector.split(" >>")[0]).count() < 2):
            continue
        element.evaluate("e => e.scrollIntoView({block: 'start'})")
        page.wait_for_timeout(200)
        box = element.bounding_box()
        view = page.viewport_size
        top = max(box["y"], 0)
        clip = {"x": max(box["x"], 0), "y": top, "width": min(box["width"], view["width"] - max(box["x"], 0)),
                "height": max(1, min(box["height"], view["height"] - top))}
        path = tmp_path / f"{stem}-{kind}.png"
        page.screenshot(path=str(path), clip=clip)
        assert path.stat().st_size > 2_000
        _keep(path)


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.timeout(180)
def test_demo_view_page_renders_input_output_and_counters(narrow_lab: Lab, tmp_path: Path) -> None:
    proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "demo", "--view", "--frames", "90",
                             "--rate", "15", "--source", "synthetic", "--no-figure"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
    try:
        url = re.match(r"live view: (http://127\.0\.0\.1:\d+/)", proc.stdout.readline())[1]
        page = narrow_lab.browser.new_page()
        page.goto(url)
        page.wait_for_function("['input', 'output'].every(id => { const i = document.getElementById(id);"
                               " return i.complete && i.naturalWidth > 0; })", timeout=30_000)
        page.wait_for_function("Number((document.getElementById('received') || {}).textContent) > 0")
        counters = page.locator("#counters").text_content()
        assert "bit-exact vs OpenCV" in counters and "frames back at the checker" in counters
        widths = page.evaluate("['input', 'output'].map(id => document.getElementById(id).naturalWidth)")
        assert widths == [640, 640]
        assert page.evaluate("document.documentElement.scrollWidth <= document.documentElement.clientWidth")
        shot = tmp_path / "demo-view.png"
        page.screenshot(path=str(shot))
        _keep(shot)
        page.close()
        out, _ = proc.communicate(timeout=60)
        # the demo ends with its verdict (its exit code is the bit-exact check's, tested in
        # tests/component/test_demo.py; a busy machine may drop a frame here, which is not this test's subject)
        assert "bit-exact: " in out and "frames: sent 90" in out, out
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
