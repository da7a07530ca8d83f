"""Bad input stays outside (issue #31 item 6): ``rfl_fabric_top`` (the generated top of
``data/fpga_laserscan_min_cdr.yaml`` inside) driven at its GMII side with malformed Ethernet,
IPv4, UDP and RTPS, one family after another, each followed by a good LaserScan sample (two
DATA_FRAG datagrams, tests/rtl/test_fabric_rtps_loop.py's) that must come out exact.

The families (the frames built here with scapy or by hand): a bad FCS, GMII rx_er in a frame,
truncated frames, a bad IPv4 header checksum, total length, version, header length, fragments and
protocol, bad UDP lengths, other ports, addresses and MACs, bad RTPS headers, unknown submessages
(alone, and inside a good sample), a DATA_FRAG flood (samples started and never completed,
fragments out of order and missing), spoofed GAP and HEARTBEAT (to the user-data and the
metatraffic ports, one with our own GUID prefix), an ACKNACK storm sent back to back.
Expected, from the lab's software and the modules' documented rules only: the user data
(``test_fabric_rtps_tx.expected``: the CDR models' output as the lab's RTPS builders send it,
writerSN 1, 2, .. one per good sample); the answers of the answer model (``rtl.discanswer``)
where timing does not matter; per family the counters that must move and those that must not
(rfl_udp_port's, rfl_rtps_rx's, the seam's, rfl_rtps_ctrl's: the bench reads them through the
hierarchy); and the bound on what the node sends, from the design's rules: the SPDP
announcement per PERIOD (one here), the answers at most ANSWER_BURST + ANSWER_RATE x the
metatraffic bytes received (rtl/limits.py), the user data at most rfl_rtps_tx's rule for each
sample the models publish. The Verilator build is test_fabric_top.py's (cached), the run some
20 s.
"""

from __future__ import annotations

import ipaddress
import struct
from pathlib import Path

import pytest
from scapy.layers.inet import IP, TCP, UDP
from scapy.layers.l2 import ARP, Ether

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discanswer import AnswerModel
from rosfpga_lab.rtl.discrom import fabric_participant, render_rom, tx_parameters, write_rom
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, SUB_READER, SUB_WRITER, discovery_multicast_port, discovery_port,
    user_port,
)
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES, SPDP_MULTICAST_ADDRESS
from rosfpga_lab.rtps.message import parse_message
from tests.rtl.test_fabric_rtps_cdr import CONFIG, MAX_BYTES
from tests.rtl.test_fabric_rtps_loop import TIME, published
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER, reference
from tests.rtl.test_fabric_rtps_tx import expected
from tests.rtl.test_fabric_top import NODE_IP, NODE_MAC, PEER, PEER_INDEX, PERIOD, _bad_fcs, _ip
from tests.rtl.test_fabric_udp import OTHER_IP, OTHER_MAC, PEER_IP, PEER_MAC, _fcs, _frames
from tests.support import fabrictop
from tests.support.rtltools import TB_DIR, cocotb_verilator

pytestmark = pytest.mark.rtl

IPV4_LENGTHS = ("IPv4 total length", "IPv4 fragments")   # refused by the generated core
SPDP, META, USER = discovery_multicast_port(0), discovery_port(0, 0), user_port(0, 0)
PEER_META, PEER_USER = discovery_port(0, PEER_INDEX), user_port(0, PEER_INDEX)
QUIET = 1500                                     # clocks waited after a group's frames
MAX_CLOCKS = 100_000                             # per group
STORM = 200                                      # ACKNACKs back to back
FLOOD = 30                                       # samples started and never completed
# rfl_rtps_tx's rule (its header): per datagram the header (20), INFO_TS (12) and DATA_FRAG's
# fields (36, the larger), per sample one HEARTBEAT (32)
TX_HEAD, TX_HEARTBEAT = 20 + 12 + 36, 32


def _eth_ip(payload: bytes, dport: int, **ip: object) -> bytes:
    """Ethernet/IPv4/UDP to the node, fields of the IPv4 header as given (scapy fills the rest:
    lengths and checksum computed unless given)."""
    return bytes(Ether(dst=NODE_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=NODE_IP, **ip) /
                 UDP(sport=40000, dport=dport) / payload)


def _patch_ip(frame: bytes, **fields: int) -> bytes:
    """``frame`` (Ethernet/IPv4) with IPv4 header fields changed and the checksum made good."""
    ip = IP(frame[14:])
    for k, v in fields.items():
        setattr(ip, k, v)
    ip.chksum = None
    raw = bytes(ip)
    head = raw[:ip.ihl * 4]
    return frame[:14] + head + frame[14 + len(head):]


def _with_seq(dg: bytes, seq: int) -> bytes:
    """A DATA_FRAG datagram of the sample with another writerSN (the sample's bytes the same)."""
    msg = parse_message(dg)
    frag = next(s for s in msg.submessages if type(s).__name__ == "DataFrag")
    out = bytearray(dg)
    out[frag.offset + 16:frag.offset + 24] = struct.pack("<iI", seq >> 32, seq & 0xFFFFFFFF)
    assert parse_message(bytes(out)).submessages[-1].seq == seq
    return bytes(out)


def _unknown(kind: int) -> bytes:
    """A submessage the walkers do not know (skipped by its length, RTPS 2.3 8.3.4.1)."""
    return bytes([kind, 0x01]) + struct.pack("<H", 8) + bytes(range(8))


class Family:
    """One family of bad input: its frames, the user datagrams and metatraffic that pass the UDP
    stage (for the models), the good samples it holds, the counters that must move."""

    def __init__(self, name: str, frames: list[bytes], user: list[bytes] = (),
                 meta: list[bytes] = (), samples: int = 0, moves: dict[str, int] | None = None,
                 errors: list[list[int]] = (), gap: int | None = 50, timed: bool = True,
                 then: dict[str, int] | None = None) -> None:
        self.name, self.frames, self.user, self.meta = name, frames, list(user), list(meta)
        self.then = then or {}                   # what the good sample after it moves too
        self.samples, self.moves, self.errors, self.gap = samples, moves or {}, errors, gap
        self.timed = timed                       # the answer model's answers are exact


def families(frags: list[bytes]) -> list[Family]:
    """The bad input, family by family."""
    good = frags[0]
    ack = b.header(PEER) + b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 1)
    whole = _eth_ip(good, USER)
    cut = whole[:len(whole) - 100]
    out = [Family("ethernet FCS", [_bad_fcs(_eth_ip(good, USER)), _bad_fcs(_eth_ip(ack, META))],
                  moves={"rx_error": 2})]
    # GMII rx_er on a payload byte (the FCS good): the PHY says the byte is wrong
    out.append(Family("GMII rx_er", [_fcs(whole)], errors=[[0, 8 + 14 + 20 + 8 + 100]],
                      moves={"rx_error": 1}))           # rfl_fabric_top makes its FCS fail
    out.append(Family("truncated", [
        _fcs(cut),                                           # lengths claim 100 more
        _fcs(whole[:14 + 12]),                               # a runt: the IPv4 header cut
        whole[:700],                                         # cut, no FCS
    ], moves={"rx_length": 1, "rx_error": 1, "rx_header": 1}))   # the runt padded: checksum
    # IPv4: dropped by LiteEth before the lab's port, said by its rx_drop_* pulses, counted by
    # rfl_udp_port: a bad header (cnt_rx_header), not for this node (cnt_rx_other)
    right = IP(whole[14:]).chksum
    out.append(Family("IPv4 header", [
        _fcs(_eth_ip(good, USER, chksum=right ^ 0x0100)),    # checksum
        _fcs(_patch_ip(whole, version=6)),                   # version
        _fcs(_patch_ip(whole, proto=6)),                     # protocol: TCP
        _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=NODE_IP) /
                   TCP(sport=40000, dport=USER) / good)),    # TCP to the user-data port
        _fcs(_eth_ip(good, USER, options=b"\x01\x01\x01\x00")),   # header length 6 (options)
    ], moves={"rx_header": 3, "rx_other": 2}))
    # the IPv4 total length, flags and fragment offset (IPV4_LENGTHS, read by the generator's
    # patches, LiteEth reads none): each carries the good sample's first DATA_FRAG, none of
    # them may reach the node; a frame shorter than its total length is cut (cnt_rx_length)
    out.append(Family("IPv4 total length", [
        _fcs(_patch_ip(whole, len=IP(whole[14:]).len + 64)),     # longer than the frame
        _fcs(_patch_ip(whole, len=IP(whole[14:]).len - 64)),     # shorter than the UDP length
        _fcs(_patch_ip(whole, len=16)),                          # shorter than its header
    ], moves={"rx_length": 1, "rx_header": 2}))
    # IPv4 fragments: not reassembled; a fragment is not a datagram
    second = bytes(UDP(sport=40000, dport=USER, len=8 + len(good), chksum=0)) + good
    out.append(Family("IPv4 fragments", [
        _fcs(_patch_ip(whole, flags=1)),                         # MF: the first of several
        _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) /
                   IP(src=PEER_IP, dst=NODE_IP, proto=17, frag=185) / second)),  # a later one
    ], moves={"rx_header": 2}))
    udp_at = 14 + 20

    def udp_len(n: int) -> bytes:
        raw = bytearray(whole)
        raw[udp_at + 4:udp_at + 6] = struct.pack(">H", n)
        return bytes(raw)
    out.append(Family("UDP length", [
        _fcs(udp_len(len(good) + 8 + 64)),                   # longer than the IPv4 payload
        _fcs(udp_len(4)),                                    # shorter than its header
        _fcs(udp_len(8)),                                    # empty
        _fcs(udp_len(8 + len(good) - 100)),                  # shorter: the payload cut to it
    ], user=[good[:len(good) - 100]], moves={"rx_header": 1, "rx_length": 2, "rx_packets": 1,
                                             "rtps_malformed": 1, "seam_dropped": 1}))
    out.append(Family("ports and addresses", [
        _fcs(_eth_ip(ack, SPDP + 1)),                        # LiteEth's mask passes it
        _fcs(_eth_ip(good, SPDP + 1)),
        _fcs(_eth_ip(ack, USER + 0x100)),                    # outside the mask
        _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=OTHER_IP) /
                   UDP(sport=40000, dport=USER) / good)),
        _fcs(bytes(Ether(dst=OTHER_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=NODE_IP) /
                   UDP(sport=40000, dport=USER) / good)),
    ], moves={"rx_packets": 2, "rx_port": 2, "rx_other": 3}))
    bad_hdr = [b"RTPX" + good[4:], good[:4] + b"\x01" + good[5:], good[:12]]
    bad_meta = [b"RTPX" + ack[4:], ack[:12]]     # rfl_rtps_ctrl ignores and counts them
    out.append(Family("RTPS header", [_fcs(_eth_ip(d, USER)) for d in bad_hdr] +
                      [_fcs(_eth_ip(d, META)) for d in bad_meta],
                      user=bad_hdr, meta=bad_meta,
                      moves={"rx_packets": 5, "rtps_packets": 3, "rtps_bad_header": 3,
                             "ctrl_bad_header": 2}))
    unknown = [b.header(PEER) + _unknown(0x33) + _unknown(0x80),
               b.header(PEER) + _unknown(0x7f)]
    inside = good[:20] + _unknown(0x33) + good[20:]            # a good sample with one inside
    out.append(Family("unknown submessages",
                      [_fcs(_eth_ip(unknown[0], USER)), _fcs(_eth_ip(unknown[1], META)),
                       _fcs(_eth_ip(inside, USER)), _fcs(_eth_ip(frags[1], USER))],
                      user=[unknown[0], inside, frags[1]], meta=[unknown[1]], samples=1,
                      moves={"rx_packets": 4, "rtps_packets": 3}))
    # DATA_FRAG flood: FLOOD samples started and left (each dropped when the next starts), a
    # fragment 3 with no start, then fragment 3 before 1 and a fragment 1 whose 3 never comes
    started = [_with_seq(good, 100 + k) for k in range(FLOOD)]
    rest = [_with_seq(frags[1], 500), frags[1], _with_seq(good, 600)]
    out.append(Family("DATA_FRAG flood", [_fcs(_eth_ip(d, USER)) for d in started + rest],
                      user=started + rest, gap=None,
                      moves={"rx_packets": FLOOD + 3, "rtps_packets": FLOOD + 3,
                             "seam_dropped": FLOOD},
                      then={"seam_dropped": 1}))
    # spoofed GAP and HEARTBEAT: to the user data (the reader keeps no history: nothing changes,
    # not even between a sample's fragments), to the metatraffic (a HEARTBEAT to our
    # publications reader is answered as the model says, one in our own name is dropped)
    user_spoof = [b.header(PEER) + b.gap(READER, WRITER, 1, 50),
                  b.header(PEER) + b.heartbeat(READER, WRITER, 1, 1000, 7)]
    meta_spoof = [b.header(PEER) + b.gap(SUB_READER, SUB_WRITER, 1, 9),
                  b.header(LOCAL) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 5, 3),
                  b.header(PEER) + b.heartbeat(PUB_READER, PUB_WRITER, 1, 3, 9)]
    out.append(Family("spoofed GAP and HEARTBEAT",
                      [_fcs(_eth_ip(d, USER)) for d in [good, *user_spoof, frags[1]]] +
                      [_fcs(_eth_ip(d, META)) for d in meta_spoof],
                      user=[good, *user_spoof, frags[1]], meta=meta_spoof, samples=1,
                      moves={"rx_packets": 7}))
    storm = [b.header(PEER) + b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 10 + k)
             for k in range(STORM)]
    out.append(Family("ACKNACK storm", [_fcs(_eth_ip(d, META)) for d in storm], meta=storm,
                      gap=None, timed=False, moves={"rx_packets": STORM}))
    return out


@pytest.fixture(scope="module")
def wire(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One run of every family, and what the test needs of the lab's software."""
    with pytest.MonkeyPatch.context() as monkeypatch:
        cocotb_verilator(monkeypatch)
        monkeypatch.syspath_prepend(str(TB_DIR))
        return _run(tmp_path_factory.mktemp("wire"))


def _run(tmp_path: Path) -> dict:
    """Every family and a good sample after each through the top; the run and the models."""
    from cocotb_tools.runner import get_runner

    gen = fabrictop.generate(CONFIG, tmp_path / "project")
    config = load_config(CONFIG)
    rom = render_rom(config, guid_prefix=LOCAL)
    write_rom(rom, tmp_path)
    part, _node, wid, _rid = fabric_participant(config, guid_prefix=LOCAL)
    reader_id = tx_parameters(rom)["READER_ID"]
    datagrams, payloads = published(5)
    frags, sample = datagrams[1:3], payloads[1]
    fams = families(frags)
    good = [_fcs(_eth_ip(d, USER)) for d in frags]

    groups, answers_model = [], AnswerModel(rom)
    n_samples, n_answers, timed_answers = 0, 0, []
    for fam in fams:
        for dg in fam.meta:
            got = answers_model.receive(dg)
            if fam.timed:
                timed_answers += [a.data for a in got]
                n_answers += len(got)
        n_samples += fam.samples + 1
        if fam.timed:
            want = 1 + 2 * n_samples + n_answers       # SPDP, two DATA_FRAGs a sample
        else:
            want = 0                                  # the storm: its answers are not predicted
        groups.append({"name": fam.name, "frames": [f.hex() for f in fam.frames],
                       "errors": fam.errors, "gap": fam.gap, "expect": 0, "quiet": QUIET})
        groups.append({"name": f"{fam.name}: good sample", "frames": [f.hex() for f in good],
                       "gap": 50, "expect": want, "samples": n_samples,
                       "quiet": QUIET if fam.timed else 20 * QUIET})
    reply = _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) /
                       ARP(op=2, hwsrc=PEER_MAC, psrc=PEER_IP, hwdst=NODE_MAC, pdst=NODE_IP)))
    case = {"node_mac": NODE_MAC.replace(":", ""), "node_ip": _ip(NODE_IP),
            "peer_ip": _ip(PEER_IP), "peer_meta_port": PEER_META, "peer_user_port": PEER_USER,
            "reader": READER, "writer": WRITER, "time": TIME, "arp_reply": reply.hex(),
            "groups": groups, "max_clocks": MAX_CLOCKS}
    runner = get_runner("verilator")
    build = fabrictop.build(runner, gen, fabrictop.top_parameters_of(rom, MAX_BYTES, PERIOD),
                            tmp_path)
    out = fabrictop.run(runner, build, "bench_rfl_fabric_top_wire", case, tmp_path,
                        "FABRIC_WIRE_CASE", "FABRIC_WIRE_OUT")
    return {"out": out, "fams": fams, "rom": rom, "sample": sample, "n_samples": n_samples,
            "timed_answers": timed_answers, "part": part, "wid": wid, "reader_id": reader_id}


@pytest.mark.timeout(900)
def test_bad_input_is_dropped_counted_and_the_next_sample_is_exact(wire: dict) -> None:
    out, fams, rom, sample = wire["out"], wire["fams"], wire["rom"], wire["sample"]
    n_samples, timed_answers = wire["n_samples"], wire["timed_answers"]
    part, wid, reader_id = wire["part"], wire["wid"], wire["reader_id"]

    sent = [Ether(f) for f in _frames([s["data"] for s in out["sent"]])]
    udp = [f for f in sent if f.type == 0x0800]
    assert all(f.haslayer(ARP) for f in sent if f.type != 0x0800)

    def to(port: int) -> list[bytes]:
        return [bytes(f[UDP].payload)[:f[UDP].len - 8] for f in udp
                if (f[IP].dst, f[UDP].dport) == (PEER_IP, port)]

    # every good sample exact, in order, writerSN 1, 2, ..; nothing else to the user port
    want_user = [d for dgs in expected([sample] * n_samples, [TIME] * n_samples, FRAGMENT_BYTES,
                                       True, MAX_BYTES, part.guid_prefix, wid, reader_id)
                 for d in dgs]
    assert to(PEER_USER) == want_user
    got_meta = to(PEER_META)
    assert got_meta[:len(timed_answers)] == timed_answers
    spdp = [f for f in udp if f[IP].dst == SPDP_MULTICAST_ADDRESS]
    assert len(spdp) == 1 and len(udp) == 1 + len(want_user) + len(got_meta)

    # per family: the counters that must move, by as much; the others stand still
    watched = ("rx_error", "rx_length", "rx_overflow", "rx_packets", "rx_port", "rx_header",
               "rx_other", "rtps_packets",
               "rtps_bad_header", "rtps_malformed", "rtps_repeated", "seam_dropped",
               "seam_too_long", "ctrl_malformed", "ctrl_bad_header", "tx_dropped", "tx_overflow")
    before = {k: 0 for k in watched}
    good_moves = {"rx_packets": 2, "rtps_packets": 2}
    for fam, (bad, after) in zip(fams, zip(out["groups"][::2], out["groups"][1::2])):
        delta = {k: bad["counters"][k] - before[k] for k in watched}
        want = {k: fam.moves.get(k, 0) for k in watched}
        if "rtps_packets" not in fam.moves:
            want["rtps_packets"] = len(fam.user)
        assert delta == want, fam.name
        walked, counts = reference(fam.user)
        assert (delta["rtps_bad_header"], delta["rtps_malformed"]) == \
            (counts["bad_header"], counts["malformed"]), fam.name
        delta = {k: after["counters"][k] - bad["counters"][k] for k in watched}
        assert delta == {k: good_moves.get(k, 0) + fam.then.get(k, 0) for k in watched}, \
            f"{fam.name}: good sample"
        before = after["counters"]
    last = out["groups"][-1]["counters"]
    assert last["samples"] == n_samples and last["rtps_dropped"] >= FLOOD + 1
    storm = out["groups"][-2]["counters"]
    assert storm["no_credit"] > 0 or storm["ctrl_busy"] > 0, "the storm met the limits"

    # the bound, at the end of each group, from the design's rules: SPDP + answers' credit +
    # rfl_rtps_tx's bytes for the samples the models publish
    sample_out = (len(b.pad_payload(sample)) + TX_HEARTBEAT +
                  TX_HEAD * -(-len(b.pad_payload(sample)) // FRAGMENT_BYTES))
    sizes = [len(bytes(f[UDP].payload)) if f.type == 0x0800 else 0 for f in sent]
    meta_in = samples_in = 0
    for fam, after in zip(fams, out["groups"][1::2]):
        meta_in += sum(map(len, fam.meta))
        samples_in += fam.samples + 1
        bound = len(rom.messages[0].data) + ANSWER_BURST + ANSWER_RATE * meta_in + \
            samples_in * sample_out
        assert sum(sizes[:after["sent"]]) <= bound, fam.name


def test_ipv4_lengths_and_fragments_are_dropped_at_the_ip_layer(wire: dict) -> None:
    groups = wire["out"]["groups"]
    names = [fam.name for fam in wire["fams"]]
    for name in IPV4_LENGTHS:
        k = names.index(name)
        before, after = groups[2 * k - 1]["counters"], groups[2 * k]["counters"]
        moved = {c: after[c] - before[c] for c in ("rx_packets", "rx_header", "rx_length")}
        frames = len(wire["fams"][k].frames)
        assert moved["rx_packets"] == 0 and moved["rx_header"] + moved["rx_length"] == frames, \
            (name, moved)


#: LaserScans sent back to back at line rate by the line-rate test (after a warm-up and one alone).
LINE_RATE_SAMPLES = 6
#: The share of the wire's bound (wire bytes a sample / 125 MB/s) the node must sustain: the
#: first sample's latency is in the measured span, the rest is at the wire's pace.
LINE_RATE_SHARE = 0.95


@pytest.mark.timeout(900)
def test_the_laserscan_keeps_up_with_gigabit_line_rate(tmp_path: Path) -> None:
    """Issue #31 item 5: LINE_RATE_SAMPLES LaserScans (data/fpga_laserscan_min_cdr.yaml, each
    two DATA_FRAGs) at the GMII side back to back at line rate (a byte a clock at 125 MHz, 8-byte
    preamble, 12-byte gap): every one comes out, the output exact, at the wire's pace (within
    LINE_RATE_SHARE of its bound). The generated circuit takes the next sample while it
    publishes the last (rfl_gsubscriber's two records): 1,597 clocks a 1,504-byte sample back to
    back, under the 1,772 wire bytes it comes in; with one record it took 3,120 and sustained
    39,962/s of the bound's 70,542/s (tests/benchmarks/bench_fabric_wire.py prints both)."""
    from tests.benchmarks.bench_fabric_wire import measure

    with pytest.MonkeyPatch.context() as monkeypatch:
        cocotb_verilator(monkeypatch)
        monkeypatch.syspath_prepend(str(TB_DIR))
        r = measure(CONFIG, LINE_RATE_SAMPLES, False, tmp_path)
    assert r["exact"]
    assert r["delivered"] == r["samples"] == LINE_RATE_SAMPLES, r["counters"]
    assert r["sustained_per_s"] >= LINE_RATE_SHARE * r["bound_per_s"], \
        (r["sustained_per_s"], r["bound_per_s"])
