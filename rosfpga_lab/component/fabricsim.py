"""The ROS 2 node in the fabric, simulated whole and bridged to the host's network, so real ROS 2
peers talk to it (``rosfpga-lab fabric sim``; issue 31 item 3).

How this works: :func:`start_fabric` renders the configuration's discovery ROM for the address
the peers reach the node at, builds (or takes from the cache) the Verilator model of
``rfl_fabric_top`` (:mod:`rosfpga_lab.rtl.fabricsim`) and starts it; a bridge then moves frames
between its PHY side and the host:

* :class:`ShimBridge` (no root needed): binds the node's metatraffic and user-data UDP ports on
  127.0.0.1 (the locators its SPDP and SEDP announce) and its counter readout's port, wraps each datagram a peer sends there
  into an Ethernet/IPv4/UDP frame for the PHY (:mod:`rosfpga_lab.graph.ethframe`: IPv4 header
  checksum, FCS), and unwraps the circuit's frames back into datagrams, sent from the port the
  circuit sent from: the circuit's SPDP (to the SPDP multicast group) goes to the unicast
  discovery ports of participant indices 0..MAX_PARTICIPANT_INDEX on 127.0.0.1, as Cyclone DDS
  configured for loopback (:func:`rosfpga_lab.rtps.cyclone.cyclone_loopback_uri`) sends its
  own; the circuit's ARP requests are answered by the bridge.

* :class:`TapBridge` (root and ``/dev/net/tun``): a TAP interface (:mod:`rosfpga_lab.graph.tap`)
  with the host's address 10.31.0.1/24; the node is 10.31.0.2 (its ROM announces it). The
  circuit's frames (FCS checked and taken off) go to the host's network stack, the host's
  frames (FCS added) to the circuit: the host's kernel answers the circuit's ARP, the circuit's
  LiteEth the host's, SPDP goes by multicast. Peers bind that interface
  (:func:`fabric_tap_peer_uri`).

The circuit learns its one peer itself (``rfl_spdp_peer`` in ``rfl_fabric_top``, cfg_learn):
from the SPDP announcements that reach its SPDP or metatraffic port it takes the first
participant's metatraffic and default unicast locators (until that participant is silent for
its lease), and sends its SEDP data and ros_discovery_info sample there, again a period later.
The bridge only moves frames. With ``bridge_peer`` (``--bridge-peer``) the old way instead: the
bridge reads the SPDP announcements that come to the node's metatraffic port, and for a
participant it has not seen sets the circuit's registers (``cfg_peer_*``) to that participant's
locators and pulses ``send_sedp``, and again once after the circuit's next SPDP announcement
(a peer drops SEDP from a participant it has not discovered yet); the participant that
appeared last is the peer. Either way one peer at a time (run the publisher and the subscriber
in one participant, as one ROS 2 process with both does); the bridge still reads the peers'
SPDP for what it forwards (below).

The circuit sends what goes to a reader to its peer's default user-data port; Fast DDS's
readers (rclpy's ``ros_discovery_info`` reader among them) announce a unicast locator of their
own in their SEDP data and take nothing at the default one, so the bridge reads the peer's SEDP
subscriptions and sends the circuit's datagrams of a writer to the locator a reader of its topic
announced (software knowledge of discovery again; the circuit has one peer port). The circuit's
built-in readers answer a peer's SEDP HEARTBEAT as a reader that has every sample (it needs
none), so a peer never sends them its SEDP data; the bridge asks the peer's SEDP subscriptions
writer once for its samples with an ACKNACK of its own in the circuit's name (its GUID prefix
and built-in reader), and reads the readers' locators from the DATA(r) that come back (which
go on to the circuit, which drops them).

The circuit answers ACKNACKs on its metatraffic port only (``rfl_fabric_top`` gives what comes
to the user-data port to the data path); its ``ros_discovery_info`` writer's SEDP data announces
the metatraffic locator as its own (``rtl.discrom.fabric_participant``), so a peer's reader asks
it there (Fast DDS's does: rclpy's graph needs the sample, which the circuit sent before the
peer had matched) and ``rfl_rtps_ctrl`` answers (the DATA and a HEARTBEAT, to the peer's
user-data port, which the bridge sends on to the reader's own locator): nothing to forward.

Fast DDS sends each datagram of a sample to every locator it has for a reader, and it has
two for the circuit's (the participant's default and the reader's own, the same address and
port): each DATA_FRAG comes twice in a row. The bridge passes both: ``rfl_rtps_rx`` skips a
DATA_FRAG whose fragments it has taken already (counted in its ``cnt_repeated``), as RTPS lets
a reader see a fragment twice.

A datagram longer than one Ethernet frame carries (1472 bytes of UDP payload: the circuit does
not reassemble IP fragments) is dropped and counted: configure the peer's DDS to send smaller
ones (Cyclone DDS: ``MaxMessageSize`` 1472B, which :func:`fabric_peer_uri` sets).
"""

from __future__ import annotations

import select
import struct
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.graph.ethframe import (
    ArpRequest, BadFrame, UdpDatagram, arp_reply, fcs, mac_bytes, parse_frame, udp_frame,
)
from rosfpga_lab.graph.tap import TapDevice
from rosfpga_lab.graph.udpports import UdpPorts
from rosfpga_lab.rtl.board import DEFAULT_MAC, mac_value
from rosfpga_lab.rtl.discrom import DiscoveryRom, counters_port, render_rom
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.rtl.fabricsim import (
    SIM_PERIOD, SIM_RATE, FabricConfig, FabricSim, build_fabric_sim, fabric_top_default,
)
from rosfpga_lab.rtl.limits import FABRIC_MAX_DATAGRAM
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri
from rosfpga_lab.rtps.discovery import parse_parameters
from rosfpga_lab.rtps.entities import (
    SPDP_WRITER, SUB_READER, SUB_WRITER, discovery_multicast_port, discovery_port, user_port,
)
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.limits import MAX_PARTICIPANT_INDEX, SPDP_MULTICAST_ADDRESS
from rosfpga_lab.rtps.message import Data, Heartbeat, parse_message

__all__ = ["HOST_MAC", "Peer", "ShimBridge", "TAP_HOST_CIDR", "TAP_NAME", "TAP_NODE_ADDRESS",
           "TapBridge", "fabric_peer_uri", "fabric_tap_peer_uri", "fastdds_peer_profile", "sedp_reader_locators",
           "spdp_peer", "start_fabric"]

#: The count of the bridge's one ACKNACK to a peer's SEDP subscriptions writer: above any the
#: circuit's answers reach in a run (they count up from rtl.discrom.ANSWER_COUNT_START).
BRIDGE_ACKNACK_COUNT = 1 << 30
#: The TAP interface's name and the host's address on it; the node's address on that link.
TAP_NAME, TAP_HOST_CIDR, TAP_NODE_ADDRESS = "rfltap0", "10.31.0.1/24", "10.31.0.2"
#: The host's side of the simulated link (locally administered, "RFL" and 1).
HOST_MAC = "02:52:46:4c:00:01"


def fabric_peer_uri(lease_seconds: float | None = None) -> str:
    """``CYCLONEDDS_URI`` for a ROS 2 peer of the simulated fabric on 127.0.0.1: the lab's
    loopback configuration, with datagrams no longer than one Ethernet frame carries."""
    return cyclone_loopback_uri(lease_seconds, max_message_bytes=FABRIC_MAX_DATAGRAM)


def fabric_tap_peer_uri(name: str = TAP_NAME) -> str:
    """``CYCLONEDDS_URI`` for a ROS 2 peer of the simulated fabric over the TAP interface
    ``name``: that interface (multicast on, as on a wired LAN), datagrams no longer than one
    Ethernet frame carries."""
    return (f'<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface name="{name}"/>'
            f'</Interfaces><MaxMessageSize>{FABRIC_MAX_DATAGRAM}B</MaxMessageSize></General>'
            '</Domain></CycloneDDS>')


def fastdds_peer_profile() -> str:
    """A Fast DDS XML profile (``FASTRTPS_DEFAULT_PROFILES_FILE``) for a ROS 2 peer of the
    simulated fabric on rmw_fastrtps_cpp: UDPv4 only (no shared memory), datagrams no longer
    than one Ethernet frame carries (Fast DDS then sends a larger sample as DATA_FRAGs)."""
    return ('<?xml version="1.0" encoding="UTF-8" ?>\n'
            '<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">'
            '<transport_descriptors><transport_descriptor><transport_id>fabric_udp</transport_id>'
            f'<type>UDPv4</type><maxMessageSize>{FABRIC_MAX_DATAGRAM}</maxMessageSize>'
            '</transport_descriptor></transport_descriptors>'
            '<participant profile_name="fabric_peer" is_default_profile="true"><rtps>'
            '<userTransports><transport_id>fabric_udp</transport_id></userTransports>'
            '<useBuiltinTransports>false</useBuiltinTransports></rtps></participant></profiles>\n')


@dataclass(frozen=True)
class Peer:
    """A participant learned from its SPDP: GUID prefix, metatraffic and user-data locators."""

    guid_prefix: bytes
    meta: tuple[str, int]
    user: tuple[str, int]


def spdp_peer(payload: bytes, source: tuple[str, int]) -> Peer | None:
    """The participant an SPDP datagram announces (a loopback locator, or one at the sender's
    address; else its port at the sender's address), or None (not SPDP, a goodbye, unusable)."""
    for prefix, data in _samples(payload, SPDP_WRITER):
        try:
            params = parse_parameters(data)
        except RtpsError:
            return None
        little = data[:2] == b.PL_CDR_LE[:2]
        meta = _pick(params, b.PID_METATRAFFIC_UNICAST_LOCATOR, little, source)
        user = _pick(params, b.PID_DEFAULT_UNICAST_LOCATOR, little, source)
        if meta and user:
            return Peer(prefix, meta, user)
    return None


def _pick(params: dict[int, list[bytes]], pid: int, little: bool,
          source: tuple[str, int]) -> tuple[str, int] | None:
    """A locator of ``pid`` the host reaches: a loopback one, or one at the sender's address;
    else the first one's port at the sender's address."""
    found = [x for x in (b.Locator.decode(raw, little) for raw in params.get(pid, []))
             if x is not None]
    for loc in found:
        if loc.address.startswith("127.") or loc.address == source[0]:
            return (loc.address, loc.port)
    return (source[0], found[0].port) if found else None


def _samples(payload: bytes, writer_id: int) -> list[tuple[bytes, bytes]]:
    """(source prefix, serialized data) of each DATA of ``writer_id`` in an RTPS datagram."""
    try:
        msg = parse_message(payload)
    except RtpsError:
        return []
    return [(prefix, sub.payload) for prefix, _dst, sub in msg.routed()
            if isinstance(sub, Data) and sub.writer_id == writer_id and sub.payload]


def sedp_reader_locators(payload: bytes, source: tuple[str, int]) -> list[tuple[str, tuple[str,
                                                                                           int]]]:
    """(DDS topic, unicast locator) of each reader an SEDP datagram announces with a locator of
    its own (Fast DDS's readers do; Cyclone's use their participant's)."""
    out = []
    for _prefix, data in _samples(payload, SUB_WRITER):
        try:
            params = parse_parameters(data)
        except RtpsError:
            continue
        little = data[:2] == b.PL_CDR_LE[:2]
        loc = _pick(params, b.PID_UNICAST_LOCATOR, little, source)
        topic = params.get(b.PID_TOPIC_NAME)
        if loc and topic and len(topic[0]) > 4:
            (n,) = struct.unpack("<I" if little else ">I", topic[0][:4])
            out.append((topic[0][4:4 + n].rstrip(b"\0").decode(errors="replace"), loc))
    return out


@dataclass
class BridgeCounts:
    """What the bridge moved and dropped."""

    to_circuit: int = 0
    from_circuit: int = 0
    arp_answered: int = 0
    spdp_copies: int = 0
    send_refused: int = 0
    sedp_pulses: int = 0
    subscriptions_asked: int = 0
    dropped: Counter = field(default_factory=Counter)
    peers: list[Peer] = field(default_factory=list)

    def lines(self) -> list[str]:
        out = [f"datagrams to the circuit: {self.to_circuit}",
               f"datagrams from the circuit: {self.from_circuit} (SPDP copies to the "
               f"discovery ports: {self.spdp_copies}, refused by the host: {self.send_refused})",
               f"ARP requests answered: {self.arp_answered}",
               f"peers seen: {len(self.peers)}; send_sedp pulses: {self.sedp_pulses}",
               f"peers asked for their SEDP subscriptions: {self.subscriptions_asked}"]
        out += [f"dropped ({why}): {n}" for why, n in sorted(self.dropped.items())]
        return out


class _PeerKeeper:
    """What both bridges do: note the participants the host side announces (for what the
    bridge forwards) and, with ``bridge_peer``, keep the circuit's one peer (its registers) and
    pulse send_sedp for it; else the circuit learns its peer itself (cfg_learn)."""

    def __init__(self, sim: FabricSim, rom: DiscoveryRom, *, node_mac: str = DEFAULT_MAC,
                 bridge_peer: bool = False,
                 log: Callable[[str], None] = lambda line: None) -> None:
        self.sim, self.rom, self.log = sim, rom, log
        self.bridge_peer = bridge_peer
        self.node_mac, self.host_mac = mac_bytes(node_mac), mac_bytes(HOST_MAC)
        self.meta, self.user = discovery_port(rom.domain, rom.index), user_port(rom.domain,
                                                                                rom.index)
        self.counters = counters_port(rom.domain)      # the counter readout's
        self.counts = BridgeCounts()
        self.peer: Peer | None = None
        self._known = {rom.guid_prefix}      # participants seen (their SPDP repeats)
        self._pulse_after_spdp = False

    def _learn(self, peer: Peer) -> None:
        self._known.add(peer.guid_prefix)
        self.counts.peers.append(peer)
        if not self.bridge_peer:
            self.peer = self.peer or peer     # the circuit's: the first, while it lives
            self.log(f"participant {peer.guid_prefix.hex()} seen: metatraffic "
                     f"{peer.meta[0]}:{peer.meta[1]}, user data {peer.user[0]}:{peer.user[1]} "
                     "(the circuit learns its peer from SPDP itself)")
            return
        self.peer = peer
        self.sim.configure(self._config(peer))
        self.sim.send_sedp()
        self.counts.sedp_pulses += 1
        self._pulse_after_spdp = True
        self.log(f"peer {peer.guid_prefix.hex()}: metatraffic {peer.meta[0]}:{peer.meta[1]}, "
                 f"user data {peer.user[0]}:{peer.user[1]} (the circuit's cfg_peer_*)")

    def _config(self, peer: Peer | None) -> FabricConfig:
        meta = peer.meta if peer else (self.rom.address, 0)
        user = peer.user if peer else (self.rom.address, 0)
        return FabricConfig(mac_value(":".join(f"{x:02x}" for x in self.node_mac)),
                            self.rom.address, meta[0], meta[1], user[1],
                            self.rom.entity_ids["reader"], learn=not self.bridge_peer)

    def _spdp_went_out(self) -> None:
        if self._pulse_after_spdp:
            self._pulse_after_spdp = False
            self.sim.send_sedp()
            self.counts.sedp_pulses += 1

    def start(self) -> None:
        """Give the circuit its registers (learning, or no peer yet: ports 0) and let it run."""
        self.sim.configure(self._config(None))


class ShimBridge(_PeerKeeper):
    """The simulated node's PHY side bridged to UDP ports on loopback (module docstring)."""

    def __init__(self, sim: FabricSim, rom: DiscoveryRom, out_topic: str, *,
                 node_mac: str = DEFAULT_MAC, bridge_peer: bool = False,
                 log: Callable[[str], None] = lambda line: None) -> None:
        super().__init__(sim, rom, node_mac=node_mac, bridge_peer=bridge_peer, log=log)
        self.ports = UdpPorts(rom.address, [self.meta, self.user, self.counters])
        self._ident = 0
        self._asked: set[bytes] = set()
        self.readers: dict[str, tuple[str, int]] = {}   # DDS topic -> a reader's own locator
        self._topics = {rom.entity_ids["ros_discovery_info"]: "ros_discovery_info",
                        rom.entity_ids["writer"]: out_topic}

    # ---- host -> circuit
    def _from_host(self, port: int, source: tuple[str, int], payload: bytes) -> None:
        if port == self.meta:
            peer = spdp_peer(payload, source)
            if peer and peer.guid_prefix not in self._known:
                self._learn(peer)
            self._ask_subscriptions(payload)
            for topic, loc in sedp_reader_locators(payload, source):
                # only the circuit's own topics: a peer announcing many others costs nothing here
                if topic in self._topics.values() and self.readers.get(topic) != loc:
                    self.readers[topic] = loc
                    self.log(f"a reader of {topic} at {loc[0]}:{loc[1]} (its own locator)")
        if len(payload) > FABRIC_MAX_DATAGRAM:
            self.counts.dropped["datagram longer than a frame carries"] += 1
            if self.counts.dropped["datagram longer than a frame carries"] == 1:
                self.log(f"a datagram of {len(payload)} bytes from {source[0]}:{source[1]} "
                         f"dropped: one frame carries {FABRIC_MAX_DATAGRAM} (configure the "
                         f"peer's DDS with MaxMessageSize {FABRIC_MAX_DATAGRAM}B)")
            return
        self._ident += 1
        self.sim.send_frame(udp_frame(payload, src_mac=self.host_mac, dst_mac=self.node_mac,
                                      src_ip=source[0], dst_ip=self.rom.address,
                                      src_port=source[1], dst_port=port, ident=self._ident))
        self.counts.to_circuit += 1

    def _ask_subscriptions(self, payload: bytes) -> None:
        """On the peer's SEDP subscriptions writer's HEARTBEAT, ask once for its samples (the
        circuit's reader answers that it has them all: it needs none)."""
        if self.peer is None or self.peer.guid_prefix in self._asked:
            return
        try:
            msg = parse_message(payload)
        except RtpsError:
            return
        for src, _dst, sub in msg.routed():
            if isinstance(sub, Heartbeat) and sub.writer_id == SUB_WRITER \
                    and src == self.peer.guid_prefix and sub.last >= sub.first >= 1:
                self._asked.add(src)
                ask = (b.header(self.rom.guid_prefix) + b.info_dst(src) +
                       b.acknack(SUB_READER, SUB_WRITER, sub.first,
                                 range(sub.first, min(sub.last, sub.first + 255) + 1),
                                 BRIDGE_ACKNACK_COUNT))
                self.ports.send(self.meta, *self.peer.meta, ask)
                self.counts.subscriptions_asked += 1
                return

    def _reader_of(self, payload: bytes) -> tuple[str, int] | None:
        """The locator of its own a reader announced for the topic of the circuit's writer that
        sent ``payload`` (the circuit sends to its peer's default user-data port)."""
        try:
            msg = parse_message(payload)
        except RtpsError:
            return None
        for _src, _dst, sub in msg.routed():
            topic = self._topics.get(getattr(sub, "writer_id", -1))
            if topic in self.readers:
                return self.readers[topic]
        return None

    # ---- circuit -> host
    def _from_circuit(self, frame: bytes) -> None:
        got = parse_frame(frame)
        if isinstance(got, BadFrame):
            self.counts.dropped[f"circuit frame: {got.reason}"] += 1
        elif isinstance(got, ArpRequest):
            self.sim.send_frame(arp_reply(got, self.host_mac))
            self.counts.arp_answered += 1
        elif isinstance(got, UdpDatagram):
            self.counts.from_circuit += 1
            if got.dst_ip == SPDP_MULTICAST_ADDRESS:
                for index in range(MAX_PARTICIPANT_INDEX + 1):
                    if index != self.rom.index:
                        self.counts.spdp_copies += 1
                        self.ports.send(got.src_port, self.rom.address,
                                        discovery_port(self.rom.domain, index), got.payload)
                self._spdp_went_out()
            else:
                to = (got.dst_ip, got.dst_port)
                # to the peer's default locator (by its port: the circuit takes the address
                # the announcement lists, which may be another of this host's than the bridge's)
                if self.peer and to[1] == self.peer.user[1]:
                    to = self._reader_of(got.payload) or to
                if not self.ports.send(got.src_port, to[0], to[1], got.payload):
                    self.counts.send_refused += 1

    def run(self, seconds: float, *, stop: Callable[[], bool] = lambda: False) -> None:
        """Bridge for ``seconds`` (or until ``stop()`` is true, or the simulation ends)."""
        deadline = time.monotonic() + seconds
        sim_fd = self.sim.fileno()
        while time.monotonic() < deadline and not stop() and self.sim.running():
            ready, _, _ = select.select([sim_fd, *self.ports.filenos()], [], [], 0.05)
            for fd in ready:
                if fd == sim_fd:
                    for frame in self.sim.read().frames:
                        self._from_circuit(frame)
                else:
                    for port, source, payload in self.ports.receive(fd):
                        self._from_host(port, source, payload)

    def close(self) -> None:
        self.ports.close()


class TapBridge(_PeerKeeper):
    """The simulated node's PHY side bridged to a TAP interface: its frames (FCS checked and
    taken off) to the host's network stack, the host's frames (FCS added) to it. The host
    answers ARP and routes; the circuit learns its peer (with ``bridge_peer`` the bridge reads
    the SPDP going to the circuit to set it).
    """

    def __init__(self, sim: FabricSim, rom: DiscoveryRom, *, name: str = TAP_NAME,
                 host_cidr: str = TAP_HOST_CIDR, node_mac: str = DEFAULT_MAC,
                 bridge_peer: bool = False,
                 log: Callable[[str], None] = lambda line: None) -> None:
        super().__init__(sim, rom, node_mac=node_mac, bridge_peer=bridge_peer, log=log)
        self.tap = TapDevice(name, host_cidr)
        self._spdp_port = discovery_multicast_port(rom.domain)

    def _from_host(self, frame: bytes) -> None:
        whole = fcs(frame)
        got = parse_frame(whole)
        if isinstance(got, UdpDatagram) and got.dst_port in (self._spdp_port, self.meta):
            peer = spdp_peer(got.payload, (got.src_ip, got.src_port))
            if peer and peer.guid_prefix not in self._known:
                self._learn(peer)
        self.sim.send_frame(whole)
        self.counts.to_circuit += 1

    def _from_circuit(self, frame: bytes) -> None:
        got = parse_frame(frame)
        if isinstance(got, BadFrame):
            self.counts.dropped[f"circuit frame: {got.reason}"] += 1
            return
        if isinstance(got, UdpDatagram) and got.dst_ip == SPDP_MULTICAST_ADDRESS:
            self._spdp_went_out()
        self.tap.write(frame[:-4])
        self.counts.from_circuit += 1

    def run(self, seconds: float, *, stop: Callable[[], bool] = lambda: False) -> None:
        """Bridge for ``seconds`` (or until ``stop()`` is true, or the simulation ends)."""
        deadline = time.monotonic() + seconds
        sim_fd, tap_fd = self.sim.fileno(), self.tap.fileno()
        while time.monotonic() < deadline and not stop() and self.sim.running():
            ready, _, _ = select.select([sim_fd, tap_fd], [], [], 0.05)
            if sim_fd in ready:
                for frame in self.sim.read().frames:
                    self._from_circuit(frame)
            if tap_fd in ready:
                for frame in self.tap.read():
                    self._from_host(frame)

    def close(self) -> None:
        self.tap.close()


def start_fabric(config: NodeConfig, *, domain: int = 0, tap: bool = False,
                 address: str | None = None, period: int = SIM_PERIOD, rate: int = SIM_RATE,
                 max_bytes: int | None = None, bridge_peer: bool = False,
                 log: Callable[[str], None] = lambda line: None) -> ShimBridge | TapBridge:
    """Build (or take from the cache) and start ``config``'s node in the fabric as participant 0
    of ``domain`` at ``address`` (default 127.0.0.1 for the shim, :data:`TAP_NODE_ADDRESS` on a
    TAP interface; ``max_bytes``: the longest sample it takes, as
    :func:`~rosfpga_lab.rtl.fabricsim.build_fabric_sim`), bridged by a :class:`ShimBridge` or a
    :class:`TapBridge` (call its ``start`` and ``run``, then ``close`` it and its ``sim``);
    ``bridge_peer``: the bridge sets the circuit's peer (else the circuit learns it)."""
    address = address or (TAP_NODE_ADDRESS if tap else "127.0.0.1")
    rom = render_rom(config, domain=domain, address=address)    # wire: cdr checked there
    bound = cdr_layout_from_config(config).layout.max_body + 4   # with the reader's length
    held = max_bytes or int(fabric_top_default("MAX_BYTES"))
    if bound > held:
        log(f"note: {config.path or 'the configuration'} accepts samples up to {bound} bytes; "
            f"the circuit takes {held} (longer ones are dropped and counted; max_bytes "
            f"{bound}, --max-bytes on the command line, takes them all)")
    started = time.monotonic()
    build = build_fabric_sim(config, rom, period=period, max_bytes=max_bytes)
    how = f"built in {build.seconds:.0f} s" if build.seconds else "from the cache"
    log(f"Verilator model {how} ({time.monotonic() - started:.1f} s): {build.program}")
    sim = FabricSim(build, FabricConfig(mac_value(DEFAULT_MAC), address, address, 0, 0,
                                        rom.entity_ids["reader"], learn=not bridge_peer),
                    rate=rate)
    try:
        if tap:
            return TapBridge(sim, rom, bridge_peer=bridge_peer, log=log)
        return ShimBridge(sim, rom, b.dds_topic(config.publisher.topic),
                          bridge_peer=bridge_peer, log=log)
    except BaseException:
        sim.close()
        raise
