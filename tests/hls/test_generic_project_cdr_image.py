"""``sensor_msgs/Image`` with ``wire: cdr`` through ``rosfpga-lab generate`` (issue 20, Build 2):
the generic CDR walkers with the data array framed as video, and the video project's 2-D
application. C simulation (g++) and RTL simulation (Icarus Verilog, random input gaps and output
backpressure) publish and refuse exactly as the lab's CDR circuit model ``hw.CdrPipeline``, byte
for byte and status for status, on samples real Cyclone DDS serialized (PyPI ``cyclonedds``, the
shipped capture script's IDL): the encapsulation header, alignment counted from after it,
``header.frame_id`` and ``encoding`` with their NUL, ``is_bigendian`` then padding to ``step``'s
alignment, the data length, Cyclone's unannounced end padding (zeros) to 4.

The accepted samples' output is also held against an independent oracle: Cyclone DDS's own
serialization of the same value with the pixels replaced by OpenCV's ``cv2.dilate``/``cv2.erode``.
The beats ``fifo2axi`` hands the application are held to the TCPROS Image project's model
(``hw.axis.fifo2axi_fast``: one pixel per beat, TUSER on the first, TLAST ending each line).
Small frames (8x4 rgba8 dilate 3x3; 7x5 rgb8 erode 5x5, whose payloads Cyclone pads).
"""

from __future__ import annotations

import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.realros import require_cxx
from tests.support.rtltools import require_iverilog
from tests.hls.test_generic_project_cdr import (
    both_simulations, check_shipped_records, cyclone, make, pad_tail, pad_to_4, record, sloc_table,
    statuses_of,
)
from rosfpga_lab.config import parse_config
from rosfpga_lab.hw import CdrPipeline
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.hw.errors import FrameFieldError

DATA = Path(__file__).resolve().parents[2] / "data"
SHIPPED = "fpga_dilate_rgba8_cdr.yaml"
#: name -> (encoding, width, height, op, ksize): small variants of the shipped configuration
SMALL = {"rgba8": ("rgba8", 8, 4, "dilate", 3), "rgb8": ("rgb8", 7, 5, "erode", 5)}
CHANNELS = {"rgba8": 4, "rgb8": 3}


def config_text(name: str) -> str:
    enc, w, h, op, k = SMALL[name]
    text = (DATA / SHIPPED).read_text()
    for old, new in (("width: 640", f"width: {w}"), ("height: 480", f"height: {h}"),
                     ("encoding: rgba8", f"encoding: {enc}"), ("op: dilate", f"op: {op}"),
                     ("ksize: 3", f"ksize: {k}")):
        assert old in text
        text = text.replace(old, new)
    return text


@pytest.fixture(scope="module")
def projects(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Both small variants through ``rosfpga-lab generate`` (as a student types it)."""
    out = {}
    for name in SMALL:
        where = tmp_path_factory.mktemp("cdr_image")
        (where / f"image_{name}_cdr.yaml").write_text(config_text(name))
        proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate",
                               str(where / f"image_{name}_cdr.yaml"), "-o", str(where / "project"),
                               "-q"], capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        out[name] = where / "project"
    return out


def image_sample(T: Any, pixels: np.ndarray, *, frame_id: str = "cam", encoding: str | None = None,
                 height: int | None = None, width: int | None = None, step: int | None = None,
                 big: int = 0, stamp: tuple[int, int] = (1700000000, 500)) -> bytes:
    """An Image as Cyclone DDS serializes it (its ``serialize()``: options 0, no end padding)."""
    h, w, c = pixels.shape
    enc = encoding or {4: "rgba8", 3: "rgb8"}[c]
    return T.Image_(T.Header_(T.Time_(*stamp), frame_id), h if height is None else height,
                    w if width is None else width, enc, big, w * c if step is None else step,
                    list(pixels.tobytes())).serialize()


def oracle(T: Any, pixels: np.ndarray, op: str, ksize: int, **kw: Any) -> bytes:
    """What the circuit must publish for a good sample: Cyclone DDS's bytes of the same Image
    with OpenCV's dilation/erosion of its pixels (an independent oracle)."""
    import cv2

    f = cv2.dilate if op == "dilate" else cv2.erode
    out = f(pixels, np.ones((ksize, ksize), np.uint8)).reshape(pixels.shape)
    return record(image_sample(T, out, **kw))


def check(name: str, project: Path, records: list[bytes], want_oracle: bytes) -> list[str]:
    """Models (hw.CdrPipeline) == oracle; csim and rtlsim == models. Returns the statuses."""
    config = parse_config(config_text(name))
    pipe = CdrPipeline(config)
    expected = b""
    for rec in records:
        try:
            expected += record(pipe.process(rec[4:]))
        except FrameFieldError:
            pass
    assert expected == want_oracle
    want = statuses_of(cdr_layout_from_config(config), records)
    csim, rtl = both_simulations(project, records)
    assert csim == (expected, want)
    assert rtl == (expected, want)
    return want


@pytest.mark.parametrize("name", list(SMALL))
def test_generated_image_cdr_project_passes_its_own_test_records(
        name: str, projects: dict[str, Path]) -> None:
    """``make csim`` and ``make rtlsim`` pass on the shipped records (good, big-endian refused,
    good with announced end padding); the Verilog holds rfl_morph.v and ``sloc`` counts it."""
    out = projects[name]
    check_shipped_records(out)
    # the expected output is hw.CdrPipeline's, not only the generator's own helper's
    inp = (out / "tb_input.bin").read_bytes()
    pipe = CdrPipeline(parse_config(config_text(name)))
    at, want = 0, b""
    while at < len(inp):
        n = struct.unpack_from("<I", inp, at)[0]
        try:
            want += record(pipe.process(inp[at + 4:at + 4 + n]))
        except FrameFieldError:
            pass
        at += 4 + n
    assert want == (out / "tb_expected.bin").read_bytes() and want
    assert ".VIDEO(1)" in (out / "rtl/rfl_node.v").read_text() and (out / "rtl/rfl_morph.v").is_file()
    assert "rfl_morph.v" in sloc_table(out)


def test_cyclone_dds_images_rgba8_through_the_generated_circuit(
        projects: dict[str, Path]) -> None:
    """8x4 rgba8, dilate 3x3: frame_ids of 0..8 characters move the alignment of everything
    after them; is_bigendian 0 and 1; each refusal (big-endian header, encoding and frame_id
    without their NUL, wrong width, height, step, encoding, data length, a sample cut short)
    then a good sample, which must come out right."""
    require_cxx()
    require_iverilog()
    T = cyclone()
    rng = np.random.default_rng(30)
    shape = (4, 8, 4)

    def px() -> np.ndarray:
        return rng.integers(0, 256, shape, dtype=np.uint8)

    good_kw = [dict(frame_id=""), dict(frame_id="c", big=1), dict(frame_id="ab"),
               dict(frame_id="cam"), dict(frame_id="abcd", stamp=(-5, 999_999_999)),
               dict(frame_id="camera_1"), dict(frame_id="x" * 13, big=1), dict(frame_id="z"),
               dict(frame_id="")]
    goods, outs = [], []
    for kw in good_kw:
        p = px()
        goods.append(record(image_sample(T, p, **kw)))
        outs.append(oracle(T, p, "dilate", 3, **kw))
    base = goods[3][4:]                                   # frame_id "cam"
    enc_nul = base.index(b"rgba8\x00") + 5
    fid_nul = 4 + 8 + 4 + 3
    p = px()
    bad = [
        record(b"\x00\x00" + base[2:]),                                        # CDR big-endian
        record(base[:enc_nul] + b"!" + base[enc_nul + 1:]),                    # encoding NUL
        record(base[:fid_nul] + b"\x01" + base[fid_nul + 1:]),                 # frame_id NUL
        record(image_sample(T, rng.integers(0, 256, (4, 7, 4), np.uint8))),    # width 7
        record(image_sample(T, rng.integers(0, 256, (5, 8, 4), np.uint8))),    # height 5
        record(image_sample(T, p, step=36)),                                   # step
        record(image_sample(T, p, encoding="bgra8")),                          # encoding
        record(image_sample(T, p)[:-1]),                                       # data length
    ]
    records, want_oracle = [], b""
    for k, b in enumerate(bad):
        records += [goods[k], b]
        want_oracle += outs[k]
    records.append(goods[8])
    want_oracle += outs[8]
    statuses = check("rgba8", projects["rgba8"], records, want_oracle)
    assert statuses[1::2] == [
        "SUB_BAD_ENCAPSULATION", "SUB_BAD_ENCODING_NUL", "SUB_BAD_HEADER_FRAME_ID_NUL",
        "SUB_BAD_WIDTH", "SUB_BAD_HEIGHT", "SUB_BAD_STEP", "SUB_BAD_ENCODING",
        "SUB_BAD_DATA_LENGTH"]
    assert set(statuses[0::2]) == {"SUB_OK"}


def test_cyclone_dds_images_rgb8_with_end_padding_through_the_generated_circuit(
        projects: dict[str, Path]) -> None:
    """7x5 rgb8, erode 5x5 (3-byte pixels in 32-bit beats): the 105 data bytes leave the payload
    short of a multiple of 4, so Cyclone DDS pads it on the wire: padding unannounced (options
    00 00) or announced is taken, zero or not (its value is never looked at), bytes beyond the
    multiple of 4 are refused by the sample length; each refusal then a good sample. The
    stream is the walk's last field, so the Verilog hands each frame over at the data's count
    (early release): the fit to the payload's end is checked there."""
    require_cxx()
    require_iverilog()
    T = cyclone()
    rng = np.random.default_rng(31)
    samples, outs = [], []
    for kw in (dict(frame_id="cam"), dict(frame_id="", big=1), dict(frame_id="left_7")):
        p = rng.integers(0, 256, (5, 7, 3), dtype=np.uint8)
        samples.append(image_sample(T, p, **kw))
        outs.append(oracle(T, p, "erode", 5, **kw))
    assert all(len(s) % 4 for s in samples)           # Cyclone pads each on the wire
    s0, s1, s2 = samples
    fill = -len(s0) % 4
    cases = [
        (record(pad_to_4(s0)), outs[0]),                                   # unannounced zeros
        (record(pad_to_4(s1, fill=b"\x05" + bytes(-len(s1) % 4 - 1))), outs[1]),  # non-zero pad
        (record(pad_tail(s2, 3)), outs[2]),                                # announced, 3 bytes
        (record(pad_to_4(s0) + bytes(4)), b""),                            # beyond the multiple
        (record(pad_to_4(s1)), outs[1]),
        (record(pad_to_4(s2, fill=bytes(-len(s2) % 4 - 1) + b"\x80")), outs[2]),  # last pad byte
        (record(s0), outs[0]),                                             # no padding at all
        (record(b"\x00\x01\x00\x00" + pad_to_4(s0)[4:-fill - 1]), b""),    # cut short
        (record(pad_to_4(s2)), outs[2]),
    ]
    statuses = check("rgb8", projects["rgb8"], [r for r, _o in cases],
                     b"".join(o for _r, o in cases))
    assert statuses == ["SUB_OK", "SUB_OK", "SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_OK", "SUB_OK",
                        "SUB_OK", "SUB_BAD_DATA_LENGTH", "SUB_OK"]


DRIVER = r"""
#include <cstdio>
#include "ros_node.h"
int main() {
    byte_stream in("in");
    elem_stream out("out");
    int c;
    while ((c = std::getchar()) != EOF) in.write((unsigned char)c);
    fifo2axi(in, out);
    while (!out.empty()) {
        elem_beat b = out.read();
        std::printf("%u %u %u %u\n", (unsigned)b.data.to_uint64(), (unsigned)b.keep.to_uint64(),
                    (unsigned)b.user.to_uint64(), (unsigned)b.last.to_uint64());
    }
    return 0;
}
"""


@pytest.mark.parametrize("name", list(SMALL))
def test_generated_fifo2axi_frames_pixels_as_the_image_project(
        name: str, projects: dict[str, Path], tmp_path: Path) -> None:
    """The generated fifo2axi (subscriber.cpp) hands the application the beats the TCPROS Image
    project's fifo2axi model makes: a pixel per beat, unused lanes zero, TKEEP of the encoding,
    TUSER on the first pixel, TLAST on the last of every line."""
    from rosfpga_lab.hw.axis import fifo2axi_fast
    from rosfpga_lab.hw.encodings import PIXEL_FORMATS

    require_cxx()
    enc, w, h, _op, _k = SMALL[name]
    project = projects[name]
    (tmp_path / "driver.cpp").write_text(DRIVER)
    binary = tmp_path / "driver"
    proc = subprocess.run(["g++", "-std=c++14", "-O1", f"-I{project}",
                           f"-I{project / 'hls_include'}", str(tmp_path / "driver.cpp"),
                           str(project / "subscriber.cpp"), "-o", str(binary)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    data = np.random.default_rng(32).integers(0, 256, h * w * CHANNELS[enc], dtype=np.uint8)
    run = subprocess.run([str(binary)], input=data.tobytes(), capture_output=True, timeout=60)
    assert run.returncode == 0
    got = np.array([[int(v) for v in line.split()] for line in run.stdout.decode().splitlines()])
    beats, left = fifo2axi_fast(data, h, w, PIXEL_FORMATS[enc])
    assert left == 0 and got.shape == (h * w, 4)
    assert got[:, 0].tolist() == beats.tdata.tolist()
    assert got[:, 1].tolist() == beats.tkeep.tolist()
    assert got[:, 2].astype(bool).tolist() == beats.tuser.tolist()
    assert got[:, 3].astype(bool).tolist() == beats.tlast.tolist()
    assert int(got[:, 3].sum()) == h                  # one TLAST per line


@pytest.mark.parametrize("name", list(SMALL))
def test_image_on_tcpros_is_the_same_project(name: str, tmp_path: Path) -> None:
    """Image on TCPROS goes through the same renderer (issue 28): its data framed as video, its
    header.seq numbered by the publisher as the Image model (hw.MessagePipeline) numbers it; the
    generated project's make csim and make rtlsim both publish exactly what the model publishes
    for the shipped test frame."""
    from rosfpga_lab.hls.generic import spec_from_config
    from rosfpga_lab.hls.program import Pub
    from rosfpga_lab.rtl.project import generate_project

    require_cxx()
    require_iverilog()
    config = parse_config(config_text(name).replace("wire: cdr", "wire: tcpros"),
                          source="small_tcpros.yaml")
    spec = spec_from_config(config)
    assert spec.video is not None and spec.wire == "tcpros"
    assert [i.pub for i in spec.program.instrs if i.name == "header.seq"] == [Pub.COUNT]
    generate_project(config, tmp_path / "proj")
    for target, extra in (("csim", []), ("rtlsim", ["SIM=iverilog", "GAP=100", "BP=200"])):
        proc = subprocess.run(["make", "-s", target, *extra], cwd=tmp_path / "proj",
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert f"{target}: PASS: output equals tb_expected.bin" in proc.stdout


@pytest.mark.parametrize("name", list(SMALL))
def test_generated_image_cdr_verilog_is_lint_clean(name: str, projects: dict[str, Path]) -> None:
    """Verilator -Wall and iverilog -Wall find nothing in the walkers with the video framing and
    rfl_morph in rfl_gtop (24-bit pixels padded to its 32-bit lanes for rgb8)."""
    from tests.support.generictools import assert_rtl_lint_clean

    assert_rtl_lint_clean(projects[name] / "rtl")


def test_the_rtl_tools_build_the_cdr_image_circuit() -> None:
    """rtl sim/cycles/synth/timing and --model rtl build a configuration's generated top
    (``design_from_config``): for the shipped CDR Image configuration, its CDR video circuit."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.hls.generic import GenericSpec
    from rosfpga_lab.rtl import design_from_config

    spec = design_from_config(load_config(DATA / SHIPPED))
    assert isinstance(spec, GenericSpec)
    assert spec.wire == "cdr" and spec.video is not None and spec.video.width == 640


def test_make_synth_reports_every_module_of_the_video_project(projects: dict[str, Path]) -> None:
    """``make synth``'s table has a row for every module of the project's Verilog (rfl_morph's
    resources were left out of the rows and the total)."""
    import re

    from rosfpga_lab.hls.rtlbuild import HARNESS_FILES
    from rosfpga_lab.rtl.synth import GENERIC_MODULES

    rtl = projects["rgba8"] / "rtl"
    modules = {m for p in rtl.glob("*.v") if p.name not in ("rfl_tb.v", *HARNESS_FILES)
               for m in re.findall(r"^\s*module\s+(\w+)", p.read_text(), re.M)}
    assert "rfl_morph" in modules
    assert modules - {"rfl_node"} <= {m for m, _row in GENERIC_MODULES}
