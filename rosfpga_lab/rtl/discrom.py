"""The fabric participant's discovery ROM: what is known at build time is built at build time.

How this works: as the paper splits XML-RPC (the node's registration known at build time, the
data path in the circuit), the ROS 2 node in the fabric splits discovery. A configuration with
``wire: cdr`` fixes everything the node's SPDP and SEDP say: its GUID prefix, domain, participant
index (ports), address, node name, topics, DDS type names and type hashes. :func:`render_rom`
builds the same sans-IO :class:`~rosfpga_lab.rtps.participant.Participant` the software node
runs, with the same entities (:class:`~rosfpga_lab.rtps.rosnode.RosNodeEntities`: the
``ros_discovery_info`` writer, then the output topic's writer and the input topic's reader, in
``component.ros2.Ros2Component.start``'s order) and writes, with the lab's RTPS builders
(:mod:`rosfpga_lab.rtps.build`), the UDP payloads the circuit sends:

* ``spdp``: the participant's SPDP announcement, the bytes ``Participant.announce`` sends
  (destination :data:`DEST_SPDP`: the SPDP multicast port, or on a loopback graph the unicast
  discovery ports of indices 0..MAX_PARTICIPANT_INDEX, as the software participant probes);
* ``sedp``: what ``Participant`` sends a participant it has just learned (``spdp._greet``): the
  SEDP publications writer's DATA(w) (``ros_discovery_info``'s writer and the output topic's;
  the former with the metatraffic locator as its own, where the software node announces its
  user-data one, so a peer's ACKNACKs to it come where ``rfl_rtps_ctrl`` reads) and HEARTBEAT,
  the subscriptions writer's DATA(r) (the input topic's) and HEARTBEAT, and the built-in
  readers' preemptive ACKNACKs (destination :data:`DEST_META`: that participant's metatraffic
  unicast port);
* ``graph``: the ``ros_discovery_info`` sample (ParticipantEntitiesInfo: the node's name and its
  endpoints' GIDs) with its HEARTBEAT, to any reader of that participant (reader
  ENTITYID_UNKNOWN; destination :data:`DEST_USER`: its user-data unicast port; Fast DDS's
  readers announce a port of their own in their SEDP data, which the software participant sends
  to and the fabric's receive side must learn).

Run-time fields (each message's :class:`PatchPoint`): ``sedp`` and ``graph`` name their
destination in INFO_DST; the ROM holds GUIDPREFIX_UNKNOWN (zeros: any participant, which RTPS
readers accept), where the circuit may write the new participant's prefix. A HEARTBEAT's count
must rise for the same reader to act on it again: the ROM holds 1 (what a participant learned
for the first time gets), where the circuit writes its counter when it sends again. The built-in
readers' preemptive ACKNACKs hold base 1 (Cyclone DDS's form); Fast DDS answers only base 0 at
once (the software participant picks by the peer's vendor id), so their base is a patch point
too. The
``graph`` sample's INFO_TS (source time) holds 0 (as the SPDP's does: constant by design) where
the circuit may write its clock. Everything else is constant: sequence numbers (each built-in
writer's history is fixed at build time), lease, locators, QoS, names, hashes; the ACKNACK
counts (1 and 2: a new participant has seen none) too.

:func:`write_rom` writes one ``$readmemh`` file per message, the concatenated image
``rfl_rtps_disc_rom.hex`` and its message table ``rfl_rtps_disc_rom_table.hex`` (what
``fabric/rfl_rtps_disc_rom.v`` reads) and an index ``rfl_rtps_disc_rom.json`` (offsets,
lengths, destinations, patch points, and ``rfl_rtps_tx``: the transmit path's parameters).
:func:`tx_parameters` gives the transmit path (``fabric/rfl_rtps_tx.v``) the same participant's
GUID prefix and data writer id, so the data comes from the writer the ROM announces.

Answers (issue 31: the built-in writers are reliable): ``answers`` are the datagrams the circuit
sends when a peer asks (``fabric/rfl_rtps_ctrl.v`` watches the received datagrams and asks,
``fabric/rfl_rtps_disc_answer.v`` sends). One *slot* per entity that answers
(:class:`AnswerSlot`): the SEDP publications and subscriptions writers and the
``ros_discovery_info`` writer (an ACKNACK to them: a HEARTBEAT for a preemptive one, base 0, else
each sample it asks for that the writer holds, one datagram each: the DATA, then a HEARTBEAT of
the writer's whole history, as ``WriterSide._on_acknack`` sends; numbers past the last written
are ignored, never GAPped, as there; every number written is held: the histories are fixed at
build time, so no GAP is owed; one that asks for no held number with its base at or below the
last held gets the HEARTBEAT too, where the software writer sends nothing and relies on its
periodic HEARTBEATs, which the circuit has not), and the built-in SEDP readers (a HEARTBEAT without F to them:
the ACKNACK of a reader that has every sample, base last + 1, no bits, flag F, as
``ReaderSide._on_heartbeat`` sends when nothing is missing: the circuit needs no peer's SEDP data,
its reader takes the configured writer). Every answer starts with the header and INFO_DST, the
asker's GUID prefix written at :data:`ANSWER_DST_AT`; it ends with its count (HEARTBEAT's or
ACKNACK's, 4 bytes, little endian: the circuit's counter); an ACKNACK's base is written at
:data:`ANSWER_BASE_AT`. A slot's messages are consecutive: a writer's HEARTBEAT, then its DATA of
sequence numbers 1 .. last; a reader's ACKNACK. :func:`answer_params` gives the Verilog the slots
(parameters), :func:`write_rom` the answer ROM and its table (``ANSWER_FILE``,
``ANSWER_TABLE_FILE``: one entry a line, {flags[7:0] (bit 0: the base is written), dest[7:0],
offset[15:0], length[15:0]}).
"""

from __future__ import annotations

import ipaddress
import json
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.fabriccounters import counters_gap
from rosfpga_lab.rtl.limits import (
    ANSWER_BURST, ANSWER_RATE, FABRIC_MAX_DATAGRAM, MAX_ANSWER_SEQ, MAX_ANSWER_SLOTS,
    MAX_DISC_ROM_BYTES,
)
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.discovery import PL_CDR_BE, PL_CDR_LE
from rosfpga_lab.rtps.entities import (
    PUB_READER, PUB_WRITER, SPDP_WRITER, SUB_READER, SUB_WRITER, Qos, discovery_multicast_port,
    discovery_port, user_port,
)
from rosfpga_lab.rtps.limits import (
    ANNOUNCE_SECONDS, DEFAULT_LEASE_SECONDS, FRAGMENT_BYTES, MAX_LEASE_SECONDS, MAX_MESSAGE_BYTES,
    SPDP_MULTICAST_ADDRESS,
)
from rosfpga_lab.rtps.message import ANY_PARTICIPANT
from rosfpga_lab.rtps.participant import Participant
from rosfpga_lab.rtps.rosnode import RosNodeEntities, split_node_name

#: Destination codes (the stream's ``tdest``): the SPDP discovery port(s), the new participant's
#: metatraffic unicast port, its user-data unicast port.
DEST_SPDP, DEST_META, DEST_USER = 0, 1, 2
DEST_NAMES = {DEST_SPDP: "spdp", DEST_META: "metatraffic", DEST_USER: "user"}
#: Bits of a message table entry: destination (8), offset (16), length (16).
TABLE_BITS = 40
#: The GUID prefix of a ROM rendered without one: "rosfpga" and the fabric's mark, 12 bytes.
DEFAULT_FABRIC_PREFIX = b"\x01\x0frflFABRIC\x00"
#: The file names :func:`write_rom` writes (the Verilog's default ROM_FILE/TABLE_FILE).
ROM_FILE, TABLE_FILE, INDEX_FILE = ("rfl_rtps_disc_rom.hex", "rfl_rtps_disc_rom_table.hex",
                                    "rfl_rtps_disc_rom.json")
#: The answer ROM and its table (``fabric/rfl_rtps_disc_answer.v``'s default files).
ANSWER_FILE, ANSWER_TABLE_FILE = "rfl_rtps_disc_answer.hex", "rfl_rtps_disc_answer_table.hex"
#: Where every answer's run-time fields are: the asker's GUID prefix (INFO_DST's, after the
#: header and INFO_DST's submessage header) and an ACKNACK's base (after INFO_DST, the
#: ACKNACK's submessage header, readerId and writerId).
ANSWER_DST_AT = len(b.header(ANY_PARTICIPANT)) + 4
ANSWER_BASE_AT = ANSWER_DST_AT + len(ANY_PARTICIPANT) + 4 + 8
#: Bits of an answer table entry: flags (8), destination (8), offset (16), length (16).
ANSWER_TABLE_BITS = 48
#: Flag bit of an answer table entry: the ACKNACK's base is written at ANSWER_BASE_AT.
ANSWER_FLAG_BASE = 0x01
#: The first answer's count: above the ROM's own (HEARTBEAT 1, preemptive ACKNACKs 1 and 2),
#: so a peer acts on the answers (rfl_rtps_disc_answer's COUNT_START).
ANSWER_COUNT_START = 3


@dataclass(frozen=True)
class PatchPoint:
    """A field of a ROM message the circuit may overwrite when it sends: ``width`` bytes at
    ``offset`` in the message, and what goes there."""

    name: str
    offset: int
    width: int
    what: str


@dataclass(frozen=True)
class RomMessage:
    """One UDP payload of the ROM and where it goes (``dest``: a DEST_* code)."""

    name: str
    data: bytes
    dest: int
    patches: tuple[PatchPoint, ...] = ()


@dataclass(frozen=True)
class AnswerSlot:
    """An entity that answers: a writer (``last``: its last sequence number; its messages from
    ``message``: the HEARTBEAT, then DATA 1 .. last) or a built-in reader (``last`` 0; its
    message: the ACKNACK)."""

    name: str
    entity_id: int
    message: int
    last: int

    @property
    def writer(self) -> bool:
        return self.last > 0


@dataclass(frozen=True)
class DiscoveryRom:
    """The fabric participant's discovery messages and the facts they were built from."""

    messages: tuple[RomMessage, ...]
    guid_prefix: bytes
    domain: int
    index: int
    address: str
    entity_ids: dict[str, int] = field(default_factory=dict)
    answers: tuple[RomMessage, ...] = ()
    slots: tuple[AnswerSlot, ...] = ()

    def message(self, name: str) -> RomMessage:
        return next(m for m in self.messages if m.name == name)

    def image(self) -> bytes:
        """The messages one after the other, as the ROM holds them."""
        return b"".join(m.data for m in self.messages)

    def answer_image(self) -> bytes:
        """The answers one after the other, as the answer ROM holds them."""
        return b"".join(m.data for m in self.answers)

    def offsets(self, answers: bool = False) -> list[int]:
        out, at = [], 0
        for m in (self.answers if answers else self.messages):
            out.append(at)
            at += len(m.data)
        return out

    def ports(self) -> dict[str, object]:
        """The destinations' ports: the SPDP multicast group and port, the unicast discovery
        ports a loopback graph probes, this participant's own metatraffic and user ports."""
        return {"spdp_multicast": [SPDP_MULTICAST_ADDRESS, discovery_multicast_port(self.domain)],
                "spdp_unicast": sorted({d[1] for d in _announce_ports(self)}),
                "own_metatraffic": discovery_port(self.domain, self.index),
                "own_user": user_port(self.domain, self.index)}

    def index_json(self) -> dict[str, object]:
        def listed(messages: tuple[RomMessage, ...], offsets: list[int]) -> list[object]:
            return [{"name": m.name, "offset": off, "length": len(m.data), "dest": m.dest,
                     "dest_name": DEST_NAMES[m.dest],
                     "patches": [{"name": p.name, "offset": p.offset, "width": p.width,
                                  "what": p.what} for p in m.patches]}
                    for m, off in zip(messages, offsets)]

        return {"guid_prefix": self.guid_prefix.hex(), "domain": self.domain, "index": self.index,
                "address": self.address, "ports": self.ports(), "entity_ids": {
                    k: f"{v:08x}" for k, v in self.entity_ids.items()},
                "rfl_rtps_tx": verilog_parameters(tx_parameters(self)),
                "rfl_fabric_top": verilog_parameters(top_parameters(self)),
                "rom_file": ROM_FILE, "table_file": TABLE_FILE,
                "rom_bytes": len(self.image()),
                "messages": listed(self.messages, self.offsets()),
                "answer_file": ANSWER_FILE, "answer_table_file": ANSWER_TABLE_FILE,
                "answers": listed(self.answers, self.offsets(answers=True)),
                "slots": [{"name": s.name, "entity_id": f"{s.entity_id:08x}",
                           "message": s.message, "last": s.last} for s in self.slots]}


def _announce_ports(rom: DiscoveryRom) -> list[tuple[str, int, bytes]]:
    return Participant(rom.domain, rom.index, rom.address, guid_prefix=rom.guid_prefix).announce()


def fabric_participant(config: NodeConfig, *, domain: int = 0, index: int = 0,
                       address: str = "127.0.0.1", guid_prefix: bytes = DEFAULT_FABRIC_PREFIX,
                       qos_in: Qos = Qos(), qos_out: Qos = Qos()
                       ) -> tuple[Participant, RosNodeEntities, int, int]:
    """The sans-IO participant of ``config``'s node as the software node builds it (the same
    entities, in the same order; its ``ros_discovery_info`` writer on the metatraffic locator):
    the participant, its node entities, the output writer's and the input reader's entity ids."""
    if config.wire != "cdr":
        raise RtlError(f"{config.path or 'configuration'}: wire is {config.wire!r}: the "
                       f"fabric's discovery ROM is for a ROS 2 node (set wire: cdr)")
    if len(guid_prefix) != 12:
        raise RtlError(f"GUID prefix of {len(guid_prefix)} bytes: it has 12")
    try:
        ipaddress.IPv4Address(address)
    except ValueError:
        raise RtlError(f"address {address!r} is not an IPv4 address (the locators are UDPv4)") \
            from None
    namespace, name = split_node_name(config.node.global_name)
    p = Participant(domain, index, address, name, guid_prefix=guid_prefix)
    # the ros_discovery_info writer announces the metatraffic locator: its readers' ACKNACKs
    # come where rfl_rtps_ctrl reads (rfl_fabric_top gives the user-data port to the data path)
    node = RosNodeEntities(p, name, namespace, graph_locator=p.meta)
    reg = config.registry()
    wid = node.add_publisher(config.publisher.topic, config.publisher.type, qos_out, reg)
    rid = node.add_subscriber(config.subscriber.topic, config.subscriber.type, qos_in, reg)
    return p, node, wid, rid


class _Message:
    """A message being written: its submessages and where each field the circuit patches is."""

    def __init__(self, prefix: bytes) -> None:
        self.data = bytearray(b.header(prefix))
        self.patches: list[PatchPoint] = []

    def add(self, sub: bytes, patch: tuple[str, int, int, str] | None = None) -> None:
        if patch is not None:
            name, at, width, what = patch
            self.patches.append(PatchPoint(name, len(self.data) + at, width, what))
        self.data += sub


def _dst(msg: _Message) -> None:
    msg.add(b.info_dst(ANY_PARTICIPANT), ("info_dst", 4, 12, "the destination participant's "
                                          "GUID prefix (zeros: any participant)"))


def _heartbeat(msg: _Message, reader: int, writer: int, last: int, what: str) -> None:
    msg.add(b.heartbeat(reader, writer, 1, last, 1),
            (f"hb_count_{what}", 4 + 24, 4, f"the HEARTBEAT count of {what} (1: first sent; must "
             f"rise for a reader to act on a HEARTBEAT again)"))


def _answer(prefix: bytes, subs: list[bytes], name: str, dest: int, count_what: str,
            base: bool = False) -> RomMessage:
    """One answer: header, INFO_DST (the asker's prefix written), ``subs`` (the last one ends
    with its count, written)."""
    msg = _Message(prefix)
    _dst(msg)
    for sub in subs[:-1]:
        msg.add(sub)
    last = subs[-1]
    if base:
        msg.patches.append(PatchPoint("acknack_base", ANSWER_BASE_AT, 8, "the ACKNACK's base: "
                                      "the HEARTBEAT's last + 1 (every sample here)"))
    msg.patches.append(PatchPoint("count", len(msg.data) + len(last) - 4, 4, f"the {count_what} "
                                  f"count (the circuit's answer counter)"))
    msg.data += last
    return RomMessage(name, bytes(msg.data), dest, tuple(msg.patches))


def render_answers(p: Participant, node: RosNodeEntities
                   ) -> tuple[tuple[RomMessage, ...], tuple[AnswerSlot, ...]]:
    """The answers of ``p``'s reliable built-in writers, its ``ros_discovery_info`` writer and
    its built-in SEDP readers, and their slots (the module docstring says what each is)."""
    writers = [(PUB_WRITER, PUB_READER, "publications", DEST_META,
                list(p.local[PUB_WRITER].history.values())),
               (SUB_WRITER, SUB_READER, "subscriptions", DEST_META,
                list(p.local[SUB_WRITER].history.values())),
               (node.graph_writer, 0, "ros_discovery_info", DEST_USER, [node.entities_info()])]
    answers: list[RomMessage] = []
    slots: list[AnswerSlot] = []
    for writer, reader, what, dest, history in writers:
        if not 1 <= len(history) <= MAX_ANSWER_SEQ:
            raise RtlError(f"the {what} writer holds {len(history)} samples: the circuit "
                           f"resends 1 .. {MAX_ANSWER_SEQ}")
        slots.append(AnswerSlot(what, writer, len(answers), len(history)))
        hb = b.heartbeat(reader, writer, 1, len(history), 1)
        answers.append(_answer(p.guid_prefix, [hb], f"{what}_hb", dest, "HEARTBEAT"))
        for seq, payload in enumerate(history, 1):
            answers.append(_answer(p.guid_prefix, [b.data(reader, writer, seq,
                                                          b.pad_payload(payload)), hb],
                                   f"{what}_{seq}", dest, "HEARTBEAT"))
    for reader, writer, what in ((PUB_READER, PUB_WRITER, "publications"),
                                 (SUB_READER, SUB_WRITER, "subscriptions")):
        slots.append(AnswerSlot(f"{what}_reader", reader, len(answers), 0))
        answers.append(_answer(p.guid_prefix, [b.acknack(reader, writer, 1, [], 1, final=True)],
                               f"{what}_ack", DEST_META, "ACKNACK", base=True))
    if len(slots) > MAX_ANSWER_SLOTS:
        raise RtlError(f"{len(slots)} answering entities: the circuit compares "
                       f"{MAX_ANSWER_SLOTS}")
    return tuple(answers), tuple(slots)


def answer_params(rom: DiscoveryRom) -> dict[str, int | str]:
    """The Verilog parameters of ``rom``'s answers: ``fabric/rfl_rtps_ctrl.v``'s slots (ids,
    first messages, last sequence numbers, slot 0 in the low bits) and
    ``fabric/rfl_rtps_disc_answer.v``'s ROM sizes and patch offsets."""
    n = len(rom.slots)
    ids = sum(s.entity_id << (32 * i) for i, s in enumerate(rom.slots))
    msgs = sum(s.message << (8 * i) for i, s in enumerate(rom.slots))
    lasts = sum(s.last << (8 * i) for i, s in enumerate(rom.slots))
    return {"SLOTS": n, "SLOT_IDS": f"{32 * n}'h{ids:x}", "SLOT_MSGS": f"{8 * n}'h{msgs:x}",
            "SLOT_LASTS": f"{8 * n}'h{lasts:x}", "ANSWER_BYTES": len(rom.answer_image()),
            "ANSWERS": len(rom.answers), "DST_AT": ANSWER_DST_AT, "BASE_AT": ANSWER_BASE_AT,
            "COUNT_START": ANSWER_COUNT_START, "BURST": ANSWER_BURST, "RATE": ANSWER_RATE}


def render_rom(config: NodeConfig | str | Path, *, domain: int = 0, index: int = 0,
               address: str = "127.0.0.1", guid_prefix: bytes = DEFAULT_FABRIC_PREFIX,
               qos_in: Qos = Qos(), qos_out: Qos = Qos()) -> DiscoveryRom:
    """The discovery ROM of ``config``'s ROS 2 node in the fabric (participant ``index`` of DDS
    ``domain`` at ``address``, GUID prefix ``guid_prefix``: all fixed at build time)."""
    if not isinstance(config, NodeConfig):
        config = load_config(config)
    p, node, wid, rid = fabric_participant(config, domain=domain, index=index, address=address,
                                           guid_prefix=guid_prefix, qos_in=qos_in,
                                           qos_out=qos_out)
    spdp = p.announce()[0][2]
    sedp = _Message(p.guid_prefix)
    _dst(sedp)
    for writer, reader, what in ((PUB_WRITER, PUB_READER, "publications"),
                                 (SUB_WRITER, SUB_READER, "subscriptions")):
        ep = p.local[writer]
        for seq, payload in ep.history.items():
            sedp.add(b.data(reader, writer, seq, b.pad_payload(payload)))
        _heartbeat(sedp, reader, writer, ep.seq, what)
    for count, (reader, writer, what) in enumerate(((PUB_READER, PUB_WRITER, "publications"),
                                                    (SUB_READER, SUB_WRITER, "subscriptions")),
                                                   1):
        sedp.add(b.acknack(reader, writer, 1, [], count),
                 (f"acknack_base_{what}", 4 + 8, 8, f"the preemptive ACKNACK's base to the "
                  f"peer's {what} writer: 1, or 0 for Fast DDS (vendor 0x010F), which answers "
                  f"only that form at once (as spdp._on_spdp picks)"))
    graph = _Message(p.guid_prefix)
    _dst(graph)
    graph.add(b.info_ts(0.0), ("info_ts", 4, 8, "the source time (0: none, as the SPDP's)"))
    graph.add(b.data(0, node.graph_writer, 1, b.pad_payload(node.entities_info())))
    _heartbeat(graph, 0, node.graph_writer, 1, "ros_discovery_info")
    messages = (RomMessage("spdp", spdp, DEST_SPDP),
                RomMessage("sedp", bytes(sedp.data), DEST_META, tuple(sedp.patches)),
                RomMessage("graph", bytes(graph.data), DEST_USER, tuple(graph.patches)))
    for m in messages:
        if len(m.data) > MAX_MESSAGE_BYTES:
            raise RtlError(f"discovery message {m.name} of {len(m.data)} bytes: more than one "
                           f"datagram ({MAX_MESSAGE_BYTES})")
    answers, slots = render_answers(p, node)
    rom = DiscoveryRom(messages, p.guid_prefix, domain, index, address,
                       {"ros_discovery_info": node.graph_writer, "writer": wid, "reader": rid},
                       answers, slots)
    for what, size in (("discovery ROM", len(rom.image())),
                       ("answer ROM", len(rom.answer_image()))):
        if size > MAX_DISC_ROM_BYTES:
            raise RtlError(f"{what} of {size} bytes: the table addresses {MAX_DISC_ROM_BYTES}")
    return rom


def answer_flags(message: RomMessage) -> int:
    """The flags of an answer's table entry: ANSWER_FLAG_BASE for an ACKNACK (its base written)."""
    return ANSWER_FLAG_BASE if any(p.name == "acknack_base" for p in message.patches) else 0


def readmemh(data: bytes) -> str:
    """Bytes as a ``$readmemh`` file: one byte (two hex digits) a line."""
    return "".join(f"{x:02x}\n" for x in data)


def table_readmemh(rom: DiscoveryRom) -> str:
    """The message table: one entry a line, {dest[7:0], offset[15:0], length[15:0]}."""
    return "".join(f"{m.dest:02x}{off:04x}{len(m.data):04x}\n"
                   for m, off in zip(rom.messages, rom.offsets()))


def answer_table_readmemh(rom: DiscoveryRom) -> str:
    """The answer table: one entry a line, {flags[7:0], dest[7:0], offset[15:0], length[15:0]}."""
    return "".join(f"{answer_flags(m):02x}{m.dest:02x}{off:04x}{len(m.data):04x}\n"
                   for m, off in zip(rom.answers, rom.offsets(answers=True)))


def write_rom(rom: DiscoveryRom, out_dir: str | Path) -> list[Path]:
    """Write the ROM files into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {ROM_FILE: readmemh(rom.image()), TABLE_FILE: table_readmemh(rom),
             INDEX_FILE: json.dumps(rom.index_json(), indent=1) + "\n",
             ANSWER_FILE: readmemh(rom.answer_image()),
             ANSWER_TABLE_FILE: answer_table_readmemh(rom)}
    for m in rom.messages:
        files[f"rfl_rtps_disc_{m.name}.hex"] = readmemh(m.data)
    paths = []
    for name, text in files.items():
        (out / name).write_text(text)
        paths.append(out / name)
    return paths


def tx_parameters(rom: DiscoveryRom, *, frag_bytes: int = FRAGMENT_BYTES,
                  max_datagram: int = FABRIC_MAX_DATAGRAM, info_ts: bool = True,
                  reader_id: int = 0) -> dict[str, int]:
    """The Verilog parameters of ``fabric/rfl_rtps_tx.v`` (the transmit path) for the participant
    ``rom`` was rendered for: its GUID prefix and its data writer's entity id (one owner: the
    same :func:`fabric_participant` the ROM announces), the DATA_FRAG fragment size (default the
    software participant's), the largest datagram, INFO_TS on or off and the reader id
    (0: ENTITYID_UNKNOWN, every reader of the topic)."""
    return {"GUID_PREFIX": int.from_bytes(rom.guid_prefix, "big"),
            "WRITER_ID": rom.entity_ids["writer"], "READER_ID": reader_id,
            "FRAG_BYTES": frag_bytes, "MAX_DATAGRAM": max_datagram, "INFO_TS": int(info_ts)}


def spdp_parameters() -> dict[str, int]:
    """The constants of ``fabric/rfl_spdp_peer.v`` (the circuit learns its peer from SPDP), from
    the software participant's owners: the SPDP writer's entity id
    (:mod:`rosfpga_lab.rtps.entities`), the parameter ids (status info, for a goodbye;
    sentinel, lease, default and metatraffic unicast locators) and the UDPv4 locator kind
    (:mod:`rosfpga_lab.rtps.build`), the parameter lists' encapsulations
    (:mod:`rosfpga_lab.rtps.discovery`), the lease when none is announced and its cap in
    seconds (:mod:`rosfpga_lab.rtps.limits`)."""
    pids = (b.PID_STATUS_INFO, b.PID_SENTINEL, b.PID_PARTICIPANT_LEASE_DURATION,
            b.PID_DEFAULT_UNICAST_LOCATOR, b.PID_METATRAFFIC_UNICAST_LOCATOR)
    return {"SPDP_WRITER_ID": SPDP_WRITER,
            "SPDP_PIDS": sum(pid << (16 * (len(pids) - 1 - i)) for i, pid in enumerate(pids)),
            "SPDP_ENCAPS": int.from_bytes(PL_CDR_BE + PL_CDR_LE, "big"),
            "SPDP_LOCATOR_KIND": b.LOCATOR_KIND_UDPV4,
            "SPDP_LEASE_DEFAULT": round(DEFAULT_LEASE_SECONDS),
            "SPDP_LEASE_MAX": round(MAX_LEASE_SECONDS)}


#: The counter readout's port past the domain's SPDP multicast port: within the domain's range
#: of ports, one the RTPS mapping gives no participant (its offsets are 0, 1, 10 + 2i, 11 + 2i).
COUNTERS_PORT_OFFSET = 8


def counters_port(domain: int) -> int:
    """The UDP port the fabric node's counter readout answers on in ``domain`` (7408 in domain
    0; ``fabric/rfl_counter_readout.v``, :mod:`rosfpga_lab.rtl.fabriccounters`)."""
    return discovery_multicast_port(domain) + COUNTERS_PORT_OFFSET


def top_parameters(rom: DiscoveryRom) -> dict[str, int]:
    """The network parameters of ``fabric/rfl_fabric_top.v`` for the participant ``rom`` was
    rendered for (one owner: the RTPS port mapping of :mod:`rosfpga_lab.rtps.entities` and the
    SPDP group of :mod:`rosfpga_lab.rtps.limits`, as :meth:`DiscoveryRom.ports` names them; the
    counter readout's port, :func:`counters_port`), and its SPDP learner's constants
    (:func:`spdp_parameters`)."""
    return {"SPDP_PORT": discovery_multicast_port(rom.domain),
            "META_PORT": discovery_port(rom.domain, rom.index),
            "USER_PORT": user_port(rom.domain, rom.index),
            "COUNTERS_PORT": counters_port(rom.domain),
            "SPDP_GROUP": int(ipaddress.IPv4Address(SPDP_MULTICAST_ADDRESS)),
            **spdp_parameters()}


#: Bits of the parameters of :func:`tx_parameters` and :func:`top_parameters` that are not Verilog
#: integers.
TX_PARAMETER_BITS = {"GUID_PREFIX": 96, "WRITER_ID": 32, "READER_ID": 32, "SPDP_GROUP": 32,
                     "SPDP_WRITER_ID": 32, "SPDP_PIDS": 80, "SPDP_ENCAPS": 32,
                     "SPDP_LOCATOR_KIND": 32}


def verilog_parameters(params: dict[str, int]) -> dict[str, str]:
    """Parameters as Verilog literals (``-G``/``-P``/``chparam`` values): the GUID prefix and
    the entity ids sized hex (96 bits do not fit an integer), the others decimal."""
    return {k: f"{TX_PARAMETER_BITS[k]}'h{v:x}" if k in TX_PARAMETER_BITS else str(v)
            for k, v in params.items()}


def node_parameters(rom: DiscoveryRom, *, period: int) -> dict[str, str]:
    """``fabric/rfl_fabric_node.v``'s parameters (``rfl_fabric_node_params.vh``) as Verilog
    literals for the participant ``rom`` was rendered for: the transmit path's
    (:func:`tx_parameters`), the discovery ROM's and answer ROM's files (:func:`write_rom` writes
    them) and sizes, SPDP every ``period`` clocks, the answers' slots (:func:`answer_params`).
    ``rfl_fabric_top`` takes these and :func:`top_parameters`."""
    if period < 1:
        raise RtlError(f"SPDP period of {period} clocks: it must be at least 1")
    if ANNOUNCE_SECONDS != 1.0:     # rfl_fabric_top counts a peer's lease in PERIODs
        raise RtlError(f"ANNOUNCE_SECONDS is {ANNOUNCE_SECONDS}: rfl_spdp_peer's second is a "
                       "PERIOD of clocks")
    return {**verilog_parameters(tx_parameters(rom)), "PERIOD": str(period),
            "ROM_FILE": f'"{ROM_FILE}"', "TABLE_FILE": f'"{TABLE_FILE}"',
            "ROM_BYTES": str(len(rom.image())), "MESSAGES": str(len(rom.messages)),
            "ANSWER_FILE": f'"{ANSWER_FILE}"', "ANSWER_TABLE_FILE": f'"{ANSWER_TABLE_FILE}"',
            **{k: str(v) for k, v in answer_params(rom).items()}}


def fabric_top_literals(rom: DiscoveryRom, *, period: int) -> dict[str, str]:
    """``fabric/rfl_fabric_top.v``'s parameters as Verilog literals: the node's
    (:func:`node_parameters`), the ports (:func:`top_parameters`) and the counter readout's gap
    (a second of ``period`` clocks, :func:`~rosfpga_lab.rtl.fabriccounters.counters_gap`); the
    board top, the simulated top, the demo and the tests take them from here."""
    return {**node_parameters(rom, period=period), **verilog_parameters(top_parameters(rom)),
            "COUNTERS_GAP": str(counters_gap(period))}
