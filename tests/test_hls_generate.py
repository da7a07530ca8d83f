"""The generator: golden files, determinism, the manifest and --force, the CLI, the SLOC table.

Golden files live in ``tests/golden/hls/<config>/`` (the default flavour, Vitis HLS) and
``tests/golden/hls-vivado/<config>/`` (``hls: {flavour: vivado}``, only the files that differ from
the default's): every text file the generator writes for the three shipped Image configurations.
The generated projects of the other examples, LaserScan and the lab's own message on both wires
(``rosfpga-lab generate``: the HLS C++, ``rtl/`` and the test frames), have theirs in
``tests/golden/hls/<config>/`` too: every file rendered for the configuration (``rtl/`` holds the
walk ``rfl_layout.vh``, the wrapper ``rfl_node.v`` and the testbench ``rfl_tb.v``), the SHA-256
of the test frames (``tb_frames.sha256``); the files copied from the library (``hls_include/``,
``rtl/rfl_fifo.v`` and the generic modules of ``rosfpga_lab/rtl/generic/``) are held equal to
their sources instead, so a change to those needs no new golden file. A template change shows
up here as a diff. To accept a change on purpose, regenerate them all (one command) and review
the diff before committing::

    ROSFPGA_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/test_hls_generate.py -k golden
    git diff tests/golden/hls tests/golden/hls-vivado
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rosfpga_lab.config import ConfigError, HlsConfig, NodeConfig, load_config, parse_config
from rosfpga_lab.config.vocabulary import DEFAULT_HLS_FLAVOUR, HLS_FLAVOURS
from rosfpga_lab.hls import GenerateError, HlsError, count_sloc, format_table, generate, render
from rosfpga_lab.hls.generator import HLS_TOOLS, MANIFEST, TEMPLATE_FILES, meta_fields
from rosfpga_lab.hls.sloc import PAPER_TABLE1, sloc
from rosfpga_lab.rtl.sloc import count_verilog, verilog_sloc

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "data"
GOLDEN = Path(__file__).resolve().parent / "golden" / "hls"
CONFIGS = ["fpga_dilate_rgba8", "fpga_erode_mono8", "fpga_passthrough_rgb8"]
UPDATE = os.environ.get("ROSFPGA_UPDATE_GOLDEN", "") not in ("", "0")


def _tree(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def _config(stem: str, flavour: str = DEFAULT_HLS_FLAVOUR) -> NodeConfig:
    """A shipped configuration, with ``hls.flavour`` set (its file name unchanged)."""
    return dataclasses.replace(load_config(DATA / f"{stem}.yaml"), hls=HlsConfig(flavour))


def _meta_bits(header: str) -> int:
    """Bits of ``struct image_meta`` in a generated ros_node.h, read from its declarations
    (``ap_uint<N>``, ``byte_t name[N]``; N a number or a #define of the header)."""
    defines = dict(re.findall(r"^#define (\w+) (\d+)", header, re.M))
    body = re.search(r"struct image_meta \{(.*?)\};", header, re.S)
    assert body, "no struct image_meta"
    value = lambda token: int(defines.get(token, token))  # noqa: E731
    bits = 0
    for line in body.group(1).strip().splitlines():
        m = re.fullmatch(r"\s*(?:ap_uint<(\w+)>|byte_t) (\w+)(?:\[(\w+)\])?;", line)
        assert m, f"unexpected member {line!r}"
        bits += (value(m.group(1)) if m.group(1) else 8) * (value(m.group(3)) if m.group(3) else 1)
    return bits


def _check_golden(folder: Path, texts: dict[str, str], default: Path | None = None) -> None:
    """``texts`` equal the golden files in ``folder`` (a file absent there: ``default``'s, when
    given); under ROSFPGA_UPDATE_GOLDEN, write them first (only those differing from
    ``default``'s)."""
    default = default or folder
    if UPDATE:
        for name, text in texts.items():
            own = folder / name
            own.parent.mkdir(parents=True, exist_ok=True)
            if folder != default and (default / name).exists() \
                    and (default / name).read_text(encoding="utf-8") == text:
                own.unlink(missing_ok=True)
            else:
                own.write_text(text, encoding="utf-8")
    problems = []
    for name, text in sorted(texts.items()):
        golden = folder / name if (folder / name).exists() else default / name
        if not golden.exists():
            problems.append(f"{golden} missing (regenerate: see this module's docstring)")
            continue
        expected = golden.read_text(encoding="utf-8")
        if expected != text:
            diff = "".join(difflib.unified_diff(expected.splitlines(True), text.splitlines(True),
                                                f"{golden.relative_to(GOLDEN.parent)}",
                                                f"generated/{name}", n=2))
            problems.append(diff)
    assert not problems, "generated code differs from the golden files:\n" + "\n".join(problems)


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
@pytest.mark.parametrize("stem", CONFIGS)
def test_golden_files(stem: str, flavour: str) -> None:
    texts = render(_config(stem, flavour))
    assert set(texts) == set(TEMPLATE_FILES)
    # The default flavour's files in golden/hls/; another flavour's golden/hls-<flavour>/ holds
    # only the files that differ from the default's (a file absent there equals the default's).
    default = GOLDEN / stem
    folder = default if flavour == DEFAULT_HLS_FLAVOUR else GOLDEN.with_name(f"hls-{flavour}") / stem
    _check_golden(folder, texts, default)


#: The other shipped examples (generic projects), each on both wires.
GENERIC_CONFIGS = ["fpga_laserscan_min", "fpga_laserscan_min_cdr", "fpga_samples_dilate",
                   "fpga_samples_dilate_cdr"]
#: The golden file holding the SHA-256 of a generic project's test frames.
FRAMES_GOLDEN = "tb_frames.sha256"


def _library_copies() -> dict[str, Path]:
    """Files a generic project copies from the library unchanged: project path -> source."""
    from rosfpga_lab.hls.generator import HLS_HEADERS, INCLUDE_DIR
    from rosfpga_lab.rtl.generic import GENERIC_MODULES, GENERIC_VERILOG_DIR, VIDEO_APP
    from rosfpga_lab.rtl.sim import VERILOG_DIR

    copies = {f"hls_include/{h}": INCLUDE_DIR / h for h in HLS_HEADERS}
    copies.update({f"rtl/{m}": GENERIC_VERILOG_DIR / m for m in GENERIC_MODULES})
    copies.update({f"rtl/{m}": VERILOG_DIR / m for m in ("rfl_fifo.v", VIDEO_APP)})
    return copies


@pytest.mark.parametrize("stem", GENERIC_CONFIGS)
def test_golden_files_of_generated_projects(stem: str, tmp_path: Path) -> None:
    """Every file ``rosfpga-lab generate`` writes for the example: rendered ones equal their
    golden files, the test frames their golden SHA-256, copies of the library their sources."""
    from rosfpga_lab.rtl.project import generate_project

    generate_project(load_config(DATA / f"{stem}.yaml"), tmp_path)
    written = {str(p.relative_to(tmp_path)): p.read_bytes()
               for p in sorted(tmp_path.rglob("*")) if p.is_file() and p.name != MANIFEST}
    copies = _library_copies()
    texts, frames = {}, []
    for name, data in written.items():
        if name in copies:
            assert data == copies[name].read_bytes(), f"{name} is not a copy of {copies[name]}"
        elif name.endswith(".bin"):
            frames.append(f"{hashlib.sha256(data).hexdigest()}  {name}\n")
        else:
            texts[name] = data.decode("utf-8")
    assert {"rtl/rfl_layout.vh", "rtl/rfl_node.v", "rtl/rfl_tb.v", "layout.h"} <= set(texts)
    assert len(frames) == 2 and any(n.startswith("rtl/rfl_g") for n in written)
    texts[FRAMES_GOLDEN] = "".join(frames)
    folder = GOLDEN / stem
    if UPDATE:  # a file the generator no longer writes goes too
        for old in folder.rglob("*"):
            if old.is_file() and str(old.relative_to(folder)) not in texts:
                old.unlink()
    _check_golden(folder, texts)
    assert sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()) == \
        sorted(texts), f"{folder} holds files the generator no longer writes (regenerate)"


def test_generation_is_deterministic(tmp_path: Path) -> None:
    config = load_config(DATA / "fpga_erode_mono8.yaml")
    generate(config, tmp_path / "a")
    generate(config, tmp_path / "b")
    a, b = _tree(tmp_path / "a"), _tree(tmp_path / "b")
    assert a == b
    assert len(a) == 16  # 10 rendered + 3 headers (Vitis: no hls_video.h) + input + expected + manifest
    # The same file elsewhere generates the same bytes (only its name appears in the output).
    moved = tmp_path / "elsewhere" / "fpga_erode_mono8.yaml"
    moved.parent.mkdir()
    moved.write_bytes((DATA / "fpga_erode_mono8.yaml").read_bytes())
    generate(load_config(moved), tmp_path / "c")
    assert _tree(tmp_path / "c") == a


def test_generated_code_names_the_configuration() -> None:
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    texts = render(config)
    assert '#define IMG_WIDTH 640' in texts["ros_node.h"]
    assert '"rgba8"' in texts["ros_node.h"]
    assert "#define KSIZE 3" in texts["image_filter.cpp"]  # Vitis HLS: its own window
    assert "md5sum=060021388200f6f0f447d0fcd9c64743" in texts["connection_headers.cpp"]
    assert "topic=/image_raw" in texts["connection_headers.cpp"]
    assert "topic=/image_dilated" in texts["connection_headers.cpp"]
    assert "callerid=/fpga_dilate" in texts["connection_headers.cpp"]
    assert "set part xc7z020clg400-1" in texts["run_hls.tcl"]
    assert "create_clock -period $clock_period" in texts["run_hls.tcl"]
    assert "set clock_period 10" in texts["run_hls.tcl"]
    for top in ("subscriber", "image_filter", "publisher"):
        assert top in texts["run_hls.tcl"]
    assert "-std=c++14 -Wall -Werror" in texts["Makefile"]
    erode = render(load_config(DATA / "fpga_erode_mono8.yaml"))
    assert "#define KSIZE 5" in erode["image_filter.cpp"] and "(u < v) ? u : v" in erode["image_filter.cpp"]
    assert "vitis_hls -f run_hls.tcl" in erode["run_hls.tcl"]
    # The paper's flavour: the HLS video library.
    vivado = render(_config("fpga_dilate_rgba8", "vivado"))
    assert "hls::Dilate(src, dst)" in vivado["image_filter.cpp"]
    assert "vivado_hls -f run_hls.tcl" in vivado["run_hls.tcl"]
    erode = render(_config("fpga_erode_mono8", "vivado"))
    assert "hls::Erode<hls::MORPH_RECT, 1>(src, dst, kernel)" in erode["image_filter.cpp"]
    assert "hls::Window<5, 5, unsigned char>" in erode["image_filter.cpp"]


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
@pytest.mark.parametrize("stem, bpp", [("fpga_dilate_rgba8", 4), ("fpga_erode_mono8", 1),
                                       ("fpga_passthrough_rgb8", 3)])
def test_hls_directives_where_the_hls_tool_needs_them(stem: str, bpp: int, flavour: str) -> None:
    texts = render(_config(stem, flavour))
    sub, pub, app = texts["subscriber.cpp"], texts["publisher.cpp"], texts["image_filter.cpp"]
    for text, ports in ((sub, ("ap_fifo port = in", "axis port = out", "ap_fifo port = meta_out",
                               "ap_fifo port = frame_id_out")),
                        (pub, ("axis port = in", "ap_fifo port = meta_in", "ap_fifo port = frame_id_in",
                               "ap_fifo port = out")),
                        (app, ("axis port = in", "axis port = out"))):
        for port in ports:
            assert f"HLS_PRAGMA(HLS INTERFACE {port})" in text
    # The C++ without its comments (which may say what the other flavour does).
    every = "".join(re.sub(r"//.*", "", text) for name, text in texts.items()
                    if name.endswith((".cpp", ".h")))
    if flavour == "vivado":
        assert "HLS_PRAGMA(HLS DATA_PACK variable = meta_out)" in sub
        assert "HLS_PRAGMA(HLS DATA_PACK variable = meta_in)" in pub
        assert "HLS_PRAGMA(HLS DATAFLOW)" in app and "#include <hls_video.h>" in app
        assert "ap_ctrl_none" not in every
    else:
        # Vitis HLS has neither DATA_PACK nor hls_video.h; its free-running cores need no start.
        assert "HLS_PRAGMA(HLS aggregate variable = meta_out)" in sub
        assert "HLS_PRAGMA(HLS aggregate variable = meta_in)" in pub
        for gone in ("DATA_PACK", "hls_video.h", "hls::Mat", "AXIvideo2Mat", "Mat2AXIvideo", "hls::Window"):
            assert gone not in every, gone
        assert "HLS_PRAGMA(HLS INTERFACE ap_ctrl_none port = return)" in app
        assert "HLS_PRAGMA(HLS INTERFACE ap_ctrl_none port = return)" in pub
        assert "ap_ctrl_none" not in re.sub(r"//.*", "", sub)  # it returns a status (ap_ctrl_hs)
        assert "open_solution -reset solution1 -flow_target vivado" in texts["run_hls.tcl"]
        assert "HLS_PRAGMA(HLS PIPELINE II = 1)" in app
    # Every loop over a variable number of bytes moves one byte per clock.
    for text in (sub, pub):
        lines = text.splitlines()
        for i, line in enumerate(lines):
            if "LOOP_TRIPCOUNT" in line:
                assert "HLS_PRAGMA(HLS PIPELINE II = 1)" in lines[i - 1], lines[i - 2:i + 1]
    # fifo2axi / axi2fifo: one byte per clock on the FIFO side, so one beat per bpp clocks.
    assert sub.count(f"HLS_PRAGMA(HLS PIPELINE II = {bpp})") >= 1
    assert pub.count(f"HLS_PRAGMA(HLS PIPELINE II = {bpp})") >= 1
    # In C simulation the directives vanish (no unknown-pragma warning under -Wall -Werror).
    assert "#define HLS_PRAGMA(x)\n" in texts["ros_node.h"]


def test_regenerating_refuses_then_force_replaces(tmp_path: Path) -> None:
    out = tmp_path / "out"
    generate(load_config(DATA / "fpga_passthrough_rgb8.yaml"), out)
    before = _tree(out)
    with pytest.raises(GenerateError, match="--force"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), out)
    assert _tree(out) == before  # nothing touched
    (out / "notes.txt").write_text("mine")
    (out / "csim_out").mkdir()
    (out / "csim_out" / "output.bin").write_bytes(b"old")
    result = generate(load_config(DATA / "fpga_erode_mono8.yaml"), out, force=True)
    assert "csim_out/" in result.removed and "subscriber.cpp" in result.removed
    assert result.kept == ("notes.txt",)
    assert (out / "notes.txt").read_text() == "mine"
    assert not (out / "csim_out").exists()
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["config"] == "fpga_erode_mono8.yaml"
    on_disk = set(_tree(out)) - {MANIFEST, "notes.txt"}
    assert on_disk == set(manifest["files"])  # no file of the old generation remains
    for name, digest in manifest["files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest
    assert "IMG_ENCODING_LENGTH 5" in (out / "ros_node.h").read_text()  # mono8, not rgb8


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
def test_the_metadata_word_is_narrow(flavour: str) -> None:
    """The subscriber passes the publisher one FIFO word per frame: stamps, frame_id's length and
    is_bigendian (81 bits with frame_id_max 256); frame_id's bytes go on an 8-bit FIFO of their
    own. (Before, the word held frame_id itself: 2,152 bits.)"""
    config = _config("fpga_dilate_rgba8", flavour)
    header = render(config)["ros_node.h"]
    assert _meta_bits(header) == sum(bits for _name, bits in meta_fields(config)) == 81
    assert "one FIFO word per frame, 81 bits of fields" in header
    small = dataclasses.replace(config, frame_id_max=16)
    assert _meta_bits(render(small)["ros_node.h"]) == 32 + 32 + 5 + 8
    assert "depth = FRAME_ID_MAX" in render(config)["ros_fpga_node.cpp"]


def test_meta_width_parser_reads_the_old_wide_word() -> None:
    """The parser above, on the word as it was (frame_id inside): 2,152 bits."""
    old = ("#define FRAME_ID_MAX 256\nstruct image_meta {\n    ap_uint<32> stamp_secs;\n"
           "    ap_uint<32> stamp_nsecs;\n    ap_uint<32> frame_id_length;\n"
           "    byte_t frame_id[FRAME_ID_MAX];\n    ap_uint<8> is_bigendian;\n};\n")
    assert _meta_bits(old) == 2152


def test_hls_flavour_is_a_configuration_key_and_the_readme_names_the_tools() -> None:
    assert set(HLS_TOOLS) == set(HLS_FLAVOURS)
    text = (DATA / "fpga_passthrough_rgb8.yaml").read_text()
    assert parse_config(text).hls.flavour == "vitis"
    assert parse_config(text + "hls: {flavour: vivado}\n").hls.flavour == "vivado"
    with pytest.raises(ConfigError, match=r"hls\.flavour.*one of vitis, vivado.*got 'vitis_hls'"):
        parse_config(text + "hls: {flavour: vitis_hls}\n")
    with pytest.raises(ConfigError, match="unknown key"):
        parse_config(text + "hls: {tool: vitis}\n")
    for flavour in HLS_FLAVOURS:
        readme = render(_config("fpga_passthrough_rgb8", flavour))["README.md"]
        assert f"This project is the `{flavour}` flavour" in readme
        assert HLS_TOOLS[flavour].command in readme
        for tool in HLS_TOOLS.values():  # both flavours and their tool versions, in each README
            assert tool.versions in readme
    assert "Vivado HLS 2016.x to 2019.2" in HLS_TOOLS["vivado"].versions
    assert "Vitis HLS 2020.2 and later" in HLS_TOOLS["vitis"].versions


def test_refuses_foreign_directory_even_with_nothing_generated(tmp_path: Path) -> None:
    (tmp_path / "main.c").write_text("int main(){}")
    with pytest.raises(GenerateError, match="not written by rosfpga-lab"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["main.c"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(GenerateError, match="not a directory"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path / "file")
    with pytest.raises(GenerateError, match="cannot write into .*Not a directory"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path / "file" / "below")


def test_damaged_manifest_is_refused(tmp_path: Path) -> None:
    generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path)
    (tmp_path / MANIFEST).write_text(json.dumps({"files": {"../../etc/passwd": "x"}}))
    with pytest.raises(GenerateError, match="outside the directory"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path, force=True)
    (tmp_path / MANIFEST).write_text("{not json")
    with pytest.raises(GenerateError, match="damaged"):
        generate(load_config(DATA / "fpga_erode_mono8.yaml"), tmp_path, force=True)


def test_cli_generate_and_sloc(tmp_path: Path) -> None:
    out = tmp_path / "proj"
    cmd = [sys.executable, "-m", "rosfpga_lab", "generate", str(DATA / "fpga_dilate_rgba8.yaml"),
           "-o", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "rendering templates" in proc.stderr and "writing 28 files" in proc.stderr  # 15 HLS (Vitis) + 13 RTL (rtl/: + the fast harness, rfl_slice.v)
    assert f"make -C {out} csim" in proc.stdout
    again = subprocess.run(cmd, capture_output=True, text=True)
    assert again.returncode == 1 and "--force" in again.stderr
    forced = subprocess.run(cmd + ["--force", "-q"], capture_output=True, text=True)
    assert forced.returncode == 0 and forced.stdout == "" and forced.stderr == ""
    loud = subprocess.run(cmd + ["--force"], capture_output=True, text=True)
    assert loud.returncode == 0
    assert loud.stderr.index("removed 29 files") < loud.stderr.index("writing 28 files")
    unwritable = subprocess.run(cmd[:-1] + [str(out / "Makefile" / "below")], capture_output=True,
                                text=True)
    assert unwritable.returncode == 1 and "Traceback" not in unwritable.stderr
    assert "error: cannot write into" in unwritable.stderr

    table = subprocess.run([sys.executable, "-m", "rosfpga_lab", "sloc", str(out)],
                           capture_output=True, text=True)
    assert table.returncode == 0, table.stderr
    counts = count_sloc(out)
    lines = table.stdout.splitlines()
    row = {line.split()[0]: line.split()[1:] for line in lines if line.split()[:1] in
           (["subscriber"], ["publisher"], ["total"])}
    verilog = count_verilog(out / "rtl")
    assert row["subscriber"] == [str(counts.subscriber), str(verilog.subscriber), "57", "415"]
    assert row["publisher"] == [str(counts.publisher), str(verilog.publisher), "70", "445"]
    assert row["total"] == [str(counts.total), str(verilog.total), "127", "860"]
    assert counts.total == counts.subscriber + counts.publisher
    missing = subprocess.run([sys.executable, "-m", "rosfpga_lab", "sloc", str(tmp_path)],
                             capture_output=True, text=True)
    assert missing.returncode == 1 and "subscriber.cpp" in missing.stderr


def test_sloc_counts_like_table1() -> None:
    text = (
        "// a comment\n"
        "\n"
        "int a = 1;  // trailing comment\n"
        "/* block\n"
        "   still block */\n"
        "int b = 2; /* inline */ int c = 3;\n"
        "   \t\n"
        "const char* s = \"// not a comment\";\n"
        "const char* t = \"/* nor this */\";\n"
        "char q = '\\'';  /* quote inside a char literal */\n"
        "#pragma HLS PIPELINE II=1\n"
        "/* one */ /* two */\n"
        "}\n"
    )
    assert sloc(text) == 7
    assert PAPER_TABLE1["total"] == (127, 860)
    assert PAPER_TABLE1["subscriber"][0] + PAPER_TABLE1["publisher"][0] == 127


def test_sloc_table_text() -> None:
    from rosfpga_lab.hls.sloc import SlocTable

    text = format_table(SlocTable(100, 40, {"image_filter.cpp": 12}), title="T")
    assert text.splitlines()[0] == "T"
    assert "total" in text and "140" in text and "860" in text and "image_filter.cpp" in text
    with pytest.raises(HlsError):
        count_sloc(ROOT / "no_such_dir")
