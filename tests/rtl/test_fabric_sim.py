"""The node in the fabric on the network as the lab's fast Verilator model (issue #31 item 3):
``rosfpga_lab.rtl.fabricsim`` (``rfl_fabric_top``'s GMII variant and the C++ main
``harness/rfl_fabric_sim.cpp``, whole Ethernet frames through a pipe) given the frames
tests/rtl/test_fabric_top.py's cocotb peer sends, answering the circuit's ARP request as that peer
does: the same frames out, checked by that test's own expectations (the lab's software only), the
same counters. The build is cached (some 15-30 s the first time); the run a fraction of a second.

And ``rosfpga-lab fabric sim``'s printout of the RTPS stages' counters (inside
``rfl_fabric_node``, read by the C++ main through the model's hierarchy): known bad input sent
to the node's UDP ports through the shim moves each printed counter by what the modules' rules
say, counted by hand here.
"""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import Ether

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discrom import DEST_META, DEST_USER, render_rom
from rosfpga_lab.rtl.fabricsim import FabricConfig, FabricSim, build_fabric_sim
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    SPDP_READER, SPDP_WRITER, discovery_multicast_port, discovery_port, user_port,
)
from rosfpga_lab.rtps.limits import SPDP_MULTICAST_ADDRESS
from tests.rtl.test_fabric_rtps_cdr import CONFIG, scan
from tests.support.proctools import interruptible, kill_if_running, stop_with
from tests.rtl.test_fabric_top import MAX_CLOCKS, PEER, PEER_INDEX, PERIOD, check_sent, scenario
from tests.rtl.test_fabric_udp import PEER_IP, PEER_MAC, _fcs, _group_mac
from tests.support.rtltools import require_fabric_sim

pytestmark = pytest.mark.rtl

PREAMBLE = "55" * 7 + "d5"
ETHERTYPE_ARP = bytes.fromhex("0806")


def run_answering_arp(sim: FabricSim, peer_ip: bytes, arp_reply: bytes,
                      seconds: float = 60) -> list[bytes]:
    """The frames the fast model sends until it stops (or ``seconds``), answering its ARP
    requests for ``peer_ip`` with ``arp_reply``."""
    sent: list[bytes] = []
    deadline = time.monotonic() + seconds
    while sim.running() and time.monotonic() < deadline:
        for frame in sim.read(0.05).frames:
            sent.append(frame)
            if frame[12:14] == ETHERTYPE_ARP and frame[20:22] == b"\x00\x01" \
                    and frame[38:42] == peer_ip:
                sim.send_frame(arp_reply)
    return sent


@pytest.mark.timeout(300)
def test_the_fast_model_sends_what_the_cocotb_bench_expects(tmp_path: Path) -> None:
    require_fabric_sim()
    sc = scenario(tmp_path)
    build = build_fabric_sim(load_config(CONFIG), sc.rom, period=PERIOD)
    assert {**build.params, "MAX_BYTES": sc.params["MAX_BYTES"]} == sc.params
    case: dict[str, Any] = sc.case
    config = FabricConfig(int(case["node_mac"], 16), _dotted(case["node_ip"]),
                          _dotted(case["peer_ip"]), case["peer_meta_port"],
                          case["peer_user_port"], case["reader"], case["writer"], case["time"])
    sim = FabricSim(build, config, rate=0, max_clocks=MAX_CLOCKS)
    peer_ip = bytes.fromhex(case["peer_ip"])
    sent: list[bytes] = []
    try:
        for raw in case["frames"]:
            sim.send_frame(bytes.fromhex(raw))
        sent += run_answering_arp(sim, peer_ip, bytes.fromhex(case["arp_reply"]))
    finally:
        report = sim.close()
    sent += report.frames
    assert report.clocks >= MAX_CLOCKS, report.clocks   # it ran to its bound
    counters = {k: v for k, v in report.counters.items()
                if k not in ("credit", "judged", "refused", "last_refusal")
                and not k.startswith("peer_")}
    # no SPDP came: the learner (not used: cfg_learn low) took nothing, refused nothing
    assert [report.counters[f"peer_{k}"] for k in ("learned", "refused", "other")] == [0, 0, 0]
    assert (report.counters["judged"], report.counters["refused"]) == (1, 0)
    check_sent(sc, [PREAMBLE + f.hex() for f in sent], counters)


@pytest.mark.timeout(300)
def test_the_fast_model_learns_its_peer_from_spdp_and_sends_it_sedp(tmp_path: Path) -> None:
    """cfg_learn high, the cfg_peer_* registers zero: the peer's SPDP announcement (the lab's
    builders, to the domain's SPDP group and port) makes the circuit send its SEDP data and
    ros_discovery_info sample (the ROM's messages after SPDP, byte for byte) to the locators
    that announcement gave, and nowhere else; a second participant's later is counted, not
    taken (no more SEDP); another domain's announcement, and one to another port, are never
    heard (the domain honoured: LiteEth's port filter, the top's three ports)."""
    require_fabric_sim()
    sc = scenario(tmp_path)
    build = build_fabric_sim(load_config(CONFIG), sc.rom, period=PERIOD)
    case: dict[str, Any] = sc.case
    meta, user = discovery_port(0, PEER_INDEX), user_port(0, PEER_INDEX)
    config = FabricConfig(int(case["node_mac"], 16), _dotted(case["node_ip"]), "0.0.0.0", 0, 0,
                          case["reader"], case["writer"], case["time"], learn=True)

    def announce(prefix: bytes, ip: str, index: int, domain: int = 0,
                 port: int | None = None) -> bytes:
        payload = b.spdp_payload(prefix, b.Locator(ip, discovery_port(domain, index)),
                                 b.Locator(ip, user_port(domain, index)), 10.0, "peer", b"",
                                 domain)
        rtps = b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)
        return _fcs(bytes(Ether(dst=_group_mac(SPDP_MULTICAST_ADDRESS), src=PEER_MAC) /
                          IP(src=ip, dst=SPDP_MULTICAST_ADDRESS) /
                          UDP(sport=40000, dport=port or discovery_multicast_port(domain)) /
                          rtps))

    sim = FabricSim(build, config, rate=0, max_clocks=MAX_CLOCKS)
    peer_ip = bytes.fromhex(case["peer_ip"])
    sent: list[bytes] = []
    other = bytes.fromhex("010f0dd00000000300000003")
    try:
        # another domain's (its SPDP port: LiteEth's filter drops it), one to a port LiteEth
        # passes but the top does not own (counted in rx_port): neither is heard, so PEER is
        # the first participant announced in this domain
        sim.send_frame(announce(other, "192.168.10.7", 0, domain=1))
        sim.send_frame(announce(other, "192.168.10.7", 0, port=discovery_multicast_port(0) + 1))
        sim.send_frame(announce(PEER, PEER_IP, PEER_INDEX))
        sim.send_frame(announce(bytes.fromhex("010fbeef0000000200000002"), "192.168.10.9", 3))
        sent += run_answering_arp(sim, peer_ip, bytes.fromhex(case["arp_reply"]))
    finally:
        report = sim.close()
    sent += report.frames
    udp = [Ether(f) for f in sent if f[12:14] == b"\x08\x00"]
    to_peer = [(f[IP].dst, f[UDP].dport, bytes(f[UDP].payload)[:f[UDP].len - 8]) for f in udp
               if f[IP].dst != SPDP_MULTICAST_ADDRESS]
    port = {DEST_META: meta, DEST_USER: user}
    assert to_peer == [(PEER_IP, port[m.dest], m.data) for m in sc.rom.messages[1:]]
    assert [report.counters[f"peer_{k}"] for k in ("learned", "refused", "other")] == [1, 0, 1]
    assert (report.counters["rx_port"], report.counters["rx_packets"]) == (1, 3)


def _dotted(hexed: str) -> str:
    return ".".join(str(b) for b in bytes.fromhex(hexed))


#: The counter test's domain (its own ports: 7400 + 250 x 228 + 10 and 11), a peer's prefix and
#: writer.
COUNT_DOMAIN = 228
PEER = bytes.fromhex("010fcafe00000002000000a1")
WRITER = 0x00001203
FRAG = 1024


def _heartbeat_too_long() -> bytes:
    """A HEARTBEAT whose octetsToNextHeader (little endian: flag E) claims 200 bytes, more than
    the datagram holds: malformed (both walkers' rule)."""
    hb = bytearray(b.heartbeat(0, WRITER, 1, 1, 1))
    hb[2:4] = struct.pack("<H", 200)
    return b.header(PEER) + bytes(hb)


@pytest.mark.timeout(300)
def test_fabric_sim_prints_the_rtps_stages_counters_moved_by_bad_input(tmp_path: Path) -> None:
    """One good LaserScan in two DATA_FRAGs with its first fragment sent twice, a bad RTPS
    header and a malformed submessage to the user-data port, the same two to the metatraffic
    port: the printed counters (on SIGUSR1 and at the end), counted by hand from the modules'
    headers (rfl_rtps_rx, rfl_rtps_ctrl)."""
    require_fabric_sim()
    config = load_config(CONFIG)
    build_fabric_sim(config, render_rom(config, domain=COUNT_DOMAIN))   # the CLI's, cached
    sample = b.pad_payload(scan(np.linspace(0.5, 20.0, 360, dtype=np.float32), 3, "laser"))
    assert FRAG < len(sample) <= 2 * FRAG                 # two fragments
    frag = [b.data_frag(0, WRITER, 1, n, FRAG, len(sample), sample[(n - 1) * FRAG:n * FRAG], 1)
            for n in (1, 2)]
    hdr = b.header(PEER)
    user, meta = user_port(COUNT_DOMAIN, 0), discovery_port(COUNT_DOMAIN, 0)
    sends = [(user, hdr + b.info_ts(1.7e9) + frag[0]),
             (user, hdr + frag[0]),                       # the same fragment again: repeated
             (user, hdr + frag[1]),                       # the sample whole
             (user, b"RTPX" + hdr[4:] + frag[1]),         # bad magic
             (user, _heartbeat_too_long()),               # a submessage past the datagram
             (meta, b"RTPX" + hdr[4:]),
             (meta, _heartbeat_too_long())]
    want = {"rfl_rtps_rx": {"cnt_packets": 5, "cnt_bad_header": 1, "cnt_malformed": 1,
                            "cnt_samples": 1, "cnt_dropped": 0, "cnt_repeated": 1},
            "rfl_rtps_to_cdr": {"cnt_samples": 1, "cnt_dropped": 0, "cnt_too_long": 0},
            "rfl_rtps_ctrl": {"cnt_requests": 0, "cnt_busy": 0, "cnt_malformed": 1,
                              "cnt_bad_header": 1}}

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    log = tmp_path / "stderr.txt"
    with log.open("w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "rosfpga_lab", "fabric", "sim", str(CONFIG), "--domain",
             str(COUNT_DOMAIN), "--seconds", "60"], stdout=subprocess.PIPE, stderr=err,
            text=True, env=env, cwd=tmp_path, preexec_fn=interruptible)
    try:
        deadline = time.monotonic() + 120
        while "\nready:" not in "\n" + log.read_text() and proc.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.05)
        assert proc.poll() is None and "\nready:" in "\n" + log.read_text(), log.read_text()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for port, datagram in sends:
                sock.sendto(datagram, ("127.0.0.1", port))
                time.sleep(0.3)                    # some 100,000 clocks: one at a time
        time.sleep(0.5)
        proc.send_signal(signal.SIGUSR1)           # the counters now, then at the end
        time.sleep(1.0)
        stdout, _ = stop_with(proc, signal.SIGINT)
    finally:
        kill_if_running(proc)
    assert proc.returncode == 0, log.read_text()
    print(stdout)
    blocks: list[dict[str, dict[str, int]]] = []
    for line in stdout.splitlines():
        if line.startswith("fabric sim: "):
            blocks.append({})
        stage, sep, rest = line.partition(": ")
        if sep and stage in want:
            blocks[-1][stage] = {k: int(v) for k, v in (kv.split(" ") for kv in rest.split(", "))}
    assert len(blocks) == 2, stdout                 # on SIGUSR1, then at the end
    for printed in blocks:
        for stage, counts in want.items():
            assert {k: printed[stage][k] for k in counts} == counts, (stage, stdout)
    top = dict(kv.rsplit(" ", 1) for kv in next(
        x for x in stdout.splitlines() if x.startswith("circuit: "))[len("circuit: "):].split(", "))
    assert (top["rx_packets"], top["rx_overflow"], top["judged"], top["refused"]) == \
        ("7", "0", "1", "0"), stdout
