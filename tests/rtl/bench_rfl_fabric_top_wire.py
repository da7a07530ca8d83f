"""cocotb testbench of ``rfl_fabric_top`` at its GMII side in groups of frames, with counters and
times (run by tests/rtl/test_fabric_wire.py and tests/benchmarks/bench_fabric_wire.py, not by
pytest).

The case (JSON, ``FABRIC_WIRE_CASE``): the node's and the peer's addresses, the receive side's
configuration, ``cfg_time``, the ARP reply the peer gives when the node asks for its MAC, and
groups of frames (whole, FCS included, hex), each with: ``gap`` (clocks of idle after each
frame, or null: back to back, cocotbext-eth's 12-byte interframe gap), ``errors`` (frame index,
byte index: GMII rx_er raised on that byte, the preamble counted), ``expect`` (how many IPv4
frames the node must have sent in all once the group is done) and ``samples`` (the samples its
transmit path must have sent in all; the bench waits for both, at most ``max_clocks``, or
``idle_clocks`` with no frame out when given) and
``quiet`` (clocks waited after). After each group the counters are read:
the top's and the node's stages' (through the hierarchy; Verilator's --public-flat-rw). With
``watch``, every clock each stage's stream is sampled: clocks it held data its next stage did not
take (stalled) and clocks it offered data. Written (``FABRIC_WIRE_OUT``): every frame the node
sent (preamble and FCS included) with its GMII times, each group's frames' times and counters.
Times in ns (8 ns a clock).
"""

from __future__ import annotations

import json
import os

import cocotb
from bench_rfl_fabric_top import COUNTERS, _arp_request_for, start_top
from cocotb.triggers import ClockCycles, RisingEdge
from cocotb.utils import get_time_from_sim_steps
from cocotbext.eth import GmiiFrame

from rosfpga_lab.rtl.fabriccounters import NODE_INSTANCE, node_wires

TOP = COUNTERS                  # the top's cnt_* outputs
# rfl_fabric_node's internal counters: rfl_rtps_rx, rfl_rtps_to_cdr, rfl_rtps_tx, rfl_rtps_ctrl
# (key -> the node's wire; the library owns the list: the fast model reads the same)
NODE = node_wires()
# streams watched (stage: valid, ready), in the top (u_node: the node's)
STAGES = {"liteeth_rx->udp_port": ("le_rx_valid", "le_rx_ready"),
          "udp_port->node": ("p_rx_tvalid", "p_rx_tready"),
          "rtps_rx->seam": ("u_node.rx_tvalid", "u_node.rx_tready"),
          "seam->cdr_node": ("u_node.rec_tvalid", "u_node.rec_tready"),
          "cdr_node->rtps_tx": ("u_node.pub_tvalid", "u_node.pub_tready"),
          "rtps_tx->arbiter": ("u_node.tx_tvalid", "u_node.tx_tready"),
          "node->udp_port": ("p_tx_tvalid", "p_tx_tready"),
          "udp_port->liteeth_tx": ("le_tx_valid", "le_tx_ready")}


def _ns(steps: int) -> int:
    return round(get_time_from_sim_steps(steps, "ns"))


def _signal(dut, path: str):
    for name in path.split("."):
        dut = getattr(dut, name)
    return dut


def _counters(dut) -> dict[str, int]:
    out = {name: int(getattr(dut, f"cnt_{name}").value) for name in TOP}
    node = getattr(dut, NODE_INSTANCE)
    out.update({name: int(getattr(node, sig).value) for name, sig in NODE.items()})
    return out


@cocotb.test()
async def fabric_wire(dut) -> None:
    with open(os.environ["FABRIC_WIRE_CASE"]) as f:
        case = json.load(f)
    source, sink = await start_top(dut, case)

    sent: list[dict] = []
    ipv4 = [0]
    peer_ip = bytes.fromhex(case["peer_ip"])

    async def peer() -> None:
        while True:
            frame = await sink.recv()
            payload = bytes(frame.get_payload())
            sent.append({"data": bytes(frame.data).hex(), "start": _ns(frame.sim_time_start),
                         "end": _ns(frame.sim_time_end)})
            ipv4[0] += payload[12:14] == b"\x08\x00"
            if _arp_request_for(payload, peer_ip):
                await source.send(GmiiFrame.from_raw_payload(bytes.fromhex(case["arp_reply"])))

    stalls = {name: [0, 0] for name in STAGES}

    async def watch() -> None:
        pairs = [(name, _signal(dut, v), _signal(dut, r)) for name, (v, r) in STAGES.items()]
        while True:
            await RisingEdge(dut.clk)
            for name, v, r in pairs:
                if v.value:
                    stalls[name][1] += 1
                    if not r.value:
                        stalls[name][0] += 1

    cocotb.start_soon(peer())
    if case.get("watch"):
        cocotb.start_soon(watch())
    groups = []
    for group in case["groups"]:
        times: list[list[int]] = []               # the source sends copies: their times
        frames = [GmiiFrame.from_raw_payload(
            bytes.fromhex(raw), tx_complete=lambda f: times.append([_ns(f.sim_time_start),
                                                                   _ns(f.sim_time_end)]))
            for raw in group["frames"]]
        for k, at in group.get("errors", []):
            frames[k].error = [int(i == at) for i in range(len(frames[k].data))]
        for frame in frames:
            if group["gap"] is None:
                await source.send(frame)
            else:
                await source.send(frame)
                await source.wait()
                await ClockCycles(dut.clk, group["gap"])
        await source.wait()
        clocks = idle = 0
        seen = ipv4[0]
        while (ipv4[0] < group["expect"] or
               int(dut.cnt_samples.value) < group.get("samples", 0)) and \
                clocks < case["max_clocks"] and idle < case.get("idle_clocks", clocks + 1):
            await ClockCycles(dut.clk, 50)
            clocks += 50
            idle = 0 if ipv4[0] != seen else idle + 50
            seen = ipv4[0]
        await ClockCycles(dut.clk, group["quiet"])
        groups.append({"name": group["name"], "ipv4": ipv4[0], "sent": len(sent), "counters": _counters(dut),
                       "in": times})
    with open(os.environ["FABRIC_WIRE_OUT"], "w") as f:
        json.dump({"sent": sent, "groups": groups,
                   "stalls": {k: {"stalled": v[0], "valid": v[1]} for k, v in stalls.items()}},
                  f)
