"""The RTL house rules (verilog-axis keeps the same ones), checked on the module files.

* Every ``rfl_*.v`` file opens with ```default_nettype none`` (before its module: a typo in a
  net name is an error, not a new 1-bit wire) and closes with ```default_nettype wire`` (so a
  testbench or a user's file read after it is not affected).
* Stream ports: an AXI4-Stream interface of beats (one with TKEEP or TLAST) is named
  ``s_axis_*`` / ``m_axis_*``; the byte-FIFO side (the TCP/IP stack's 8-bit valid/ready
  stream, and the FIFO and slice that carry any word) is ``s_t*`` / ``m_t*``; no other stream
  prefix; ``s_`` inputs and ``m_`` outputs (TREADY the other way round), each stream with its
  TDATA, TVALID and TREADY.
* Parameter contracts: a module refuses an illegal parameter at elaboration with its message,
  under Verilator and Yosys, and at time 0 under Icarus (``-g2005`` has no elaboration tasks).

FILES is the list of module files the rules cover: the lab's hand modules, the harness and
testbenches, and the generated projects' static modules (``generic/``, with their testbench).
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from rosfpga_lab.rtl.sim import VERILOG_DIR
from tests.support.rtltools import require_iverilog, require_verilator, require_yosys

RTL = Path(VERILOG_DIR).parent
FILES = ["verilog/rfl_*.v", "harness/rfl_*.v", "tb/rfl_*.v", "generic/rfl_*.v",
         "generic/tb/rfl_*.v", "fabric/rfl_*.v", "exhibit/rfl_*.v"]
MODULE_FILES = sorted(p for pattern in FILES for p in RTL.glob(pattern))

_COMMENT = re.compile(r"//.*?$|/\*.*?\*/", re.S | re.M)
_PORT = re.compile(r"\b(input|output|inout)\s+(?:wire\s+|reg\s+)?(?:signed\s+)?(?:\[[^\]]*\]\s*)?"
                   r"(\w+)")
_STREAM = re.compile(r"^(\w*?)t(data|keep|strb|user|last|valid|ready|id|dest)$")


def _code_lines(path: Path) -> list[str]:
    return [ln.strip() for ln in _COMMENT.sub("", path.read_text()).splitlines() if ln.strip()]


def ports(path: Path) -> dict[str, str]:
    """The ANSI port list of the file's module: name -> direction."""
    text = _COMMENT.sub("", path.read_text())
    head = re.search(r"\bmodule\s+\w+\s*(?:#\s*\((?:[^()]|\([^()]*\))*\))?\s*\((.*?)\);", text,
                     re.S)
    if head is None:
        return {}
    return {m.group(2): m.group(1) for m in _PORT.finditer(head.group(1))}


def stream_problems(port_dirs: dict[str, str]) -> list[str]:
    """What breaks the stream naming rule in one port list."""
    streams: dict[str, dict[str, str]] = {}
    for name, direction in port_dirs.items():
        m = _STREAM.match(name)
        if m:
            streams.setdefault(m.group(1), {})[m.group(2)] = direction
    problems = []
    for prefix, sigs in sorted(streams.items()):
        beats = "keep" in sigs or "last" in sigs
        allowed = ("s_axis_", "m_axis_") if beats else ("s_axis_", "m_axis_", "s_", "m_")
        if prefix not in allowed:
            kind = "an AXI4-Stream of beats" if beats else "a stream"
            problems.append(f"{prefix}t{'/'.join(sorted(sigs))}: {kind} is named "
                            f"{' or '.join(a + 't*' for a in allowed)}")
            continue
        sink = prefix.startswith("s_")
        for sig, direction in sigs.items():
            want = ("output" if sig == "ready" else "input") if sink else \
                   ("input" if sig == "ready" else "output")
            if direction != want:
                problems.append(f"{prefix}t{sig} is an {direction}, a {'sink' if sink else 'source'}"
                                f"'s t{sig} is an {want}")
        if not {"data", "valid", "ready"} <= set(sigs):
            problems.append(f"{prefix}t*: no tdata, tvalid and tready")
    return problems


def test_the_rules_cover_every_module_file_in_scope() -> None:
    names = {p.name for p in MODULE_FILES}
    assert {"rfl_fifo.v", "rfl_fifo2axi.v", "rfl_axi2fifo.v", "rfl_slice.v", "rfl_subscriber.v",
            "rfl_publisher.v", "rfl_top.v", "rfl_morph.v", "rfl_harness.v", "rfl_tb.v",
            "rfl_rtps_disc_rom.v", "rfl_rtps_rx.v", "rfl_rtps_to_cdr.v", "rfl_rtps_tx.v",
            "rfl_udp_store.v", "rfl_udp_port.v", "rfl_rtps_ctrl.v", "rfl_rtps_disc_answer.v",
            "rfl_gsubscriber.v", "rfl_gpublisher.v", "rfl_gtop.v", "rfl_elem_pack.v",
            "rfl_elem_unpack.v", "rfl_window1d.v", "rfl_elem_tb.v"} <= names


@pytest.mark.parametrize("path", MODULE_FILES, ids=[p.name for p in MODULE_FILES])
def test_default_nettype_none_and_restored(path: Path) -> None:
    lines = _code_lines(path)
    first = next(ln for ln in lines if not ln.startswith("`timescale"))
    assert first == "`default_nettype none", f"{path.name} starts with {first!r}"
    assert lines[-1] == "`default_nettype wire", f"{path.name} ends with {lines[-1]!r}"
    assert sum(ln.startswith("`default_nettype") for ln in lines) == 2, path.name


@pytest.mark.parametrize("path", MODULE_FILES, ids=[p.name for p in MODULE_FILES])
def test_stream_ports_follow_the_names(path: Path) -> None:
    found = ports(path)
    assert found or path.name in ("rfl_tb.v", "rfl_elem_tb.v", "rfl_fabric_demo_tb.v"), \
        f"no port list parsed in {path.name}"
    assert stream_problems(found) == []


def test_the_port_rule_catches_what_it_should() -> None:
    """The checker itself: the old mixes and wrong directions are found."""
    assert stream_problems({"s_axis_tdata": "input", "s_axis_tvalid": "input",
                            "s_axis_tready": "output", "m_tdata": "output", "m_tvalid": "output",
                            "m_tready": "input"}) == []
    assert stream_problems({"s_tdata": "input", "s_tkeep": "input", "s_tvalid": "input",
                            "s_tready": "output"})          # beats without axis
    assert stream_problems({"in_tdata": "input", "in_tvalid": "input", "in_tready": "output"})
    assert stream_problems({"s_axis_tdata": "input", "s_axis_tvalid": "input",
                            "s_axis_tready": "input"})      # tready the wrong way
    assert ports(RTL / "exhibit" / "rfl_fifo2axi.v")["m_axis_tready"] == "input"


# (module, parameters, message): every contract, each with a value just past its edge
CONTRACTS = [
    ("rfl_fifo", {"DEPTH": 1}, "rfl_fifo: DEPTH must be at least 2 (3 with OUTREG = 1)"),
    ("rfl_fifo", {"DEPTH": 2, "OUTREG": 1},
     "rfl_fifo: DEPTH must be at least 2 (3 with OUTREG = 1)"),
    ("rfl_fifo", {"OUTREG": 2}, "rfl_fifo: OUTREG must be 0 or 1"),
    ("rfl_fifo", {"WIDTH": 0}, "rfl_fifo: WIDTH must be at least 1"),
    ("rfl_slice", {"WIDTH": 0}, "rfl_slice: WIDTH must be at least 1"),
    ("rfl_fifo2axi", {"BYTES": 5},
     "rfl_fifo2axi: BYTES must be 1..4 (one pixel per 32-bit beat)"),
    ("rfl_fifo2axi", {"WIDTH": 65537},
     "rfl_fifo2axi: WIDTH and HEIGHT must be 1..65536 (16-bit counters)"),
    ("rfl_morph", {"KSIZE": 4}, "rfl_morph: KSIZE must be odd and at least 1"),
    ("rfl_morph", {"OP": 3}, "rfl_morph: OP must be 0 (dilate), 1 (erode) or 2 (passthrough)"),
    ("rfl_morph", {"BYTES": 5}, "rfl_morph: BYTES must be 1..4 (one pixel per 32-bit beat)"),
    ("rfl_morph", {"HEIGHT": 0}, "rfl_morph: WIDTH and HEIGHT must be at least 1"),
    ("rfl_subscriber", {"ENC_LEN": 33, "ENCODING_MAX": 40},
     "rfl_subscriber: ENC_LEN must be 1..32 and at most ENCODING_MAX"),
    ("rfl_subscriber", {"ENC_LEN": 5, "ENCODING_MAX": 4},
     "rfl_subscriber: ENC_LEN must be 1..32 and at most ENCODING_MAX"),
    ("rfl_subscriber", {"FRAME_ID_MAX": 16777216},
     "rfl_subscriber: FRAME_ID_MAX must be 1..2**24-1 and ENCODING_MAX below 2**24"),
    ("rfl_subscriber", {"MIN_BODY": 100, "MAX_FRAME": 99},
     "rfl_subscriber: MIN_BODY must be below 2**24 and at most MAX_FRAME"),
    ("rfl_publisher", {"ENC_LEN": 0}, "rfl_publisher: ENC_LEN must be 1..32"),
    ("rfl_publisher", {"FRAME_ID_MAX": 0}, "rfl_publisher: FRAME_ID_MAX must be at least 1"),
    ("rfl_rtps_walk", {"POS_BITS": 17}, "rfl_rtps_walk: POS_BITS must be 1..16"),
    ("rfl_rtps_rx", {"COUNT_BITS": 33}, "rfl_rtps_rx: COUNT_BITS must be 1..32"),
    ("rfl_rtps_disc_rom", {"ROM_BYTES": 65537},
     "rfl_rtps_disc_rom: ROM_BYTES must be 1..65536 (16-bit offsets)"),
    ("rfl_rtps_disc_rom", {"MESSAGES": 0}, "rfl_rtps_disc_rom: MESSAGES must be 1..256"),
    ("rfl_rtps_disc_rom", {"PERIOD": 0}, "rfl_rtps_disc_rom: PERIOD must be at least 1"),
    ("rfl_rtps_disc_rom", {"DEST_BITS": 9}, "rfl_rtps_disc_rom: DEST_BITS must be 1..8"),
    ("rfl_rtps_to_cdr", {"MAX_BYTES": 3}, "rfl_rtps_to_cdr: MAX_BYTES must be 4..2**24"),
    ("rfl_rtps_to_cdr", {"COUNT_BITS": 33}, "rfl_rtps_to_cdr: COUNT_BITS must be 1..32"),
    ("rfl_rtps_tx", {"GUID_PREFIX": 0},
     "rfl_rtps_tx: GUID_PREFIX must be the participant's, not 0"),
    ("rfl_rtps_tx", {"WRITER_ID": 0x204},
     "rfl_rtps_tx: WRITER_ID must be a writer's entity id (kind 0x02/0x03)"),
    ("rfl_rtps_tx", {"READER_ID": 0x203},
     "rfl_rtps_tx: READER_ID must be 0 or a reader's entity id (kind 0x04/0x07)"),
    ("rfl_rtps_tx", {"FRAG_BYTES": 1346},
     "rfl_rtps_tx: FRAG_BYTES must be 4..65532 and a multiple of 4"),
    ("rfl_rtps_tx", {"MAX_DATAGRAM": 1443},
     "rfl_rtps_tx: MAX_DATAGRAM must be at most 65507 and hold a DATA_FRAG's datagram"),
    ("rfl_rtps_tx", {"MAX_SAMPLE": 0}, "rfl_rtps_tx: MAX_SAMPLE must be 1..2**31-1"),
    ("rfl_rtps_tx", {"INFO_TS": 2}, "rfl_rtps_tx: INFO_TS must be 0 or 1"),
    ("rfl_rtps_tx", {"COUNT_BITS": 33}, "rfl_rtps_tx: COUNT_BITS must be 1..32"),
    ("rfl_udp_store", {"ADDR_BITS": 16}, "rfl_udp_store: ADDR_BITS must be 4..15"),
    ("rfl_udp_store", {"ADDR_BITS": 3}, "rfl_udp_store: ADDR_BITS must be 4..15"),
    ("rfl_udp_store", {"QUEUE_BITS": 7}, "rfl_udp_store: QUEUE_BITS must be 1..6"),
    ("rfl_udp_store", {"META_W": 0}, "rfl_udp_store: META_W must be 1..128"),
    ("rfl_udp_store", {"WAIT": 2}, "rfl_udp_store: WAIT must be 0 or 1"),
    # rfl_udp_port needs rfl_udp_store beside it: its contract is tests/rtl/test_fabric_udp.py's
    ("rfl_rtps_ctrl", {"SLOTS": 9}, "rfl_rtps_ctrl: SLOTS must be 1..8"),
    ("rfl_rtps_ctrl", {"COUNT_BITS": 33}, "rfl_rtps_ctrl: COUNT_BITS must be 1..32"),
    ("rfl_rtps_ctrl", {"SLOTS": 1, "SLOT_LASTS": 9}, "rfl_rtps_ctrl: a slot's last must be 0..8"),
    ("rfl_rtps_disc_answer", {"ROM_BYTES": 65537},
     "rfl_rtps_disc_answer: ROM_BYTES must be 1..65536 (16-bit offsets)"),
    ("rfl_rtps_disc_answer", {"MESSAGES": 0}, "rfl_rtps_disc_answer: MESSAGES must be 1..256"),
    ("rfl_rtps_disc_answer", {"COUNT_START": 0},
     "rfl_rtps_disc_answer: COUNT_START must be at least 1"),
    ("rfl_rtps_disc_answer", {"BURST": 65536}, "rfl_rtps_disc_answer: BURST must be 1..65535"),
    ("rfl_rtps_disc_answer", {"RATE": 256}, "rfl_rtps_disc_answer: RATE must be 0..255"),
    ("rfl_rtps_disc_answer", {"DEST_BITS": 9}, "rfl_rtps_disc_answer: DEST_BITS must be 1..8"),
    ("rfl_rtps_disc_answer", {"COUNT_BITS": 33},
     "rfl_rtps_disc_answer: COUNT_BITS must be 1..32"),
    # the generated projects' element modules (the walkers and rfl_gtop need a project's
    # rfl_layout.vh: their contracts are elaborated in hls/test_generic_project.py's lint)
    ("rfl_elem_pack", {"EBYTES": 9}, "rfl_elem_pack: EBYTES must be 1..8"),
    ("rfl_elem_pack", {"LENGTH": 6, "LINE": 4},
     "rfl_elem_pack: LINE must be at least 1 and divide LENGTH"),
    ("rfl_elem_unpack", {"EBYTES": 9}, "rfl_elem_unpack: EBYTES must be 1..8"),
    ("rfl_window1d", {"KSIZE": 4}, "rfl_window1d: KSIZE must be odd, 1..15"),
    ("rfl_window1d", {"EBYTES": 3}, "rfl_window1d: EBYTES must be 1, 2, 4 or 8"),
    ("rfl_window1d", {"KIND": 3}, "rfl_window1d: KIND must be 0 (unsigned), 1 (signed) or 2 (float)"),
]
# Icarus cannot elaborate these at all (a part select [-1:0] before the check runs): refused,
# though with its own message
ICARUS_ELABORATION_FAILS = {("rfl_morph", "HEIGHT"), ("rfl_udp_store", "META_W")}
_IDS = [f"{m}-{'-'.join(f'{k}{v}' for k, v in p.items())}" for m, p, _ in CONTRACTS]


def _source(module: str) -> str:
    for folder in (Path(VERILOG_DIR), RTL / "generic", RTL / "fabric", RTL / "exhibit"):
        path = folder / f"{module}.v"
        if path.exists():
            return str(path)
    raise FileNotFoundError(f"no Verilog file for module {module}")


def _sources(module: str) -> list[str]:
    """The module's file and the ones it instantiates (a receiving stage's walk)."""
    from rosfpga_lab.rtl.proofs import FABRIC_DIR, RTPS_CTRL, RTPS_RX, SPDP_PEER

    stages = {"rfl_rtps_rx": RTPS_RX, "rfl_rtps_ctrl": RTPS_CTRL, "rfl_spdp_peer": SPDP_PEER}
    if module in stages:
        return [str(FABRIC_DIR / name) for name in stages[module]]
    return [_source(module)]


@pytest.mark.rtl
@pytest.mark.parametrize("module,params,message", CONTRACTS, ids=_IDS)
def test_verilator_refuses_an_illegal_parameter(module: str, params: dict[str, int],
                                               message: str, tmp_path: Path) -> None:
    verilator = require_verilator()
    sets = [f"-G{k}={v}" for k, v in params.items()]
    done = subprocess.run([verilator, "--lint-only", f"-I{Path(_source(module)).parent}", "--top-module", module,
                           *sets, *_sources(module)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode != 0 and "USERERROR" in done.stderr and message in done.stderr, \
        done.stderr[-3000:]


@pytest.mark.rtl
@pytest.mark.parametrize("module,params,message", CONTRACTS, ids=_IDS)
def test_icarus_refuses_an_illegal_parameter(module: str, params: dict[str, int],
                                             message: str, tmp_path: Path) -> None:
    iverilog = require_iverilog()
    sets = [f"-P{module}.{k}={v}" for k, v in params.items()]
    done = subprocess.run([iverilog, "-g2005", f"-I{Path(_source(module)).parent}", "-s", module, *sets, "-o",
                           "m.vvp", *_sources(module)], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    if any((module, k) in ICARUS_ELABORATION_FAILS for k in params):
        assert done.returncode != 0 and "error" in done.stderr, done.stdout + done.stderr
        return
    assert done.returncode == 0, done.stdout + done.stderr
    run = subprocess.run(["vvp", "-n", "m.vvp"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode != 0 and "FATAL" in run.stdout + run.stderr, run.stdout + run.stderr
    assert message in run.stdout + run.stderr


@pytest.mark.rtl
@pytest.mark.parametrize("module,params,message", CONTRACTS, ids=_IDS)
def test_yosys_refuses_an_illegal_parameter(module: str, params: dict[str, int],
                                            message: str, tmp_path: Path) -> None:
    require_yosys()
    from rosfpga_lab.rtl.synth import yosys_command

    yosys = yosys_command()
    assert yosys is not None
    sets = " ".join(f"-chparam {k} {v}" for k, v in params.items())
    (tmp_path / "m.ys").write_text(f"read_verilog -defer -I{Path(_source(module)).parent} "
                                   f"{' '.join(_sources(module))}\n"
                                   f"hierarchy -check -top {module} {sets}\n")
    done = subprocess.run([*yosys, "-q", "m.ys"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode != 0 and message in done.stdout + done.stderr, \
        (done.stdout + done.stderr)[-3000:]


@pytest.mark.rtl
@pytest.mark.parametrize("module", sorted({m for m, _, _ in CONTRACTS}))
def test_legal_defaults_pass_every_contract(module: str, tmp_path: Path) -> None:
    """The defaults (and the edge values the shipped tops use) elaborate in all three."""
    verilator = require_verilator()
    done = subprocess.run([verilator, "--lint-only", "-Wno-fatal", f"-I{Path(_source(module)).parent}",
                           "--top-module", module, *_sources(module)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "USERERROR" not in done.stderr, done.stderr[-3000:]
    iverilog = require_iverilog()
    done = subprocess.run([iverilog, "-g2005", f"-I{Path(_source(module)).parent}", "-s", module, "-o", "m.vvp",
                           *_sources(module)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    run = subprocess.run(["vvp", "-n", "m.vvp"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0 and "FATAL" not in run.stdout + run.stderr, run.stdout


@pytest.mark.rtl
def test_fifo_edge_depths_are_legal(tmp_path: Path) -> None:
    """DEPTH 2 (and 3 with OUTREG) is the smallest FIFO: accepted."""
    verilator = require_verilator()
    for sets in (["-GDEPTH=2"], ["-GDEPTH=3", "-GOUTREG=1"]):
        done = subprocess.run([verilator, "--lint-only", "-Wno-fatal", "--top-module", "rfl_fifo",
                               *sets, _source("rfl_fifo")], cwd=tmp_path, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == 0 and "USERERROR" not in done.stderr, done.stderr[-3000:]


def test_the_exhibits_node_wrapper_follows_the_rules(tmp_path: Path) -> None:
    """The exhibit's rfl_node.v (``rtl.exhibit.params.node_wrapper``) too."""
    from rosfpga_lab.rtl.exhibit.params import node_wrapper, rtl_params
    from tests.rtl.test_sim import small_config

    path = tmp_path / "rfl_node.v"
    path.write_text(node_wrapper(rtl_params(small_config("rgba8", width=5, height=3))))
    lines = _code_lines(path)
    assert lines[0] == "`default_nettype none" and lines[-1] == "`default_nettype wire"
    assert stream_problems(ports(path)) == []


# (module, parameters, message) of the modules that read a generated project's rfl_layout.vh
GENERATED_CONTRACTS = [
    ("rfl_gtop", {"LENGTH": 16, "OUT_DEPTH": 17},
     "rfl_gtop: OUT_DEPTH must be at least LENGTH + 2 (a whole stream; EARLY: 2)"),
    ("rfl_gsubscriber", {"CARRY_BYTES": 65, "CW": 6},
     "rfl_gsubscriber: CARRY_BYTES must be at least 1 and at most 2**CW (CW 1..16)"),
    ("rfl_gsubscriber", {"MIN_BODY": 100, "MAX_FRAME": 99},
     "rfl_gsubscriber: MIN_BODY must be at most MAX_FRAME"),
    ("rfl_gsubscriber", {"EARLY": 5},
     "rfl_gsubscriber: EARLY must be the walk's STREAM_EARLY (rfl_layout.vh)"),
]


@pytest.mark.rtl
def test_a_generated_projects_modules_refuse_an_illegal_parameter(tmp_path: Path) -> None:
    """The walkers and rfl_gtop, with a generated project's rfl_layout.vh (lab_msgs/Samples):
    Verilator refuses each illegal value at elaboration with its message, and takes the
    project's own parameters."""
    verilator = require_verilator()
    from rosfpga_lab.config import load_config
    from rosfpga_lab.hls.generic import spec_from_config
    from rosfpga_lab.rtl.generic import generic_rtl_files

    data = RTL.parent.parent / "data"
    for name, text in generic_rtl_files(spec_from_config(
            load_config(data / "fpga_samples_dilate.yaml"))).items():
        (tmp_path / name).write_bytes(text)
    sources = sorted(p.name for p in tmp_path.glob("*.v") if p.name != "rfl_tb.v")

    def lint(top: str, params: dict[str, int]) -> subprocess.CompletedProcess[str]:
        return subprocess.run([verilator, "--lint-only", "-I.", "--top-module", top,
                               *(f"-G{k}={v}" for k, v in params.items()), *sources],
                              cwd=tmp_path, capture_output=True, text=True, timeout=120)

    done = lint("rfl_node", {})
    assert done.returncode == 0 and "USERERROR" not in done.stderr, done.stderr[-3000:]
    for module, params, message in GENERATED_CONTRACTS:
        done = lint(module, params)
        assert done.returncode != 0 and "USERERROR" in done.stderr and message in done.stderr, \
            (module, params, done.stderr[-3000:])
