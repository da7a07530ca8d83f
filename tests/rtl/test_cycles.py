"""Cycles of the generated RTL against the walk's cycle model (``hls.program.frame_clocks``):
random message definitions on both wires, ``rtl cycles`` of a configuration, and Image frames
with streaming early release, exactly without backpressure (the RTL is the oracle) and within
four standard deviations with 50 % backpressure (the output takes a byte on a random half of
the clocks: sending ``n`` bytes takes ``n / p`` clocks on average, standard deviation
``sqrt(n (1 - p)) / p``). (The hand-written exhibit's cycle tests against the old
``hw.cycles`` and ``hw.clocked`` models went with them: ``tests/rtl/test_exhibit.py`` holds its
output to the generated circuit's.)
"""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.rtltools import require_iverilog
from rosfpga_lab.hls.compiler import program_from_cdr
from rosfpga_lab.hls.generic import spec_from_layout, stream_path
from rosfpga_lab.hls.program import RECORDS, Refused, frame_clocks, stream_clocks
from rosfpga_lab.hw import image_frame
from rosfpga_lab.hw.cdrlayout import derive_cdr_layout
from rosfpga_lab.hw.layout import Action, StepKind, derive_layout
from rosfpga_lab.msg import serialize
from rosfpga_lab.msg.cdr import serialize_cdr
from rosfpga_lab.msg.ros2 import ros2_registry
from rosfpga_lab.msg.strategies import message
from rosfpga_lab.rtl import build, run
from rosfpga_lab.rtl.cycles import read_stats
from rosfpga_lab.rtl.generic import project_files, simulate_project
from tests.hw.test_walker import definitions  # the models' strategy over message definitions
from tests.rtl.test_sim import random_image, small_config

pytestmark = pytest.mark.rtl


# -- generated circuits (any message type): the walk's cycle model equals the RTL ----------------

def _small_limits(steps: Any) -> dict[str, int]:
    return {s.path + ("[]" if s.label.endswith("[] length") else ""): 3 for s in steps[1:]
            if s.kind is StepKind.LENGTH and s.action is not Action.STREAM}


@settings(max_examples=6, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_the_generated_circuits_clocks_equal_the_walks_model(
        data: st.DataObject, tmp_path_factory: pytest.TempPathFactory) -> None:
    """Random message definitions (the models' strategy: every field kind, nesting, arrays of
    messages), each on TCPROS or CDR: every accepted frame's clocks in the RTL (``make rtlsim``,
    no backpressure), first byte in to last byte out, and the publisher's span, equal
    ``hls.program.frame_clocks``'s, and the accepted frames back to back ``stream_clocks``'s
    (the RTL is the oracle; Icarus Verilog only, no C++)."""
    require_iverilog()
    reg, type_name, stream = data.draw(definitions())
    cdr = data.draw(st.booleans())
    values = [data.draw(message(ros2_registry(reg) if cdr else reg, type_name))
              for _ in range(2)]
    n = max(1, len(values[0][stream]))  # (the circuit streams at least one element)
    values = [v if len(v[stream]) == n else {**v, stream: [0] * n} for v in values]
    if cdr:
        walk = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n)
        walk = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n,
                                 limits_=_small_limits(walk.base.steps))
        prog = program_from_cdr(walk)
        spec = spec_from_layout(walk.layout, walk.registry, program=prog, wire="cdr",
                                op="dilate", ksize=3)
        bodies = [serialize_cdr(ros2_registry(reg), type_name, v) for v in values]
    else:
        layout = derive_layout(reg, type_name, stream=stream, stream_length=n)
        layout = derive_layout(reg, type_name, stream=stream, stream_length=n,
                               limits_=_small_limits(layout.steps))
        spec = spec_from_layout(layout, reg, op="erode", ksize=3)
        prog = spec.program
        bodies = [serialize(reg, type_name, v) for v in values]
    frames = [struct.pack("<I", len(b)) + b for b in bodies]
    where = tmp_path_factory.mktemp("cycles")
    for name, blob in project_files(spec).items():
        (where / name).parent.mkdir(parents=True, exist_ok=True)
        (where / name).write_bytes(blob)
    accepted = []
    for frame in frames:
        _out, statuses = simulate_project(where, frame, target="rtlsim", simulator="iverilog",
                                          out="c")
        try:
            model = frame_clocks(prog, frame, latency=stream_path(spec))
        except Refused as exc:  # a value over the small limits: the RTL refuses it alike
            assert statuses == [prog.statuses[exc.status][0]]
            continue
        assert statuses == ["SUB_OK"]
        rtl = read_stats(where / "c" / "stats.txt")
        assert rtl["tx"].last - rtl["rx"].first + 1 == model.total
        assert rtl["publisher_out"].last - rtl["publisher_out"].first + 1 == model.publisher
        assert rtl["tx"].count == model.out_bytes and rtl["rx"].count >= model.in_bytes - 3
        accepted.append(frame)
    if accepted:  # back to back, three times over (hls.program.stream_clocks)
        _out, statuses = simulate_project(where, b"".join(accepted * 3), target="rtlsim",
                                          simulator="iverilog", out="b")
        assert statuses == ["SUB_OK"] * 3 * len(accepted)
        rtl = read_stats(where / "b" / "stats.txt")
        assert rtl["tx"].last - rtl["rx"].first + 1 == \
            stream_clocks(prog, accepted * 3, latency=stream_path(spec))[-1]


def test_cli_rtl_cycles_of_a_generated_circuit(capsys: pytest.CaptureFixture[str]) -> None:
    """``rtl cycles CONFIG`` of the custom-message example on CDR: each test frame without
    backpressure exactly as the model says, with 50 % within four standard deviations."""
    from rosfpga_lab.cli import main

    require_iverilog()
    data = Path(__file__).resolve().parents[2] / "data"
    assert main(["rtl", "cycles", str(data / "fpga_samples_dilate_cdr.yaml"), "--simulator",
                 "iverilog"]) == 0
    captured = capsys.readouterr()
    rows = [line.split() for line in captured.out.splitlines()
            if line.startswith("frame ") and line.split()[1].isdigit()]
    # two test frames, without and with backpressure, then each 4 times back to back
    assert len(rows) == 6 and "generating the project" in captured.err
    for row in rows[4:]:
        assert row[5] == row[6] and row[7] == "+0.00%" and row[8] == row[9], row
    for row in rows[:4]:
        out_bytes, bp, model, rtl = (int(row[3].replace(",", "")), row[4],
                                     int(row[5].replace(",", "")), int(row[6].replace(",", "")))
        if bp == "0%":
            assert model == rtl and row[7] == "+0.00%" and row[8] == row[9]
        else:
            assert abs(rtl - model) <= 4 * math.sqrt(out_bytes * 0.5) / 0.5 + 16
    assert main(["rtl", "cycles", str(data / "fpga_samples_dilate.yaml"), "--size", "4x4"]) == 1
    assert "--size are for an Image configuration" in capsys.readouterr().err


def _early_cases() -> list[tuple[str, Any, list[bytes], Any]]:
    """Walks with streaming early release: small Image frames on TCPROS (the publisher waits
    for the 2-D window's line, or writes its header first), a message whose stream is
    followed by carried fixed fields (the publisher waits for them in the carry memory), and a
    CDR message whose stream is its last field: the payload exact, then with its unannounced
    end padding (zeros, then not: padding is never looked at)."""
    from rosfpga_lab.hls.generic import spec_from_config
    from rosfpga_lab.msg.registry import MsgRegistry

    cases = []
    for encoding, width in (("rgba8", 40), ("mono8", 8)):
        config = small_config(encoding, width=width, height=3)
        frame = image_frame(random_image(config, 2), encoding, frame_id="cam")
        cases.append((f"Image {encoding} {width}x3", spec_from_config(config), [frame],
                      config))
    reg = MsgRegistry.with_defaults()
    reg.add("lab_msgs/Tail", "string name\nuint8[] data\nuint64 stamp\nuint8 mode\n")
    layout = derive_layout(reg, "lab_msgs/Tail", stream="data", stream_length=6)
    for op, ksize in (("erode", 3), ("passthrough", 1)):
        spec = spec_from_layout(layout, reg, op=op, ksize=ksize)
        frames = []
        for name in ("", "a long name"):
            body = serialize(reg, "lab_msgs/Tail", {"name": name, "data": list(range(6)),
                                                    "stamp": 2**63 + 5, "mode": 7})
            frames.append(struct.pack("<I", len(body)) + body)
        cases.append((f"lab_msgs/Tail {op}", spec, frames, None))
    reg.add("lab_msgs/Last", "string name\nuint16[] data\n")
    walk = derive_cdr_layout(reg, "lab_msgs/Last", stream="data", stream_length=5)
    spec = spec_from_layout(walk.layout, walk.registry, program=program_from_cdr(walk),
                            wire="cdr", op="dilate", ksize=3)
    frames = []
    for name, fill in (("abc", b""), ("a", b"\0\0"), ("ab", b"\x5a\x01")):
        body = serialize_cdr(ros2_registry(reg), "lab_msgs/Last",
                             {"name": name, "data": [1, 900, 3, 65535, 7]})
        assert len(body) % 4 == 2, name  # the header, the name to 4, the count, 10 bytes
        frames.append(struct.pack("<I", len(body + fill)) + body + fill)
    cases.append(("lab_msgs/Last on CDR", spec, frames, None))
    # an array shorter than the window: it flushes a clock per missing element
    reg.add("lab_msgs/Short", "float32[] data\nuint64 stamp\n")
    for n, ksize in ((1, 5), (2, 7)):
        layout = derive_layout(reg, "lab_msgs/Short", stream="data", stream_length=n)
        body = serialize(reg, "lab_msgs/Short", {"data": [1.5] * n, "stamp": 9})
        cases.append((f"lab_msgs/Short {n} in {ksize}",
                      spec_from_layout(layout, reg, op="erode", ksize=ksize),
                      [struct.pack("<I", len(body)) + body], None))
    return cases


def test_streaming_early_release_keeps_the_cycle_model_exact() -> None:
    """A walk whose stream only fixed, unrefusable fields follow is handed over at the stream's
    count (``Program.stream_early``): the FIFO after the application is ``axis_depth`` beats,
    not the whole array, and each frame's clocks in the RTL (no backpressure), first byte in to
    last byte out, and the publisher's span equal ``frame_clocks`` with the stream's path
    (``stream_path``): the RTL is the oracle. With random gaps and backpressure the output is
    the models' (the overlap loses nothing)."""
    from rosfpga_lab.hls.generic import stream_path
    from rosfpga_lab.rtl.generic import generic_params
    from rosfpga_lab.rtl.project import model_output as node_model_output

    require_iverilog()
    for label, spec, frames, config in _early_cases():
        assert spec.program.stream_early is not None, label
        params = generic_params(spec)
        assert params["EARLY"] == 1 and params["OUT_DEPTH"] == spec.axis_depth, label
        sim = build(spec, simulator="iverilog", cache=True)
        for frame in frames:
            result = run(sim, frame)
            s = result.streams
            model = frame_clocks(spec.program, frame, latency=stream_path(spec))
            assert (s["tx"].last - s["rx"].first + 1, s["publisher_out"].last
                    - s["publisher_out"].first + 1) == (model.total, model.publisher), label
        if config is not None:
            both = b"".join(frames) * 2
            for gap, bp in ((300, 300), (0, 700)):
                assert run(sim, both, gap=gap, bp=bp, seed=5).output == \
                    node_model_output(config, both), label


def test_frames_back_to_back_keep_the_cycle_model_exact() -> None:
    """Frames back to back (no gaps, no backpressure): the subscriber reads the next frame while
    the publisher writes one (``rfl_gsubscriber``'s RECORDS records), and the clocks from the
    first byte in to the last byte out equal ``hls.program.stream_clocks`` (the RTL is the
    oracle). A short message whose stream only fixed fields follow (early release) and one whose
    string follows it (whole frames): a long frame, then short ones, so that the subscriber waits
    for the publisher to release the long frame's record; then each shipped LaserScan's test
    frames repeated, where a frame costs the subscriber's walk alone in steady state, not the
    walk and the publisher's span one after the other (the single record's 3,120 clocks a
    1,504-byte frame)."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.msg.registry import MsgRegistry
    from rosfpga_lab.rtl.cycles import SteadyRow, generic_rows

    require_iverilog()
    assert RECORDS == 2
    reg = MsgRegistry.with_defaults()
    reg.add("lab_msgs/Tail", "string name\nuint8[] data\nuint64 stamp\nuint8 mode\n")
    reg.add("lab_msgs/Head", "uint8[] data\nstring name\n")
    for type_name, fields in (("lab_msgs/Tail", {"stamp": 5, "mode": 7}), ("lab_msgs/Head", {})):
        layout = derive_layout(reg, type_name, stream="data", stream_length=6)
        spec = spec_from_layout(layout, reg, op="erode", ksize=3)
        assert (spec.program.stream_early is not None) == (type_name == "lab_msgs/Tail")

        def frame(name: str) -> bytes:
            body = serialize(reg, type_name, {"name": name, "data": list(range(6)), **fields})
            return struct.pack("<I", len(body)) + body

        long, short = frame("x" * 200), frame("")
        sim = build(spec, simulator="iverilog", cache=True)
        for frames in ([long, short], [long, short, short, short], [short, long, short] * 2):
            s = run(sim, b"".join(frames)).streams
            assert s["tx"].last - s["rx"].first + 1 == \
                stream_clocks(spec.program, frames, latency=stream_path(spec))[-1], type_name
    data = Path(__file__).resolve().parents[2] / "data"
    for name in ("fpga_laserscan_min_cdr.yaml", "fpga_laserscan_min.yaml"):
        steady: list[SteadyRow] = []
        generic_rows(load_config(data / name), bp=0, simulator="iverilog", copies=3,
                     steady=steady)
        assert steady, name
        for row in steady:
            assert (row.model, row.model_alone) == (row.rtl, row.rtl_alone), name
            # the larger of the two walks, not their sum: under the frame's bytes in and out
            assert row.rtl_per_frame < 1.1 * max(row.in_bytes, row.out_bytes), (name, row)
