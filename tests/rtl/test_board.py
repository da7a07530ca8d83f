"""The board build's files (``rtl.board``; ``make bitstream`` itself: test_fabric_bitstream.py):
what ``generate --target fabric`` writes, no tools needed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rosfpga_lab.cli import main
from rosfpga_lab.rtl.board import default_peer

CONFIG = Path(__file__).resolve().parents[2] / "data" / "fpga_laserscan_min_cdr.yaml"


def test_generate_writes_the_board_build(tmp_path: Path) -> None:
    assert main(["generate", str(CONFIG), "-o", str(tmp_path), "-q", "--target", "fabric",
                 "--address", "10.0.0.7", "--mac", "02:00:00:00:00:2a"]) == 0
    index = json.loads((tmp_path / "board" / "parameters.json").read_text())
    p = index["parameters"]
    # no peer at build time: the board learns it from SPDP (RTPS 2.3: the SPDP writer's id,
    # PID_METATRAFFIC_UNICAST_LOCATOR 0x32, PID_DEFAULT_UNICAST_LOCATOR 0x31, UDPv4 kind 1)
    assert not any(k.startswith("PEER") for k in p) and "SEDP_WAIT" not in p
    assert (p["SPDP_WRITER_ID"], p["SPDP_LOCATOR_KIND"]) == ("32'h100c2", "32'h1")
    assert p["SPDP_PIDS"] == "80'h710001000200310032" and p["SPDP_ENCAPS"] == "32'h20003"
    assert (p["IP"], p["MAC"]) == ("32'ha000007", "48'h2000000002a")
    assert index["peer_ip"] == "10.0.0.1"
    assert p["SPDP_GROUP"] == "32'hefff0001" and p["PERIOD"] == "125000000"
    assert p["ROM_FILE"] == '"rfl_rtps_disc_rom.hex"'
    assert (tmp_path / "rfl_rtps_disc_rom.hex").exists()
    make = (tmp_path / "Makefile").read_text()
    assert "--25k --package CABGA256 --speed 6" in make
    assert "--lpf board/rfl_board_5a75b.lpf" in make
    assert "ECPPACK" in make and "board/rfl_board_5a75b.bit" in make
    script = (tmp_path / "board" / "synth.ys").read_text()
    assert "-D RFL_FABRIC_RGMII" in script and "board/node/rfl_node.v" in script
    assert "synth_ecp5 -top rfl_board_5a75b -json board/netlist.json" in script
    lpf = (tmp_path / "board" / "rfl_board_5a75b.lpf").read_text()
    # LiteX-Boards' _io_v8_0: clk25 P6, eth_clocks 0 rx J1
    assert 'LOCATE COMP "clk25" SITE "P6";' in lpf
    assert 'LOCATE COMP "rgmii_rx_clk" SITE "J1";' in lpf
    readme = (tmp_path / "board" / "README.md").read_text()
    assert "No board was available" in readme and "sudo ip addr add 10.0.0.1/24" in readme


def test_default_peer_and_bad_addresses(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert default_peer("192.168.10.2") == "192.168.10.1"
    assert default_peer("192.168.10.1") == "192.168.10.2"
    assert main(["generate", str(CONFIG), "-o", str(tmp_path), "-q", "--target", "fabric",
                 "--mac", "02:00:00:00:2a"]) != 0
    assert "is not six hex pairs" in capsys.readouterr().err
    assert main(["generate", str(CONFIG), "-o", str(tmp_path / "b"), "-q", "--target",
                 "fabric", "--address", "10.0.0.1", "--peer-ip", "10.0.0.1"]) != 0
    assert "is the node's own" in capsys.readouterr().err


def test_the_board_defaults_to_the_tap_link_not_loopback(tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """Without --address the board is on a real link, the one `fabric sim --tap` sets up (the
    node 10.31.0.2, the host 10.31.0.1/24), not loopback, where no frame leaves the host."""
    from rosfpga_lab.component.fabricsim import TAP_HOST_CIDR, TAP_NODE_ADDRESS

    assert main(["generate", str(CONFIG), "-o", str(tmp_path), "-q", "--target", "fabric"]) == 0
    index = json.loads((tmp_path / "board" / "parameters.json").read_text())
    assert (index["ip"], index["peer_ip"]) == (TAP_NODE_ADDRESS, TAP_HOST_CIDR.split("/")[0])
    assert index["parameters"]["IP"] == "32'ha1f0002"        # 10.31.0.2
    readme = (tmp_path / "board" / "README.md").read_text()
    assert f"sudo ip addr add {TAP_HOST_CIDR} dev eth0" in readme and "127.0.0" not in readme
    with pytest.raises(SystemExit):
        main(["generate", "--help"])
    assert f"default {TAP_NODE_ADDRESS}" in " ".join(capsys.readouterr().out.split())
