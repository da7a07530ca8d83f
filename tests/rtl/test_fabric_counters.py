"""The counter readout of the node in the fabric (``rfl_counter_readout`` in ``rfl_fabric_top``,
``rtl.fabriccounters``), on the fast Verilator model (``rtl.fabricsim``: the whole top, frames
through its GMII side): after some traffic (good and bad RTPS datagrams, a datagram to a port
the top does not own) a request is answered with every counter, equal to the hierarchy's wires
(the model's counter reports: the top's ports and the node's wires); malformed requests (a byte
short, a byte long, the wrong magic, a non-zero padding byte) are counted and never answered; a
flood of well-formed requests is answered at most once per gap, the rest counted. And the
checked-in include is the rendering of the one table.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.component.fabricsim import HOST_MAC as SHIM_HOST_MAC
from rosfpga_lab.graph.ethframe import (
    ArpRequest, UdpDatagram, arp_reply, mac_bytes, parse_frame, udp_frame,
)
from rosfpga_lab.rtl.board import DEFAULT_MAC, mac_value
from rosfpga_lab.rtl.discrom import counters_port, render_rom
from rosfpga_lab.rtl.fabriccounters import (
    FABRIC_COUNTERS, INCLUDE_FILE, MAGIC, answer_bytes, counters_gap, parse_answer, request,
    verilog_include,
)
from rosfpga_lab.rtl.fabricsim import COUNTERS, FabricConfig, FabricSim, build_fabric_sim
from rosfpga_lab.rtl.proofs import FABRIC_DIR
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import discovery_port, user_port
from tests.rtl.test_fabric_rtps_cdr import CONFIG, scan
from tests.support.rtltools import require_fabric_sim

pytestmark = pytest.mark.rtl

NODE_IP, HOST_IP = "192.168.10.2", "192.168.10.1"
HOST_MAC = mac_bytes(SHIM_HOST_MAC)
NODE_MAC = mac_value(DEFAULT_MAC).to_bytes(6, "big")
PERIOD = 400_000                    # the gap: 400 clocks
ASKER = 40001
PEER = bytes.fromhex("010fcafe00000002000000a1")


def test_the_include_is_the_tables_rendering() -> None:
    assert (FABRIC_DIR / INCLUDE_FILE).read_text() == verilog_include()
    assert len({c.key for c in FABRIC_COUNTERS}) == len(FABRIC_COUNTERS)
    assert len(request()) == answer_bytes() == 8 + 4 * len(FABRIC_COUNTERS)
    # the fast model's top-level report names are the table's
    top = {c.key for c in FABRIC_COUNTERS if c.scope == "top"}
    assert top <= set(COUNTERS)


class _Host:
    """The model and a host on its link: frames to it, ARP answered, datagrams back."""

    def __init__(self, sim: FabricSim) -> None:
        self.sim = sim
        self.ident = 0
        self.got: list[UdpDatagram] = []

    def send(self, port: int, payload: bytes, sport: int = ASKER) -> None:
        self.ident += 1
        self.sim.send_frame(udp_frame(payload, src_mac=HOST_MAC, dst_mac=NODE_MAC,
                                      src_ip=HOST_IP, dst_ip=NODE_IP, src_port=sport,
                                      dst_port=port, ident=self.ident))

    def run(self, seconds: float, until: int | None = None) -> list[UdpDatagram]:
        """Datagrams to the asker's port within ``seconds`` (or once ``until`` came)."""
        answers: list[UdpDatagram] = []
        end = time.monotonic() + seconds
        while time.monotonic() < end and self.sim.running():
            for frame in self.sim.read(0.05).frames:
                got = parse_frame(frame)
                if isinstance(got, ArpRequest):
                    self.sim.send_frame(arp_reply(got, HOST_MAC))
                elif isinstance(got, UdpDatagram) and got.dst_port == ASKER:
                    answers.append(got)
            if until is not None and len(answers) >= until:
                break
        return answers

    def report(self) -> dict[str, int]:
        """The hierarchy's counters now (the model's 'K' and 'N' reports), by the table's keys."""
        before = self.sim.node_counters
        self.sim.ask_counters()
        end = time.monotonic() + 10
        while self.sim.node_counters is before and time.monotonic() < end:
            self.run(0.05)
        return {**self.sim.counters, **self.sim.node_counters}


@pytest.mark.timeout(300)
def test_the_readout_answers_every_counter_and_nothing_else(tmp_path: Path) -> None:
    require_fabric_sim()
    config = load_config(CONFIG)
    rom = render_rom(config, address=NODE_IP)
    build = build_fabric_sim(config, rom, period=PERIOD)
    gap = counters_gap(PERIOD)
    assert build.params["COUNTERS_GAP"] == str(gap) == "400"
    port = counters_port(rom.domain)
    sim = FabricSim(build, FabricConfig(mac_value(DEFAULT_MAC), NODE_IP, HOST_IP, 0, 0,
                                        rom.entity_ids["reader"], learn=True), rate=PERIOD)
    host = _Host(sim)
    try:
        # traffic: a good sample, a bad RTPS header, one to a port nobody owns
        sample = b.pad_payload(scan(np.linspace(0.5, 20.0, 360, dtype=np.float32), 3, "laser"))
        hdr = b.header(PEER)
        host.send(user_port(0, 0), hdr + b.data(0, 0x1203, 1, sample))
        host.send(user_port(0, 0), b"RTPX" + hdr[4:])
        host.send(discovery_port(0, 0), b"RTPX" + hdr[4:])
        host.send(port + 1, b"nobody's")
        host.run(0.5)

        # malformed: none answered, each counted
        good = request()
        for bad in (good[:-1], good + b"\0", b"RFC\x02" + good[4:],
                    good[:-1] + b"\x01"):
            host.send(port, bad)
        assert host.run(1.0) == []

        host.send(port, good)
        answers = host.run(5.0, until=1)
        assert len(answers) == 1, answers
        answer = answers[0]
        assert (answer.src_ip, answer.src_port, answer.dst_ip) == (NODE_IP, port, HOST_IP)
        assert len(answer.payload) == answer_bytes()
        assert int.from_bytes(answer.payload[:4], "big") == MAGIC
        values = parse_answer(answer.payload)
        wires = host.report()
        assert set(wires) - set(values) == {"credit", "judged", "refused", "last_refusal"}
        for key, value in values.items():
            if key == "tx_packets":     # the answer itself (and maybe an SPDP announcement)
                assert value < wires[key] <= value + 3, (key, value, wires[key])
            elif key in wires:
                assert value == wires[key], (key, value, wires[key])
        assert values["rtps_samples"] == 1 and values["rtps_bad_header"] == 1
        assert values["ctrl_bad_header"] == 1 and values["rx_port"] == 1
        assert values["counters_malformed"] == 4 and values["counters_answered"] == 1
        assert values["counters_limited"] == 0

        # a flood: 40 well-formed requests back to back (206 clocks each on the wire: preamble,
        # headers, FCS, gap) is answered at most once a gap, one answer a request at most
        for _ in range(40):
            host.send(port, good)
        flood = host.run(3.0)
        assert 2 <= len(flood) <= 40 * 206 // gap + 1, len(flood)
        host.send(port, good)               # well after the gap: answered
        final = parse_answer(host.run(5.0, until=1)[0].payload)
        assert final["counters_answered"] == 1 + len(flood) + 1
        assert final["counters_limited"] == 40 - len(flood)
        assert final["counters_malformed"] == 4
        assert final["rx_packets"] - values["rx_packets"] == 41
    finally:
        sim.close()
