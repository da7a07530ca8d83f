"""Widgets in an executed notebook carry a static HTML form that needs no kernel or JavaScript.

The notebook runs headless in a fresh kernel (nbclient); every widget output must hold both the
live widget view and ``text/html``; the HTML export with ``STATIC_EXPORT_PRIORITY``, with every
``<script>`` and ``<style>`` removed (as GitHub's notebook view does), must still name the
fields, pixels and beats.
"""

from __future__ import annotations

import re
from pathlib import Path

import nbformat
import pytest

CELLS = [
    r'''
from rosfpga_lab import msg
from rosfpga_lab.widgets import message_viewer
reg = msg.default_registry()
body = msg.serialize(reg, "sensor_msgs/Image", {
    "header": {"seq": 1, "stamp": {"secs": 2, "nsecs": 3}, "frame_id": "cam<&>"}, "height": 2, "width": 2,
    "encoding": "mono8", "is_bigendian": 0, "step": 2, "data": b"\x01\x02\x03\x04"})
message_viewer("sensor_msgs/Image", body)
''',
    r'''
import struct
from rosfpga_lab.widgets import SeqEvent, SequenceDiagram
hdr = struct.pack("<I", 15) + struct.pack("<I", 11) + b"topic=/chat"
SequenceDiagram([SeqEvent("/sub", "/pub", "TCPROS header", hdr, 0.0, "tcpros_header")])
''',
    r'''
import numpy as np
from rosfpga_lab.widgets import ImageDiffViewer, BeatViewer
ref = np.zeros((4, 4, 3), np.uint8); out = ref.copy(); out[1, 2] = 9
display(ImageDiffViewer(frames=[(ref, ref, ref), (ref, out, ref)]))
td = np.arange(16, dtype=np.uint32)
BeatViewer(tdata=td, tkeep=0b0111, tuser=td == 0, tlast=td % 4 == 3, width=4, height=4, bytes_per_pixel=3)
''',
]


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_executed_notebook_outputs_have_a_static_form(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from nbclient import NotebookClient
    from nbconvert import HTMLExporter

    for name in ("JUPYTER_RUNTIME_DIR", "JUPYTER_DATA_DIR", "JUPYTER_CONFIG_DIR", "IPYTHONDIR"):
        (tmp_path / name).mkdir()
        monkeypatch.setenv(name, str(tmp_path / name))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in CELLS]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    NotebookClient(nb, timeout=60, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()

    outputs = [o for cell in nb.cells for o in cell.outputs if o.output_type in ("execute_result", "display_data")]
    assert len(outputs) == 4
    for o in outputs:
        assert "application/vnd.jupyter.widget-view+json" in o.data and "text/html" in o.data
    html_outputs = [o.data["text/html"] for o in outputs]
    assert all("<script" not in h for h in html_outputs)

    from traitlets.config import Config

    from rosfpga_lab.widgets import STATIC_EXPORT_PRIORITY

    # nbconvert's default prefers widget views (rendered by JavaScript from a CDN); an offline
    # export picks the static forms instead
    config = Config({"NbConvertBase": {"display_data_priority": STATIC_EXPORT_PRIORITY}})
    page, _ = HTMLExporter(config=config).from_notebook_node(nb)
    assert '<script type="application/vnd.jupyter.widget-view+json">' not in page  # no output left to JS
    bare = re.sub(r"<(script|style)\b.*?</\1>", "", page, flags=re.S | re.I)
    text = re.sub(r"<[^>]+>", " ", bare)
    # byte viewer: fields and values; the frame_id's '<&>' arrives escaped, never as markup
    for needle in ("sensor_msgs/Image", "header.frame_id", "height", "encoding", "cam&lt;&amp;&gt;"):
        assert needle in bare, needle
    assert "cam<&>" not in bare
    # sequence diagram: the arrow and its bytes' fields
    assert "1. TCPROS header" in text and "topic.length" in text
    # image diff (a sequence: a line per frame) and beats
    assert "bit-exact: all 16 pixels equal" in text and "1 of 16 pixels differ" in text
    assert "16 beats carrying 48 bytes" in text


def test_code_files_fold_one_block_per_file_highlighted(tmp_path) -> None:
    from rosfpga_lab.widgets import CodeFiles

    a = tmp_path / "subscriber.cpp"
    a.write_text("#include <x.h>\nint main() { return 0; }  // done\n")
    b = tmp_path / "run_hls.tcl"
    b.write_text("open_project p\n")
    html = CodeFiles([a, b], open=["subscriber.cpp"]).to_html()
    assert html.count("<details") == 2 and "<details open><summary><code>subscriber.cpp</code> (2 lines)" in html
    assert "<summary><code>run_hls.tcl</code> (1 lines)</summary>" in html
    assert 'style="color:' in html and "<script" not in html   # highlighted with inline colours
    assert "white-space:pre-wrap" in html                        # long lines wrap, never scroll
