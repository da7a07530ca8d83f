"""The node runtime inside a running Jupyter kernel (threads next to the kernel's own loop)."""

from __future__ import annotations

import nbformat
import pytest
from nbclient import NotebookClient

pytestmark = [pytest.mark.slow, pytest.mark.timeout(180)]

CELLS = [
    """import threading, time
from rosfpga_lab.graph import EmbeddedMaster, Node
before = set(threading.enumerate())
master = EmbeddedMaster(port=0).start()
talker, listener = Node('/nb_talker', master=master), Node('/nb_listener', master=master)
got = []
sub = listener.subscribe('/chatter', 'std_msgs/String', got.append)
pub = talker.advertise('/chatter', 'std_msgs/String')
assert pub.wait_for_subscribers(1, 10)""",
    # a later cell: the threads kept running between cells
    """for i in range(3):
    pub.publish({'data': f'cell {i}'})
deadline = time.monotonic() + 10
while len(got) < 3 and time.monotonic() < deadline:
    time.sleep(0.01)
print(got)""",
    """talker.shutdown(); listener.shutdown(); master.stop()
time.sleep(0.2)
print(sorted(t.name for t in set(threading.enumerate()) - before))""",
]


def test_nodes_work_inside_a_kernel() -> None:
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(src) for src in CELLS]
    NotebookClient(nb, timeout=60, kernel_name="python3").execute()
    outputs = [c.outputs for c in nb.cells]
    assert outputs[1][0]["text"].strip() == "[{'data': 'cell 0'}, {'data': 'cell 1'}, {'data': 'cell 2'}]"
    assert outputs[2][0]["text"].strip() == "[]"  # no thread of ours left behind
