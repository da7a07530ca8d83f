"""The fast C++ harness (``rosfpga_lab/rtl/harness``) against today's Verilog testbench.

The harness does on Verilator, without ``--timing``, what ``rtl/tb/rfl_tb.v`` does; here both
run the same frames with the same seed, gaps and backpressure, and must give the same output
bytes, the same status per frame, the same first/last clock and count of every stream between
the stages (the cycle counts of ``rtl cycles``), the same total clocks and the same beats into
and out of the application. The testbench runs on Icarus Verilog (quick to build for small
images); both are also checked against the Python models.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from realros import require_rtl
from rosfpga_lab.rtl import RtlError, build, rtl_params, run
from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl.project import generate_project
from rosfpga_lab.rtl.sim import EVAL_MODES, RtlBuild, RtlResult, harness_command, nba_only
from rosfpga_lab.rtl.sim import find_tool as tool
from test_rtl_sim import model_output, random_image, refusal_frames, small_config

pytestmark = pytest.mark.rtl


def assert_same_run(fast: RtlResult, tb: RtlResult) -> None:
    assert fast.output == tb.output
    assert fast.status == tb.status
    assert fast.streams == tb.streams          # every stage's first/last handshake clock
    assert fast.cycles == tb.cycles
    assert fast.input_beats == tb.input_beats and fast.output_beats == tb.output_beats
    assert fast.cut_short == tb.cut_short
    assert fast.framing == tb.framing == 0     # no stage saw a damaged frame (hw.framing)


def mixed_frames(config) -> tuple[list[bytes], list[str]]:
    """Two good frames around one a column too narrow (refused: width)."""
    enc = config.image.encoding
    a, b = random_image(config, 21), random_image(config, 22)
    return ([image_frame(a, enc, frame_id="a"), image_frame(b[:, :-1], enc, frame_id="narrow"),
             image_frame(b, enc, frame_id="b")], ["SUB_OK", "SUB_BAD_WIDTH", "SUB_OK"])


@pytest.mark.parametrize("encoding,gap,bp", [("mono8", 300, 500), ("rgba8", 0, 0)])
def test_harness_equals_the_testbench(encoding: str, gap: int, bp: int, tmp_path: Path) -> None:
    """mono8: every refusal reason, each followed by a good frame, with input gaps and
    backpressure; rgba8: good frames around a refused one at full speed, then cut short.
    (Each case compiles a Verilator model: two cases keep the file near a minute.)"""
    require_rtl("verilator")
    require_rtl("iverilog")
    if encoding == "mono8":
        config = small_config(encoding, frame_id_max=16)
        frames, names = refusal_frames(config)
    else:
        config = small_config(encoding)
        frames, names = mixed_frames(config)
    data = b"".join(frames)
    fast_build = build(rtl_params(config), tmp_path / "fast", simulator="verilator")
    tb_build = build(rtl_params(config), tmp_path / "tb", simulator="iverilog")
    assert fast_build.harness and not tb_build.harness
    fast = run(fast_build, data, seed=29, gap=gap, bp=bp, beats=True)
    tb = run(tb_build, data, seed=29, gap=gap, bp=bp, beats=True)
    assert_same_run(fast, tb)
    expected, verdicts = model_output(config, frames)
    assert fast.output == expected
    assert [s if s == "SUB_OK" else "refused" for _, s in fast.status] == verdicts
    assert [s for _, s in fast.status] == names
    assert fast.cycles > 0 and fast.input_beats is not None and len(fast.input_beats) > 0
    if encoding == "rgba8":   # and when the input ends inside a frame (the circuit waits)
        cut = data + frames[0][: len(frames[0]) // 2]
        fast = run(fast_build, cut, seed=3, gap=200, bp=200, idle_limit=2000)
        tb = run(tb_build, cut, seed=3, gap=200, bp=200, idle_limit=2000)
        assert fast.cut_short and tb.cut_short
        assert_same_run(fast, tb)


def test_make_rtlsim_on_verilator_runs_the_fast_harness(tmp_path: Path) -> None:
    """The generated project's ``make rtlsim`` builds the harness and checks its output."""
    require_rtl("verilator")
    config = small_config("rgb8")
    result = generate_project(config, tmp_path / "proj")
    assert "rtl/rfl_harness.cpp" in result.files and "rtl/rfl_harness.v" in result.files
    proj = tmp_path / "proj"
    verilator = tool("verilator") or tool("verilator-cli")
    proc = subprocess.run(["make", "-s", "rtlsim", "SIM=verilator", f"VERILATOR={verilator}",
                           "GAP=100", "BP=200"], cwd=proj,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "rtlsim: PASS: output equals tb_expected.bin" in proc.stdout
    assert (proj / "rtl" / "obj_fast" / "rfl_fast").exists()
    assert not (proj / "rtl" / "obj_dir").exists()     # the testbench was not built


def test_harness_refuses_testbench_only_options(tmp_path: Path) -> None:
    require_rtl("verilator")
    config = small_config("mono8")
    # the options are checked before anything runs: a build that was never compiled will do
    sim = RtlBuild("verilator", ("false",), tmp_path, rtl_params(config), 0.0, False, True)
    with pytest.raises(RtlError, match="harness=False"):
        run(sim, b"", plusargs=["+clocks_f2a=x.txt"])
    with pytest.raises(RtlError, match="trace=True"):
        run(sim, b"", vcd=tmp_path / "w.vcd")
    with pytest.raises(RtlError, match="Verilator without waveform"):
        build(rtl_params(config), tmp_path / "x", simulator="verilator", trace=True, harness=True)


@pytest.mark.parametrize("mode", EVAL_MODES[1:])
def test_the_eval_fallbacks_equal_the_testbench(tmp_path: Path, mode: str) -> None:
    """By default the harness runs only the model's nonblocking region once per clock (the
    test above holds that to the testbench). Built for a Verilator whose model lacks what
    that calls, it falls back to the model's inner eval of the rising edge ("root") or to
    eval() of both edges ("plain"): each must give the same bytes, statuses, stream spans,
    clocks and beats, with gaps and backpressure."""
    require_rtl("verilator")
    require_rtl("iverilog")
    from rosfpga_lab.rtl.sim import _run_command, harness_command, write_sources

    config = small_config("mono8", frame_id_max=16)
    frames, _ = refusal_frames(config)
    data = b"".join(frames)
    plain_dir = tmp_path / mode
    write_sources(rtl_params(config), plain_dir)
    done = subprocess.run(harness_command(plain_dir, eval_mode=mode), cwd=plain_dir,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    plain = RtlBuild("verilator", _run_command("verilator", plain_dir, True), plain_dir,
                     rtl_params(config), 0.0, False, True)
    tb = build(rtl_params(config), tmp_path / "tb", simulator="iverilog")
    assert_same_run(run(plain, data, seed=6, gap=100, bp=700, beats=True),
                    run(tb, data, seed=6, gap=100, bp=700, beats=True))


def test_the_shipped_design_runs_in_the_nonblocking_region_alone(tmp_path: Path) -> None:
    """The harness registers its inputs, so the Verilated model of the shipped node has no input
    region and no active region: the default build takes the fastest mode, and the check that
    guards it tells a model with such a region apart."""
    require_rtl("verilator")
    built = build(rtl_params(small_config("rgb8")), tmp_path / "fast", simulator="verilator")
    obj_dir = built.directory / "obj_dir"
    assert nba_only(obj_dir)
    assert "-DRFL_EVAL_NBA" in (obj_dir / "Vrfl_harness.mk").read_text()
    other = tmp_path / "other"
    other.mkdir()
    (other / "Vx___024root__0.cpp").write_text(
        "void Vx___024root___eval_ico(Vx___024root* vlSelf) {}\n"
        "void Vx___024root___eval_nba(Vx___024root* vlSelf) {}\n")
    assert not nba_only(other)
    with pytest.raises(RtlError, match="eval_mode must be one of nba, root, plain"):
        harness_command(tmp_path, eval_mode="fast")


def _code_mappings(pid: int) -> list[tuple[str, int]]:
    """(what is mapped, AnonHugePages in kB) per executable mapping of a process."""
    found: list[tuple[str, int]] = []
    code = False                     # the fields that follow belong to an executable mapping
    for line in Path(f"/proc/{pid}/smaps").read_text().splitlines():
        parts = line.split()
        if len(parts) >= 5 and "-" in parts[0] and not parts[0].endswith(":"):
            code = parts[1] == "r-xp"
            if code:
                found.append((parts[5] if len(parts) > 5 else "", 0))
        elif code and line.startswith("AnonHugePages:"):
            found[-1] = (found[-1][0], int(parts[1]))
    return found


def _thp_fallbacks() -> int:
    """How often the kernel gave small pages where a huge page was asked for."""
    for line in Path("/proc/vmstat").read_text().splitlines():
        if line.startswith("thp_fault_fallback "):
            return int(line.split()[1])
    return 0


@pytest.mark.parametrize("huge", [True, False])
def test_the_harness_runs_its_code_from_a_huge_page(tmp_path: Path, huge: bool) -> None:
    """Linux: the harness moves its machine code onto a 2 MiB transparent huge page as it
    starts (an anonymous mapping where the loader had mapped the file); RFL_NO_HUGE_TEXT=1
    leaves it on the file's pages. Either way it serves the same bytes."""
    import os
    import sys
    import time

    require_rtl("verilator")
    if not sys.platform.startswith("linux"):
        pytest.skip("the huge code page is Linux only")
    thp = Path("/sys/kernel/mm/transparent_hugepage/enabled")
    if not thp.exists() or "[never]" in thp.read_text():
        pytest.skip("transparent huge pages are off on this machine")
    config = small_config("rgb8")
    built = build(rtl_params(config), tmp_path / "fast", simulator="verilator")
    env = {**os.environ, "RFL_NO_HUGE_TEXT": "" if huge else "1"}
    fallbacks = _thp_fallbacks()
    proc = subprocess.Popen([*built.command, "--serve"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, env=env)
    try:
        binary = str(Path(built.command[0]).resolve())
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            maps = _code_mappings(proc.pid)
            ours = [m for m in maps if m[0] in ("", binary)]
            if huge and any(kb == 2048 and name == "" for name, kb in ours):
                break
            if not huge and any(name == binary for name, _ in ours):
                break
            time.sleep(0.05)
        if huge:
            assert not any(name == binary for name, _ in ours), maps   # the code was moved
            if _thp_fallbacks() == fallbacks:    # unless the kernel had no huge page to give
                assert any(kb == 2048 and name == "" for name, kb in ours), maps
        else:
            assert any(name == binary for name, _ in ours), maps
    finally:
        proc.stdin.close()    # end of input ends the serve loop
        proc.wait(timeout=30)
    assert proc.returncode == 0
