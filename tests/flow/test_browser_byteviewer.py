"""Browser test: JupyterLab in Debian's headless Chromium runs a notebook with a byte viewer,
a byte is clicked, and both the page and the kernel report the field.

No browser is downloaded: Playwright drives ``/usr/bin/chromium``. Without it (or without the
playwright package) the test skips with a reason; ``ROSFPGA_REQUIRE_BROWSER=1`` makes that a
failure. The JupyterLab server, its kernel and Chromium use temporary directories only, listen
on loopback, and are stopped at the end. The screenshot is kept in the test's tmp dir.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import nbformat
import numpy as np
import pytest

from tests.support.realros import free_port, skip_or_fail

CHROMIUM = os.environ.get("ROSFPGA_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage",
]
TOKEN = "rosfpga-lab-browser-test"

# A real sensor_msgs/Image, serialised by the lab's msg layer; the offsets the test checks are
# worked out here by hand from the ROS 1 wire format (little endian, uint32 length prefixes).
FRAME_ID = "camera"
HEIGHT_OFFSET = 4 + 4 + 4 + 4 + len(FRAME_ID)  # seq, secs, nsecs, frame_id length, frame_id

BUILD_CELL = f'''
import numpy as np
from rosfpga_lab import msg
from rosfpga_lab.widgets import message_viewer

reg = msg.default_registry()
h, w = 20, 21  # 1260 pixel bytes: three pages of 512
image = {{"header": {{"seq": 7, "stamp": {{"secs": 1700000000, "nsecs": 5}}, "frame_id": {FRAME_ID!r}}},
          "height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0, "step": w * 3,
          "data": (np.arange(h * w * 3) % 251).astype(np.uint8).tobytes()}}
body = msg.serialize(reg, "sensor_msgs/Image", image)
viewer = message_viewer("sensor_msgs/Image", body)
viewer
'''
REPORT_CELL = 'print("SELECTED", viewer.selection.path, viewer.selection.offset, viewer.selection.size)'


def _require_browser() -> None:
    if not Path(CHROMIUM).exists():
        skip_or_fail(f"no Chromium at {CHROMIUM} (apt-get install chromium)", "ROSFPGA_REQUIRE_BROWSER")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        skip_or_fail("the playwright Python package is not installed", "ROSFPGA_REQUIRE_BROWSER")


def _wait_http(url: str, timeout: float, proc: subprocess.Popen, log: Path) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"JupyterLab exited early ({proc.returncode}):\n{log.read_text()[-3000:]}")
        try:
            with urllib.request.urlopen(url, timeout=2) as resp:
                if resp.status == 200:
                    return
        except OSError:
            time.sleep(0.3)
    raise AssertionError(f"JupyterLab did not answer {url} within {timeout} s:\n{log.read_text()[-3000:]}")


def _stop_server(proc: subprocess.Popen, base: str) -> None:
    try:
        req = urllib.request.Request(f"{base}api/shutdown?token={TOKEN}", method="POST", data=b"")
        urllib.request.urlopen(req, timeout=5).close()
        proc.wait(15)
    except (OSError, subprocess.TimeoutExpired):
        pass
    if proc.poll() is None:  # the server's own session: its kernels go with it
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)


class Lab:
    """A JupyterLab server and a Chromium context, both on loopback and in temporary dirs."""

    def __init__(self, root: Path, base: str, browser: object) -> None:
        self.root, self.base, self.browser = root, base, browser
        self.errors: list[str] = []

    def run_notebook(self, name: str, cells: list[str]) -> object:
        """Write a notebook, open it in a new tab, run all cells; return the page."""
        nb = nbformat.v4.new_notebook()
        nb.cells = [nbformat.v4.new_code_cell(c) for c in cells]
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        nbformat.write(nb, self.root / name)
        page = self.browser.new_page()
        page.set_default_timeout(60_000)
        page.on("pageerror", lambda exc: self.errors.append(str(exc)))
        page.goto(f"{self.base}lab/tree/{name}?reset&token={TOKEN}")
        page.wait_for_function("window.jupyterapp && window.jupyterapp.shell.currentWidget"
                               " && window.jupyterapp.shell.currentWidget.sessionContext"
                               " && window.jupyterapp.shell.currentWidget.sessionContext.session"
                               " && window.jupyterapp.shell.currentWidget.sessionContext.session.kernel")
        page.evaluate("window.jupyterapp.shell.currentWidget.sessionContext.ready")
        page.evaluate("window.jupyterapp.commands.execute('notebook:run-all-cells')")
        return page

    def screenshot(self, page: object, path: Path) -> None:
        page.screenshot(path=str(path), full_page=True)
        assert path.stat().st_size > 10_000
        keep = os.environ.get("ROSFPGA_SCREENSHOT_DIR")
        if keep:
            shutil.copy(path, Path(keep) / path.name)


#: The lab's own JupyterLab settings (what ./lab.sh installs): no news pop-up, no update check.
LAB_OVERRIDES = Path(__file__).resolve().parents[2] / "data" / "jupyterlab_overrides.json"


@contextmanager
def lab_session(tmp: Path, width: int = 1400, height: int = 900,
                settings: dict | None = None) -> Iterator[Lab]:
    """JupyterLab (with the lab's settings overrides plus ``settings``) and Chromium at
    ``width`` x ``height``, both stopped at the end."""
    _require_browser()
    from playwright.sync_api import sync_playwright

    notebooks = tmp / "notebooks"
    notebooks.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("JUPYTER", "IPYTHON"))}
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTER_RUNTIME_DIR", "JUPYTER_DATA_DIR", "IPYTHONDIR",
                 "JUPYTERLAB_SETTINGS_DIR", "JUPYTERLAB_WORKSPACES_DIR"):
        path = tmp / name.lower()
        path.mkdir()
        env[name] = str(path)
    env["JUPYTER_PLATFORM_DIRS"] = "1"
    # the lab's overrides answer JupyterLab's "get news?" question with no (nothing fetched, no
    # toast over the outputs); the test checks that no such toast appears
    overrides = json.loads(LAB_OVERRIDES.read_text())
    for plugin, values in (settings or {}).items():
        overrides.setdefault(plugin, {}).update(values)
    app_settings = tmp / "app_settings"
    app_settings.mkdir()
    (app_settings / "overrides.json").write_text(json.dumps(overrides))
    port = free_port()
    base = f"http://127.0.0.1:{port}/"
    log = tmp / "jupyterlab.log"
    with open(log, "wb") as log_file:
        server = subprocess.Popen(
            [sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={port}", "--port-retries=0",
             "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={TOKEN}",
             f"--ServerApp.root_dir={notebooks}", "--LabApp.expose_app_in_browser=True",
             "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
             "--LabApp.extension_manager=readonly", f"--LabApp.app_settings_dir={app_settings}",
             *(["--allow-root"] if os.geteuid() == 0 else [])],
            env=env, cwd=notebooks, stdout=log_file, stderr=subprocess.STDOUT, start_new_session=True,
        )
    try:
        _wait_http(f"{base}api/status?token={TOKEN}", 60, server, log)
        with sync_playwright() as pw:
            browser = pw.chromium.launch_persistent_context(
                str(tmp / "chromium-profile"), executable_path=CHROMIUM, headless=True,
                args=CHROMIUM_ARGS, viewport={"width": width, "height": height},
            )
            try:
                yield Lab(notebooks, base, browser)
            finally:
                browser.close()
    finally:
        _stop_server(server, base)


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Lab]:
    with lab_session(tmp_path_factory.mktemp("jupyterlab")) as session:
        yield session


def _highlighted(page: object) -> list[int]:
    return page.eval_on_selector_all(".rfl-bv-hex .b.hl", "els => els.map(e => Number(e.dataset.off))")


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.timeout(120)
def test_click_a_byte_in_jupyterlab_names_its_field(lab: Lab, tmp_path: Path) -> None:
    page = lab.run_notebook("byteviewer.ipynb", [BUILD_CELL, REPORT_CELL])
    byte = page.locator(f'.rfl-bv .rfl-bv-hex .b[data-off="{HEIGHT_OFFSET}"]')
    byte.wait_for(state="visible")
    # hovering names the field under the mouse (here `width`, the next four bytes)
    page.locator(f'.rfl-bv .rfl-bv-hex .b[data-off="{HEIGHT_OFFSET + 5}"]').hover()
    page.wait_for_function("document.querySelector('.rfl-bv-info').textContent.startsWith('width')")
    byte.click()
    page.wait_for_function("document.querySelector('.rfl-bv-info').textContent.includes('height')")
    text = page.locator(".rfl-bv-info").text_content()
    assert "height" in text and "uint32" in text, text
    assert f"offset {HEIGHT_OFFSET}" in text and "size 4" in text and "value 20" in text, text
    assert _highlighted(page) == list(range(HEIGHT_OFFSET, HEIGHT_OFFSET + 4))  # its four bytes only
    # the click reached the kernel: re-run the report cell and read its output
    page.evaluate("""() => { const nb = window.jupyterapp.shell.currentWidget;
                              nb.content.activeCellIndex = 1;
                              return window.jupyterapp.commands.execute('notebook:run-cell'); }""")
    page.wait_for_function("[...document.querySelectorAll('.jp-OutputArea-output')]"
                           ".some(e => e.textContent.includes('SELECTED height'))")
    outputs = page.eval_on_selector_all(".jp-OutputArea-output", "els => els.map(e => e.textContent)")
    assert any(f"SELECTED height {HEIGHT_OFFSET} 4" in o for o in outputs), outputs
    # the field list selects the same way: click `width` in the list
    page.locator('.rfl-bv-list tr[data-i="6"]').click()
    page.wait_for_function("document.querySelector('.rfl-bv-info').textContent.includes('width')")
    assert _highlighted(page) == list(range(HEIGHT_OFFSET + 4, HEIGHT_OFFSET + 8))
    lab.screenshot(page, tmp_path / "byteviewer.png")
    # paging: the next page starts at byte 512, inside the pixel data
    page.locator(".rfl-bv-next").click()
    page.wait_for_selector('.rfl-bv-hex .b[data-off="512"]')
    assert page.locator(".rfl-bv-hex .b").count() == 512
    assert page.locator('.rfl-bv-hex .b[data-off="0"]').count() == 0
    page.locator('.rfl-bv-hex .b[data-off="600"]').hover()
    page.wait_for_function("document.querySelector('.rfl-bv-info').textContent.startsWith('data [array]')")
    assert "size 1260" in page.locator(".rfl-bv-info").text_content()
    assert lab.errors == []
    page.close()


OTHERS_CELL = r"""
import struct
import numpy as np
from rosfpga_lab.widgets import SeqEvent, SequenceDiagram, ImageDiffViewer, BeatViewer, LiveView

header = struct.pack("<I", 27) + struct.pack("<I", 11) + b"callerid=/a" + struct.pack("<I", 8) + b"topic=/t"
diagram = SequenceDiagram([
    SeqEvent("/talker", "/master", "registerPublisher", b"POST /RPC2 HTTP/1.1\r\n\r\n", 0.0, "xmlrpc"),
    SeqEvent("/listener", "/talker", "TCPROS header", header, 0.004, "tcpros_header"),
])
display(diagram)
ref = (np.arange(8 * 8 * 3) % 256).astype(np.uint8).reshape(8, 8, 3)
out = ref.copy(); out[2, 5] = 0
diff = ImageDiffViewer(out, ref, ref)
display(diff)
td = np.arange(12, dtype=np.uint32)
display(BeatViewer(tdata=td, tkeep=0b0111, tuser=td == 0, tlast=td % 4 == 3, width=4, height=3,
                   bytes_per_pixel=3, image=ref[:3, :4]))
live = LiveView(max_fps=5, trailing=False)
display(live)
live.update(ref)
"""


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.timeout(120)
def test_other_widgets_render_and_a_sequence_arrow_opens_its_bytes(lab: Lab, tmp_path: Path) -> None:
    page = lab.run_notebook("others.ipynb", [OTHERS_CELL])
    arrow = page.locator('.rfl-svgpane g[data-index="1"] text').first  # the arrow's label
    try:
        arrow.wait_for(state="visible", timeout=20_000)
    except Exception:
        lab.screenshot(page, tmp_path / "failure.png")
        raise
    arrow.click()
    # the byte viewer below the diagram now shows the header's fields
    page.wait_for_function("[...document.querySelectorAll('.rfl-bv-list td')].some(e => e.textContent === 'callerid')")
    page.locator('.rfl-bv .rfl-bv-hex .b[data-off="10"]').click()
    page.wait_for_function("document.querySelector('.rfl-bv-info').textContent.includes('callerid')")
    assert "value '/a'" in page.locator(".rfl-bv-info").text_content()
    assert page.locator('.rfl-svgpane g.sel[data-index="1"]').count() == 1
    # image diff, beat viewer and live view drew their images and tables
    page.wait_for_function("document.querySelectorAll('.jp-OutputArea-output img').length >= 6")
    text = page.locator(".jp-OutputArea").first.text_content()
    # clicking the output image's pixel (1, 6) zooms there: its value table is outlined at (1, 6)
    picture = page.locator(".rfl-clickimage img").nth(1)
    # measure only once the pictures have loaded (before that the box is not the picture's)
    page.wait_for_function("[...document.querySelectorAll('.rfl-clickimage img')]"
                           ".every(i => i.complete && i.naturalWidth > 0)")
    box = picture.bounding_box()
    picture.click(position={"x": box["width"] * 1.5 / 8, "y": box["height"] * 6.5 / 8})
    page.wait_for_function("[...document.querySelectorAll('.jp-OutputArea-output input')]"
                           ".some(e => e.value === '6')")
    cells = page.eval_on_selector_all("td", "els => els.filter(e => e.style.outline.includes('solid'))"
                                            ".map(e => e.textContent)")
    assert ",".join(str(v) for v in (np.arange(8 * 8 * 3) % 256).reshape(8, 8, 3)[6, 1]) in cells, cells
    assert "1 of 64 pixels differ" in text and "12 beats carrying 36 bytes" in text and "1 frames received" in text
    lab.screenshot(page, tmp_path / "widgets.png")
    page.locator(".jp-OutputArea-output img").first.scroll_into_view_if_needed()
    lab.screenshot(page, tmp_path / "widgets-2.png")
    page.locator(".jp-OutputArea-output img").last.scroll_into_view_if_needed()
    lab.screenshot(page, tmp_path / "widgets-3.png")
    assert lab.errors == []
    page.close()
