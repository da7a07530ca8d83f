"""``rtl.fabriccounters``: every counter it lists is a stage's output port, connected in
``rfl_fabric_node.v`` to the wire it names, and the README names the stages (read from the Verilog
here, never from the module's own renderings)."""

from __future__ import annotations

import re

from rosfpga_lab.rtl.fabriccounters import NODE_COUNTERS, NODE_INSTANCE, cxx_header, stage_lines
from rosfpga_lab.rtl.proofs import FABRIC_DIR


def _instance(text: str, module: str) -> str:
    """The port connections of ``module``'s one instance in ``text``."""
    found = re.findall(rf"\b{module}\b\s*(?:#\s*\(.*?\)\s*)?\w+\s*\((.*?)\);", text, re.S)
    assert len(found) == 1, module
    return found[0]


def test_each_counter_is_a_stage_port_wired_to_its_node_wire() -> None:
    node = (FABRIC_DIR / "rfl_fabric_node.v").read_text()
    for c in NODE_COUNTERS:
        stage = (FABRIC_DIR / f"{c.stage}.v").read_text()
        assert re.search(rf"output\s+wire\s+\[[^]]+\]\s+{c.port}\b", stage), c
        assert re.search(rf"\.{c.port}\(\s*{c.wire}\s*\)", _instance(node, c.stage)), c
    top = (FABRIC_DIR / "rfl_fabric_top.v").read_text()
    assert re.search(rf"\brfl_fabric_node\b\s*#\s*\(.*?\)\s*{NODE_INSTANCE}\s*\(", top, re.S)
    assert len({c.key for c in NODE_COUNTERS}) == len(NODE_COUNTERS)


def test_the_header_and_the_printout_follow_the_list() -> None:
    header = cxx_header("rfl_fabric_top")
    assert "RFL_NODE_COUNTER_COUNT 15" in header
    assert "X(rfl_fabric_top__DOT__u_node__DOT__cnt_rx_repeated)" in header
    assert stage_lines({"rtps_repeated": 2, "seam_dropped": 1, "ctrl_bad_header": 3}) == [
        "rfl_rtps_rx: cnt_repeated 2", "rfl_rtps_to_cdr: cnt_dropped 1",
        "rfl_rtps_ctrl: cnt_bad_header 3"]
