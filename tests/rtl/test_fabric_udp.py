"""The UDP stage of the node in the fabric (issue #31): the vendored LiteEth core
(``rtl/fabric/vendor``) behind ``rfl_udp_port``, as ``udp_gmii_top``, driven at its GMII side.

A peer (cocotbext-eth's GMII models, in ``bench_udp_gmii_top.py``) sends frames the test builds
with scapy: an ARP request for the node's IP (it must answer), one for another IP (no answer),
then Ethernet/IPv4/UDP frames to the node's IP and port with random payload sizes (1 to 1,400
bytes, padded frames among them) and random gaps, mixed with frames the node must drop: a bad
FCS, a bad IPv4 header checksum, another destination IP, another unicast MAC, another UDP port, a
frame cut short (its IP and UDP lengths claim more), an empty datagram, another multicast
group, IPv4 fragments (MF set, an offset), an IPv4 total length above the frame, below the UDP
length or below 28, a runt (not padded) that ends inside its Ethernet, IPv4 or UDP header. Good frames go to the node's IP, broadcast, or the SPDP multicast group, and to any of
its participant's ports (user and metatraffic unicast, SPDP multicast: one masked port).
Exactly the good payloads must come out, in order, with the sender's IP and ports, and the
counters must count what ``rfl_udp_port`` says it counts. Then the lab side sends payloads to
the peer: after ARP (the bench answers the node's request), each must leave as one well-formed
frame (preamble, FCS, IPv4 header checksum, addresses, ports, lengths), parsed here with scapy.
Runs on Verilator (a first build some 20 to 50 s here, then cached; the simulation some 5 s).
"""

from __future__ import annotations

import hashlib
import ipaddress
import json
import random
import struct
import subprocess
import zlib
from pathlib import Path

import pytest
from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import ARP, Ether

from rosfpga_lab.rtl.sim import cache_root, simulator_version
from rosfpga_lab.rtps.entities import discovery_multicast_port, discovery_port, user_port
from rosfpga_lab.rtps.limits import SPDP_MULTICAST_ADDRESS
from tests.support.rtltools import TB_DIR, cocotb_verilator, require_verilator, run_bench

pytestmark = pytest.mark.rtl

FABRIC = Path(__file__).resolve().parents[2] / "rosfpga_lab" / "rtl" / "fabric"
SOURCES = [FABRIC / "vendor" / "liteeth_udp_gmii.v", FABRIC / "rfl_udp_store.v",
           FABRIC / "rfl_udp_port.v", Path(__file__).with_name("udp_gmii_top.v")]
NODE_MAC, NODE_IP = "02:52:46:4c:00:02", "192.168.10.2"
PEER_MAC, PEER_IP = "02:00:00:00:00:aa", "192.168.10.1"
OTHER_MAC, OTHER_IP = "02:00:00:00:00:bb", "192.168.10.9"
NODE_PORT = user_port(0, 0)
PORT_MASK = 0xFFE0                               # 7392..7423: the domain 0 participant's ports
NODE_PORTS = (NODE_PORT, discovery_port(0, 0), discovery_multicast_port(0))
OTHER_GROUP = "239.255.0.2"
PREAMBLE = bytes.fromhex("55555555555555d5")
MIN_FRAME = 60                                   # without the FCS


def _fcs(frame: bytes) -> bytes:
    """Pad to the minimum frame and append the FCS (IEEE 802.3 CRC-32, little-endian)."""
    frame = frame.ljust(MIN_FRAME, b"\x00")
    return frame + struct.pack("<I", zlib.crc32(frame))


def _udp(payload: bytes, *, mac: str = NODE_MAC, ip: str = NODE_IP, dport: int = NODE_PORT,
         sport: int = 40000, chksum: int | None = None) -> bytes:
    ip_layer = IP(src=PEER_IP, dst=ip) if chksum is None else IP(src=PEER_IP, dst=ip, chksum=chksum)
    return bytes(Ether(dst=mac, src=PEER_MAC) / ip_layer / UDP(sport=sport, dport=dport) / payload)


def _group_mac(group: str) -> str:
    """The Ethernet address of an IPv4 multicast group (RFC 1112: 01:00:5e + its low 23 bits)."""
    low = int(ipaddress.IPv4Address(group)) & 0x7FFFFF
    return "01:00:5e:" + ":".join(f"{b:02x}" for b in low.to_bytes(3, "big"))


def _arp_request(target: str) -> bytes:
    return bytes(Ether(dst="ff:ff:ff:ff:ff:ff", src=PEER_MAC) /
                 ARP(op=1, hwsrc=PEER_MAC, psrc=PEER_IP, pdst=target))


KINDS = ["good"] * 8 + ["bcast", "mcast", "bad_fcs", "bad_ipsum", "other_ip", "other_mac",
                        "other_port", "other_group", "cut", "more_fragments", "fragment",
                        "ip_long", "ip_short", "ip_tiny", "runt"]


def _with_ip(frame: bytes, **fields: int) -> bytes:
    """``frame`` (Ethernet/IPv4/UDP) with IPv4 header fields changed, the checksum made good."""
    ip = IP(frame[14:34])
    for k, v in fields.items():
        setattr(ip, k, v)
    ip.chksum = None
    return frame[:14] + bytes(ip)[:20] + frame[34:]


def make_case(seed: int, frames: int, sends: int, gap: int, bp: int) -> dict:
    """The peer's frames, the lab side's payloads and what must come out of them."""
    rng = random.Random(seed)
    wire = [_fcs(_arp_request(NODE_IP)), _fcs(_arp_request(OTHER_IP))]
    good: list[dict] = []
    counts = {"rx_packets": 0, "rx_error": 0, "rx_length": 0, "rx_overflow": 0,
              "tx_packets": sends, "tx_overflow": 0, "rx_header": 0, "rx_other": 0}
    kinds = [rng.choice(KINDS) for _ in range(frames)] + sorted(set(KINDS)) + ["empty"]
    rng.shuffle(kinds)
    for kind in kinds:
        size = rng.choice([rng.randint(1, 17), rng.randint(18, 200), rng.randint(200, 1400)])
        payload = rng.randbytes(size)
        sport = rng.randint(1024, 65535)
        if kind in ("good", "bcast", "mcast"):
            dport = rng.choice(NODE_PORTS)
            if kind == "mcast":
                frame = _udp(payload, sport=sport, dport=dport, ip=SPDP_MULTICAST_ADDRESS,
                             mac=_group_mac(SPDP_MULTICAST_ADDRESS))
            else:
                frame = _udp(payload, sport=sport, dport=dport,
                             mac="ff:ff:ff:ff:ff:ff" if kind == "bcast" else NODE_MAC)
            wire.append(_fcs(frame))
            good.append({"data": payload.hex(), "ip": int(ipaddress.IPv4Address(PEER_IP)),
                         "sport": sport, "dport": dport, "length": size})
            counts["rx_packets"] += 1
        elif kind == "bad_fcs":
            frame = bytearray(_fcs(_udp(payload, sport=sport)))
            frame[-rng.randint(1, 4)] ^= 1 << rng.randrange(8)
            wire.append(bytes(frame))
            counts["rx_error"] += 1
        elif kind == "bad_ipsum":
            right = IP(bytes(IP(src=PEER_IP, dst=NODE_IP) / UDP(dport=NODE_PORT) / payload)).chksum
            wire.append(_fcs(_udp(payload, sport=sport, chksum=right ^ 0x0100)))
            counts["rx_header"] += 1
        elif kind == "other_ip":
            wire.append(_fcs(_udp(payload, sport=sport, ip=OTHER_IP)))
            counts["rx_other"] += 1
        elif kind == "other_mac":
            wire.append(_fcs(_udp(payload, sport=sport, mac=OTHER_MAC)))
            counts["rx_other"] += 1
        elif kind == "other_port":                 # just past the ports the mask takes
            wire.append(_fcs(_udp(payload, sport=sport, dport=rng.choice([7391, 7424, 7411 + 32]))))
            counts["rx_other"] += 1
        elif kind == "other_group":
            wire.append(_fcs(_udp(payload, sport=sport, ip=OTHER_GROUP,
                                  mac=_group_mac(OTHER_GROUP))))
            counts["rx_other"] += 1
        elif kind == "cut":
            whole = _udp(rng.randbytes(rng.randint(80, 1400)), sport=sport)
            wire.append(_fcs(whole[:len(whole) - rng.randint(1, 40)]))
            counts["rx_length"] += 1
        elif kind in ("more_fragments", "fragment", "ip_short", "ip_tiny"):
            fields = {"more_fragments": {"flags": 1}, "fragment": {"frag": rng.randint(1, 8191)},
                      "ip_short": {"len": 20 + 8 + size - rng.randint(1, min(size, 8))},
                      "ip_tiny": {"len": rng.randint(0, 27)}}[kind]
            wire.append(_fcs(_with_ip(_udp(payload, sport=sport), **fields)))
            counts["rx_header"] += 1
        elif kind == "runt":                     # not padded: it ends inside a header
            body = _udp(payload, sport=sport)[:rng.randint(14, 14 + 20 + 7)]
            wire.append(body + struct.pack("<I", zlib.crc32(body)))
            counts["rx_header"] += 1
        elif kind == "ip_long":                  # the frame (padding aside) ends before it
            whole = _udp(payload, sport=sport)
            wire.append(_fcs(_with_ip(whole, len=max(len(whole), 60) - 14 + rng.randint(1, 64))))
            counts["rx_length"] += 1
        else:                                    # empty: LiteEth passes one padding byte
            wire.append(_fcs(_udp(b"", sport=sport)))
            counts["rx_length"] += 1
    peer = int(ipaddress.IPv4Address(PEER_IP))
    out = [{"data": rng.randbytes(rng.choice([1, rng.randint(2, 64), rng.randint(64, 1400)]))
            .hex(), "ip": peer, "sport": NODE_PORT, "dport": rng.randint(7400, 7500)}
           for _ in range(sends)]
    reply = _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) /
                       ARP(op=2, hwsrc=PEER_MAC, psrc=PEER_IP, hwdst=NODE_MAC, pdst=NODE_IP)))
    packed = {k: ipaddress.IPv4Address(v).packed.hex()
              for k, v in (("group", SPDP_MULTICAST_ADDRESS), ("node_ip", NODE_IP),
                           ("peer_ip", PEER_IP))}
    return {"seed": seed, "gap": gap, "bp": bp, "node_mac": NODE_MAC.replace(":", ""),
            "port_mask": PORT_MASK, **packed, "node_port": NODE_PORT,
            "frames": [f.hex() for f in wire], "arp_reply": reply.hex(), "replies": 1,
            "sends": out, "good": good, "counts": counts}


def test_the_case_is_not_trivial() -> None:
    case = make_case(5, 40, 6, 300, 300)
    assert len(case["good"]) > 15 and case["counts"]["rx_error"] and case["counts"]["rx_length"]
    assert case["counts"]["rx_header"] >= 5 and case["counts"]["rx_other"] >= 4
    sizes = [len(g["data"]) // 2 for g in case["good"]]
    assert min(sizes) < 18 and max(sizes) > 1000          # padded frames and long ones
    assert {g["dport"] for g in case["good"]} == set(NODE_PORTS)
    for seed in (1, 2, 5):                                 # both groups reach the node
        frames = make_case(seed, 40, 6, 0, 0)["frames"]
        for group in (SPDP_MULTICAST_ADDRESS, OTHER_GROUP):
            assert any(f.startswith(_group_mac(group).replace(":", "")) for f in frames)


def _frames(sent: list[str]) -> list[bytes]:
    """The node's frames without preamble and FCS, each checked for both (the GMII sink
    model sees the preamble from the clock after TX_EN rises: one 0x55 fewer)."""
    frames = []
    for hexed in sent:
        raw = bytes.fromhex(hexed)
        sfd = raw.index(PREAMBLE[-1])
        assert sfd >= 6 and raw[:sfd] == PREAMBLE[:sfd], raw[:8].hex()
        body, fcs = raw[sfd + 1:-4], raw[-4:]
        assert struct.pack("<I", zlib.crc32(body)) == fcs, "bad FCS"
        assert len(body) >= MIN_FRAME
        frames.append(body)
    return frames


def _check_sent(case: dict, frames: list[bytes]) -> None:
    replies = [f for f in frames if Ether(f).haslayer(ARP) and Ether(f)[ARP].op == 2]
    assert len(replies) == 1, "one ARP reply: for the node's IP, none for another"
    arp = Ether(replies[0])
    assert (arp.dst, arp.src) == (PEER_MAC, NODE_MAC)
    assert (arp[ARP].hwsrc, arp[ARP].psrc, arp[ARP].hwdst, arp[ARP].pdst) == \
        (NODE_MAC, NODE_IP, PEER_MAC, PEER_IP)
    requests = [Ether(f) for f in frames if Ether(f).haslayer(ARP) and Ether(f)[ARP].op == 1]
    for req in requests:                         # the node asks for the peer's MAC, if it must
        assert (req.dst, req[ARP].hwsrc, req[ARP].psrc, req[ARP].pdst) == \
            ("ff:ff:ff:ff:ff:ff", NODE_MAC, NODE_IP, PEER_IP)
    udp = [Ether(f) for f in frames if Ether(f).type == 0x0800]
    assert len(udp) == len(case["sends"]) and len(frames) == len(udp) + len(requests) + 1
    for pkt, want in zip(udp, case["sends"]):
        ip = pkt[IP]
        assert (pkt.dst, pkt.src) == (PEER_MAC, NODE_MAC)
        assert (ip.src, ip.dst, ip.version, ip.ihl, ip.proto) == (NODE_IP, PEER_IP, 4, 5, 17)
        header = bytes(ip)[:20]
        assert sum(struct.unpack(">10H", header)) % 0xFFFF == 0, "bad IPv4 header checksum"
        payload = bytes.fromhex(want["data"])
        assert ip.len == 20 + 8 + len(payload)
        assert (ip[UDP].sport, ip[UDP].dport, ip[UDP].len) == \
            (want["sport"], want["dport"], 8 + len(payload))
        assert bytes(ip[UDP].payload)[:len(payload)] == payload


def cosimulate(tmp_path: Path, case: dict, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Run the bench on Verilator (Icarus never leaves time 0 on LiteX's Verilog: see
    tests.support.rtltools.cocotb_verilator); the build is kept in the lab's RTL cache, keyed
    by the sources, so a second run only simulates."""
    cocotb_verilator(monkeypatch)
    from cocotb_tools.runner import get_runner

    (tmp_path / "case.json").write_text(json.dumps(case))
    # Verilator's dependency files name the sources' and cocotb's absolute paths: a build made
    # from another clone or environment must not be reused (its make fails on paths now gone).
    import cocotb
    digest = hashlib.sha256(f"{cocotb.__file__} {simulator_version('verilator')}".encode())
    for path in SOURCES:
        digest.update(str(path).encode() + b"\0" + path.read_bytes() + b"\0")
    key = digest.hexdigest()[:20]
    build = cache_root() / f"cocotb-udp-{key}"
    runner = get_runner("verilator")
    runner.build(sources=SOURCES, hdl_toplevel="udp_gmii_top", build_dir=build,
                 timescale=("1ns", "1ps"), build_args=["-Wno-fatal", "-Wno-lint", "-Wno-style",
                                                       "-Wno-UNOPTFLAT"],
                 log_file=tmp_path / "build.log")
    run_bench(runner, "bench_udp_gmii_top", "udp_gmii_top", build, tmp_path,
              {"UDP_CASE": str(tmp_path / "case.json"),
               "UDP_OUT": str(tmp_path / "out.json")})
    return json.loads((tmp_path / "out.json").read_text())


@pytest.mark.parametrize("seed,gap,bp", [(1, 300, 300), (2, 0, 0)],
                         ids=["gaps-backpressure", "full-rate"])
def test_udp_stage_passes_exactly_the_good_payloads(seed: int, gap: int, bp: int,
                                                    tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))
    case = make_case(seed, 40, 6, gap, bp)
    out = cosimulate(tmp_path, case, monkeypatch)
    got = out["received"]
    assert [g["data"] for g in got] == [g["data"] for g in case["good"]]
    assert got == case["good"]
    assert out["counters"] == case["counts"]
    _check_sent(case, _frames(out["sent"]))


def make_fcs_case() -> dict:
    """Bad FCS at every frame length modulo 4 (the core's 32-bit words), padded and not, each
    frame followed by a good one: the core's word holding the FCS's last byte is shifted by the
    Ethernet header's 14 bytes, and its error must follow it (gen_liteeth.py, the
    depacketizer's error lanes)."""
    case = make_case(7, 0, 1, 0, 0)
    wire = [bytes.fromhex(f) for f in case["frames"][:2]]   # the two ARP requests
    good, counts = [], {**case["counts"], "rx_packets": 0, "rx_error": 0, "rx_length": 0,
                        "rx_header": 0, "rx_other": 0}
    for size in (1, 5, 18, 19, 20, 21, 100, 101, 102, 103):
        payload = bytes(range(size))
        bad = bytearray(_fcs(_udp(payload, sport=40000 + size)))
        bad[-1] ^= 0x80
        wire += [bytes(bad), _fcs(_udp(payload, sport=50000 + size))]
        good.append({"data": payload.hex(), "ip": int(ipaddress.IPv4Address(PEER_IP)),
                     "sport": 50000 + size, "dport": NODE_PORT, "length": size})
        counts["rx_packets"] += 1
        counts["rx_error"] += 1
    assert {len(f) % 4 for f in wire[2::2]} == {0, 1, 2, 3}
    return {**case, "frames": [f.hex() for f in wire], "good": good, "counts": counts}


def test_a_bad_fcs_is_caught_at_every_frame_length(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))
    case = make_fcs_case()
    out = cosimulate(tmp_path, case, monkeypatch)
    assert out["received"] == case["good"]
    assert out["counters"] == case["counts"]


def test_verilator_wall_is_silent_on_the_labs_files(tmp_path: Path) -> None:
    """Verilator -Wall says nothing about the lab's files (the vendored core's own warnings,
    generated code, are not the lab's to fix)."""
    verilator = require_verilator()
    done = subprocess.run([verilator, "--lint-only", "-Wall", "-Wno-fatal", "--timescale",
                           "1ns/1ps", "--top-module", "udp_gmii_top", *map(str, SOURCES)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    ours = [ln for ln in done.stderr.splitlines()
            if ln.startswith("%Warning") and "/vendor/" not in ln]
    assert done.returncode == 0 and ours == [], done.stderr[-3000:]
    done = subprocess.run([verilator, "--lint-only", "-Wall", str(FABRIC / "rfl_udp_store.v"),
                           str(FABRIC / "rfl_udp_port.v")], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-3000:]


@pytest.mark.parametrize("params,message", [
    ({"COUNT_BITS": 33}, "rfl_udp_port: COUNT_BITS must be 1..32"),
    ({"RX_BITS": 16}, "rfl_udp_store: ADDR_BITS must be 4..15"),
    ({"TX_BITS": 3}, "rfl_udp_store: ADDR_BITS must be 4..15"),
    ({"QUEUE_BITS": 0}, "rfl_udp_store: QUEUE_BITS must be 1..6"),
])
def test_verilator_refuses_an_illegal_port_parameter(params: dict[str, int], message: str,
                                                     tmp_path: Path) -> None:
    """rfl_udp_port's contracts (tests/rtl/test_house_rules.py compiles one file per module;
    this one needs rfl_udp_store beside it); the defaults pass."""
    verilator = require_verilator()
    files = [str(FABRIC / "rfl_udp_store.v"), str(FABRIC / "rfl_udp_port.v")]
    sets = [f"-G{k}={v}" for k, v in params.items()]
    done = subprocess.run([verilator, "--lint-only", "--top-module", "rfl_udp_port", *sets,
                           *files], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode != 0 and message in done.stderr, done.stderr[-3000:]
    done = subprocess.run([verilator, "--lint-only", "--top-module", "rfl_udp_port", *files],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
