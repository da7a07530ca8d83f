"""Formal proofs of the stream handshakes (``rosfpga_lab/rtl/formal``, run by ``rtl.proofs``).

Every check of :data:`PROOFS` must pass (``prove``: bounded check plus k-induction, so true in
every reachable state; ``bmc``: true in the first ``depth`` clocks), every module of the circuit
must be covered, and a copy of the FIFO with a planted bug (a word written into an empty FIFO
is lost) must make the FIFO's proof fail: the properties are not vacuous.
"""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor

import pytest

from rosfpga_lab.rtl.proofs import FORMAL_DIR, PROOFS, format_results, prove, sby_text
from rosfpga_lab.rtl.sim import VERILOG_DIR
from rtltools import TB_DIR, require_formal

pytestmark = pytest.mark.rtl


def test_every_module_has_a_proof() -> None:
    modules = {m for p in VERILOG_DIR.glob("*.v")
               for m in re.findall(r"^\s*module\s+(\w+)", p.read_text(), re.M)}
    proven = {f"rfl_{p.name}" for p in PROOFS}
    assert modules == proven
    for p in PROOFS:
        assert (FORMAL_DIR / f"fv_{p.name}.sv").exists()
        assert p.mode in ("prove", "bmc") and p.depth > 0
    # each valid/ready output of a wrapper is checked by the stream rules
    for wrapper in FORMAL_DIR.glob("fv_*.sv"):
        assert "`FV_SINK(" in wrapper.read_text(), wrapper.name


def test_every_proof_passes() -> None:
    """All checks, two at a time (the tools are single-threaded; CI runs this twice)."""
    require_formal()
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(prove, PROOFS))
    table = format_results(results)
    print(table)
    bad = [r for r in results if r.status != "PASS"]
    assert not bad, table + "\n" + "\n".join(r.log[-2000:] for r in bad)
    for r in results:
        if r.proof.mode == "prove":
            assert "successful proof by k-induction" in r.log, r.proof
        else:
            assert f"depth {r.proof.depth}" in sby_text(r.proof, [])


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
    assert "no check named nosuch" in err and "axi2fifo" in err
    assert main(["rtl", "prove", "--only", "axi2fifo"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["check", "mode", "depth", "result", "s", "claim"]
    assert [line.split()[:4] for line in out[1:]] == [["axi2fifo", "prove", "8", "PASS"],
                                                      ["axi2fifo", "bmc", "12", "PASS"]]
