"""The node in the fabric on the network (issue #31): ``rfl_fabric_top`` (LiteEth's GMII
variant -> rfl_udp_port -> rfl_fabric_node, rosfpga_lab/rtl/fabric/rfl_fabric_top.v) driven at
its GMII side by a peer (cocotbext-eth, ``bench_rfl_fabric_top.py``) under Verilator, the generated
top of ``data/fpga_laserscan_min_cdr.yaml`` inside.

The peer (participant 1 of domain 0) sends, as Ethernet/IPv4/UDP frames built here with scapy:
a user datagram with a bad FCS, an ACKNACK to a port LiteEth passes but the node does not own
and one to the user-data port (neither answered), then
tests/rtl/test_fabric_rtps_loop.py's two DATA_FRAG datagrams of one LaserScan sample to the
user-data port, an ACKNACK with a bad FCS and a good one to the metatraffic port. Expected, from
the lab's software only: the SPDP announcement to 239.255.0.1 and the domain's SPDP port, byte
for byte the discovery ROM's (``rtl.discrom``); the CDR models' output sample as the lab's RTPS
builders send it from the fabric participant's writer (``test_fabric_rtps_tx.expected``), to the
peer's user-data port; the answers of the answer model (``rtl.discanswer``) to the peer's
metatraffic port; nothing else (the bad frames, the other port), and the counters saying why.
Ports from the RTPS port mapping (``rtps.entities``), the same owner ``rtl.discrom.top_parameters``
reads. A first Verilator build some 30 s here (kept in the lab's RTL cache with the generated
files it was built from), then the whole test some 6 s.
"""

from __future__ import annotations

import ipaddress
import struct
from dataclasses import dataclass
from pathlib import Path

import pytest
from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import ARP, Ether

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discanswer import AnswerModel
from rosfpga_lab.rtl.discrom import (
    DiscoveryRom, fabric_participant, fabric_top_literals, render_rom, tx_parameters, write_rom,
)
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, discovery_multicast_port, discovery_port, user_port,
)
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES, SPDP_MULTICAST_ADDRESS
from tests.rtl.test_fabric_answer import _names
from tests.rtl.test_fabric_rtps_cdr import CONFIG, FABRIC, MAX_BYTES
from tests.rtl.test_fabric_rtps_loop import TIME, published
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER
from tests.rtl.test_fabric_rtps_tx import check_parsed, expected
from tests.rtl.test_fabric_udp import PEER_IP, PEER_MAC, _fcs, _frames, _group_mac
from tests.support import fabrictop
from tests.support.rtltools import TB_DIR, cocotb_verilator

pytestmark = pytest.mark.rtl

NODE_MAC, NODE_IP = "02:52:46:4c:00:02", "192.168.10.2"
PEER = bytes.fromhex("010fcafe0000000100000001")
PEER_INDEX = 1
PERIOD = 1_000_000       # one SPDP announcement (at reset) in the run
MAX_CLOCKS = 200_000
SOURCES = fabrictop.SOURCES                      # tests/rtl/test_lint.py lints them


def _udp(payload: bytes, dport: int, sport: int = 40000) -> bytes:
    return bytes(Ether(dst=NODE_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=NODE_IP) /
                 UDP(sport=sport, dport=dport) / payload)


def _bad_fcs(frame: bytes) -> bytes:
    bad = bytearray(_fcs(frame))
    bad[-2] ^= 0x10
    return bytes(bad)


def _ip(addr: str) -> str:
    return ipaddress.IPv4Address(addr).packed.hex()


@dataclass
class Scenario:
    """The peer's frames and what must come out (built from the lab's software only)."""

    rom: DiscoveryRom
    case: dict[str, object]
    params: dict[str, str]
    sample: list[bytes]
    want_user: list[bytes]
    answers: list
    wid: int
    guid_prefix: bytes


def scenario(tmp_path: Path) -> Scenario:
    """The ROM (written into ``tmp_path``), the frames the peer sends, the ARP reply it gives,
    the top's parameters and the expected datagrams (the module docstring says which)."""
    config = load_config(CONFIG)
    rom = render_rom(config, guid_prefix=LOCAL)  # the node's one prefix (the ROMs')
    write_rom(rom, tmp_path)
    part, _node, wid, _rid = fabric_participant(config, guid_prefix=LOCAL)
    p = tx_parameters(rom)
    spdp_port, meta, user = discovery_multicast_port(0), discovery_port(0, 0), user_port(0, 0)
    peer_meta, peer_user = discovery_port(0, PEER_INDEX), user_port(0, PEER_INDEX)

    # one LaserScan sample in two DATA_FRAG datagrams (each fits a frame); the models' output
    datagrams, payloads = published(5)
    frags, sample = datagrams[1:3], payloads[1:2]
    assert max(map(len, frags)) <= 1472 < len(datagrams[0])
    want_user = [d for dgs in expected(sample, [TIME], FRAGMENT_BYTES, True, MAX_BYTES,
                                       part.guid_prefix, wid, p["READER_ID"]) for d in dgs]
    ack = b.header(PEER) + b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 1)
    answers = AnswerModel(rom).receive(ack)
    assert [rom.answers[i].name for i in _names(rom, answers)] == \
        ["publications_1", "publications_2"]
    other_port = spdp_port + 1               # LiteEth's port filter passes it, the top does not
    # the ACKNACK to another port and to the user-data port must not be answered
    frames = [_bad_fcs(_udp(frags[0], user)), _fcs(_udp(ack, other_port)), _fcs(_udp(ack, user)),
              _fcs(_udp(frags[0], user)), _fcs(_udp(frags[1], user)),
              _bad_fcs(_udp(ack, meta)), _fcs(_udp(ack, meta))]
    reply = _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) /
                       ARP(op=2, hwsrc=PEER_MAC, psrc=PEER_IP, hwdst=NODE_MAC, pdst=NODE_IP)))
    case = {"node_mac": NODE_MAC.replace(":", ""), "node_ip": _ip(NODE_IP),
            "peer_ip": _ip(PEER_IP), "peer_meta_port": peer_meta, "peer_user_port": peer_user,
            "reader": READER, "writer": WRITER, "time": TIME,
            "frames": [f.hex() for f in frames], "arp_reply": reply.hex(), "gap": 50,
            "expect": 1 + len(want_user) + len(answers), "max_clocks": MAX_CLOCKS}
    params = dict(fabric_top_literals(rom, period=PERIOD), MAX_BYTES=str(MAX_BYTES))
    return Scenario(rom, case, params, sample, want_user, answers, wid, part.guid_prefix)


def check_sent(sc: Scenario, sent: list[str], counters: dict[str, int]) -> None:
    """What the node sent (frames as the GMII sink saw them, preamble and FCS included, hex)
    is what ``sc`` expects, and the counters say why nothing else came."""
    rom, p = sc.rom, tx_parameters(sc.rom)
    spdp_port, meta, user = discovery_multicast_port(0), discovery_port(0, 0), user_port(0, 0)
    peer_meta, peer_user = discovery_port(0, PEER_INDEX), user_port(0, PEER_INDEX)
    sent_frames = [Ether(f) for f in _frames(sent)]
    arp = [f for f in sent_frames if f.haslayer(ARP)]
    assert all(f[ARP].op == 1 and f[ARP].pdst == PEER_IP for f in arp)   # it asks for the peer
    udp = [f for f in sent_frames if f.type == 0x0800]
    assert len(sent_frames) == len(arp) + len(udp)
    for f in udp:
        assert (f.src, f[IP].src, f[IP].ihl, f[IP].proto) == (NODE_MAC, NODE_IP, 5, 17)
        assert sum(struct.unpack(">10H", bytes(f[IP])[:20])) % 0xFFFF == 0, "IPv4 checksum"
        assert f[UDP].len == f[IP].len - 20

    def to(ip: str, port: int) -> list[bytes]:
        got = [f for f in udp if (f[IP].dst, f[UDP].dport) == (ip, port)]
        return [bytes(f[UDP].payload)[:f[UDP].len - 8] for f in got]

    # (1) the SPDP announcement, to the group's MAC, from the metatraffic port
    spdp = [f for f in udp if f[IP].dst == SPDP_MULTICAST_ADDRESS]
    assert len(spdp) == 1 and spdp[0].dst == _group_mac(SPDP_MULTICAST_ADDRESS)
    assert (spdp[0][UDP].sport, spdp[0][UDP].dport) == (meta, spdp_port)
    assert to(SPDP_MULTICAST_ADDRESS, spdp_port) == [rom.messages[0].data]
    # (2) the sample, as the software writer sends it, from the user-data port
    got_user = to(PEER_IP, peer_user)
    assert got_user == sc.want_user
    check_parsed(got_user, sc.sample, MAX_BYTES, sc.guid_prefix, sc.wid, p["READER_ID"], True)
    assert all(f[UDP].sport == user for f in udp if f[UDP].dport == peer_user)
    # (3) the answers to the ACKNACK, to the peer's metatraffic port
    assert to(PEER_IP, peer_meta) == [x.data for x in sc.answers]
    assert all(f.dst == PEER_MAC for f in udp if f[IP].dst == PEER_IP)
    assert len(udp) == 1 + len(sc.want_user) + len(sc.answers)          # nothing else
    assert counters == {
        "samples": 1, "answers": len(sc.answers), "no_credit": 0, "rx_packets": 5,
        "rx_error": 2, "rx_length": 0, "rx_overflow": 0, "tx_packets": len(udp),
        "tx_overflow": 0, "rx_port": 1, "rx_header": 0, "rx_other": 0}


@pytest.mark.timeout(600)
def test_the_top_announces_routes_and_answers_on_the_wire(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    cocotb_verilator(monkeypatch)
    monkeypatch.syspath_prepend(str(TB_DIR))
    from cocotb_tools.runner import get_runner

    gen = fabrictop.generate(CONFIG, tmp_path / "project")
    sc = scenario(tmp_path)
    runner = get_runner("verilator")
    build = fabrictop.build(runner, gen, sc.params, tmp_path)
    out = fabrictop.run(runner, build, "bench_rfl_fabric_top", sc.case, tmp_path,
                        "FABRIC_TOP_CASE", "FABRIC_TOP_OUT")
    check_sent(sc, out["sent"], out["counters"])


@pytest.mark.parametrize("bug", [
    ("wire to_user = p_rx_dport == USER;", "wire to_user = p_rx_dport != META;"),
    ("wire keep = to_user ||", "wire keep = 1'b1 || to_user ||"),
    ("p_tx_dport = peer_meta_port;", "p_tx_dport = peer_user_port;"),
], ids=["kind", "other-port", "tdest"])
def test_a_planted_bug_fails_the_proof(bug: tuple[str, str], tmp_path: Path) -> None:
    """The glue's proof (rtl/formal/fv_fabric_top.sv) sees a wrong kind, a datagram to another
    port passed on, a destination mixed up."""
    from rosfpga_lab.rtl.proofs import PROOFS, prove
    from tests.support.rtltools import require_formal

    require_formal()
    proof = next(p for p in PROOFS if p.name == "fabric_top")
    text = (FABRIC / "rfl_fabric_top.v").read_text()
    assert bug[0] in text
    planted = tmp_path / "rfl_fabric_top.v"
    planted.write_text(text.replace(bug[0], bug[1]))
    assert prove(proof, replace={"rfl_fabric_top.v": planted}).status == "FAIL"
