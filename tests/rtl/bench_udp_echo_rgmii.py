"""cocotb testbench of ``udp_echo_rgmii`` (tests/benchmarks: the vendored LiteEth core's RGMII
board variant behind ``rfl_udp_port``), run by tests/rtl/test_fabric_rgmii.py, not by pytest.

The case (JSON, ``RGMII_CASE``): frames (whole, FCS included, hex) and for each the indices of the
bytes (the preamble counted) sent with RGMII's RX_ER (cocotbext-eth's RGMII source: RX_DV on the
rising edge, RX_DV xor RX_ER on the falling edge). Written (``RGMII_OUT``): rfl_udp_port's
counters once the frames are in.
"""

from __future__ import annotations

import json
import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, Timer
from cocotbext.eth import GmiiFrame, RgmiiSource


@cocotb.test()
async def rgmii_rx_error(dut) -> None:
    with open(os.environ["RGMII_CASE"]) as f:
        case = json.load(f)
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    cocotb.start_soon(Clock(dut.eth_clk, 19.2, unit="ns").start())  # LiteEth's core: 52.08 MHz
    await Timer(3, unit="ns")                    # the PHY's clock, another phase
    cocotb.start_soon(Clock(dut.rgmii_rx_clk, 8, unit="ns").start())
    source = RgmiiSource(dut.rgmii_rxd, dut.rgmii_rx_ctl, dut.rgmii_rx_clk)
    await ClockCycles(dut.clk, 200)              # out of reset, LiteEth's FIFOs settled
    for hexed, errors in zip(case["frames"], case["errors"]):
        frame = GmiiFrame.from_payload(bytes.fromhex(hexed)[:-4])  # the source adds the FCS
        frame.error = [0] * len(frame.data)
        for k in errors:
            frame.error[k] = 1
        await source.send(frame)
        await source.wait()
        await ClockCycles(dut.clk, 300)
    counters = {name: int(getattr(dut, f"c_{name}").value) for name in ("rx", "err", "len")}
    with open(os.environ["RGMII_OUT"], "w") as f:
        json.dump(counters, f)
