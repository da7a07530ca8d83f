"""C simulation of the generated HLS C++ with g++, against the Python models, bit for bit.

For each shipped configuration the generated project is compiled once per session (with the
Makefile: ``g++ -std=c++14 -Wall -Werror`` against the lab's HLS headers) and fed TCPROS frames
serialized by real ROS (genpy, under the system Python; the lab's own serializer stands in only
where ROS is not installed). The output bytes and the AXI4-Stream beats on both sides of the
application must equal those of :class:`rosfpga_lab.hw.MessagePipeline` for the same
configuration (``tests.support.imagemodel`` adds its beats), and the output image must equal OpenCV's dilate/erode of the input. Without g++ these tests
skip (with ROSFPGA_REQUIRE_CXX=1, as in CI, they fail).
"""

from __future__ import annotations

import dataclasses
import os
import struct
import subprocess
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.realros import require_cxx, ros_missing_reason, run_ros_python
from rosfpga_lab.config import HlsConfig, load_config, parse_config
from rosfpga_lab.config.vocabulary import DEFAULT_HLS_FLAVOUR, HLS_FLAVOURS
from rosfpga_lab.hls import CsimError, build_csim, generate, run_csim
from tests.support.imagemodel import ImageModel
from rosfpga_lab.hls.csim import CsimResult
from rosfpga_lab.hw import Beats, PipelineError, image_frame
from rosfpga_lab.msg import default_registry, deserialize

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
CONFIGS = ["fpga_dilate_rgba8", "fpga_erode_mono8", "fpga_passthrough_rgb8"]
IMAGE_MD5 = "060021388200f6f0f447d0fcd9c64743"  # sensor_msgs/Image, from genpy

GENPY_FRAME = """
import io, struct, sys
import genpy
from sensor_msgs.msg import Image
m = Image()
m.header.seq = {seq}
m.header.stamp = genpy.Time({secs}, {nsecs})
m.header.frame_id = {frame_id!r}
m.height, m.width, m.encoding, m.is_bigendian, m.step = {h}, {w}, {encoding!r}, {big}, {step}
m.data = sys.stdin.buffer.read()
buf = io.BytesIO()
m.serialize(buf)
sys.stdout.buffer.write(struct.pack('<I', len(buf.getvalue())) + buf.getvalue())
"""


def ros_frame(image: np.ndarray, encoding: str, *, seq: int = 3, stamp: tuple[int, int] = (1700000000, 5),
              frame_id: str = "camera_link", step: int | None = None, is_bigendian: int = 0) -> bytes:
    """A TCPROS frame (length + Image) serialized by genpy; by the lab where ROS is missing
    (unless ROSFPGA_REQUIRE_ROS=1, as in CI: then a missing ROS fails the test)."""
    h, w = image.shape[:2]
    step = image.shape[1] * (image.shape[2] if image.ndim == 3 else 1) if step is None else step
    reason = ros_missing_reason()
    if reason is not None:
        if os.environ.get("ROSFPGA_REQUIRE_ROS", "") not in ("", "0", "false", "no"):
            pytest.fail(f"{reason} (and ROSFPGA_REQUIRE_ROS=1 says it must be there)", pytrace=False)
        return image_frame(image, encoding, seq=seq, stamp=stamp, frame_id=frame_id,
                           is_bigendian=is_bigendian)
    code = GENPY_FRAME.format(seq=seq, secs=stamp[0], nsecs=stamp[1], frame_id=frame_id, h=h, w=w,
                              encoding=encoding, big=is_bigendian, step=step)
    frame = run_ros_python(code, input=image.tobytes()).stdout
    if step == image.shape[1] * (image.shape[2] if image.ndim == 3 else 1):
        # The lab's frame builder must agree with genpy (so the fallback is the same frame).
        assert frame == image_frame(image, encoding, seq=seq, stamp=stamp, frame_id=frame_id,
                                    is_bigendian=is_bigendian)
    return frame


def random_image(config_stem: str, seed: int = 1) -> tuple[np.ndarray, str]:
    config = load_config(DATA / f"{config_stem}.yaml")
    rng = np.random.default_rng(seed)
    img = config.image
    image = rng.integers(0, 256, (img.height, img.width, img.bytes_per_pixel), dtype=np.uint8)
    image[rng.random((img.height, img.width)) < 0.9] //= 4  # sparse bright dots: dilation shows
    return image, img.encoding


class Project:
    def __init__(self, path: Path, binary: Path) -> None:
        self.path, self.binary = path, binary

    def run(self, frames: bytes) -> CsimResult:
        return run_csim(self.path, frames, binary=self.binary)


@pytest.fixture(scope="module")
def projects(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Project]:
    """Generated and compiled projects, built on first use, once per session."""
    require_cxx()
    cache: dict[str, Project] = {}

    class Lazy(dict):
        def __missing__(self, key: str) -> Project:
            # "STEM" (the default flavour) or "STEM:FLAVOUR".
            stem, _, flavour = key.partition(":")
            out = tmp_path_factory.mktemp(stem)
            config = load_config(DATA / f"{stem}.yaml")
            if flavour:
                config = dataclasses.replace(config, hls=HlsConfig(flavour))
            generate(config, out / "proj")
            cache[key] = Project(out / "proj", build_csim(out / "proj"))
            self[key] = cache[key]
            return cache[key]

    return Lazy()


def _decode(frame: bytes) -> dict:
    (length,) = struct.unpack_from("<I", frame)
    assert length == len(frame) - 4
    return deserialize(default_registry(), "sensor_msgs/Image", frame[4:])


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
@pytest.mark.parametrize("stem", CONFIGS)
def test_csim_equals_python_models_and_opencv(projects: dict[str, Project], stem: str,
                                               flavour: str) -> None:
    """Both flavours of the generated C++ (the same application, its own line buffer; the
    flavours differ in one directive), each with g++ alone, give the models' bytes and beats."""
    image, encoding = random_image(stem)
    frame = ros_frame(image, encoding)
    project = projects[stem if flavour == DEFAULT_HLS_FLAVOUR else f"{stem}:{flavour}"]
    assert "hls_video.h" not in os.listdir(project.path / "hls_include")
    got = project.run(frame)
    config = load_config(DATA / f"{stem}.yaml")
    model = ImageModel(config).process(frame)
    assert got.status == ((0, "SUB_OK"),)
    assert len(got.input_beats) == config.image.width * config.image.height
    assert got.input_beats == model.input_beats, f"first differing beat {got.input_beats.first_difference(model.input_beats)}"
    assert got.output_beats == model.output_beats, f"first differing beat {got.output_beats.first_difference(model.output_beats)}"
    assert got.output == model.output_frame
    # Independent oracle: OpenCV on the input image, and the header as ROS would publish it.
    out = _decode(got.output)
    kernel = np.ones((config.application.ksize,) * 2, np.uint8)
    expected = {"dilate": lambda a: cv2.dilate(a, kernel), "erode": lambda a: cv2.erode(a, kernel),
                "passthrough": lambda a: a}[config.application.op](image)
    assert np.array_equal(np.frombuffer(bytes(out["data"]), np.uint8).reshape(image.shape),
                          expected.reshape(image.shape))
    assert out["header"]["seq"] == 1 and out["header"]["frame_id"] == "camera_link"
    assert (out["header"]["stamp"].secs, out["header"]["stamp"].nsecs) == (1700000000, 5)
    assert (out["height"], out["width"], out["encoding"]) == (image.shape[0], image.shape[1], encoding)
    assert got.log.count("WARNING") == 0, got.log


@pytest.mark.parametrize("stem", CONFIGS)
def test_make_csim_passes_on_the_shipped_test_frame(projects: dict[str, Project], stem: str) -> None:
    proj = projects[stem]
    proc = subprocess.run(["make", "-s", "csim"], cwd=proj.path, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "csim: PASS: output equals tb_expected.bin" in proc.stdout
    assert "WARNING" not in proc.stderr
    # Other frames: simulated, not compared with the shipped frame's expected output.
    two = proj.path / "two_frames.bin"
    two.write_bytes((proj.path / "tb_input.bin").read_bytes() * 2)
    other = subprocess.run(["make", "-s", "csim", f"INPUT={two}", "OUT=csim_two"], cwd=proj.path,
                           capture_output=True, text=True, timeout=300)
    assert other.returncode == 0, other.stdout + other.stderr
    assert "2 frame(s) in, 0 refused" in other.stdout and "PASS" not in other.stdout


def _header_fields(data: bytes) -> dict[str, str]:
    (total,) = struct.unpack_from("<I", data)
    assert total == len(data) - 4
    fields, pos, keys = {}, 4, []
    while pos < len(data):
        (n,) = struct.unpack_from("<I", data, pos)
        key, _, value = data[pos + 4:pos + 4 + n].decode().partition("=")
        fields[key] = value
        keys.append(key)
        pos += 4 + n
    assert keys == sorted(keys)  # roscpp and rospy order
    return fields


def test_connection_headers_from_the_circuit(projects: dict[str, Project]) -> None:
    image, encoding = random_image("fpga_passthrough_rgb8")
    got = projects["fpga_passthrough_rgb8"].run(image_frame(image, encoding))
    sub = _header_fields(got.subscriber_header)
    pub = _header_fields(got.publisher_header)
    assert sub["md5sum"] == pub["md5sum"] == IMAGE_MD5
    assert sub["type"] == pub["type"] == "sensor_msgs/Image"
    assert sub["callerid"] == pub["callerid"] == "/fpga_passthrough"
    assert (sub["topic"], pub["topic"]) == ("/image_rgb", "/image_rgb_copy")
    assert sub["tcp_nodelay"] == "1" and pub["latching"] == "0"
    definition = sub["message_definition"]
    assert definition == pub["message_definition"]
    golden = Path(__file__).resolve().parents[1] / "golden" / "sensor_msgs_Image.full_text"
    assert definition == golden.read_text()   # genpy's _full_text, comments included


def _frame(body: bytes) -> bytes:
    return struct.pack("<I", len(body)) + body


def test_refused_frames_are_skipped_and_the_next_good_frame_comes_out_right(
        projects: dict[str, Project]) -> None:
    stem = "fpga_erode_mono8"
    config = load_config(DATA / f"{stem}.yaml")
    image, encoding = random_image(stem, seed=5)
    other, _ = random_image(stem, seed=6)
    # Frames whose strings fit the frame length but whose fixed fields after them do not: the
    # circuit must refuse them without reading past the frame's end (into the next frame), at
    # the first field that runs past it (the walk knows no fixed size after frame_id: the
    # encoding and data that follow vary).
    stamp = struct.pack("<III", 1, 2, 3)
    fid_overrun = _frame(stamp + struct.pack("<I", 30) + b"f" * 30 + struct.pack("<I", 240) + b"\x40")
    enc_overrun = _frame(stamp + struct.pack("<I", 3) + b"cam" + struct.pack("<III", 240, 320, 5)
                         + b"mono8" + b"\x00" + b"\x40\x01")
    frames = [
        ("wrong width", image_frame(image[:, :-1], encoding), "SUB_BAD_WIDTH"),
        ("wrong height", image_frame(image[:-1], encoding), "SUB_BAD_HEIGHT"),
        ("wrong encoding", image_frame(np.repeat(image, 3, axis=2), "rgb8"), "SUB_BAD_ENCODING"),
        ("good", ros_frame(image, encoding, seq=10), "SUB_OK"),
        ("frame_id too long", image_frame(image, encoding, frame_id="f" * 300), "SUB_BAD_HEADER_FRAME_ID_LENGTH"),
        ("frame length too short", struct.pack("<I", 10) + bytes(10), "SUB_BAD_FRAME_LENGTH"),
        ("frame ends after frame_id", fid_overrun, "SUB_BAD_WIDTH"),
        ("frame ends after encoding", enc_overrun, "SUB_BAD_STEP"),
        ("data length differs from step x height",
         _frame(image_frame(image, encoding)[4:-4 - image.size] + struct.pack("<I", image.size - 1)
                + image.tobytes()[:-1]), "SUB_BAD_DATA_LENGTH"),
        ("good again", ros_frame(other, encoding, seq=11, frame_id="cam2"), "SUB_OK"),
    ]
    stream = b"".join(f for _, f, _ in frames)
    got = projects[stem].run(stream)
    # Every frame was read exactly to its end: no read of an empty stream, no byte left over.
    assert "WARNING" not in got.log, got.log
    offsets = np.cumsum([0] + [len(f) for _, f, _ in frames])[:-1]
    assert got.status == tuple((int(o), s) for o, (_, _, s) in zip(offsets, frames))
    # The Python model refuses the same frames and numbers the accepted ones 1, 2.
    pipe = ImageModel(config)
    expected, beats_in, beats_out = b"", [], []
    for name, frame, status in frames:
        try:
            res = pipe.process(frame)
        except PipelineError:
            assert status != "SUB_OK", name
            continue
        assert status == "SUB_OK", name
        expected += res.output_frame
        beats_in.append(res.input_beats)
        beats_out.append(res.output_beats)
    assert got.output == expected
    first = 4 + struct.unpack_from("<I", got.output)[0]
    one, two = _decode(got.output[:first]), _decode(got.output[first:])
    assert (one["header"]["seq"], one["header"]["frame_id"]) == (1, "camera_link")
    assert (two["header"]["seq"], two["header"]["frame_id"]) == (2, "cam2")
    n = config.image.width * config.image.height
    assert len(got.input_beats) == len(got.output_beats) == 2 * n
    for i in range(2):
        for side, model_beats in ((got.input_beats, beats_in[i]), (got.output_beats, beats_out[i])):
            part = Beats(side.tdata[i * n:(i + 1) * n], side.tkeep[i * n:(i + 1) * n],
                         side.tuser[i * n:(i + 1) * n], side.tlast[i * n:(i + 1) * n])
            assert part == model_beats, f"frame {i}: first differing beat {part.first_difference(model_beats)}"


CUSTOM_FILTER = r"""
// A user's application: invert every channel (the paper's input (c), written by hand).
#include "ros_node.h"

void stream_filter(pixel_stream& in, pixel_stream& out) {
    for (int p = 0; p < IMG_HEIGHT * IMG_WIDTH; p++) {
        pixel_beat beat = in.read();
        beat.data = (~beat.data.to_uint()) & PIXEL_MASK;
        out.write(beat);
    }
}
"""


def test_custom_application_file(tmp_path: Path) -> None:
    require_cxx()
    (tmp_path / "invert.cpp").write_text(CUSTOM_FILTER)
    text = (DATA / "fpga_erode_mono8.yaml").read_text().replace(
        "  op: erode\n  ksize: 5\n", "  op: custom\n  source: invert.cpp\n")
    (tmp_path / "node.yaml").write_text(text)
    config = load_config(tmp_path / "node.yaml")
    result = generate(config, tmp_path / "proj")
    assert "tb_expected.bin" not in result.files
    assert (tmp_path / "proj" / "stream_filter.cpp").read_text() == CUSTOM_FILTER
    image, encoding = random_image("fpga_erode_mono8", seed=9)
    got = run_csim(tmp_path / "proj", image_frame(image, encoding, frame_id="x"))
    out = _decode(got.output)
    assert np.array_equal(np.frombuffer(bytes(out["data"]), np.uint8).reshape(image.shape), 255 - image)
    assert got.output_beats.tkeep.tolist() == [1] * image.size


def test_build_failure_quotes_the_compiler(tmp_path: Path) -> None:
    require_cxx()
    (tmp_path / "broken.cpp").write_text('#include "ros_node.h"\nvoid stream_filter(pixel_stream& in) {}\n')
    text = (DATA / "fpga_erode_mono8.yaml").read_text().replace(
        "  op: erode\n  ksize: 5\n", "  op: custom\n  source: broken.cpp\n")
    (tmp_path / "node.yaml").write_text(text)
    generate(load_config(tmp_path / "node.yaml"), tmp_path / "proj")
    with pytest.raises(CsimError, match="building the testbench .* failed"):
        build_csim(tmp_path / "proj")


def test_builds_without_make(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    require_cxx()
    import rosfpga_lab.hls.csim as csim

    real_which = csim.shutil.which
    monkeypatch.setattr(csim.shutil, "which", lambda name: None if name == "make" else real_which(name))
    config = load_config(DATA / "fpga_passthrough_rgb8.yaml")
    generate(config, tmp_path / "proj")
    binary = build_csim(tmp_path / "proj")
    frame = (tmp_path / "proj" / "tb_input.bin").read_bytes()
    got = run_csim(tmp_path / "proj", frame, binary=binary)
    assert got.output == (tmp_path / "proj" / "tb_expected.bin").read_bytes()
    with pytest.raises(CsimError, match="no C\\+\\+ compiler"):
        build_csim(tmp_path / "proj", cxx="no-such-g++")


def test_a_frame_cut_short_is_not_simulated(projects: dict[str, Project]) -> None:
    proj = projects["fpga_passthrough_rgb8"]
    good = (proj.path / "tb_input.bin").read_bytes()
    got = proj.run(good + good[: len(good) // 2])
    assert got.status == ((0, "SUB_OK"),)
    assert got.output == (proj.path / "tb_expected.bin").read_bytes()
    assert f"the frame at byte {len(good)} is cut short ({len(good) // 2} of {len(good)} bytes)" in got.log
    assert "WARNING" not in got.log


def test_a_batch_of_varied_frames_equals_the_models(projects: dict[str, Project]) -> None:
    """Many frames in one run: frame_id from empty to the limit (and one past), stamps,
    is_bigendian, pixel content; the circuit and the Python model agree on every one."""
    stem = "fpga_erode_mono8"
    config = load_config(DATA / f"{stem}.yaml")
    rng = np.random.default_rng(11)
    frames = []
    for i, n in enumerate([0, 1, 7, 255, 256, 257, 3, 64]):
        image = rng.integers(0, 256, (config.image.height, config.image.width, 1), dtype=np.uint8)
        frame_id = "".join(chr(c) for c in rng.integers(97, 123, n))
        frames.append(image_frame(image, "mono8", seq=int(rng.integers(0, 2**32)),
                                  stamp=(int(rng.integers(0, 2**32)), int(rng.integers(0, 10**9))),
                                  frame_id=frame_id, is_bigendian=i % 2))
    got = projects[stem].run(b"".join(frames))
    pipe = ImageModel(config)
    expected, statuses = b"", []
    for frame in frames:
        try:
            expected += pipe.process(frame).output_frame
            statuses.append("SUB_OK")
        except PipelineError:
            statuses.append("refused")
    assert statuses.count("refused") == 1  # the 257-byte frame_id
    assert [s if s == "SUB_OK" else "refused" for _, s in got.status] == statuses
    assert got.output == expected


def test_frame_id_max_is_the_same_limit_in_the_circuit_and_the_models(tmp_path: Path) -> None:
    """``frame_id_max`` below the lab's limit: C and Python refuse the same frames."""
    require_cxx()
    text = (DATA / "fpga_passthrough_rgb8.yaml").read_text() + "frame_id_max: 16\n"
    (tmp_path / "node.yaml").write_text(text)
    config = load_config(tmp_path / "node.yaml")
    generate(config, tmp_path / "proj")
    image, encoding = random_image("fpga_passthrough_rgb8", seed=3)
    frames = [image_frame(image, encoding, frame_id="f" * n) for n in (15, 16, 17, 0)]
    got = run_csim(tmp_path / "proj", b"".join(frames))
    assert [s for _, s in got.status] == ["SUB_OK", "SUB_OK", "SUB_BAD_HEADER_FRAME_ID_LENGTH", "SUB_OK"]
    pipe = ImageModel(config)
    expected = b""
    for n, frame in zip((15, 16, 17, 0), frames):
        if n == 17:
            with pytest.raises(PipelineError, match="header.frame_id length"):
                pipe.process(frame)
        else:
            expected += pipe.process(frame).output_frame
    assert got.output == expected
    assert "WARNING" not in got.log, got.log


@pytest.mark.parametrize("op, ksize, encoding, width, height", [
    ("dilate", 7, "rgb8", 9, 5),   # the window taller than the image
    ("erode", 5, "bgra8", 4, 3),   # and wider
    ("dilate", 1, "mono8", 6, 4),  # a 1x1 window: the pixels pass
])
def test_vitis_line_buffer_on_small_images_and_kernels(tmp_path: Path, op: str, ksize: int,
                                                       encoding: str, width: int, height: int) -> None:
    """The Vitis flavour's own line buffer and window at the edges: kernels as large as or
    larger than the image, and the static line buffer carrying nothing from one frame into the
    next (three frames in one run); the models and OpenCV agree, beat for beat."""
    require_cxx()
    text = (DATA / "fpga_passthrough_rgb8.yaml").read_text()
    text = text.replace("  op: passthrough\n", f"  op: {op}\n  ksize: {ksize}\n")
    text = re.sub(r"image: .*|image:\n(  .*\n)+",
                  f"image: {{width: {width}, height: {height}, encoding: {encoding}}}\n", text)
    config = parse_config(text, source="small.yaml")
    assert (config.application.op, config.application.ksize, config.image.width) == (op, ksize, width)
    assert config.hls.flavour == "vitis"
    generate(config, tmp_path / "proj")
    rng = np.random.default_rng(ksize)
    channels = config.image.bytes_per_pixel
    images = [rng.integers(0, 256, (height, width, channels), dtype=np.uint8) for _ in range(3)]
    images[1][:] = 255 if op == "erode" else 0  # a flat frame after a busy one: no leftovers
    frames = [image_frame(im, encoding, seq=i, frame_id=f"f{i}") for i, im in enumerate(images)]
    got = run_csim(tmp_path / "proj", b"".join(frames))
    assert "WARNING" not in got.log, got.log
    pipe = ImageModel(config)
    results = [pipe.process(f) for f in frames]
    assert got.output == b"".join(r.output_frame for r in results)
    n = width * height
    for i, res in enumerate(results):
        part = Beats(got.output_beats.tdata[i * n:(i + 1) * n], got.output_beats.tkeep[i * n:(i + 1) * n],
                     got.output_beats.tuser[i * n:(i + 1) * n], got.output_beats.tlast[i * n:(i + 1) * n])
        assert part == res.output_beats, f"frame {i}: first differing beat {part.first_difference(res.output_beats)}"
        kernel = np.ones((ksize, ksize), np.uint8)
        morph = cv2.dilate if op == "dilate" else cv2.erode
        expected = morph(images[i], kernel).reshape(images[i].shape)
        published = np.frombuffer(bytes(_decode(res.output_frame)["data"]), np.uint8)
        assert np.array_equal(published.reshape(images[i].shape), expected)
