"""cocotb testbench of the node in the fabric on the network, ``rfl_fabric_top``
(rosfpga_lab/rtl/fabric/rfl_fabric_top.v; run by tests/rtl/test_fabric_top.py, not by pytest).

The case comes in a JSON file (``FABRIC_TOP_CASE``): the node's and the peer's addresses, the
receive side's configuration, ``cfg_time``, the frames the peer sends on the GMII side (whole,
FCS included, hex; built by the test), the ARP reply it gives when the node asks for its MAC,
how many IPv4 frames must come out and a bound on the clocks. The bench plays the peer
(cocotbext-eth's GMII source and sink: a frame after the previous one and a gap) and writes
every frame the node sent (preamble and FCS included) and the counters (``FABRIC_TOP_OUT``).
It ends 3000 clocks after the IPv4 frames expected came out (more would show), or at the bound.
"""

from __future__ import annotations

import json
import os

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles
from cocotbext.eth import GmiiFrame, GmiiSink, GmiiSource

ETHERTYPE_ARP = b"\x08\x06"
COUNTERS = ("samples", "answers", "no_credit", "rx_packets", "rx_error", "rx_length",
            "rx_overflow", "tx_packets", "tx_overflow", "rx_port", "rx_header", "rx_other")


def _arp_request_for(frame: bytes, ip: bytes) -> bool:
    """Is this Ethernet frame (no preamble) an ARP request for ``ip``?"""
    return frame[12:14] == ETHERTYPE_ARP and frame[20:22] == b"\x00\x01" and frame[38:42] == ip


async def start_top(dut, case: dict) -> tuple[GmiiSource, GmiiSink]:
    """Set the top's registers from ``case``, start its 125 MHz clock and reset it; the peer's
    GMII source and sink (tests/rtl/bench_rfl_fabric_top_wire.py starts the top the same way)."""
    dut.cfg_mac.value = int(case["node_mac"], 16)
    dut.cfg_ip.value = int(case["node_ip"], 16)
    dut.cfg_learn.value = int(case.get("learn", 0))
    dut.cfg_peer_ip.value = int(case["peer_ip"], 16)
    dut.cfg_peer_meta_port.value = case["peer_meta_port"]
    dut.cfg_peer_user_port.value = case["peer_user_port"]
    dut.cfg_reader.value = case["reader"]
    dut.cfg_writer.value = case["writer"]
    dut.cfg_time.value = case["time"]
    dut.send_sedp.value = 0
    dut.gmii_rx_dv.value = 0
    dut.gmii_rx_er.value = 0
    dut.gmii_rxd.value = 0
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    source = GmiiSource(dut.gmii_rxd, dut.gmii_rx_er, dut.gmii_rx_dv, dut.clk)
    sink = GmiiSink(dut.gmii_txd, dut.gmii_tx_er, dut.gmii_tx_en, dut.clk)
    dut.rst_n.value = 0
    await ClockCycles(dut.clk, 10)
    dut.rst_n.value = 1
    return source, sink


@cocotb.test()
async def fabric_top(dut) -> None:
    with open(os.environ["FABRIC_TOP_CASE"]) as f:
        case = json.load(f)
    source, sink = await start_top(dut, case)

    sent: list[str] = []
    ipv4 = [0]
    peer_ip = bytes.fromhex(case["peer_ip"])

    async def peer() -> None:
        while True:
            frame = await sink.recv()
            sent.append(bytes(frame.data).hex())
            ipv4[0] += bytes(frame.get_payload())[12:14] == b"\x08\x00"
            if _arp_request_for(bytes(frame.get_payload()), peer_ip):
                await source.send(GmiiFrame.from_raw_payload(bytes.fromhex(case["arp_reply"])))

    cocotb.start_soon(peer())
    for raw in case["frames"]:
        await source.send(GmiiFrame.from_raw_payload(bytes.fromhex(raw)))
        await source.wait()
        await ClockCycles(dut.clk, case["gap"])
    clocks = 0
    while clocks < case["max_clocks"]:
        if ipv4[0] >= case["expect"]:
            break
        await ClockCycles(dut.clk, 100)
        clocks += 100
    await ClockCycles(dut.clk, 3000)
    counters = {name: int(getattr(dut, f"cnt_{name}").value) for name in COUNTERS}
    with open(os.environ["FABRIC_TOP_OUT"], "w") as f:
        json.dump({"sent": sent, "counters": counters}, f)
