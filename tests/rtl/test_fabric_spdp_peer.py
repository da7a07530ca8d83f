"""The fabric participant learns its one peer from SPDP (issue 31 item 2): ``rfl_spdp_peer``
under cocotb and Icarus (tests/rtl/bench_rfl_spdp_peer.py), fed SPDP announcements built with
the lab's RTPS builders (``rtps.build.spdp_payload``: what the software participant announces),
one written big-endian here by hand, and hostile ones; its constants from
``rtl.discrom.spdp_parameters`` (the software's owners).

What holds it (the expected peers are the locators written into the announcements here, never
read back from the circuit): the first participant's UDPv4 metatraffic and default locators
are taken (a UDPv6 locator before them skipped; the first UDPv4 one, or the first at the
address its datagram came from) and send_sedp pulses at once and
RESEND clocks later; a second participant, and a flood of 20 more, while the peer lives are
counted, never taken, no pulse; our own announcement (looped back) is ignored; a newer
announcement of the peer with another port updates it (two pulses again); after the peer's
lease (announced 1000 s, capped at rtps.limits.MAX_LEASE_SECONDS, TICK clocks a second) another
participant takes the place, not before, and after the peer's goodbye at once (another's
goodbye changes nothing; a real Cyclone DDS participant's announcement and goodbye likewise);
cut parameter lists, a huge parameter length, a
locator of another kind only, an unknown encapsulation and a short octetsToInlineQos are
refused and counted; two pulses per peer change, no more.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from rosfpga_lab.rtl.discrom import spdp_parameters, verilog_parameters
from rosfpga_lab.rtl.proofs import FABRIC_DIR, SPDP_PEER
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import SPDP_READER, SPDP_WRITER
from rosfpga_lab.rtps.limits import MAX_LEASE_SECONDS
from tests.support.rtltools import require_cocotb, require_iverilog

pytestmark = pytest.mark.rtl

HERE = Path(__file__).resolve().parent
OWN = bytes.fromhex("010f7266 6c464142 52494300".replace(" ", ""))
A = bytes.fromhex("010fcafe0000000100000001")
B = bytes.fromhex("010fbeef0000000200000002")
TICK, RESEND, IDLE = 20, 50, 120
#: The IPv4 source of a participant's datagrams (by GUID prefix; others 0.0.0.0).
SOURCES = {A: "10.1.2.3", B: "10.1.2.99"}
LEASE_CLOCKS = (int(MAX_LEASE_SECONDS) + 1) * TICK     # A's 1000 s lease, capped


def spdp(prefix: bytes, meta: list[tuple[int, int, str]], user: list[tuple[int, int, str]],
         lease: float = 1000.0, little: bool = True) -> bytes:
    """An SPDP datagram of participant ``prefix``: the lab's announcement (``spdp_payload``)
    when each list is one UDPv4 locator; else the same parameters with the locators given
    ((kind, port, address) each, in order), little- or big-endian, written here."""
    if little and len(meta) == len(user) == 1 and meta[0][0] == user[0][0] == 1:
        payload = b.spdp_payload(prefix, b.Locator(meta[0][2], meta[0][1]),
                                 b.Locator(user[0][2], user[0][1]), lease, "peer", b"", 0)
    else:
        o = "<" if little else ">"

        def loc(kind: int, port: int, addr: str) -> bytes:
            return struct.pack(o + "iI", kind, port) + bytes(12) + bytes(
                int(x) for x in addr.split("."))

        params = [(b.PID_PARTICIPANT_GUID, prefix + b"\x00\x00\x01\xc1")]
        params += [(b.PID_METATRAFFIC_UNICAST_LOCATOR, loc(*x)) for x in meta]
        params += [(b.PID_DEFAULT_UNICAST_LOCATOR, loc(*x)) for x in user]
        params += [(b.PID_PARTICIPANT_LEASE_DURATION, struct.pack(o + "iI", int(lease), 0))]
        body = (b"\x00\x03" if little else b"\x00\x02") + b"\x00\x00"
        for pid, value in params:
            body += struct.pack(o + "HH", pid, len(value)) + value
        payload = body + struct.pack(o + "HH", b.PID_SENTINEL, 0)
    return b.header(prefix) + b.info_ts(1.0) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)


def goodbye(prefix: bytes) -> bytes:
    """The software participant's goodbye (``rtps.spdp``'s): disposed and unregistered in the
    inline QoS, the key only."""
    guid = prefix + b"\x00\x00\x01\xc1"
    qos = b.inline_qos([(b.PID_KEY_HASH, guid), (b.PID_STATUS_INFO, b"\x00\x00\x00\x03")])
    key = b.param_list([(b.PID_PARTICIPANT_GUID, guid)])
    return b.header(prefix) + b.info_ts(0.0) + b.data(SPDP_READER, SPDP_WRITER, 2, key, qos)


def _ip(addr: str) -> int:
    return int.from_bytes(bytes(int(x) for x in addr.split(".")), "big")


def _run(datagrams: list[tuple[bytes, int]], tmp_path: Path, tick: int = TICK) -> dict:
    require_iverilog()
    require_cocotb()
    import cocotb_tools.runner as runner_mod

    params: dict[str, object] = {k: v for k, v in spdp_parameters().items()}
    params.update(TICK=tick, RESEND=RESEND)
    runner = runner_mod.get_runner("icarus")
    runner.build(sources=[FABRIC_DIR / m for m in SPDP_PEER], includes=[FABRIC_DIR],
                 hdl_toplevel="rfl_spdp_peer",
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"), parameters=params)
    (tmp_path / "case.json").write_text(json.dumps(
        {"prefix": OWN.hex(),
         "datagrams": [[d.hex(), idle, _ip(SOURCES.get(d[8:20], "0.0.0.0"))]
                       for d, idle in datagrams]}))
    results = runner.test(hdl_toplevel="rfl_spdp_peer", test_module="bench_rfl_spdp_peer",
                          test_dir=HERE, build_dir=tmp_path / "build",
                          results_xml=str(tmp_path / "results.xml"),
                          extra_env={"SPDP_PEER_CASE": str(tmp_path / "case.json"),
                                     "SPDP_PEER_OUT": str(tmp_path / "out.json")})
    assert runner_mod.get_results(results)[1] == 0, f"the bench failed: {tmp_path / 'build'}"
    return json.loads((tmp_path / "out.json").read_text())


def test_the_circuit_learns_its_peer_from_spdp_and_refuses_the_rest(tmp_path: Path) -> None:
    assert verilog_parameters(spdp_parameters())["SPDP_PIDS"] == "80'h710001000200310032"
    # UDPv6 first: skipped; then the first UDPv4 one, but a later one at the sender's address
    # (A sends from 10.1.2.3) taken instead, and not the one after it
    good_a = spdp(A, [(2, 7410, "0.0.0.0"), (1, 9999, "10.9.9.9"), (1, 7412, "10.1.2.3"),
                      (1, 7777, "10.1.2.3")], [(1, 7413, "10.1.2.3")])
    a_lab = spdp(A, [(1, 7412, "10.1.2.3")], [(1, 7415, "10.1.2.4")])  # the lab's builder
    whole = spdp(B, [(1, 7414, "10.1.2.5")], [(1, 7415, "10.1.2.5")])
    cut = whole[:-12]                                           # no sentinel, ends early
    # the DATA's length says so too (after the header and INFO_TS: 32 bytes)
    cut = cut[:34] + struct.pack("<H", len(cut) - 36) + cut[36:]
    huge = bytearray(whole)
    at = huge.index(struct.pack("<HH", b.PID_METATRAFFIC_UNICAST_LOCATOR, 24))
    huge[at + 2:at + 4] = struct.pack("<H", 0xFFF0)
    v6_only = spdp(B, [(2, 7414, "0.0.0.0")], [(1, 7415, "10.1.2.5")])
    bad_enc = bytearray(whole)
    bad_enc[bad_enc.index(b"\x00\x03\x00\x00")] = 0x7F
    short_q = bytearray(whole)
    d_at = 20 + 12
    short_q[d_at + 6:d_at + 8] = struct.pack("<H", 8)         # octetsToInlineQos 8
    flood = [(spdp(bytes([1, 15]) + i.to_bytes(10, "big"), [(1, 8000 + i, "10.2.0.1")],
                   [(1, 9000 + i, "10.2.0.1")]), 0) for i in range(20)]
    b_be = spdp(B, [(1, 7420, "10.1.2.6")], [(1, 7421, "10.1.2.7")], lease=1000, little=False)
    own = spdp(OWN, [(1, 7410, "127.0.0.1")], [(1, 7411, "127.0.0.1")])
    seq = [(cut, IDLE), (bytes(huge), IDLE), (v6_only, IDLE), (bytes(bad_enc), IDLE),
           (bytes(short_q), IDLE), (own, IDLE),
           (good_a, IDLE), (whole, IDLE), *flood, (b"", 0), (a_lab, IDLE)]
    seq = [x for x in seq if x[0]]
    # the lease from A's last announcement: B before it ends is another, after it the peer
    seq += [(b_be, LEASE_CLOCKS - 2 * TICK - 300), (b_be, 300 + 2 * TICK + IDLE), (b_be, IDLE)]
    # goodbyes: another's (nothing), then the peer's: the next announcement takes the place
    seq += [(goodbye(A), IDLE), (a_lab, IDLE), (goodbye(B), IDLE), (a_lab, IDLE)]
    out = _run(seq, tmp_path)
    pulses = [(p["clock"], p["peer"]) for p in out["pulses"]]
    ends = out["ends"]
    a1 = [1, _ip("10.1.2.3"), 7412, _ip("10.1.2.3"), 7413]
    a2 = [1, _ip("10.1.2.3"), 7412, _ip("10.1.2.4"), 7415]
    b1 = [1, _ip("10.1.2.6"), 7420, _ip("10.1.2.7"), 7421]
    assert [p for _, p in pulses] == [a1, a1, a2, a2, b1, b1, a2, a2], pulses
    i_a, i_a2, i_b = 6, 6 + 2 + 20, 6 + 2 + 20 + 2
    firsts = [pulses[0][0] - ends[i_a], pulses[2][0] - ends[i_a2], pulses[4][0] - ends[i_b]]
    assert all(0 < d <= 4 for d in firsts), firsts               # at the announcement's end
    assert [pulses[k + 1][0] - pulses[k][0] for k in (0, 2, 4)] == [RESEND] * 3
    assert pulses[6][0] - ends[-1] in range(1, 5)
    assert out["peer"] == a2
    # learned A, A's new port, B, A after B's goodbye; refused: cut, huge, UDPv6 only,
    # encapsulation, short octetsToInlineQos; others: B and the flood while A lived, B once more
    # before A's lease ended, A while B lived (the goodbyes: none of these)
    assert out["counters"] == [4, 5, 1 + 20 + 1 + 1], out["counters"]


CYCLONE_DOMAIN = 227


def test_a_cyclone_dds_participants_spdp_and_goodbye_are_learned(tmp_path: Path) -> None:
    """A real Cyclone DDS participant (PyPI cyclonedds, configured as the fabric's peers are:
    ``fabric_peer_uri``) announces itself to the discovery port of participant index 0, bound
    here first, and says goodbye when it is deleted; both datagrams, captured, go to the
    circuit from 127.0.0.1: the peer it learns is the first UDPv4 metatraffic and default
    locators the lab's software decoder reads in the announcement
    (``rtps.discovery.parse_parameters``, ``rtps.build.Locator.decode``); another participant
    (B) is refused while Cyclone's lives, and taken at once after Cyclone's own goodbye
    (its status info, read here with ``rtps.build``'s ids, disposed and unregistered)."""
    import socket

    from rosfpga_lab.rtps.discovery import PL_CDR_BE, PL_CDR_LE, parse_parameters
    from rosfpga_lab.rtps.entities import discovery_port
    from rosfpga_lab.rtps.message import Data, parse_message
    from tests.support.fabricpeer import fabric_participant

    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", discovery_port(CYCLONE_DOMAIN, 0)))
    sock.settimeout(15)
    try:
        proc = fabric_participant(CYCLONE_DOMAIN, 2, lease_seconds=7)
    except BaseException:
        sock.close()
        raise
    announce: tuple[bytes, bytes, Data] | None = None
    bye = None
    try:
        while bye is None:
            raw, source = sock.recvfrom(65536)
            for prefix, _dst, sub in parse_message(raw).routed():
                if not (isinstance(sub, Data) and sub.writer_id == SPDP_WRITER):
                    continue
                status = parse_parameters(
                    (PL_CDR_LE if sub.flags & 1 else PL_CDR_BE) + b"\0\0" + sub.inline_qos
                ).get(b.PID_STATUS_INFO) if sub.inline_qos else None
                if status and status[0][3] & 3 == 3:
                    bye = raw
                elif announce is None and sub.payload:
                    announce = (raw, prefix, sub)
    finally:
        sock.close()
        proc.wait(timeout=30)
    assert announce is not None, "Cyclone's goodbye came before any announcement"
    raw, prefix, data = announce
    little = data.payload[:2] == PL_CDR_LE
    params = parse_parameters(data.payload)

    def first(pid: int) -> list[int]:
        loc = next(x for x in (b.Locator.decode(v, little) for v in params[pid]) if x)
        return [_ip(loc.address), loc.port]

    SOURCES[prefix] = source[0]
    b_lab = spdp(B, [(1, 7420, "10.1.2.6")], [(1, 7421, "10.1.2.7")])
    # a second is 20 TICKs here: Cyclone's 7 s lease (over 2,800 clocks) outlasts the run up to
    # B's second announcement, so only Cyclone's goodbye can free the place for B
    tick = 20 * TICK
    assert len(raw) + 2 * len(b_lab) + len(bye) + 5 * IDLE < 7 * tick
    out = _run([(raw, 2 * IDLE), (b_lab, IDLE), (bye, 2 * IDLE), (b_lab, 2 * IDLE)], tmp_path,
               tick)
    want = [1, *first(b.PID_METATRAFFIC_UNICAST_LOCATOR), *first(b.PID_DEFAULT_UNICAST_LOCATOR)]
    b1 = [1, _ip("10.1.2.6"), 7420, _ip("10.1.2.7"), 7421]
    assert [p["peer"] for p in out["pulses"]] == [want, want, b1, b1]
    assert out["peer"] == b1
    assert out["counters"] == [2, 0, 1]          # learned Cyclone's, then B's; B once refused
    (tmp_path / "cyclone_spdp.bin").write_bytes(raw)


def test_at_most_one_peer_change_a_second(tmp_path: Path) -> None:
    """A second of 1000 clocks: the peer's new locators a few hundred clocks after it was taken
    are counted, not taken (no SEDP); its next announcement after the second has ended takes
    them: at most two SEDP sets a second, whatever comes in."""
    first = spdp(A, [(1, 7412, "10.1.2.3")], [(1, 7413, "10.1.2.3")])
    moved = spdp(A, [(1, 7412, "10.1.2.3")], [(1, 7999, "10.1.2.3")])
    out = _run([(first, 100), (moved, 1200), (moved, 100)], tmp_path, tick=1000)
    a1 = [1, _ip("10.1.2.3"), 7412, _ip("10.1.2.3"), 7413]
    a2 = [1, _ip("10.1.2.3"), 7412, _ip("10.1.2.3"), 7999]
    assert [p["peer"] for p in out["pulses"]] == [a1, a1, a2, a2]
    assert out["pulses"][2]["clock"] > out["ends"][2] > out["pulses"][0]["clock"] + 1000
    assert out["counters"] == [2, 0, 1]
