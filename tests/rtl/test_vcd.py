"""The VCD reader: a real dump of ``rfl_morph`` made by Icarus Verilog, and synthetic dumps
checked against a plain line-by-line reference reader."""

from __future__ import annotations

import random
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from rosfpga_lab.errors import LabError
from rosfpga_lab.rtl import vcd
from rosfpga_lab.rtl.errors import VcdError
from rosfpga_lab.rtl.vcd import read_vcd

from tests.support.rtltools import TB_DIR, VERILOG_DIR, cxx_compiler, require_iverilog, tool

WIDTH, HEIGHT, CLOCKS = 5, 3, 80


@pytest.fixture(scope="module")
def dump(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray]:
    """``(morph.vcd, image)``: a 5x3 rgba8 frame dilated by rfl_morph under iverilog."""
    iverilog = require_iverilog()
    work = tmp_path_factory.mktemp("vcd")
    rng = np.random.default_rng(7)
    image = rng.integers(0, 256, (HEIGHT, WIDTH, 4), dtype=np.uint8)
    words = image.reshape(-1, 4).copy().view("<u4").reshape(-1)
    (work / "pixels.hex").write_text("".join(f"{int(w):08x}\n" for w in words))
    subprocess.run([iverilog, "-g2005", "-o", str(work / "tb.vvp"),
                    str(TB_DIR / "morph_vcd_tb.v"), str(VERILOG_DIR / "rfl_morph.v")],
                   check=True, capture_output=True, timeout=120)
    subprocess.run([tool("vvp"), "-n", str(work / "tb.vvp")], cwd=work, check=True,
                   capture_output=True, timeout=120)
    return work / "morph.vcd", image


def test_real_dump_gives_the_frame_clock_by_clock(dump: tuple[Path, np.ndarray]) -> None:
    path, image = dump
    wave = read_vcd(path, clock="aclk")
    assert wave.clock == "morph_vcd_tb.aclk"
    assert wave.cycles == CLOCKS                       # the testbench stops after CLOCKS edges
    assert wave.timescale == pytest.approx(1e-12) and wave.timescale_text == "1ps"
    assert wave.period == pytest.approx(10e-9)
    assert np.array_equal(np.diff(wave.times), np.full(CLOCKS - 1, 10_000))
    assert "morph_vcd_tb.dut.m_axis_tdata" in wave.signals
    assert wave.width("dut.m_axis_tdata") == 32 and wave.width("dut.hmask1") == 3

    # the output stream, read off the waveform at the clocks where a handshake happened
    fire = (wave.values("dut.m_axis_tvalid") == 1) & (wave.values("dut.m_axis_tready") == 1)
    tdata = wave.values("dut.m_axis_tdata")[fire]
    tuser = wave.values("dut.m_axis_tuser")[fire]
    tlast = wave.values("dut.m_axis_tlast")[fire]
    assert tdata.dtype == np.uint64 and len(tdata) == WIDTH * HEIGHT
    expected = cv2.dilate(image, np.ones((3, 3), np.uint8)).reshape(-1, 4).copy().view("<u4")
    assert tdata.tolist() == expected.reshape(-1).tolist()
    assert tuser.tolist() == [1] + [0] * (WIDTH * HEIGHT - 1)
    assert tlast.tolist() == ([0] * (WIDTH - 1) + [1]) * HEIGHT

    # the input stream the same way: the pixels went in once each, in order
    take = (wave.values("dut.s_axis_tvalid") == 1) & (wave.values("dut.s_axis_tready") == 1)
    assert wave.values("dut.s_axis_tdata")[take].tolist() == \
        image.reshape(-1, 4).copy().view("<u4").reshape(-1).tolist()

    # x before reset: registers are unknown until the reset edge has passed
    unknown = wave.unknown("dut.m_axis_tvalid")
    assert unknown[0] and not unknown[5:].any()
    assert wave.unknown("dut.sr")[0]                    # a 96-bit bus of x
    # the testbench's clock counter, an integer variable, counts the edges
    assert wave.values("morph_vcd_tb.clock").tolist() == list(range(CLOCKS))


def test_filtering_signals_and_small_chunks_read_the_same(
        dump: tuple[Path, np.ndarray], monkeypatch: pytest.MonkeyPatch) -> None:
    path, _ = dump
    whole = read_vcd(path)
    few = read_vcd(path, signals=["dut.m_axis_tdata", "dut.hext"])
    assert set(few.signals) == {"morph_vcd_tb.aclk", "morph_vcd_tb.dut.aclk",
                                "morph_vcd_tb.dut.m_axis_tdata", "morph_vcd_tb.dut.hext"}
    monkeypatch.setattr(vcd, "CHUNK_BYTES", 7)
    tiny = read_vcd(path.read_bytes())
    for name in ("dut.m_axis_tdata", "dut.hext", "dut.sr", "dut.m_axis_tlast"):
        assert np.array_equal(whole.values(name), tiny.values(name))
        assert np.array_equal(whole.unknown(name), tiny.unknown(name))
    assert np.array_equal(whole.values("dut.m_axis_tdata"), few.values("dut.m_axis_tdata"))
    assert isinstance(whole.values("dut.sr")[-1], int)          # wider than 64 bits


def test_names_resolve_by_unique_suffix(dump: tuple[Path, np.ndarray]) -> None:
    wave = read_vcd(dump[0])
    assert wave.resolve("m_axis_tuser") == "morph_vcd_tb.dut.m_axis_tuser"
    with pytest.raises(VcdError, match="ambiguous"):
        wave.resolve("aclk")                            # tb.aclk and tb.dut.aclk
    with pytest.raises(VcdError, match="no signal 'nothing'"):
        wave.values("nothing")


def _reference(text: str, clock: str) -> tuple[int, dict[str, list[int]]]:
    """A plain reader: whole text, line by line, value of every signal before each rise."""
    codes: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while not lines[i].startswith("$enddefinitions"):
        part = lines[i].split()
        if part and part[0] == "$var":
            codes[part[4]] = part[3]
        i += 1
    value = {code: 0 for code in codes.values()}
    samples: dict[str, list[int]] = {name: [] for name in codes}
    changes: list[tuple[str, int]] = []
    clk = codes[clock]
    for line in lines[i + 1:] + ["#999999999"]:
        if line.startswith("#"):
            new = dict(value)
            for code, v in changes:
                new[code] = v
            if value[clk] == 0 and new[clk] == 1:
                for name, code in codes.items():
                    samples[name].append(value[code])
            value, changes = new, []
        elif line.startswith("b"):
            bits, code = line[1:].split()
            changes.append((code, int(bits, 2)))
        elif line and line[0] in "01":
            changes.append((line[1:], int(line[0])))
    return len(samples[clock]), samples


def test_synthetic_dump_matches_a_plain_reader() -> None:
    rng = random.Random(3)
    widths = {"clk": 1, "a": 1, "bus": 12, "wide": 70}
    codes = {"clk": "!", "a": '"', "bus": "#", "wide": "%"}
    lines = ["$timescale 10ns $end", "$scope module top $end"]
    lines += [f"$var wire {widths[n]} {codes[n]} {n} $end" for n in widths]
    lines += ["$upscope $end", "$enddefinitions $end", "#0", "$dumpvars", "0!", "0\"",
              "b0 #", "b0 %", "$end"]
    clk, t = 0, 0
    for _ in range(3000):
        t += rng.choice([1, 2, 5])
        lines.append(f"#{t}")
        changes = []
        if rng.random() < 0.5:
            clk ^= 1
            changes.append(f"{clk}!")
        for name in ("a", "bus", "wide"):
            if rng.random() < 0.4:
                v = rng.getrandbits(widths[name])
                changes.append(f"{v}{codes[name]}" if widths[name] == 1
                               else f"b{v:b} {codes[name]}")
        rng.shuffle(changes)                  # a value may come before or after the clock's
        lines += changes
    text = "\n".join(lines) + "\n"
    cycles, ref = _reference(text, "clk")
    wave = read_vcd(text.encode(), clock="clk")
    assert wave.cycles == cycles > 500
    assert wave.timescale == pytest.approx(1e-8)
    for name in ("a", "bus", "wide"):
        assert [int(v) for v in wave.values(name)] == ref[name], name


def test_x_and_z_bits_read_as_zero_and_unknown() -> None:
    text = b"""$timescale 1ns $end $scope module t $end $var wire 1 ! c $end
$var wire 4 " d [3:0] $end $upscope $end $enddefinitions $end
#0 0! bx1z1 "
#5 1!
#10 0! b101 "
#15 1!
#20 0! z"
"""
    wave = read_vcd(text, clock="c")
    assert wave.cycles == 2
    assert wave.values("d").tolist() == [0b0101, 0b0101]
    assert wave.unknown("d").tolist() == [True, False]


@pytest.mark.parametrize("data,message", [
    (b"hello world", "no \\$enddefinitions"),
    (b"", "no \\$enddefinitions"),
    (b"$timescale 3ns $end $enddefinitions $end", "timescale"),
    (b"$var wire 1 ! c $end $enddefinitions $end #0 1! q", "unexpected 'q'"),
    (b"$var wire 1 ! c $end $enddefinitions $end", "no signal 'aclk'"),
    (b"$var wire 2 ! c $end $enddefinitions $end", "not one bit"),
    (b"$var wire 1 ! c $end $enddefinitions $end #x", "bad timestamp"),
])
def test_bad_dumps_are_refused_with_a_typed_error(data: bytes, message: str) -> None:
    clock = "aclk" if b"#0 1! q" not in data and b"2 ! c" not in data and \
        b"#x" not in data else "c"
    with pytest.raises(VcdError, match=message) as info:
        read_vcd(data, clock=clock)
    assert isinstance(info.value, LabError)


def test_missing_file_is_a_typed_error(tmp_path: Path) -> None:
    with pytest.raises(VcdError, match="cannot read"):
        read_vcd(tmp_path / "none.vcd")


def test_a_bad_value_is_reported_when_its_signal_is_read() -> None:
    text = b"$var wire 1 ! c $end $var wire 4 # d $end $enddefinitions $end #0 0! b12 # #5 1!"
    wave = read_vcd(text, clock="c")
    assert wave.values("c").tolist() == [0]
    with pytest.raises(VcdError, match="bad value b'b12' for d"):
        wave.values("d")


@pytest.mark.parametrize("simulator", ["iverilog", pytest.param("verilator",
                                                                 marks=pytest.mark.slow)])
def test_whole_path_dump_gives_the_output_bytes(simulator: str, tmp_path: Path) -> None:
    """The dump of the whole circuit (rtl.sim, either simulator): the bytes read off the
    output stream's handshakes equal the bytes the testbench wrote, the clocks are the run's."""
    import dataclasses

    from tests.support.realros import skip_or_fail
    from rosfpga_lab.hls import sample_frames
    from rosfpga_lab.rtl import build, design_from_config, run, simulator_missing_reason

    reason = simulator_missing_reason(simulator)
    if simulator == "verilator" and not reason and cxx_compiler() is None:
        reason = "no C++ compiler for Verilator's model (apt-get install g++)"
    if reason:
        if simulator == "iverilog":
            skip_or_fail(reason, "ROSFPGA_REQUIRE_RTL")
        pytest.skip(reason)
    from rosfpga_lab.config import load_config

    config = load_config(Path(__file__).resolve().parents[2] / "data" /
                         "fpga_erode_mono8.yaml")
    config = dataclasses.replace(config, image=dataclasses.replace(config.image, width=12,
                                                                   height=6))
    frames, _ = sample_frames(config)
    sim = build(design_from_config(config), tmp_path / "build", simulator=simulator, trace=True)
    result = run(sim, frames, gap=200, bp=300, vcd=tmp_path / "wave.vcd")
    wave = read_vcd(tmp_path / "wave.vcd", clock="u_top.clk")
    fire = (wave.values("u_top.tx_tvalid") == 1) & (wave.values("u_top.tx_tready") == 1)
    assert bytes(wave.values("u_top.tx_tdata")[fire].astype(np.uint8)) == result.output
    assert len(result.output) > 12 * 6
    assert abs(wave.cycles - result.cycles) <= 8
