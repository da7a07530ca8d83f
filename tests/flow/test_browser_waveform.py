"""Browser test: in JupyterLab, a click on a clock of the waveform viewer puts the cursor there,
and the page and the kernel report every signal's value at that clock.

The waves come from the clock-by-clock fifo2axi model (no simulator needed): rgba8, so a beat
every 4 clocks. Same JupyterLab + Chromium set-up as the byte-viewer test (loopback, temporary
directories, skipped with a reason without Chromium, a failure with ROSFPGA_REQUIRE_BROWSER=1).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.flow.test_browser_byteviewer import Lab, lab  # noqa: F401  (the module's JupyterLab fixture)

BUILD_CELL = '''
import numpy as np
from rosfpga_lab.checks.circuit import elem_pack_clocks
from rosfpga_lab.widgets import Waves, WaveformViewer

data = (np.arange(4 * 3 * 4) * 5 % 251).astype(np.uint8)   # a 4x3 rgba8 frame's pixel bytes
waves = Waves.from_arrays(elem_pack_clocks(data, 4, 4), widths={"m_axis_tdata": 32, "m_axis_tkeep": 4})
viewer = WaveformViewer(waves, width=4, span=40)
viewer
'''
REPORT_CELL = 'print("CURSOR", viewer.cursor, waves.values_at(viewer.cursor)["m_axis_tdata"])'


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.timeout(120)
def test_click_a_clock_reads_every_signal(lab: Lab, tmp_path: Path) -> None:  # noqa: F811
    page = lab.run_notebook("waveform.ipynb", [BUILD_CELL, REPORT_CELL])
    # clock 8 carries beat 1 (pixel (1, 0)): bytes 4..7 of the frame, a beat every 4 clocks
    column = page.locator('.rfl-svgpane rect[data-index="8"]')
    column.wait_for(state="attached")
    column.click(force=True)
    page.wait_for_function("[...document.querySelectorAll('.widget-html-content b')]"
                           ".some(e => e.textContent === 'clock 8')")
    expected = bytes((k * 5) % 251 for k in range(4, 8))[::-1].hex()  # lane 0 in bits 7..0
    tvalid = page.locator('.rfl-wave-values [data-signal="m_axis_tvalid"]').text_content()
    tdata = page.locator('.rfl-wave-values [data-signal="m_axis_tdata"]').text_content()
    assert tvalid == "m_axis_tvalid = 1" and tdata == f"m_axis_tdata = {expected}", (tvalid, tdata)
    # the cursor line is drawn at the clicked clock
    assert page.locator('.rfl-svgpane line[stroke="#d00"]').count() == 1
    # the click reached the kernel
    page.evaluate("""() => { const nb = window.jupyterapp.shell.currentWidget;
                              nb.content.activeCellIndex = 1;
                              return window.jupyterapp.commands.execute('notebook:run-cell'); }""")
    page.wait_for_function("[...document.querySelectorAll('.jp-OutputArea-output pre')]"
                           ".some(e => e.textContent.includes('CURSOR 8'))")
    out = [t for t in page.locator(".jp-OutputArea-output pre").all_text_contents() if "CURSOR" in t]
    assert out and out[-1].split() == ["CURSOR", "8", expected], out
    lab.screenshot(page, tmp_path / "waveform.png")
    assert lab.errors == []
