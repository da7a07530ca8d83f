"""Generated projects of message types other than Image: C simulation (g++) and RTL simulation
(Icarus Verilog, random input gaps and output backpressure) equal the lab's Python models
(``hw.walker`` + ``hw.morph1d``) byte for byte.

Cases: the shipped examples through ``rosfpga-lab generate`` and the generated Makefile
(``make csim``, ``make rtlsim`` with the frames it ships: a good frame, a refused one, a good
one); refusals of every kind followed by a good frame; hand-written walks with what the shipped
types lack (loops in loops, constants, zeros, message numbers) against the program's executor
with a numpy oracle; and a few random message definitions (the models' own hypothesis strategy).
"""

from __future__ import annotations

import struct
import sys
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.generictools import (
    assert_rtl_lint_clean, nested_program, scan_program, spec_for, window_oracle,
)
from tests.support.realros import require_cxx
from tests.support.rtltools import require_iverilog
from rosfpga_lab.config import load_config
from rosfpga_lab.hls.vectors import model_output, sample_tokens
from rosfpga_lab.hls.generic import spec_from_layout
from rosfpga_lab.hls.program import run_program
from rosfpga_lab.hw.layout import (
    Action, StepKind, derive_layout, frame_geometry, layout_from_config, marshal,
)
from rosfpga_lab.msg import deserialize, serialize
from rosfpga_lab.msg.strategies import message
from rosfpga_lab.rtl.generic import project_files, simulate_project
from rosfpga_lab.rtl.project import generate_project
from tests.hw.test_walker import definitions  # the models' strategy over message definitions

DATA = Path(__file__).resolve().parents[2] / "data"
SHIPPED = ("fpga_laserscan_min.yaml", "fpga_samples_dilate.yaml")


def write(files: dict[str, bytes], where: Path) -> Path:
    for name, data in files.items():
        (where / name).parent.mkdir(parents=True, exist_ok=True)
        (where / name).write_bytes(data)
    return where


def make(project: Path, *args: str) -> str:
    proc = subprocess.run(["make", "-s", *args], cwd=project, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def simulate(project: Path, frames: list[bytes], gap: int = 250, bp: int = 350) -> tuple[bytes, bytes]:
    """The C simulation's and the RTL simulation's output bytes for ``frames``."""
    (project / "in.bin").write_bytes(b"".join(frames))
    make(project, "csim", "INPUT=in.bin", "OUT=c_out")
    make(project, "rtlsim", "SIM=iverilog", "INPUT=in.bin", "OUT=r_out", f"GAP={gap}", f"BP={bp}",
         "SEED=3")
    return (project / "c_out/output.bin").read_bytes(), (project / "r_out/output.bin").read_bytes()


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_example_generates_and_simulates_exactly(name: str, tmp_path: Path) -> None:
    require_cxx()
    require_iverilog()
    out = tmp_path / "project"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(DATA / name), "-o",
                           str(out), "-q"], capture_output=True, text=True, timeout=300,
                          )
    assert proc.returncode == 0, proc.stderr
    assert "PASS: output equals tb_expected.bin" in make(out, "csim")
    assert (out / "csim_out/status.txt").read_text().split()[1::2][1].startswith("SUB_BAD_")
    assert "PASS: output equals tb_expected.bin" in make(out, "rtlsim", "SIM=iverilog", "GAP=300",
                                                         "BP=400")
    expected = (out / "tb_expected.bin").read_bytes()
    assert len(expected) > 0 and expected == (out / "rtlsim_out/output.bin").read_bytes()
    table = subprocess.run([sys.executable, "-m", "rosfpga_lab", "sloc", str(out)], capture_output=True,
                           text=True, timeout=60)
    assert table.returncode == 0 and "rfl_window1d.v" in table.stdout, table.stderr


def test_refusals_then_good_frames_match_the_models(tmp_path: Path) -> None:
    """lab_msgs/Samples: a failed check, a string over its maximum, a bad stream length (one
    element too many: one too few can be below the shortest body accepted), bytes
    after the last field and a frame length below the minimum, each followed by a good frame."""
    require_cxx()
    require_iverilog()
    config = load_config(DATA / "fpga_samples_dilate.yaml")
    reg = config.registry()
    layout = layout_from_config(config, reg)
    spec = spec_from_layout(layout, reg, op=config.application.op, ksize=config.application.ksize)
    project = write(project_files(spec), tmp_path)
    rng = np.random.default_rng(5)

    def with_value(path: str, value: object) -> bytes:
        toks = sample_tokens(layout, rng)
        step = layout.step(path).index
        return marshal(layout, [t._replace(value=value) if t.step == step else t for t in toks])

    good = [marshal(layout, sample_tokens(layout, rng)) for _ in range(6)]
    body = good[0][4:] + b"\x00"
    frames = [good[0], with_value("calibration_mode", 3), good[1],
              with_value("label_length", 33), good[2],
              marshal(layout, sample_tokens(layout, rng, stream_count=65)), good[3],
              struct.pack("<I", len(body)) + body, good[4],
              struct.pack("<I", 3) + b"abc", good[5]]
    # the two refusals whose bytes were altered after marshal's length keep a consistent frame:
    # label_length 33 > 32 is refused at once (its bytes never read)
    expected, why = model_output(layout, "dilate", 3, frames)
    assert [bool(w) for w in why] == [False, True] * 5 + [False]
    csim, rtl = simulate(project, frames)
    assert csim == expected
    assert rtl == expected
    # the status of each frame names the field the models refused it at
    names = [name for name, _label in layout.statuses]
    want = ["SUB_OK", "SUB_BAD_CALIBRATION_MODE", "SUB_OK", "SUB_BAD_LABEL_LENGTH", "SUB_OK",
            "SUB_BAD_SAMPLES_LENGTH", "SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_OK",
            "SUB_BAD_FRAME_LENGTH", "SUB_OK"]
    for refusal, status in zip(why, want):
        label = dict((n, lbl) for n, lbl in layout.statuses)[status]
        assert (refusal == "") == (status == "SUB_OK") and (not refusal or label in refusal), refusal
    assert (project / "c_out/status.txt").read_text().split()[1::2] == want
    assert [names[int(c)] for c in (project / "r_out/status.txt").read_text().split()[1::2]] == want
    # the same through the Python entry point (what a notebook calls)
    for target in ("csim", "rtlsim"):
        assert simulate_project(project, b"".join(frames), target=target, simulator="iverilog",
                                gap=100, bp=100) == (expected, want)


def test_hand_written_walks_match_the_executor(tmp_path: Path) -> None:
    """Loops two deep, a fixed loop, constants, zeros, a message counter, a stream between
    carried fields; good and refused frames, against the program executor + numpy."""
    require_cxx()
    require_iverilog()

    def s(b: bytes) -> bytes:
        return struct.pack("<I", len(b)) + b

    def frame(version=7, kind=b"abc", points=(), values=(1, 2, 3, 4, 5), extras=0, counter=9):
        body = struct.pack("<H", version) + s(kind) + struct.pack("<I", len(points))
        for x, label, pairs in points:
            body += struct.pack("<d", x) + s(label)
            for flag, codes in pairs:
                body += bytes([flag]) + struct.pack("<I", len(codes)) + np.asarray(codes, "<i2").tobytes()
        body += struct.pack("<I", len(values)) + np.asarray(values, "<i2").tobytes()
        body += struct.pack("<I", extras) + bytes(extras) + struct.pack("<I", counter)
        return struct.pack("<I", len(body)) + body

    pts = [(1.5, b"ab", [(1, [1, -2]), (0, [])]), (2.5, b"", [(1, [3]), (1, [4, 5, 6])])]
    frames = [frame(points=pts), frame(version=8), frame(kind=b"abd"), frame(values=(1, 2, 3)),
              frame(points=pts, extras=1), frame(points=pts * 2), frame(extras=3),
              frame(points=[(1.0, b"toolong!", [(0, []), (0, [])])]),
              frame(values=(-32768, 32767, 0, -1, 1)), frame(counter=1)]
    prog = nested_program(5)
    expected, statuses = run_program(prog, frames, lambda b: window_oracle(b, "<i2", 3, "erode"))
    assert statuses.count(0) == 4 and len(expected) > 0
    project = write(project_files(spec_for(prog, op="erode", kind="signed", stream="values")),
                    tmp_path / "nested")
    assert simulate(project, frames) == (expected, expected)

    scan = scan_program(16)
    rng = np.random.default_rng(2)

    def scan_frame(ranges: np.ndarray, intensities: list[float]) -> bytes:
        body = struct.pack("<III", 1, 2, 3) + s(b"laser") + struct.pack("<7f", *range(7))
        body += struct.pack("<I", len(ranges)) + np.asarray(ranges, "<f4").tobytes()
        body += struct.pack("<I", len(intensities)) + np.asarray(intensities, "<f4").tobytes()
        return struct.pack("<I", len(body)) + body

    specials = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1.0], np.float32)
    frames = [scan_frame(rng.choice(specials, 16), [1.0]), scan_frame(rng.standard_normal(15), []),
              scan_frame(rng.standard_normal(16), [2.0] * 9), scan_frame(rng.choice(specials, 16), [])]
    expected, statuses = run_program(scan, frames, lambda b: window_oracle(b, "<f4", 5, "dilate"))
    assert statuses == [0, 3, 4, 0]
    project = write(project_files(spec_for(scan, ksize=5)), tmp_path / "scan")
    assert simulate(project, frames) == (expected, expected)


@settings(max_examples=3, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_random_message_definitions_simulate_as_the_models(data: st.DataObject,
                                                           tmp_path_factory: pytest.TempPathFactory) -> None:
    require_cxx()
    require_iverilog()
    reg, type_name, stream = data.draw(definitions())
    values = [data.draw(message(reg, type_name)) for _ in range(2)]
    n = max(1, len(values[0][stream]))
    layout = derive_layout(reg, type_name, stream=stream, stream_length=n)
    # small maxima (the defaults nest to megabytes of carry memory): 3 per array and string
    small = {s.path: 3 for s in layout.steps[1:] if s.kind is StepKind.LENGTH
             and s.action is not Action.STREAM and not s.label.endswith("[] length")}
    layout = derive_layout(reg, type_name, stream=stream, stream_length=n, limits_=small)
    frames = []
    for v in values:
        body = serialize(reg, type_name, v)
        frames.append(struct.pack("<I", len(body)) + body)
    frames.append(marshal(layout, sample_tokens(layout, np.random.default_rng(1))))
    op = data.draw(st.sampled_from(["dilate", "erode", "passthrough"]))
    expected, why = model_output(layout, op, 3, frames)
    spec = spec_from_layout(layout, reg, op=op, ksize=3)
    project = write(project_files(spec), tmp_path_factory.mktemp("random"))
    assert simulate(project, frames) == (expected, expected), why


@pytest.mark.parametrize("name", SHIPPED)
def test_generated_verilog_is_lint_clean_and_readable(name: str, tmp_path: Path) -> None:
    """Verilator -Wall and iverilog -Wall find nothing in the generic modules and the generated
    walk (the lab's rfl_fifo.v is another file's business); the walk names every field."""
    config = load_config(DATA / name)
    reg = config.registry()
    layout = layout_from_config(config, reg)
    rtl = write(project_files(spec_from_layout(layout, reg)), tmp_path) / "rtl"
    walk = (rtl / "rfl_layout.vh").read_text()
    for step in layout.steps[1:]:
        if step.kind.value not in ("length", "end"):
            assert f"// {step.label} (" in walk or f"//   {step.label} (" in walk, step.label
    assert_rtl_lint_clean(rtl)


def test_custom_application_runs_the_users_cpp(tmp_path: Path) -> None:
    """``op: custom``: the user's stream_filter() (here: negate every float32 range) replaces the
    application; the output is the models' pass-through output with every range negated."""
    require_cxx()
    source = tmp_path / "negate.cpp"
    source.write_text('#include "ros_node.h"\n'
                      "void stream_filter(elem_stream& in, elem_stream& out) {\n"
                      "    for (int e = 0; e < STREAM_LENGTH; e++) {\n"
                      "        elem_beat beat = in.read();\n"
                      "        beat.data = beat.data.to_uint64() ^ 0x80000000ull;\n"
                      "        out.write(beat);\n    }\n}\n")
    text = (DATA / "fpga_laserscan_min.yaml").read_text().replace(
        "application: {op: erode, ksize: 5}", "application: {op: custom, source: negate.cpp}")
    (tmp_path / "scan.yaml").write_text(text)
    out = tmp_path / "project"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(tmp_path / "scan.yaml"),
                           "-o", str(out), "-q"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert not (out / "rtl").exists() and not (out / "tb_expected.bin").exists()
    make(out, "csim")
    config = load_config(tmp_path / "scan.yaml")
    layout = layout_from_config(config)
    data = (out / "tb_input.bin").read_bytes()
    frames, at = [], 0
    while at < len(data):
        size = 4 + struct.unpack_from("<I", data, at)[0]
        frames.append(data[at:at + size])
        at += size
    expected, why = model_output(layout, "passthrough", 1, frames)
    got = (out / "csim_out/output.bin").read_bytes()
    assert len(got) == len(expected) > 0 and got != expected
    flipped = bytearray(expected)
    at = 0
    for frame, refused in zip(frames, why):
        if refused:
            continue
        geo = frame_geometry(layout, deserialize(config.registry(), layout.type_name, frame[4:]))
        for k in range(geo.stream_offset + 3, geo.stream_offset + geo.stream_bytes, 4):
            flipped[at + k] ^= 0x80
        at += 4 + geo.frame_length
    assert got == bytes(flipped)


CHANNEL = """node: {name: /fpga_channel}
subscriber: {topic: /channel, type: sensor_msgs/ChannelFloat32}
publisher: {topic: /channel_max}
stream: {field: values, length: 8}
limits: {name: 8}
fifo: {input_depth: 16, output_depth: 16, axis_depth: 4}
application: {op: dilate, ksize: 3}
"""


@pytest.mark.slow
@pytest.mark.timeout(900)       # 30 s idle; 248 s seen beside the proofs on a loaded machine
def test_yosys_synthesizes_a_generated_project(tmp_path: Path) -> None:
    """The smallest generic project that has every part (a carried string, a stream; about 30 s
    of Yosys): synth_xilinx elaborates it from rfl_node with no latch, no multiple driver, and
    reports a row per generic module."""
    from tests.support.rtltools import require_yosys
    from rosfpga_lab.rtl.synth import GENERIC_MODULES, synthesize_dir

    require_yosys()
    (tmp_path / "ch.yaml").write_text(CHANNEL)
    config = load_config(tmp_path / "ch.yaml")
    reg = config.registry()
    spec = spec_from_layout(layout_from_config(config, reg), reg, input_depth=16, output_depth=16,
                            axis_depth=4)
    rtl = write(project_files(spec), tmp_path / "p") / "rtl"
    report = synthesize_dir(rtl, config.part)
    # every generic module but the video application (rfl_morph: Image on CDR only)
    assert [row.module for row in report.rows] == [m for m, _ in GENERIC_MODULES
                                                   if m != "rfl_morph"]
    assert report.row("rfl_gsubscriber").counts["FF"] > 0
    assert report.row("rfl_window1d").counts["LUT"] > 0
    assert report.total["LUT"] == sum(row.counts["LUT"] for row in report.rows)


def test_the_generic_circuit_given_the_image_layout_publishes_as_the_image_project(
        tmp_path: Path) -> None:
    """sensor_msgs/Image through the generic renderer (pixels as a byte stream, a pass-through,
    header.seq numbered by the publisher as the Image project's does): C simulation and RTL
    simulation publish what the Image project's Python model (its video stream through the
    2-D application) publishes, frame for frame,
    including a frame of the wrong width refused between good ones."""
    from rosfpga_lab.config import parse_config
    from rosfpga_lab.hls.compiler import program_from_layout
    from rosfpga_lab.hw import MessagePipeline
    from rosfpga_lab.hw.errors import PipelineError
    from rosfpga_lab.hw.sample import image_frame

    require_cxx()
    require_iverilog()
    text = (DATA / "fpga_passthrough_rgb8.yaml").read_text().replace(
        "width: 160", "width: 6").replace("height: 120", "height: 4")
    config = parse_config(text)
    reg = config.registry()
    layout = layout_from_config(config, reg)
    prog = program_from_layout(layout, count="header.seq")
    spec = spec_from_layout(layout, reg, op="passthrough", ksize=1, program=prog)
    project = write(project_files(spec), tmp_path)
    rng = np.random.default_rng(11)
    frames = []
    for k, (w, fid) in enumerate([(6, "cam"), (6, ""), (5, "cam"), (6, "x" * 40)]):
        pic = rng.integers(0, 256, (4, w, 3), dtype=np.uint8)
        frames.append(image_frame(pic, "rgb8", seq=100 + k, stamp=(7 + k, 9), frame_id=fid))
    pipe = MessagePipeline.from_config(config)  # with the video stage: the Image project's model
    expected = b""
    refused = 0
    for frame in frames:
        try:
            expected += pipe.process(frame).output_frame
        except PipelineError:
            refused += 1
    assert refused == 1 and expected
    assert simulate(project, frames) == (expected, expected)


def test_a_vivado_flavour_of_a_generic_project(tmp_path: Path) -> None:
    """hls.flavour: vivado (once refused for a generic project, before that ignored quietly)
    writes Vivado HLS's script and packing directive into the same project."""
    from rosfpga_lab.config import parse_config

    text = (DATA / "fpga_samples_dilate.yaml").read_text(encoding="utf-8")
    vivado = parse_config(text + "\nhls: {flavour: vivado}\n", base_dir=DATA)
    generate_project(vivado, tmp_path / "out")
    out = tmp_path / "out"
    assert "vivado_hls -f run_hls.tcl" in (out / "run_hls.tcl").read_text()
    assert "HLS_PRAGMA(HLS DATA_PACK variable = meta_out)" in (out / "subscriber.cpp").read_text()
    assert "HLS_PRAGMA(HLS DATA_PACK variable = meta_in)" in (out / "publisher.cpp").read_text()
    assert "This project is the `vivado` flavour" in (out / "README.md").read_text()