"""The fabric's discovery ROM (``rosfpga_lab.rtl.discrom``, issue 31 item 2): its payloads parse
into the submessages a ROS 2 participant's discovery needs, equal what the software participant
sends for the same configuration and GUID prefix, and a real DDS (PyPI cyclonedds, configured as
rmw_cyclonedds configures it on loopback) discovers the participant, its topics and type names
from the ROM's bytes alone, sent from a plain UDP socket as the circuit sends them.
"""

from __future__ import annotations

import json
import os
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from tests.support.realros import skip_or_fail
from rosfpga_lab.config import load_config
from rosfpga_lab.msg.typehash import type_hash
from rosfpga_lab.rtl.discrom import (
    DEST_META, DEST_SPDP, DEST_USER, INDEX_FILE, ROM_FILE, TABLE_FILE, render_rom, tx_parameters,
    verilog_parameters, write_rom,
)
from rosfpga_lab.rtps import Data, Heartbeat, parse_message, parse_parameters
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.participant import Participant
from rosfpga_lab.rtps.rosnode import RosNodeEntities
from rosfpga_lab.rtps.limits import MAX_PARTICIPANT_INDEX
from tests.support.ros2tools import CYCLONE_CONFIG, DOMAIN, cyclone, wait

DATA = Path(__file__).resolve().parents[2] / "data"
CONFIG = DATA / "fpga_samples_dilate_cdr.yaml"
PREFIX = bytes.fromhex("0110aabbccddeeff00112233")
PEER = bytes.fromhex("01100102030405060708090a")


def _strings(payload: bytes) -> dict[int, list[bytes]]:
    return parse_parameters(payload)


def _octets(value: bytes) -> bytes:
    """A sequence<octet> parameter value's bytes (without the count and the padding)."""
    (n,) = struct.unpack("<I", value[:4])
    return value[4:4 + n]


def test_rom_messages_parse_into_spdp_sedp_and_graph() -> None:
    rom = render_rom(CONFIG, domain=7, index=3, guid_prefix=PREFIX)
    spdp, sedp, graph = (parse_message(m.data) for m in rom.messages)
    assert [m.dest for m in rom.messages] == [DEST_SPDP, DEST_META, DEST_USER]
    assert spdp.header.guid_prefix == sedp.header.guid_prefix == PREFIX
    (sub,) = [s for s in spdp.submessages if isinstance(s, Data)]
    params = _strings(sub.payload)
    assert (sub.writer_id, sub.reader_id, sub.seq) == (0x000100C2, 0x000100C7, 1)
    assert params[b.PID_PARTICIPANT_GUID][0] == PREFIX + bytes.fromhex("000001c1")
    meta = b.Locator.decode(params[b.PID_METATRAFFIC_UNICAST_LOCATOR][0])
    user = b.Locator.decode(params[b.PID_DEFAULT_UNICAST_LOCATOR][0])
    # RTPS 2.3 9.6.1.1: 7400 + 250 * domain + 10 (11) + 2 * index
    assert (meta, user) == (b.Locator("127.0.0.1", 7400 + 1750 + 10 + 6),
                            b.Locator("127.0.0.1", 7400 + 1750 + 11 + 6))
    assert b.cdr_string_value(params[b.PID_ENTITY_NAME][0]) == "fpga_samples"
    datas = [s for s in sedp.submessages if isinstance(s, Data)]
    seen, locators = {}, {}
    for s in datas:
        p = _strings(s.payload)
        topic = b.cdr_string_value(p[b.PID_TOPIC_NAME][0])
        seen[(s.writer_id, topic)] = (
            b.cdr_string_value(p[b.PID_TYPE_NAME][0]), _octets(p.get(b.PID_USER_DATA, [bytes(4)])[0]))
        locators[topic] = b.Locator.decode(p[b.PID_UNICAST_LOCATOR][0])
    # the ros_discovery_info writer's own locator is the metatraffic one (its readers' ACKNACKs
    # go where rfl_rtps_ctrl reads); the topics' endpoints announce the user-data one
    assert locators == {"ros_discovery_info": meta, "rt/samples_dilated": user, "rt/samples": user}
    hash_in = type_hash("lab_msgs/Samples", load_config(CONFIG).registry())
    assert seen == {
        (0x3C2, "ros_discovery_info"): ("rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_", b""),
        (0x3C2, "rt/samples_dilated"): ("lab_msgs::msg::dds_::Samples_",
                                        f"typehash={hash_in};".encode()),
        (0x4C2, "rt/samples"): ("lab_msgs::msg::dds_::Samples_",
                                f"typehash={hash_in};".encode())}
    hbs = [(s.writer_id, s.first, s.last, s.count) for s in sedp.submessages
           if isinstance(s, Heartbeat)]
    assert hbs == [(0x3C2, 1, 2, 1), (0x4C2, 1, 1, 1)]
    assert [s.name for s in graph.submessages] == ["INFO_DST", "INFO_TS", "DATA", "HEARTBEAT"]
    gdata = graph.submessages[2]
    assert gdata.payload[4:16] == PREFIX and b"fpga_samples" in gdata.payload
    # each patch point lies on what it names
    assert sorted(p.name for m in rom.messages for p in m.patches) == sorted([
        "info_dst", "hb_count_publications", "hb_count_subscriptions",
        "acknack_base_publications", "acknack_base_subscriptions",
        "info_dst", "info_ts", "hb_count_ros_discovery_info"])
    for m in rom.messages:
        for p in m.patches:
            field = m.data[p.offset:p.offset + p.width]
            expect = {"info_dst": bytes(12), "info_ts": bytes(8)}.get(
                p.name, struct.pack("<iI", 0, 1) if p.name.startswith("acknack_base")
                else struct.pack("<i", 1))
            assert field == expect, (m.name, p)


def test_rom_equals_what_the_software_participant_sends() -> None:
    """A software participant with the same prefix and entities (its ros_discovery_info writer
    on the metatraffic locator, as the fabric's) learns a peer: its SPDP and its SEDP datagram
    are the ROM's bytes (the SEDP's INFO_DST names the peer where the ROM says any)."""
    rom = render_rom(CONFIG, domain=7, index=3, guid_prefix=PREFIX)
    config = load_config(CONFIG)
    p = Participant(7, 3, "127.0.0.1", "fpga_samples", guid_prefix=PREFIX)
    node = RosNodeEntities(p, "fpga_samples", "/",
                           graph_locator=("127.0.0.1", 7400 + 1750 + 10 + 6))   # RTPS 9.6.1.1
    node.add_publisher("/samples_dilated", "lab_msgs/Samples", registry=config.registry())
    node.add_subscriber("/samples", "lab_msgs/Samples", registry=config.registry())
    peer = Participant(7, 4, "127.0.0.1", "peer", guid_prefix=PEER)
    spdp_peer = peer.announce()[0][2]
    out = p.receive(spdp_peer, ("127.0.0.1", peer.meta[1]), 0.0)
    assert [(h, port) for h, port, _ in out] == [("127.0.0.1", peer.meta[1])] * 2
    assert out[0][2] == rom.message("spdp").data
    sedp = bytearray(rom.message("sedp").data)
    (dst,) = [q for q in rom.message("sedp").patches if q.name == "info_dst"]
    sedp[dst.offset:dst.offset + 12] = PEER
    assert out[1][2] == bytes(sedp)


def test_rom_files_hold_the_image_and_its_table(tmp_path: Path) -> None:
    """``rosfpga-lab generate CONFIG -o DIR --target fabric`` writes the ROM and its table, and
    its index names the transmit path's parameters (the same participant's)."""
    from rosfpga_lab.cli import main

    assert main(["generate", str(CONFIG), "-o", str(tmp_path), "-q", "--target", "fabric",
                 "--domain", "9", "--participant-index", "1"]) == 0
    from rosfpga_lab.component.fabricsim import TAP_NODE_ADDRESS

    # the board's default address is fabric sim --tap's node's (one host set-up for both)
    rom = render_rom(CONFIG, domain=9, index=1, address=TAP_NODE_ADDRESS)
    assert rom.address == "10.31.0.2"
    image = bytes(int(x, 16) for x in (tmp_path / ROM_FILE).read_text().split())
    assert image == b"".join(m.data for m in rom.messages)
    table = [int(x, 16) for x in (tmp_path / TABLE_FILE).read_text().split()]
    at = 0
    for entry, m in zip(table, rom.messages, strict=True):
        assert (entry >> 32, (entry >> 16) & 0xFFFF, entry & 0xFFFF) == (m.dest, at, len(m.data))
        assert image[at:at + len(m.data)] == m.data
        one = bytes(int(x, 16) for x in (tmp_path / f"rfl_rtps_disc_{m.name}.hex").read_text().split())
        assert one == m.data
        at += len(m.data)
    index = json.loads((tmp_path / INDEX_FILE).read_text())
    assert index["rfl_rtps_tx"] == verilog_parameters(tx_parameters(rom))
    assert index["rfl_rtps_tx"]["GUID_PREFIX"] == f"96'h{rom.guid_prefix.hex().lstrip('0')}"
    # the network top's ports: RTPS 2.3 9.6.1.1 for domain 9, participant 1 (PB 7400, DG 250,
    # PG 2, d0 0, d1 10, d3 11), the SPDP group 239.255.0.1; the SPDP learner's constants:
    # ENTITYID_SPDP_BUILTIN_PARTICIPANT_WRITER (9.3.1.2), PID_STATUS_INFO 0x71, PID_SENTINEL 1,
    # PID_PARTICIPANT_LEASE_DURATION 2, PID_DEFAULT_UNICAST_LOCATOR 0x31,
    # PID_METATRAFFIC_UNICAST_LOCATOR 0x32 (9.6.2.2), PL_CDR_BE 2 / PL_CDR_LE 3 (10.5),
    # LOCATOR_KIND_UDPv4 1, the default lease 100 s (8.5.3.1), the lab's cap 300 s
    assert index["rfl_fabric_top"] == {
        "SPDP_PORT": "9650", "META_PORT": "9662", "USER_PORT": "9663",
        "COUNTERS_PORT": "9658",            # the counter readout's: the SPDP port + 8, unused by RTPS
        "SPDP_GROUP": "32'hefff0001", "SPDP_WRITER_ID": "32'h100c2",
        "SPDP_PIDS": "80'h710001000200310032", "SPDP_ENCAPS": "32'h20003",
        "SPDP_LOCATOR_KIND": "32'h1", "SPDP_LEASE_DEFAULT": "100", "SPDP_LEASE_MAX": "300"}


def _require_cyclonedds():
    """cyclonedds with CYCLONEDDS_URI set as rmw's users on loopback do; skip on a bare machine,
    fail under ROSFPGA_REQUIRE_WIRE=1 or ROSFPGA_REQUIRE_ROS2=1 (CI)."""
    try:
        import cyclonedds.builtin as builtin
        import cyclonedds.domain as domain
    except ImportError as exc:
        reason = f"cyclonedds does not import ({exc}); pip install cyclonedds"
        if os.environ.get("ROSFPGA_REQUIRE_ROS2") == "1":
            skip_or_fail(reason, "ROSFPGA_REQUIRE_ROS2")
        skip_or_fail(reason, "ROSFPGA_REQUIRE_WIRE")
    os.environ["CYCLONEDDS_URI"] = CYCLONE_CONFIG
    return builtin, domain


def _bind_free_index(domain: int) -> tuple[int, socket.socket, socket.socket]:
    """The circuit's ports, held by two sockets: the first free participant index's."""
    from rosfpga_lab.rtps.entities import discovery_port, user_port
    for index in range(MAX_PARTICIPANT_INDEX, -1, -1):    # from the top: Cyclone takes from 0
        socks = []
        try:
            for port in (discovery_port(domain, index), user_port(domain, index)):
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                socks.append(s)
                s.bind(("127.0.0.1", port))
            return index, socks[0], socks[1]
        except OSError:
            for s in socks:
                s.close()
    pytest.fail(f"no free participant index in DDS domain {domain}")


def _peer_locators(datagram: bytes) -> tuple[int, int] | None:
    """The metatraffic and user ports a peer's SPDP announces (None: not an SPDP with both;
    Fast DDS announces its LAN addresses: the port is what counts on one host)."""
    try:
        msg = parse_message(datagram)
    except Exception:
        return None
    for s in msg.submessages:
        if isinstance(s, Data) and s.writer_id == 0x000100C2 and s.payload:
            p = parse_parameters(s.payload)
            little = s.payload[:2] == b.PL_CDR_LE[:2]
            ports = []
            for pid in (b.PID_METATRAFFIC_UNICAST_LOCATOR, b.PID_DEFAULT_UNICAST_LOCATOR):
                locs = [b.Locator.decode(v, little) for v in p.get(pid, [])]
                ports += [loc.port for loc in locs if loc is not None][:1]
            if len(ports) == 2:
                return ports[0], ports[1]
    return None


class RomSender:
    """The circuit's side on a UDP socket: SPDP to the discovery ports a loopback graph probes,
    every PERIOD seconds; on a new peer's SPDP (send_sedp), the SEDP datagram to its metatraffic
    port and the ros_discovery_info one to its user port, again every period (the circuit has
    no ACKNACK handling yet: a peer that dropped them, as Cyclone sometimes does with SEDP data
    that comes right after our first SPDP, gets them then). Runs on a thread until closed."""

    PERIOD = 0.5

    def __init__(self, domain: int, config: Path = CONFIG, guid_prefix: bytes = PREFIX) -> None:
        self.index, self.meta, self.user = _bind_free_index(domain)
        self.rom = render_rom(config, domain=domain, index=self.index, guid_prefix=guid_prefix)
        self.peers: set[tuple[int, int]] = set()
        self.meta.settimeout(0.05)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _send(self, name: str, port: int) -> None:
        self.meta.sendto(self.rom.message(name).data, ("127.0.0.1", port))

    def send_data(self, datagram: bytes) -> None:
        """A datagram of the circuit's data writer to every peer's user-data port."""
        for _meta, user in list(self.peers):
            self.user.sendto(datagram, ("127.0.0.1", user))

    def _run(self) -> None:
        last = -1.0
        while not self._stop.is_set():
            if time.monotonic() - last > self.PERIOD:          # the period tick
                last = time.monotonic()
                for port in self.rom.ports()["spdp_unicast"]:
                    self._send("spdp", port)
                for meta, user in list(self.peers):
                    self._send("sedp", meta)
                    self._send("graph", user)
            try:
                datagram, _ = self.meta.recvfrom(65536)
            except (socket.timeout, OSError):
                continue
            ports = _peer_locators(datagram)
            if ports is not None and ports not in self.peers:     # send_sedp: a new participant
                self.peers.add(ports)
                self._send("sedp", ports[0])
                self._send("graph", ports[1])

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.meta.close()
        self.user.close()


@pytest.mark.timeout(30)
def test_cyclone_discovers_the_rom_participant_and_its_topics() -> None:
    """The ROM's bytes from a UDP socket, as the circuit sends them (RomSender), and Cyclone
    DDS's built-in topics show the participant, its publication and its subscription with their
    type names and the ROM's GUIDs, and a Cyclone reader of ros_discovery_info (rmw's QoS) takes
    the node's ParticipantEntitiesInfo."""
    builtin, dds = _require_cyclonedds()
    types = cyclone()
    sender = RomSender(DOMAIN)
    try:
        dp = dds.DomainParticipant(DOMAIN)
        P = types.Policy
        graph = types.DataReader(dp, types.Topic(dp, "ros_discovery_info",
                                                 types.ParticipantEntitiesInfo_),
                                 qos=types.Qos(P.Reliability.Reliable(1_000_000_000),
                                               P.Durability.TransientLocal, P.History.KeepLast(1)))
        infos: list = []
        readers = {name: builtin.BuiltinDataReader(dp, topic) for name, topic in (
            ("participant", builtin.BuiltinTopicDcpsParticipant),
            ("publication", builtin.BuiltinTopicDcpsPublication),
            ("subscription", builtin.BuiltinTopicDcpsSubscription))}
        seen: dict[str, list] = {name: [] for name in readers}
        ours = {"publication": ("rt/samples_dilated", "lab_msgs::msg::dds_::Samples_"),
                "subscription": ("rt/samples", "lab_msgs::msg::dds_::Samples_")}

        def found() -> bool:
            for name, r in readers.items():
                seen[name] += r.take(N=64)
            infos.extend(graph.take(N=8))
            return bool(infos) and any(s.key.bytes[:12] == PREFIX for s in seen["participant"]) and all(
                any(s.key.bytes[:12] == PREFIX and (s.topic_name, s.type_name) == ours[name]
                    for s in seen[name]) for name in ours)

        assert wait(found, 10.0), (sender.peers, {k: len(v) for k, v in seen.items()})
        ids = sender.rom.entity_ids
        for name, eid in (("publication", ids["writer"]), ("subscription", ids["reader"])):
            (ep,) = [s for s in seen[name] if s.topic_name == ours[name][0]]
            assert ep.key.bytes == PREFIX + eid.to_bytes(4, "big")
            assert ep.participant_key.bytes == PREFIX + bytes.fromhex("000001c1")
        # ros_discovery_info: the node, its reader and writer by GID (what ros2 node list reads)
        (info,) = infos
        gid = lambda g: bytes(g.data)  # noqa: E731
        assert gid(info.gid) == PREFIX + bytes.fromhex("000001c1")
        (node,) = info.node_entities_info_seq
        assert (node.node_namespace, node.node_name) == ("/", "fpga_samples")
        assert [gid(g) for g in node.reader_gid_seq] == [PREFIX + ids["reader"].to_bytes(4, "big")]
        assert [gid(g) for g in node.writer_gid_seq] == [PREFIX + ids["writer"].to_bytes(4, "big")]
        dp = None
    finally:
        sender.close()


def test_rom_sedp_equals_the_software_component_s() -> None:
    """The ROS 2 component of the same configuration, on sockets: its SEDP writers' samples are
    the ROM's (its random GUID prefix put in the ROM's place): same entities, order, QoS,
    names, hashes, locators; but the ros_discovery_info writer's, which the component announces
    at its user-data port and the fabric at its metatraffic port (rfl_rtps_ctrl answers there)."""
    from rosfpga_lab.component.ros2 import Ros2Component
    from rosfpga_lab.rtps.entities import PUB_WRITER, SUB_WRITER

    with Ros2Component(CONFIG, domain=DOMAIN) as comp:
        p = comp.node.participant
        rom = render_rom(CONFIG, domain=DOMAIN, index=p.index, guid_prefix=PREFIX)
        theirs = [payload.replace(p.guid_prefix, PREFIX) for wid in (PUB_WRITER, SUB_WRITER)
                  for payload in p.local[wid].history.values()]
        graph = theirs[0]
        assert b"ros_discovery_info" in graph and b.Locator(*p.user).encode() in graph
        theirs[0] = graph.replace(b.Locator(*p.user).encode(), b.Locator(*p.meta).encode())
    ours = [s.payload for s in parse_message(rom.message("sedp").data).submessages
            if isinstance(s, Data)]
    assert ours == theirs and len(ours) == 3
