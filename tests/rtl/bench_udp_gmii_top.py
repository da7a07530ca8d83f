"""cocotb testbench of ``udp_gmii_top`` (run by tests/rtl/test_fabric_udp.py, not pytest).

The case comes in a JSON file (``UDP_CASE``): the node's addresses, ports and multicast group,
the frames a peer sends on the GMII side (whole, FCS included, hex; built by the test with
scapy), the payloads the lab side sends, the ARP reply the peer gives when the node asks for
its MAC, per-mille input gaps and output backpressure. The bench plays the peer (cocotbext-eth's
GMII source and sink) and the lab side (the AXI4-Stream ports, byte by byte, with random gaps
and backpressure), and writes what came out (``UDP_OUT``): the payloads received with their
sideband, every frame the node sent (preamble and FCS included), the counters. The test checks
them; the bench checks only the stream rules (a valid beat held until taken, the sideband
constant over a packet).
"""

from __future__ import annotations

import json
import os
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, ReadOnly, RisingEdge
from cocotbext.eth import GmiiFrame, GmiiSink, GmiiSource

ETHERTYPE_ARP = b"\x08\x06"


def _arp_request_for(frame: bytes, ip: bytes) -> bool:
    """Is this Ethernet frame (no preamble) an ARP request for ``ip``?"""
    return frame[12:14] == ETHERTYPE_ARP and frame[20:22] == b"\x00\x01" and frame[38:42] == ip


async def _collect(dut, prng: random.Random, bp: float, got: list[dict]) -> None:
    """The lab side's receiver: every packet out of m_axis with its sideband."""
    cur: dict | None = None
    held = None
    while True:
        ready = prng.random() >= bp
        dut.m_axis_tready.value = int(ready)
        await ReadOnly()
        beat = None
        if int(dut.m_axis_tvalid.value):
            beat = (int(dut.m_axis_tdata.value), int(dut.m_axis_tlast.value),
                    int(dut.m_udp_ip.value), int(dut.m_udp_src_port.value),
                    int(dut.m_udp_dst_port.value), int(dut.m_udp_length.value))
        if held is not None:
            assert beat == held, "a valid beat changed before it was taken"
        held = beat if beat is not None and not ready else None
        if beat is not None and ready:
            if cur is None:
                cur = {"data": bytearray(), "meta": beat[2:]}
            assert beat[2:] == cur["meta"], "the sideband changed within a packet"
            cur["data"].append(beat[0])
            if beat[1]:
                ip, sport, dport, length = cur["meta"]
                got.append({"data": cur["data"].hex(), "ip": ip, "sport": sport,
                            "dport": dport, "length": length})
                cur = None
        await RisingEdge(dut.clk)


async def _send_payloads(dut, prng: random.Random, gap: float, sends: list[dict]) -> None:
    """The lab side's sender: each payload byte by byte, its sideband held over the packet."""
    for item in sends:
        data = bytes.fromhex(item["data"])
        dut.s_udp_ip.value = item["ip"]
        dut.s_udp_src_port.value = item["sport"]
        dut.s_udp_dst_port.value = item["dport"]
        i = 0
        while i < len(data):
            offer = prng.random() >= gap
            dut.s_axis_tvalid.value = int(offer)
            dut.s_axis_tdata.value = data[i] if offer else prng.getrandbits(8)
            dut.s_axis_tlast.value = int(i == len(data) - 1) if offer else prng.getrandbits(1)
            await ReadOnly()
            took = offer and int(dut.s_axis_tready.value)
            await RisingEdge(dut.clk)
            i += int(took)
        dut.s_axis_tvalid.value = 0
        await ClockCycles(dut.clk, prng.randint(0, 40))


@cocotb.test()
async def udp_gmii(dut) -> None:
    with open(os.environ["UDP_CASE"]) as f:
        case = json.load(f)
    prng = random.Random(case["seed"])
    gap, bp = case["gap"] / 1000, case["bp"] / 1000
    dut.cfg_mac.value = int(case["node_mac"], 16)
    dut.cfg_ip.value = int(case["node_ip"], 16)
    dut.cfg_port.value = case["node_port"]
    dut.cfg_port_mask.value = case["port_mask"]
    dut.cfg_mcast.value = int(case["group"], 16)
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 0
    dut.gmii_rx_dv.value = 0
    dut.gmii_rx_er.value = 0
    dut.gmii_rxd.value = 0
    cocotb.start_soon(Clock(dut.clk, 8, unit="ns").start())
    source = GmiiSource(dut.gmii_rxd, dut.gmii_rx_er, dut.gmii_rx_dv, dut.clk)
    sink = GmiiSink(dut.gmii_txd, dut.gmii_tx_er, dut.gmii_tx_en, dut.clk)
    dut.rst_n.value = 0
    await ClockCycles(dut.clk, 10)
    dut.rst_n.value = 1
    await ClockCycles(dut.clk, 10)

    got: list[dict] = []
    cocotb.start_soon(_collect(dut, prng, bp, got))
    sent: list[str] = []
    peer_ip = bytes.fromhex(case["peer_ip"])

    async def peer() -> None:
        while True:
            frame = await sink.recv()
            sent.append(bytes(frame.data).hex())
            if _arp_request_for(bytes(frame.get_payload()), peer_ip):
                await source.send(GmiiFrame.from_raw_payload(bytes.fromhex(case["arp_reply"])))

    cocotb.start_soon(peer())

    # the peer's frames, with random gaps (beyond the 12-byte inter-frame gap)
    for raw in case["frames"]:
        await source.send(GmiiFrame.from_raw_payload(bytes.fromhex(raw)))
        await source.wait()
        if prng.random() < gap * 2:
            await ClockCycles(dut.clk, prng.randint(1, 300))
    await ClockCycles(dut.clk, 3000)

    # the lab side's payloads out, through ARP
    await _send_payloads(dut, prng, gap, case["sends"])
    want = len(case["sends"]) + case["replies"]
    for _ in range(400):
        if sum(1 for s in sent if s[40:44] == "0800") >= len(case["sends"]) and len(sent) >= want:
            break
        await ClockCycles(dut.clk, 100)
    await ClockCycles(dut.clk, 2000)

    counters = {name: int(getattr(dut, f"cnt_{name}").value) for name in
                ("rx_packets", "rx_error", "rx_length", "rx_overflow", "tx_packets",
                 "tx_overflow", "rx_header", "rx_other")}
    with open(os.environ["UDP_OUT"], "w") as f:
        json.dump({"received": got, "sent": sent, "counters": counters}, f)
