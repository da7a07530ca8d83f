"""The shortest message a circuit accepts (``Layout.min_body``) counts the stream's fixed length:
notebook 10's layout said "body 33..369 bytes" and its layout.h ``MIN_BODY_BYTES 33 // the
shortest message accepted``, but a 33-byte body carries no values and is refused; the shortest
accepted is 97. Every figure here is counted by hand from the message below."""

from __future__ import annotations

import re
import struct
from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import require_cxx
from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.hw.errors import FrameFieldError
from rosfpga_lab.hw.layout import Layout, format_layout, layout_from_config
from rosfpga_lab.hw.walker import extract_fast
from rosfpga_lab.msg import MsgRegistry, serialize

MSG = """Header header
string sensor
uint8 gain
float32[2] window
uint16[] values
"""
CONFIG = """node: {name: /fpga_linescan}
subscriber: {topic: /line, type: my_msgs/LineScan}
publisher: {topic: /line_eroded}
msg_path: [msg]
stream: {field: values, length: 32}
checks: {gain: 4}
limits: {sensor: 16}
application: {op: erode, ksize: 3}
"""
# seq 4 + stamp 8 + frame_id length 4 + sensor length 4 + gain 1 + window 8 + values length 4
EMPTY = 4 + 8 + 4 + 4 + 1 + 8 + 4
SHORTEST = EMPTY + 32 * 2          # the 32 uint16 values the circuit was built for


@pytest.fixture(scope="module")
def linescan(tmp_path_factory: pytest.TempPathFactory) -> tuple[NodeConfig, Layout, MsgRegistry]:
    root: Path = tmp_path_factory.mktemp("minbody")
    (root / "msg/my_msgs/msg").mkdir(parents=True)
    (root / "msg/my_msgs/msg/LineScan.msg").write_text(MSG)
    config = parse_config(CONFIG, source="test", base_dir=root)
    reg = config.registry()
    return config, layout_from_config(config, reg), reg


def shortest(reg: MsgRegistry) -> bytes:
    body = serialize(reg, "my_msgs/LineScan", {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}, "sensor": "",
        "gain": 4, "window": [0.0, 0.0], "values": np.arange(32, dtype=np.uint16)})
    assert len(body) == SHORTEST == 97
    return body


def framed(body: bytes) -> bytes:
    return struct.pack("<I", len(body)) + body


def test_min_body_is_the_shortest_accepted_body(linescan) -> None:
    _config, layout, reg = linescan
    assert layout.min_body == SHORTEST
    assert layout.steps[0].check.low == SHORTEST
    assert f"body {SHORTEST}.." in format_layout(layout).splitlines()[0]
    body = shortest(reg)
    assert len(extract_fast(layout, framed(body)).stream) == 32      # accepted
    with pytest.raises(FrameFieldError) as info:                     # one byte less: refused
        extract_fast(layout, framed(body[:-1]))
    assert info.value.field == "frame length"


def test_the_generated_program_and_layout_h_say_the_same(linescan, tmp_path: Path) -> None:
    from rosfpga_lab.hls import program
    from rosfpga_lab.hls.compiler import program_from_layout
    from rosfpga_lab.hls.generic import render_generic, spec_from_config

    config, layout, reg = linescan
    prog = program_from_layout(layout)
    assert prog.min_body == SHORTEST
    layout_h = render_generic(spec_from_config(config))["layout.h"]
    assert re.search(rf"#define MIN_BODY_BYTES {SHORTEST}\b", layout_h), layout_h[:2000]
    body = shortest(reg)
    program.subscribe(prog, framed(body))                              # accepted
    with pytest.raises(program.Refused) as info:
        program.subscribe(prog, framed(body[:-1]))
    assert info.value.status == program.FRAME_LENGTH_STATUS == 1       # SUB_BAD_FRAME_LENGTH


def test_the_c_simulation_accepts_the_shortest_body_and_refuses_one_byte_less(
        linescan, tmp_path: Path) -> None:
    require_cxx()
    from rosfpga_lab.rtl.generic import simulate_project
    from rosfpga_lab.rtl.project import generate_project

    config, _layout, reg = linescan
    project = tmp_path / "project"
    generate_project(config, project)
    body = shortest(reg)
    _out, statuses = simulate_project(project, framed(body) + framed(body[:-1]) + framed(body),
                                      target="csim")
    assert statuses == ["SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_OK"]
