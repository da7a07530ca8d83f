"""The generator: golden files, determinism, the manifest and --force, the CLI, the SLOC table.

Golden files live in ``tests/golden/hls/<config>/`` (the default flavour, Vitis HLS) for every
shipped example: the three Image configurations, LaserScan and the lab's own message on both
wires. Each holds every file ``rosfpga-lab generate`` renders for the configuration (the HLS
C++, ``rtl/`` with the walk ``rfl_layout.vh``, the wrapper ``rfl_node.v`` and the testbench
``rfl_tb.v``) and the SHA-256 of the test frames (``tb_frames.sha256``); the files copied from
the library (``hls_include/``, ``rtl/rfl_fifo.v`` and the generic modules of
``rosfpga_lab/rtl/generic/``) are held equal to their sources instead, so a change to those
needs no new golden file. ``tests/golden/hls-vivado/<config>/`` holds, for ``hls: {flavour:
vivado}``, only the files that differ from the default's. A template change shows up here as a
diff. To accept a change on purpose, regenerate them all (one command) and review the diff
before committing::

    ROSFPGA_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/hls/test_generate.py -k golden
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
from rosfpga_lab.hls.generator import MANIFEST
from rosfpga_lab.hls.generic import GENERIC_FILES, HLS_TOOLS
from rosfpga_lab.hls.sloc import PAPER_TABLE1, sloc
from rosfpga_lab.rtl.sloc import count_verilog, verilog_sloc

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "hls"
CONFIGS = ["fpga_dilate_rgba8", "fpga_erode_mono8", "fpga_passthrough_rgb8"]
UPDATE = os.environ.get("ROSFPGA_UPDATE_GOLDEN", "") not in ("", "0")


def _tree(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def _config(stem: str, flavour: str = DEFAULT_HLS_FLAVOUR) -> NodeConfig:
    """A shipped configuration, with ``hls.flavour`` set (its file name unchanged)."""
    return dataclasses.replace(load_config(DATA / f"{stem}.yaml"), hls=HlsConfig(flavour))


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


@pytest.mark.parametrize("flavour", [f for f in HLS_FLAVOURS if f != DEFAULT_HLS_FLAVOUR])
@pytest.mark.parametrize("stem", CONFIGS)
def test_golden_files_of_another_flavour(stem: str, flavour: str) -> None:
    """Another flavour's golden/hls-<flavour>/ holds only the files that differ from the
    default's (a file absent there equals the default's, golden/hls/)."""
    texts = render(_config(stem, flavour))
    assert set(texts) == set(GENERIC_FILES)
    _check_golden(GOLDEN.with_name(f"hls-{flavour}") / stem, texts, GOLDEN / stem)


#: The other shipped examples, each on both wires.
GENERIC_CONFIGS = ["fpga_laserscan_min", "fpga_laserscan_min_cdr", "fpga_samples_dilate",
                   "fpga_samples_dilate_cdr"]
#: The golden file holding the SHA-256 of a generic project's test frames.
FRAMES_GOLDEN = "tb_frames.sha256"


def _library_copies() -> dict[str, Path]:
    """Files a generic project copies from the library unchanged: project path -> source."""
    from rosfpga_lab.hls.csim import HLS_HEADERS, INCLUDE_DIR
    from rosfpga_lab.hls.rtlbuild import HARNESS_FILES
    from rosfpga_lab.rtl.generic import GENERIC_MODULES, GENERIC_VERILOG_DIR, VIDEO_APP
    from rosfpga_lab.rtl.sim import VERILOG_DIR
    from rosfpga_lab.rtl.tools import HARNESS_DIR

    copies = {f"hls_include/{h}": INCLUDE_DIR / h for h in HLS_HEADERS}
    copies.update({f"rtl/{h}": HARNESS_DIR / h for h in HARNESS_FILES})
    copies.update({f"rtl/{m}": GENERIC_VERILOG_DIR / m for m in GENERIC_MODULES})
    copies.update({f"rtl/{m}": VERILOG_DIR / m for m in ("rfl_fifo.v", VIDEO_APP)})
    return copies


@pytest.mark.parametrize("stem", CONFIGS + GENERIC_CONFIGS)
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
    assert set(GENERIC_FILES) <= set(texts)
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
    assert len(a) == 17  # 11 rendered + 3 headers + input + expected + manifest
    # The same file elsewhere generates the same bytes (only its name appears in the output).
    moved = tmp_path / "elsewhere" / "fpga_erode_mono8.yaml"
    moved.parent.mkdir()
    moved.write_bytes((DATA / "fpga_erode_mono8.yaml").read_bytes())
    generate(load_config(moved), tmp_path / "c")
    assert _tree(tmp_path / "c") == a


def test_generated_code_names_the_configuration() -> None:
    config = load_config(DATA / "fpga_dilate_rgba8.yaml")
    texts = render(config)
    assert "#define IMG_WIDTH 640" in texts["ros_node.h"] and "#define IMG_HEIGHT 480" in texts["ros_node.h"]
    assert "#define KSIZE 3" in texts["stream_filter.cpp"]  # its own window
    assert "md5sum=060021388200f6f0f447d0fcd9c64743" in texts["connection_headers.cpp"]
    assert "topic=/image_raw" in texts["connection_headers.cpp"]
    assert "topic=/image_dilated" in texts["connection_headers.cpp"]
    assert "callerid=/fpga_dilate" in texts["connection_headers.cpp"]
    assert "set part xc7z020clg400-1" in texts["run_hls.tcl"]
    assert "create_clock -period $clock_period" in texts["run_hls.tcl"]
    assert "set clock_period 10" in texts["run_hls.tcl"]
    assert "foreach top {subscriber fifo2axi stream_filter axi2fifo publisher}" in texts["run_hls.tcl"]
    assert "-std=c++14 -Wall -Werror" in texts["Makefile"]
    # the walk names Image's fields; the checks are the configuration's
    assert "header.seq (uint32)" in texts["layout.h"] and "out: message number" in texts["layout.h"]
    assert "encoding (string)" in texts["layout.h"] and "must be b'rgba8'" in texts["layout.h"]
    erode = render(load_config(DATA / "fpga_erode_mono8.yaml"))
    assert "#define KSIZE 5" in erode["stream_filter.cpp"] and "(u < v) ? u : v" in erode["stream_filter.cpp"]
    assert "vitis_hls -f run_hls.tcl" in erode["run_hls.tcl"]
    vivado = render(_config("fpga_dilate_rgba8", "vivado"))
    assert "vivado_hls -f run_hls.tcl" in vivado["run_hls.tcl"]


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
@pytest.mark.parametrize("stem", CONFIGS)
def test_the_flavours_differ_in_the_packing_directive_only(stem: str, flavour: str) -> None:
    """Both flavours are the same C++ but for the directive that packs the metadata word (Vivado
    HLS's DATA_PACK, which Vitis HLS removed; Vitis HLS's aggregate); neither uses the HLS video
    library (hls_video.h, which Vitis HLS no longer ships)."""
    texts = render(_config(stem, flavour))
    other = render(_config(stem, next(f for f in HLS_FLAVOURS if f != flavour)))
    code = {name for name in texts if name.endswith((".cpp", ".h"))}
    differ = {name for name in code if texts[name] != other[name]}
    assert differ == {"subscriber.cpp", "publisher.cpp"}
    pack = HLS_TOOLS[flavour].pack
    assert f"HLS_PRAGMA({pack} variable = meta_out)" in texts["subscriber.cpp"]
    assert f"HLS_PRAGMA({pack} variable = meta_in)" in texts["publisher.cpp"]
    for name in code:  # (the comments may say what the video library did)
        for gone in ("hls_video.h", "hls::Mat", "AXIvideo2Mat", "hls::Window", "DATA_PACK"
                     if flavour == "vitis" else "aggregate"):
            assert gone not in re.sub(r"//.*", "", texts[name]), (name, gone)
    assert "HLS_PRAGMA(HLS INTERFACE ap_ctrl_none port = return)" in texts["stream_filter.cpp"]
    assert "#define HLS_PRAGMA(x)\n" in texts["ros_node.h"]  # C simulation: the directives vanish


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
    assert "must be b'mono8'" in (out / "layout.h").read_text()  # mono8, not rgb8


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
        assert "kept, not retired" in readme and "hls_video.h" in readme
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
    assert "rendering templates" in proc.stderr and "writing 30 files" in proc.stderr  # 16 HLS + 14 RTL (rtl/: the walkers, the walk, the 2-D application, the fast harness)
    assert f"make -C {out} csim" in proc.stdout
    again = subprocess.run(cmd, capture_output=True, text=True)
    assert again.returncode == 1 and "--force" in again.stderr
    forced = subprocess.run(cmd + ["--force", "-q"], capture_output=True, text=True)
    assert forced.returncode == 0 and forced.stdout == "" and forced.stderr == ""
    loud = subprocess.run(cmd + ["--force"], capture_output=True, text=True)
    assert loud.returncode == 0
    assert loud.stderr.index("removed 31 files") < loud.stderr.index("writing 30 files")
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
