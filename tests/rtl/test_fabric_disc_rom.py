"""rtl/fabric/rfl_rtps_disc_rom.v sends the discovery ROM (rosfpga_lab.rtl.discrom) byte for
byte: the SPDP announcement right after reset and every PERIOD clocks, the SEDP and
ros_discovery_info datagrams on each send_sedp request, each whole, TLAST on its last byte and
TDEST its destination, under random backpressure, a beat offered staying offered and unchanged
until taken (tests/rtl/rtps_disc_rom_tb.v under Icarus Verilog; about a second).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from rosfpga_lab.rtl.discrom import ROM_FILE, TABLE_FILE, render_rom, write_rom
from rosfpga_lab.rtl.sim import VERILOG_DIR, find_tool
from tests.support.rtltools import require_iverilog

pytestmark = pytest.mark.rtl
HERE = Path(__file__).resolve().parents[1]
DATA = HERE.parent / "data"
SOURCE = Path(VERILOG_DIR).parent / "fabric" / "rfl_rtps_disc_rom.v"


def simulate(rom, tmp_path: Path, bp: int, seed: int, period: int, sedp_at: tuple[int, int],
             datagrams: int) -> tuple[list[tuple[int, bytes]], str]:
    """The datagrams the module sends (destination, bytes) and the testbench's last words."""
    write_rom(rom, tmp_path)
    params = {"ROM_FILE": f'"{ROM_FILE}"', "TABLE_FILE": f'"{TABLE_FILE}"',
              "ROM_BYTES": len(rom.image()), "MESSAGES": len(rom.messages), "PERIOD": period,
              "BP": bp, "SEED": seed, "SEDP_AT": sedp_at[0], "SEDP_AT2": sedp_at[1],
              "DATAGRAMS": datagrams}
    top = "rtps_disc_rom_tb"
    built = subprocess.run([require_iverilog(), "-g2005", "-Wall", "-s", top, "-o", "tb.vvp",
                            *(f"-P{top}.{k}={v}" for k, v in params.items()),
                            str(HERE / "rtl" / "rtps_disc_rom_tb.v"), str(SOURCE)],
                           cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert built.returncode == 0, built.stdout + built.stderr
    run = subprocess.run([find_tool("vvp") or "vvp", "-n", "tb.vvp"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    out: list[tuple[int, bytes]] = []
    cur, dests = bytearray(), set()
    for line in (tmp_path / "out.txt").read_text().split("\n"):
        if not line:
            continue
        dest, byte, last = line.split()
        cur.append(int(byte, 16))
        dests.add(int(dest))
        if last == "1":
            assert len(dests) == 1, "TDEST changed inside a datagram"
            out.append((dests.pop(), bytes(cur)))
            cur = bytearray()
    assert not cur, "the run ended inside a datagram"
    return out, run.stdout


@pytest.mark.parametrize("bp,seed", [(0, 1), (600, 7)])
def test_the_module_sends_the_rom_whole_under_backpressure(bp: int, seed: int,
                                                           tmp_path: Path) -> None:
    rom = render_rom(DATA / "fpga_samples_dilate_cdr.yaml", domain=5, index=2)
    spdp, sedp, graph = ((m.dest, m.data) for m in rom.messages)
    # send_sedp at clock 10 (while the first SPDP goes: it waits), and at 6000 (the ROM takes
    # ~1500 clocks without backpressure, ~3700 at 600 per mille: the second SPDP is due then)
    got, said = simulate(rom, tmp_path, bp, seed, period=6000, sedp_at=(10, 6000), datagrams=6)
    assert "UNSTABLE" not in said, said
    assert got == [spdp, sedp, graph, spdp, sedp, graph]
    assert [d for d, _ in got] == [0, 1, 2, 0, 1, 2]


def test_announcements_repeat_every_period(tmp_path: Path) -> None:
    """Without a request, only SPDP: one right after reset and one per PERIOD clocks."""
    rom = render_rom(DATA / "fpga_laserscan_min_cdr.yaml")
    got, said = simulate(rom, tmp_path, 0, 3, period=400, sedp_at=(-1, -1), datagrams=3)
    assert got == [(0, rom.message("spdp").data)] * 3
    clocks = int(said.split("clocks")[1])
    # the third ends after two periods and one SPDP's bytes (plus a clock or two to start each)
    assert 2 * 400 + len(rom.message("spdp").data) <= clocks <= 2 * 400 + 2 * 228 + 10, said


def test_the_proof_catches_a_byte_that_moves_while_stalled(tmp_path: Path) -> None:
    """The formal check of rfl_rtps_disc_rom (rtl.proofs: any ROM contents; that it passes is
    tests/rtl/test_formal.py's) fails on a planted bug: the ROM read on every clock of a
    datagram, taken or not."""
    from tests.support.rtltools import require_formal
    from rosfpga_lab.rtl.proofs import FABRIC_DIR, PROOFS, prove

    require_formal()
    proof = next(p for p in PROOFS if p.name == "rtps_disc_rom")
    src = (FABRIC_DIR / "rfl_rtps_disc_rom.v").read_text()
    planted = src.replace("if (start || (take && !last)) begin", "if (start || !last) begin")
    assert planted != src
    (tmp_path / "rfl_rtps_disc_rom.v").write_text(planted)
    bad = prove(proof, replace={"rfl_rtps_disc_rom.v": tmp_path / "rfl_rtps_disc_rom.v"})
    assert bad.status == "FAIL" and any("fv_rtps_disc_rom.sv" in f for f in bad.failed), bad.log
