"""The fabric participant answers ACKNACK and HEARTBEAT (issue 31, item 2): ``rfl_rtps_ctrl``
into ``rfl_rtps_disc_answer``, the metatraffic side of ``rfl_fabric_node``, under cocotb
(tests/rtl/bench_rfl_rtps_ctrl.py), datagrams built with the lab's RTPS encoders
(``rtps.build``; big-endian ones by swapping their fields).

What holds it:
* each answer the circuit sends is the model's (``rtl.discanswer``: the lab's decoder and the
  rendered ROM), byte for byte, in order, under backpressure; the cases and what each must
  answer are written here (the kinds of answer), not computed by the model;
* the answers are what the software participant (``rtps.Participant`` with the fabric's
  entities, after a whole discovery with a software peer) sends for the same ACKNACK or
  HEARTBEAT: the same DATA bytes, the same HEARTBEAT range, the same ACKNACK (base, bits,
  flags), only the counts differ (each its own counter);
* malformed ACKNACKs (numBits > 256, cut short, fields missing) are dropped and counted;
* a flood of ACKNACKs: at every clock the bytes sent are at most BURST + RATE x the bytes
  received (the bench asserts it), the answers it could not afford counted.
"""

from __future__ import annotations

import select
import struct
import threading
import time
from pathlib import Path

import pytest

from rosfpga_lab.rtl.discanswer import AnswerModel
from rosfpga_lab.rtl.discrom import (
    DEST_META, DiscoveryRom, answer_params, fabric_participant, render_rom,
)
from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import PUB_READER, PUB_WRITER, SUB_READER, SUB_WRITER
from rosfpga_lab.rtps.message import AckNack, Data, Heartbeat, InfoDst, parse_message
from rosfpga_lab.rtps.participant import Participant
from tests.rtl.test_fabric_rtps_rx import _swap
from tests.support.fabrictools import generate_project, run_fabric_node
from tests.support.rtltools import TB_DIR

pytestmark = pytest.mark.rtl

DATA_DIR = Path(__file__).resolve().parents[2] / "data"
CONFIG = DATA_DIR / "fpga_samples_dilate_cdr.yaml"
PEER, PEER2 = bytes.fromhex("010fcafe0000000100000001"), bytes.fromhex("0110beef0000000200000007")
USER_READER = 0x00000504
IDLE = 1500           # clocks after a datagram: its answers (at most ~800 bytes) go out
PERIOD = 100_000_000  # one SPDP announcement (at reset) in a run


@pytest.fixture(autouse=True)
def _bench_on_path(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))        # cocotb imports the bench by name


def _rom() -> DiscoveryRom:
    return render_rom(CONFIG)


def _dg(prefix: bytes, *subs: bytes, dst: bytes | None = None) -> bytes:
    return b.header(prefix) + (b.info_dst(dst) if dst is not None else b"") + b"".join(subs)


def cosimulate(rom: DiscoveryRom, datagrams: list[tuple[bytes, int]], tmp_path: Path,
               bp: int = 300, seed: int = 1, **credit: int) -> dict:
    """The circuit's answers (dest, prefix, bytes) and counters for ``datagrams`` (each with the
    idle clocks after it) as metatraffic into ``rfl_fabric_node`` (its discovery ROM's one SPDP
    announcement left out); ``credit``: BURST and RATE other than the lab's."""
    params = {**answer_params(rom), **credit}
    case = {"seed": seed, "bp": bp, "burst": params["BURST"], "rate": params["RATE"],
            "datagrams": [[d.hex(), idle] for d, idle in datagrams]}
    gen = generate_project(CONFIG, tmp_path / "project")
    return run_fabric_node(gen, rom, case, tmp_path, period=PERIOD, bench="bench_rfl_rtps_ctrl",
                           **{k: str(v) for k, v in credit.items()})


def _cases(rom: DiscoveryRom) -> list[tuple[str, bytes, list[str]]]:
    """(what, datagram, the answers it must get, by name)."""
    me, graph = rom.guid_prefix, rom.entity_ids["ros_discovery_info"]
    return [
        ("Cyclone's ACKNACK for both DATA(w)", _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1,
                                                                   [1, 2], 1), dst=me),
         ["publications_1", "publications_2"]),
        ("Fast DDS's preemptive ACKNACK (base 0)",
         _dg(PEER, b.acknack(SUB_READER, SUB_WRITER, 0, [], 1), dst=me), ["subscriptions_hb"]),
        ("ros_discovery_info: 1 held, 5 never written (ignored, no GAP)",
         _dg(PEER, b.acknack(USER_READER, graph, 1, [1, 5], 2)), ["ros_discovery_info_1"]),
        ("Cyclone's preemptive ACKNACK (base 1, no bits)",
         _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1, [], 1), dst=me), ["publications_hb"]),
        ("an ACKNACK acknowledging all: nothing", _dg(PEER, b.acknack(PUB_READER, PUB_WRITER,
                                                                      3, [], 3), dst=me), []),
        ("HEARTBEAT to the publications reader", _dg(PEER, b.heartbeat(PUB_READER, PUB_WRITER,
                                                                       1, 3, 4), dst=me),
         ["publications_ack"]),
        ("HEARTBEAT with F: nothing", _dg(PEER, b.heartbeat(PUB_READER, PUB_WRITER, 1, 3, 5,
                                                            final=True), dst=me), []),
        ("HEARTBEAT to ENTITYID_UNKNOWN from the subscriptions writer",
         _dg(PEER, b.heartbeat(0, SUB_WRITER, 1, 7, 6)), ["subscriptions_ack"]),
        ("big-endian ACKNACK, INFO_SRC another participant",
         _dg(PEER, b.info_src(PEER2), _swap(b.acknack(PUB_READER, PUB_WRITER, 2, [2], 7)),
             dst=me), ["publications_2"]),
        ("for another participant: nothing",
         _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1, [1], 8), dst=PEER2), []),
        ("our own, looped back: nothing", _dg(me, b.acknack(PUB_READER, PUB_WRITER, 1, [1], 9)),
         []),
        ("two ACKNACKs in one datagram", _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 2, [2], 10),
                                             b.acknack(SUB_READER, SUB_WRITER, 1, [1], 10),
                                             dst=me), ["publications_2", "subscriptions_1"]),
    ]


def _malformed(rom: DiscoveryRom) -> list[bytes]:
    """ACKNACKs the circuit must drop and count: numBits 300, cut by the datagram's end, its
    body too short for its fields."""
    ok = b.acknack(PUB_READER, PUB_WRITER, 1, [1], 11)
    big = bytearray(ok)
    big[20:24] = struct.pack("<I", 300)
    short = bytearray(ok[:24])
    short[2:4] = struct.pack("<H", 20)
    return [_dg(PEER, bytes(big), dst=rom.guid_prefix), _dg(PEER, ok, dst=rom.guid_prefix)[:-4],
            _dg(PEER, bytes(short), dst=rom.guid_prefix) + bytes(4)]


def _bad_headers() -> list[bytes]:
    """Datagrams the circuit must ignore and count as bad headers: another magic, RTPS major
    version 1, shorter than the 20-byte header (each an ACKNACK the circuit would answer)."""
    ok = _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1, [1], 12))
    return [b"RTPX" + ok[4:], ok[:4] + b"\x01" + ok[5:], ok[:12]]


def test_the_circuit_answers_as_the_model_and_drops_malformed(tmp_path: Path) -> None:
    rom = _rom()
    cases, bad, bad_hdr = _cases(rom), _malformed(rom), _bad_headers()
    empty = b.header(PEER)                      # a message of no submessages: not bad
    datagrams = [(d, IDLE) for _, d, _ in cases] + [(d, IDLE) for d in bad] + \
        [(d, IDLE) for d in [*bad_hdr, empty]]
    got = cosimulate(rom, datagrams, tmp_path)
    model = AnswerModel(rom)
    want = []
    for (what, dg, names), _ in zip(cases, datagrams):
        answers = model.receive(dg)
        assert [rom.answers[i].name for i in _names(rom, answers)] == names, what
        want += answers
    for dg in [*bad, *bad_hdr, empty]:
        assert model.receive(dg) == []
    assert [(a["dest"], bytes.fromhex(a["prefix"]), bytes.fromhex(a["data"]))
            for a in got["answers"]] == [(a.dest, a.prefix, a.data) for a in want]
    for a in got["answers"]:
        parse_message(bytes.fromhex(a["data"]))         # each parses whole
    assert got["cnt_malformed"] == len(bad)
    assert got["cnt_bad_header"] == 3       # not the empty message, nor our own looped back
    assert got["cnt_answers"] == len(want) and got["cnt_busy"] == 0
    assert got["cnt_no_credit"] == 0


def _names(rom: DiscoveryRom, answers: list) -> list[int]:
    """Which ROM answer each one is (equal to it outside the fields the circuit writes)."""
    def blank(m, data: bytes) -> bytes:
        out = bytearray(data)
        for p in m.patches:
            out[p.offset:p.offset + p.width] = bytes(p.width)
        return bytes(out)

    return [next(i for i, m in enumerate(rom.answers)
                 if len(m.data) == len(a.data) and blank(m, m.data) == blank(m, a.data))
            for a in answers]


# ---- the software participant's answers -------------------------------------------------------
def _software_pair(whole: bool) -> tuple[Participant, Participant]:
    """The fabric's participant in software and a software peer: after the peer's SPDP only
    (``whole`` False: its readers have acknowledged nothing yet) or a whole discovery."""
    p, node, _w, _r = fabric_participant(load_config(CONFIG))
    p.write(node.graph_writer, node.entities_info())
    peer = Participant(0, 1, "127.0.0.1", "peer", guid_prefix=PEER)
    peer.add_writer("rt/a", "std_msgs::msg::dds_::String_")
    peer.add_reader("rt/b", "std_msgs::msg::dds_::String_")
    if not whole:
        p.receive(peer.announce()[0][2], ("127.0.0.1", 7412), 1.0)
        return p, peer
    queue = [(p, p.announce()[0][2]), (peer, peer.announce()[0][2])]     # (sender, datagram)
    for _ in range(200):
        if not queue:
            break
        sender, dg = queue.pop(0)
        target = peer if sender is p else p
        queue += [(target, d) for *_a, d in target.receive(dg, ("127.0.0.1", 7400), 1.0)]
    return p, peer


def _subs(datagrams: list[bytes]) -> list:
    return [s for d in datagrams for s in parse_message(d).submessages]


@pytest.mark.parametrize("ask", ["both DATA(w)", "preemptive", "HEARTBEAT"])
def test_the_answers_are_the_software_participants(ask: str) -> None:
    """The ACKNACKs come from a peer whose readers have acknowledged nothing yet (one that has
    acknowledged samples and asks them again gets a GAP from the software writer, which keeps
    each reader's state, and the samples again from the circuit, which keeps none: both are
    RTPS, the circuit's bounded by its credit); the HEARTBEAT after a whole discovery (the
    software reader has every sample: it acknowledges all, as the circuit does)."""
    rom = _rom()
    me = rom.guid_prefix
    p, peer = _software_pair(whole=ask == "HEARTBEAT")
    datagram = {"both DATA(w)": _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 50),
                                    dst=me),
                "preemptive": _dg(PEER, b.acknack(SUB_READER, SUB_WRITER, 0, [], 51), dst=me),
                "HEARTBEAT": _dg(PEER, b.heartbeat(PUB_READER, PUB_WRITER, 1,
                                                   peer.local[PUB_WRITER].seq, 52), dst=me)}[ask]
    soft = _subs([d for *_a, d in p.receive(datagram, ("127.0.0.1", 7412), 10.0)])
    hard = _subs([a.data for a in AnswerModel(rom).receive(datagram)])
    # the circuit sends one datagram per sample (its INFO_DST and HEARTBEAT each), the software
    # one datagram: the same submessages, once each, in the same order
    hard = [h for i, h in enumerate(hard) if h not in hard[:i] or not isinstance(h, InfoDst)]
    hard = [h for i, h in enumerate(hard) if not (isinstance(h, Heartbeat) and i + 1 < len(hard))]
    assert soft and [type(s) for s in soft] == [type(s) for s in hard], (soft, hard)
    for s, h in zip(soft, hard):
        if isinstance(s, Data):
            assert (s.reader_id, s.writer_id, s.seq, s.payload) == \
                   (h.reader_id, h.writer_id, h.seq, h.payload)
        elif isinstance(s, Heartbeat):
            assert (s.reader_id, s.writer_id, s.first, s.last, s.flags) == \
                   (h.reader_id, h.writer_id, h.first, h.last, h.flags)
        elif isinstance(s, AckNack):
            assert (s.reader_id, s.writer_id, s.base, s.missing, s.flags) == \
                   (h.reader_id, h.writer_id, h.base, h.missing, h.flags)
        else:
            assert s.guid_prefix == h.guid_prefix == PEER


@pytest.mark.parametrize("burst,rate,idle", [(ANSWER_BURST, ANSWER_RATE, 0), (1024, 1, 100)],
                         ids=["lab-credit", "small-credit"])
def test_a_flood_of_acknacks_stays_within_the_bound(burst: int, rate: int, idle: int,
                                                    tmp_path: Path) -> None:
    """200 ACKNACK datagrams (52 bytes each, asking both DATA(w): ~710 bytes of answers), back
    to back or ``idle`` clocks apart: the bench checks sent <= BURST + RATE x received at every
    clock. Back to back with the lab's credit, the output's byte a clock limits first (requests
    find their slot pending: dropped, counted); spaced, with a small credit, the credit does
    (answers it cannot afford: counted)."""
    rom = _rom()
    ask = _dg(PEER, b.acknack(PUB_READER, PUB_WRITER, 1, [1, 2], 1))
    got = cosimulate(rom, [(ask, idle)] * 200, tmp_path, bp=0, seed=3, BURST=burst, RATE=rate)
    assert got["received"] == 200 * len(ask)
    assert got["sent"] <= burst + rate * got["received"]
    assert got["sent"] > burst                # it did answer, past the first burst
    assert got["cnt_busy"] > 0 and got["cnt_requests"] + got["cnt_busy"] == 200
    assert (got["cnt_no_credit"] > 0) == (rate == 1)


@pytest.mark.parametrize("module,proof_mode,good,bad", [
    ("rfl_rtps_disc_answer.v", "bmc", "(cred >= entry[15:0]) &&",
     "1'b1 &&"),                                        # answers without the credit
    ("rfl_rtps_ctrl.v", "prove", "assign rx_byte = take;",
     "assign rx_byte = take && !tl;"),                  # a datagram's last byte earns no credit
], ids=["answer-without-credit", "ctrl-credit-short"])
def test_a_planted_bug_fails_the_proof(module: str, proof_mode: str, good: str, bad: str,
                                       tmp_path: Path) -> None:
    """The formal checks of the answer path (rtl.proofs; that they pass is
    tests/rtl/test_formal.py's) fail on planted bugs: on the wrapper's assertions or on the
    module's own (its FORMAL block: the answers' byte bound with its invariants)."""
    from rosfpga_lab.rtl.proofs import FABRIC_DIR, PROOFS, prove
    from tests.support.rtltools import require_formal

    require_formal()
    name = module[len("rfl_"):-len(".v")]
    proof = next(p for p in PROOFS if p.name == name and p.mode == proof_mode)
    src = (FABRIC_DIR / module).read_text()
    planted = src.replace(good, bad)
    assert planted != src
    (tmp_path / module).write_text(planted)
    failed = prove(proof, replace={module: tmp_path / module})
    assert failed.status == "FAIL" and any(f"fv_{name}.sv" in f or f.startswith(f"{module}:")
                                           for f in failed.failed), failed.log[-3000:]


# ---- Cyclone DDS on loopback, the circuit's answers played by the model -----------------------
class AnsweringSender:
    """The circuit on UDP sockets, its logic the model's (``rtl.discanswer``, the Verilog's
    tables): SPDP every PERIOD to the discovery ports a loopback graph probes, and every
    datagram received on its two ports answered as rfl_rtps_ctrl and rfl_rtps_disc_answer
    answer it, to the asker's metatraffic or user port (learned from its SPDP). The SEDP and
    ros_discovery_info datagrams are never sent unasked (``send_sedp`` unused, no periodic
    re-send): a peer gets them only by ACKNACK. Runs on a thread until closed."""

    PERIOD = 0.5

    def __init__(self, domain: int) -> None:
        from tests.rtl.test_discrom import PREFIX, _bind_free_index

        self.index, self.meta, self.user = _bind_free_index(domain)
        self.rom = render_rom(CONFIG, domain=domain, index=self.index, guid_prefix=PREFIX)
        self.model = AnswerModel(self.rom)
        self.peers: dict[bytes, tuple[int, int]] = {}
        self.answered: list[str] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from tests.rtl.test_discrom import _peer_locators

        last = -1.0
        while not self._stop.is_set():
            if time.monotonic() - last > self.PERIOD:
                last = time.monotonic()
                for port in self.rom.ports()["spdp_unicast"]:
                    self.meta.sendto(self.rom.message("spdp").data, ("127.0.0.1", port))
            ready, _, _ = select.select([self.meta, self.user], [], [], 0.05)
            for sock in ready:
                try:
                    datagram, _ = sock.recvfrom(65536)
                except OSError:
                    continue
                ports = _peer_locators(datagram)
                if ports is not None:
                    self.peers[datagram[8:20]] = ports
                for a in self.model.receive(datagram):
                    if a.prefix in self.peers:
                        port = self.peers[a.prefix][0 if a.dest == DEST_META else 1]
                        self.meta.sendto(a.data, ("127.0.0.1", port))
                        self.answered.append(_names_of(self.rom, a))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.meta.close()
        self.user.close()


def _names_of(rom: DiscoveryRom, answer) -> str:
    return rom.answers[_names(rom, [answer])[0]].name


@pytest.mark.timeout(30)
def test_cyclone_matches_through_the_answers_alone() -> None:
    """Cyclone DDS (as rmw_cyclonedds configures it on loopback) learns the fabric participant's
    publication, subscription and ros_discovery_info sample though the circuit never sends its
    SEDP unasked: Cyclone's readers' preemptive ACKNACKs get the writers' HEARTBEATs, their
    ACKNACKs the DATA."""
    from tests.rtl.test_discrom import PREFIX, _require_cyclonedds
    from tests.support.ros2tools import DOMAIN, cyclone, wait

    builtin, dds = _require_cyclonedds()
    types = cyclone()
    sender = AnsweringSender(DOMAIN)
    try:
        dp = dds.DomainParticipant(DOMAIN)
        P = types.Policy
        graph = types.DataReader(dp, types.Topic(dp, "ros_discovery_info",
                                                 types.ParticipantEntitiesInfo_),
                                 qos=types.Qos(P.Reliability.Reliable(1_000_000_000),
                                               P.Durability.TransientLocal, P.History.KeepLast(1)))
        infos: list = []
        readers = {name: builtin.BuiltinDataReader(dp, topic) for name, topic in (
            ("publication", builtin.BuiltinTopicDcpsPublication),
            ("subscription", builtin.BuiltinTopicDcpsSubscription))}
        seen: dict[str, list] = {name: [] for name in readers}
        ours = {"publication": "rt/samples_dilated", "subscription": "rt/samples"}

        def found() -> bool:
            for name, r in readers.items():
                seen[name] += r.take(N=64)
            infos.extend(graph.take(N=8))
            return bool(infos) and all(any(s.key.bytes[:12] == PREFIX and s.topic_name == topic
                                           for s in seen[name]) for name, topic in ours.items())

        assert wait(found, 10.0), (sender.answered, {k: len(v) for k, v in seen.items()})
        # what it took: HEARTBEATs for the preemptive ACKNACKs, then the DATA asked for
        assert {"publications_hb", "subscriptions_hb", "publications_1", "publications_2",
                "subscriptions_1", "ros_discovery_info_1"} <= set(sender.answered), \
            sender.answered
        assert sender.model.no_credit == 0
        dp = None
    finally:
        sender.close()
