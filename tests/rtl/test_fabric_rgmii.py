"""RGMII's receive error at the vendored LiteEth core's board variant (issue 31 item 6):
``tests/benchmarks/udp_echo_rgmii.v`` (``liteeth_udp_ecp5_rgmii.v`` behind ``rfl_udp_port``)
under Verilator, its ECP5 cells from ``ecp5_io_models.v`` (the test's own models of Lattice's
DDR cells: Yosys' are black boxes). A peer (cocotbext-eth's RGMII source) sends good UDP
datagrams to the echo's port and one with RX_ER on a payload byte: the generator's receiver must
turn that byte bad so the frame fails its FCS (counted in ``cnt_rx_error``), the others pass.
What it cannot show: the real cells' timing, and a board's PHY (vendor/README.md).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.rtl.test_fabric_udp import NODE_IP, NODE_MAC, _fcs, _udp
from tests.support.rtltools import TB_DIR, cocotb_verilator, run_bench

pytestmark = pytest.mark.rtl

ROOT = Path(__file__).resolve().parents[2]
SOURCES = [ROOT / "rosfpga_lab" / "rtl" / "fabric" / "vendor" / "liteeth_udp_ecp5_rgmii.v",
           Path(__file__).with_name("ecp5_io_models.v"),
           ROOT / "rosfpga_lab" / "rtl" / "fabric" / "rfl_udp_store.v",
           ROOT / "rosfpga_lab" / "rtl" / "fabric" / "rfl_udp_port.v",
           ROOT / "tests" / "benchmarks" / "udp_echo_rgmii.v"]
ECHO_PORT = 7411                                 # udp_echo_rgmii's PORT (its MAC and IP: the
PREAMBLE = 8                                     # UDP test's node's)


@pytest.mark.timeout(600)
def test_an_rgmii_rx_er_byte_fails_its_frame(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    assert (NODE_MAC, NODE_IP) == ("02:52:46:4c:00:02", "192.168.10.2")   # the echo's
    cocotb_verilator(monkeypatch)
    monkeypatch.syspath_prepend(str(TB_DIR))
    from cocotb_tools.runner import get_runner

    frames = [_fcs(_udp(bytes(range(k, k + 100)), dport=ECHO_PORT)) for k in range(4)]
    at = PREAMBLE + 14 + 20 + 8 + 50             # a payload byte of the second frame
    case = {"frames": [f.hex() for f in frames], "errors": [[], [at], [], []]}
    (tmp_path / "case.json").write_text(json.dumps(case))
    runner = get_runner("verilator")
    runner.build(sources=SOURCES, hdl_toplevel="udp_echo_rgmii", build_dir=tmp_path / "build",
                 timescale=("1ns", "1ps"), build_args=["-Wno-fatal", "-Wno-lint", "-Wno-style",
                                                       "-Wno-UNOPTFLAT", "--timing"],
                 log_file=tmp_path / "build.log")
    run_bench(runner, "bench_udp_echo_rgmii", "udp_echo_rgmii", tmp_path / "build", tmp_path,
              {"RGMII_CASE": str(tmp_path / "case.json"),
               "RGMII_OUT": str(tmp_path / "out.json")})
    got = json.loads((tmp_path / "out.json").read_text())
    assert got == {"rx": 3, "err": 1, "len": 0}
