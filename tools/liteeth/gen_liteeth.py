#!/usr/bin/env python3
"""Generate the lab's vendored LiteEth UDP/IP core (issue 31) as one Verilog file.

Run it in a virtual environment of its own (LiteX and Migen are not lab dependencies)::

    python -m venv /tmp/leth
    /tmp/leth/bin/pip install liteeth==2024.12 litex==2024.12 migen==0.10.0 pyyaml
    /tmp/leth/bin/python tools/liteeth/gen_liteeth.py tools/liteeth/liteeth_gmii.yml \
        -o rosfpga_lab/rtl/fabric/vendor

It builds what LiteEth's own ``liteeth_gen`` builds for ``core: udp`` (PHY, MAC, ARP, IPv4,
ICMP, UDP), from the same LiteEth classes, with differences ``liteeth_gen`` has no
configuration key for (so this script, not a YAML file for ``liteeth_gen``), and fixes:

* the node's MAC address, IP address, UDP port and one multicast group are inputs of the core
  (``mac_address``, ``ip_address``, ``udp_rx_port`` with ``udp_rx_port_mask``: the ports taken
  are those equal to it on the mask's bits, ``ip_multicast``), so one vendored file serves every
  configuration;
  ``liteeth_gen``'s ``raw`` port receives on the port its transmit side sends to
  (``sink_dst_port``), which an RTPS node (listening on its port, sending to its peer's) cannot use;
* received frames are filtered by destination MAC (ours, broadcast, IPv4 multicast) before the
  EtherType dispatch (LiteEth's crossbar MAC takes every frame; only its ``hybrid`` MAC filters)
  and by destination IP (ours or ``ip_multicast``: LiteEth's ``with_ip_broadcast``, a switch
  that takes every IPv4 frame when on, is driven by that comparison);
* the PHY's receive stream gets ``last_be`` = ``last`` (without it LiteEth 2024.12's 8-bit
  receive path never flags a bad FCS: its CRC checker looks at the lanes ``last_be`` enables);
* the 32-to-8 converter's last word is whole (LiteX's converter ignores ``last_be``):
  ``LastByteTrim`` ends each packet at its ``last_be`` byte and puts the packet's error on it
  (LiteEth's MAC depacketizer moves the payload by the Ethernet header's 14 bytes but not the
  error lanes, so a bad FCS's flag may come on an earlier byte or word);
* the UDP receiver holds a payload's last byte until its frame ends (``HoldingUDPRX``), so a
  padded frame's bad FCS is not lost with the padding LiteEth's own receiver drops;
* the IPv4 receiver (``CheckingIPRX``) also refuses fragments (MF set or an offset: LiteEth does
  not reassemble) and a total length below 28 (an IPv4 and a UDP header); the UDP receiver
  refuses a UDP length above the IPv4 payload (total length - 20), and ends a datagram whose
  frame is shorter than its IPv4 total length with ``length`` 0 (so ``rfl_udp_port`` counts it
  cut: its bytes are not its length); a frame longer than it (Ethernet padding) is fine;
* a frame that ends inside a header is dropped (LiteEth's depacketizers would take the next
  frame's first bytes as the rest of the header: ``Depacketizer`` patched);
* two one-clock outputs say what the core dropped (``rx_drop_header``: cut inside its Ethernet,
  IPv4 or UDP header, a bad IPv4 header (checksum, version, options, fragment, total length), a
  UDP length above the IPv4 payload; ``rx_drop_other``: not for this node (another MAC or
  EtherType, another IP address, a protocol not UDP or ICMP, a port outside the mask)), for
  the lab's counters (LiteEth's are CSRs, without a bus here);
* the ECP5 RGMII PHY's receiver (``ErrorRGMIIRX``) reads ``rx_ctl``'s second half too (RX_DV xor
  RX_ER): a byte the PHY marks errored is inverted, so the frame's FCS fails (LiteEth's reads
  only RX_DV);
* ``data_width: 32``: LiteEth's MAC, ARP, IPv4 and ICMP at 32 bits (a word a clock: the core
  keeps gigabit line rate from 31.25 MHz up, where its 8-bit datapath needed 125 MHz and, on an
  ECP5-6, closes at some 60), its PHY side (preamble, CRC) at 8 bits on the PHY's clock as
  LiteEth builds it; the UDP layer stays at 8 bits (``PortUDP``: the IPv4 crossbar's UDP port
  crosses at 32 bits, LiteX's StrideConverter then ``LastByteTrim`` make bytes of it, and the
  receive rules below run on bytes as before), so the lab's port is 8 bits either way;
* ``port_clock: true``: that UDP layer and the port on a clock of their own (ports
  ``port_clock``, ``port_reset``; LiteX's asynchronous FIFOs from and to the core's ``sys``,
  the drop pulses crossed by a toggle), so the lab's node runs at the byte rate while the core
  runs slower; without it (the GMII simulation variant) one clock runs all;
* ``phy: gmii_model`` is LiteEth's GMII PHY in its ``model`` mode (RX and TX clocked by the
  core's clock, no vendor clock buffers): the simulation variant; ``phy: ecp5_rgmii`` is
  ``LiteEthECP5PHYRGMII`` (DELAYG, IDDRX1F, ODDRX1F), the board variant.
"""

from __future__ import annotations

import argparse
import re
from importlib.metadata import version
from pathlib import Path

import yaml
from migen import FSM, Cat, ClockDomain, ClockDomainsRenamer, If, NextState, NextValue, \
    Replicate, Signal
from migen.genlib.cdc import PulseSynchronizer
from migen.fhdl.structure import _Assign

import liteeth.core.ip
import liteeth.mac
import liteeth.packet
import liteeth.phy.ecp5rgmii
from liteeth.common import eth_ipv4_user_description, eth_phy_description, \
    eth_udp_user_description, ipv4_header_length, udp_header, udp_protocol
from liteeth.core.ip import LiteEthIPRX, LiteEthIPV4Crossbar
from liteeth.core.udp import LiteEthUDPCrossbar, LiteEthUDPDepacketizer, LiteEthUDPTX
from liteeth import phy as liteeth_phys
from liteeth.core import LiteEthIPCore
from liteeth.gen import _io, get_udp_raw_port_ios
from liteeth.mac.common import LiteEthMACCrossbar
from liteeth.mac.crc import LiteEthMACCRC32Checker
from liteeth.phy.ecp5rgmii import LiteEthPHYRGMIIRX
from litex.build.generic_platform import Pins, Subsignal
from litex.build.io import CRG
from litex.build.lattice.platform import LatticePlatform
from litex.gen import LiteXModule
from litex.soc.interconnect import stream
from litex.soc.integration.builder import Builder
from litex.soc.integration.soc_core import SoCMini

MCAST_MAC_MASK = 0xFFFFFF000000
MCAST_MAC_OUI = 0x01005E000000
BCAST_MAC = 0xFFFFFFFFFFFF

# The PHY pads the core drives: data and control only. LiteEth's MDIO master and the PHY's
# reset are CSR-driven (no CSR bus here: the board's top drives the PHY's reset), and MDIO's
# tristate buffer is a vendor primitive a simulator does not have.
PADS = [
    ("gmii_pads", 0,
        Subsignal("rx_dv", Pins(1)), Subsignal("rx_er", Pins(1)), Subsignal("rx_data", Pins(8)),
        Subsignal("tx_en", Pins(1)), Subsignal("tx_er", Pins(1)), Subsignal("tx_data", Pins(8))),
    ("rgmii_pads", 0,
        Subsignal("rx_ctl", Pins(1)), Subsignal("rx_data", Pins(4)),
        Subsignal("tx_ctl", Pins(1)), Subsignal("tx_data", Pins(4))),
    ("udp_rx_port", 0, Pins(16)),
    ("udp_rx_port_mask", 0, Pins(16)),
    ("ip_multicast", 0, Pins(32)),
    ("rx_drop_header", 0, Pins(1)),
    ("rx_drop_other", 0, Pins(1)),
    ("port_clock", 0, Pins(1)),
    ("port_reset", 0, Pins(1)),
]
MIN_IPV4_UDP = ipv4_header_length + udp_header.length   # the least total length taken: 28


class DropSaying:
    """A LiteEth crossbar that says when its dispatcher gave a packet no port (its ``default``
    case takes it): ``dropped``, one clock at the packet's last beat. Mixed in before the
    crossbar's class; ``do_finalize`` after the parent's."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)
        self.dropped = Signal()

    def do_finalize(self) -> None:
        super().do_finalize()
        sink = self.master.sink
        taken = Signal()
        self.comb += [
            taken.eq(sum(port.source.valid for port in self.users.values()) != 0),
            self.dropped.eq(sink.valid & sink.ready & sink.last & ~taken),
        ]


_depacketizer_init = liteeth.packet.Depacketizer.__init__


def _cut_dropping_init(self: object, *args: object, **kwargs: object) -> None:
    """LiteEth's depacketizer, but a frame that ends inside the header is dropped (``cut``: one
    clock): LiteEth's only leaves the header state once the header is whole, so it would take
    the next frame's first bytes as the rest of this header."""
    _depacketizer_init(self, *args, **kwargs)
    sink, fsm = self.sink, self.fsm
    self.cut = Signal()
    self.comb += self.cut.eq(sink.valid & sink.last &
                             (fsm.ongoing("IDLE") | fsm.ongoing("HEADER-RECEIVE")))
    # the later assignment wins in Migen: back to IDLE, the partial header forgotten
    fsm.act("IDLE", If(sink.valid & sink.last, NextState("IDLE")))
    fsm.act("HEADER-RECEIVE", If(sink.valid & sink.last, NextState("IDLE")))


class FilteringMACCrossbar(DropSaying, LiteEthMACCrossbar):
    """LiteEth's MAC crossbar, dispatching only frames for our MAC, broadcast or IPv4 multicast.

    A frame for another station gets no user port: LiteX's Dispatcher then drops it (its
    ``default`` case takes the frame).
    """

    hw_mac: Signal | None = None

    def do_finalize(self) -> None:
        super().do_finalize()
        target = self.master.sink.target_mac
        ours = ((target == self.hw_mac) | (target == BCAST_MAC) |
                ((target & MCAST_MAC_MASK) == MCAST_MAC_OUI))
        # The parent set sel by EtherType; in Migen the later assignment wins: no port for a
        # frame that is not ours.
        self.comb += If(~ours, self.dispatcher.sel.eq(0))


class CountingIPCrossbar(DropSaying, LiteEthIPV4Crossbar):
    """LiteEth's IPv4 crossbar, saying when it drops a datagram (a protocol not UDP or ICMP)."""


class CheckingIPRX(LiteEthIPRX):
    """LiteEth's IPv4 receiver, refusing also fragments (MF set or a fragment offset: LiteEth
    does not reassemble) and a total length below an IPv4 and a UDP header; ``drop_header`` and
    ``drop_other`` (one clock) say it refused a datagram for its header or for its address."""

    def __init__(self, mac_address: object, ip_address: object, with_broadcast: object = True,
                 dw: int = 8) -> None:
        super().__init__(mac_address, ip_address, with_broadcast, dw)
        dep, fsm = self.depacketizer, self.fsm
        src = dep.source
        header = dep.header                      # byte k at bits 8k..8k+7
        more = header[6 * 8 + 5]                 # flags: MF
        offset = Signal(13)
        self.comb += offset.eq(Cat(header[7 * 8:8 * 8], header[6 * 8:6 * 8 + 5]))
        header_ok = Signal()
        ours = Signal()
        self.comb += [
            header_ok.eq((src.version == 0x4) & (src.ihl == 0x5) & (self.checksum.value == 0) &
                         ~more & (offset == 0) & (src.total_length >= MIN_IPV4_UDP)),
            ours.eq((src.target_ip == ip_address) | with_broadcast),
        ]
        decide = Signal()
        self.comb += decide.eq(fsm.ongoing("IDLE") & src.valid & self.checksum.done)
        # LiteEth's IDLE goes to RECEIVE on its own checks; the later assignment wins
        fsm.act("IDLE", If(decide & ~(header_ok & ours), NextState("DROP")))
        self.drop_header = Signal()
        self.drop_other = Signal()
        self.comb += [
            self.drop_header.eq(decide & ~header_ok),
            self.drop_other.eq(decide & header_ok & ~ours),
        ]


class MaskedUDPCrossbar(DropSaying, LiteEthUDPCrossbar):
    """LiteEth's UDP crossbar with its one user port taking every destination port equal to
    the port's key on the bits of ``mask`` (an RTPS participant listens on several: the SPDP
    multicast port, its metatraffic and its user-data unicast ports; the sideband says which)."""

    mask: Signal | None = None

    def do_finalize(self) -> None:
        super().do_finalize()
        assert len(self.users) == 1
        (key,) = self.users.keys()
        dst = self.master.sink.dst_port
        self.comb += If(((dst ^ key) & self.mask) == 0, self.dispatcher.sel.eq(1))


class ErrorRGMIIRX(LiteEthPHYRGMIIRX):
    """LiteEth's ECP5 RGMII receiver, with RGMII's receive error: ``rx_ctl`` carries RX_DV on the
    clock's rising edge and RX_DV xor RX_ER on its falling edge (IDDRX1F's two outputs, LiteEth
    reads the first only); a byte with RX_DV and RX_ER is inverted, so its frame's FCS fails
    (CRC-32 finds any one bad byte), as rfl_fabric_top does for GMII's rx_er. Found in LiteEth's
    statements (their names are local): the one registering ``source.valid`` from the rising
    edge's half of ``rx_ctl``, the one registering ``source.data``.
    """

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)
        sync = self._fragment.sync["sys"]
        valid = [st for st in sync if isinstance(st, _Assign) and st.l is self.source.valid]
        data = [st for st in sync if isinstance(st, _Assign) and st.l is self.source.data]
        assert len(valid) == 1 and len(data) == 1, "LiteEth's RGMII receiver changed"
        ctl = valid[0].r.value                  # rx_ctl_reg: [0] rising edge, [1] falling
        assert len(ctl) == 2 and valid[0].r.start == 0, "LiteEth's RGMII receiver changed"
        errored = Signal()
        self.comb += errored.eq(ctl[0] & ~ctl[1])         # RX_DV and (RX_DV xor RX_ER) = 0
        data[0].r = data[0].r ^ Replicate(errored, 8)


class HoldingUDPRX(LiteXModule):
    """LiteEth's UDP receiver (8 bits), but a payload shorter than its frame (Ethernet padding,
    trailing bytes) keeps its last byte until the frame ends, so that the frame's error (a bad
    FCS, known at its end) comes with it. LiteEth's own ends the payload at the UDP length and
    drops the rest, error included: a padded frame with a bad FCS would pass as good.
    Also refused: a UDP length above the IPv4 payload (``drop_header``, one clock); a frame
    shorter than its IPv4 total length ends its payload with ``length`` 0 (its bytes are not its
    length: the lab's port drops and counts it as cut).
    """

    def __init__(self, ip_address: object, dw: int = 8) -> None:
        assert dw == 8
        self.sink = sink = stream.Endpoint(eth_ipv4_user_description(dw))
        self.source = source = stream.Endpoint(eth_udp_user_description(dw))
        self.depacketizer = dep = LiteEthUDPDepacketizer(dw)
        self.comb += sink.connect(dep.sink)
        d = dep.source
        # count: the number of the byte after this one (from 1); more: this byte is not the
        # payload's last (count < payload_len a byte earlier, a register: the compare after the
        # UDP length's subtraction sat on the clock's critical path between the depacketizer's
        # header and this FSM)
        count = Signal(16)
        more = Signal()
        err = Signal()
        held = Signal(8)
        sport, dport, length, ip = Signal(16), Signal(16), Signal(16), Signal(32)
        payload_len = Signal(16)
        # bytes of the IPv4 payload after this beat (a register: no arithmetic between the
        # IPv4 header and the payload's length, LiteEth's long paths are there already); the
        # frame ends before its IPv4 payload if its last beat leaves some
        rest = Signal(16)
        cut = Signal()
        self.comb += [
            payload_len.eq(d.length - udp_header.length),
            cut.eq(rest != 0),
        ]
        take = [NextValue(count, count + 1), NextValue(more, count < payload_len),
                If(cut, NextValue(rest, rest - 1))]
        self.drop_header = Signal()
        self.fsm = fsm = FSM(reset_state="IDLE")
        fsm.act("IDLE",
            NextValue(count, 2), NextValue(more, payload_len > 1), NextValue(err, 0),
            NextValue(rest, sink.length - (udp_header.length + 1)),
            If(sink.length <= udp_header.length, NextValue(rest, 0)),
            If(d.valid, NextState("DROP"),
                If(sink.protocol == udp_protocol,
                    If(d.length > sink.length, self.drop_header.eq(1)
                    ).Else(NextState("RECEIVE")))))
        fsm.act("RECEIVE",
            source.src_port.eq(d.src_port), source.dst_port.eq(d.dst_port),
            source.length.eq(payload_len), source.ip_address.eq(sink.ip_address),
            source.data.eq(d.data),
            If(d.last | more,
                source.valid.eq(d.valid), d.ready.eq(source.ready),
                source.last.eq(d.last), source.error.eq(d.error | err),
                If(d.last & cut, source.length.eq(0)),
                If(d.valid & source.ready,
                    *take, NextValue(err, err | d.error),
                    If(d.last, NextState("IDLE"))),
            ).Else(                              # the payload's last byte, the frame goes on
                d.ready.eq(1),
                If(d.valid,
                    NextValue(held, d.data), NextValue(err, err | d.error),
                    NextValue(sport, d.src_port), NextValue(dport, d.dst_port),
                    NextValue(length, payload_len), NextValue(ip, sink.ip_address),
                    *take,
                    NextState("HOLD"))))
        fsm.act("HOLD",
            d.ready.eq(1),
            If(d.valid, NextValue(err, err | d.error), *take,
                If(d.last, If(cut, NextValue(length, 0)), NextState("EMIT"))))
        fsm.act("EMIT",
            source.valid.eq(1), source.last.eq(1), source.data.eq(held), source.error.eq(err),
            source.src_port.eq(sport), source.dst_port.eq(dport), source.length.eq(length),
            source.ip_address.eq(ip),
            If(source.ready, NextState("IDLE")))
        fsm.act("DROP",
            d.ready.eq(1),
            If(d.valid & d.last, NextState("IDLE")))


class LastByteTrim(LiteXModule):
    """A byte stream from LiteEth's 32-to-8 converter, ended where LiteEth's ``last_be`` says:
    a packet's last word is whole on the 8-bit side (the converter ignores ``last_be``), so
    the bytes after the one with ``last_be`` are dropped and ``last`` moves to it. Its error:
    any byte's of the packet, on its last byte only (as LiteEth's 8-bit path flags a bad FCS).
    Any byte's, not the last's: LiteEth's MAC depacketizer shifts the payload by the Ethernet
    header's 14 bytes but passes the error lanes through unshifted (``source.error =
    sink.error``), so a bad FCS's flag comes on another lane than the frame's last byte, or on
    the word before it (when the last word goes out a clock later, its last_be FSM's DELAYED
    state), never after it."""

    def __init__(self, layout: object) -> None:
        self.sink = sink = stream.Endpoint(layout)
        self.source = source = stream.Endpoint(layout)
        err = Signal()
        end = Signal()
        self.comb += end.eq(sink.last_be | sink.last)
        self.fsm = fsm = FSM(reset_state="COPY")
        fsm.act("COPY",
            sink.connect(source, omit={"last", "error"}),
            source.last.eq(end), source.error.eq(end & (err | sink.error)),
            If(sink.valid & source.ready,
                NextValue(err, err | sink.error),
                If(end, NextValue(err, 0), If(~sink.last, NextState("TRIM")))))
        fsm.act("TRIM",
            sink.ready.eq(1),
            If(sink.valid & sink.last, NextState("COPY")))


class PortUDP(LiteXModule):
    """The UDP layer at 8 bits in the port's clock domain ``cd``, beside a wider LiteEth core
    (``dw``) in ``sys``: the IPv4 crossbar's UDP port crosses (LiteX's ClockDomainCrossing, an
    asynchronous FIFO when ``cd`` is not ``sys``) at the core's width, converts in ``cd``
    (LiteX's StrideConverter, then :class:`LastByteTrim`), then LiteEth's UDP receiver and
    sender at 8 bits (the receiver :class:`HoldingUDPRX`) and the masked crossbar: so the
    lab's 8-bit receive rules hold as they are, and a byte a clock at the port's clock is a
    word every ``dw // 8`` clocks at the core's."""

    def __init__(self, ip: object, ip_address: object, dw: int, cd: str,
                 rx_depth: int, tx_depth: int) -> None:
        ip_port = ip.crossbar.get_port(udp_protocol, dw)
        wide, narrow = eth_ipv4_user_description(dw), eth_ipv4_user_description(8)
        renamed = ClockDomainsRenamer(cd)
        self.rx_cdc = stream.ClockDomainCrossing(wide, cd_from="sys", cd_to=cd, depth=rx_depth)
        self.rx_converter = renamed(stream.StrideConverter(wide, narrow))
        self.rx_trim = renamed(LastByteTrim(narrow))
        self.rx = renamed(HoldingUDPRX(ip_address, 8))
        self.tx = renamed(LiteEthUDPTX(ip_address, 8))
        self.tx_converter = renamed(stream.StrideConverter(narrow, wide))
        self.tx_cdc = stream.ClockDomainCrossing(wide, cd_from=cd, cd_to="sys", depth=tx_depth)
        self.crossbar = renamed(MaskedUDPCrossbar(8))
        # registers both ways between the byte-wide stages (LiteX's Buffer): LiteEth's stages
        # pass ready and valid combinationally, which chained across the layers was the 8-bit
        # core's critical path
        self.rx_buffer = renamed(stream.Buffer(narrow, pipe_valid=True, pipe_ready=True))
        self.tx_buffer = renamed(stream.Buffer(narrow, pipe_valid=True, pipe_ready=True))
        # and between the UDP receiver and the crossbar: its FSM's outputs went through the
        # crossbar's port select into the lab port's input register (clk's critical path)
        self.rx_out = renamed(stream.Buffer(eth_udp_user_description(8), pipe_valid=True))
        self.comb += [
            ip_port.source.connect(self.rx_cdc.sink),
            self.rx_cdc.source.connect(self.rx_converter.sink),
            self.rx_converter.source.connect(self.rx_trim.sink),
            self.rx_trim.source.connect(self.rx_buffer.sink),
            self.rx_buffer.source.connect(self.rx.sink),
            self.rx.source.connect(self.rx_out.sink),
            self.rx_out.source.connect(self.crossbar.master.sink),
            self.crossbar.master.source.connect(self.tx.sink),
            self.tx.source.connect(self.tx_buffer.sink),
            self.tx_buffer.source.connect(self.tx_converter.sink),
            self.tx_converter.source.connect(self.tx_cdc.sink),
            self.tx_cdc.source.connect(ip_port.sink),
        ]


class PulseMerge(LiteXModule):
    """One-clock pulses of several sources as one-clock pulses out, none lost: several at once
    go out on the clocks after (a backlog of 3 bits: the drops it carries come frames apart,
    and the layers between the CDC FIFOs may each drop one of different frames at once)."""

    def __init__(self, pulses: list[Signal]) -> None:
        self.o = Signal()
        backlog = Signal(3)
        total = Signal(4)
        self.comb += [total.eq(sum(pulses) + backlog), self.o.eq(total != 0)]
        self.sync += backlog.eq(total - self.o)


class UDPPortCore(SoCMini):
    """PHY + LiteEthIPCore (``data_width`` bits) + ``PortUDP`` + one raw UDP port (8 bits)
    with run-time addresses and port."""

    def __init__(self, platform: LatticePlatform, cfg: dict) -> None:
        SoCMini.__init__(self, platform, clk_freq=int(float(cfg["clk_freq"])))
        self.crg = CRG(platform.request("sys_clock"), platform.request("sys_reset"))

        phy = cfg["phy"]
        if phy == "gmii_model":
            ethphy = liteeth_phys.LiteEthPHYGMII(clock_pads=None, pads=platform.request("gmii_pads"),
                                                  model=True)
        elif phy == "ecp5_rgmii":
            ethphy = liteeth_phys.LiteEthECP5PHYRGMII(
                clock_pads=platform.request("rgmii_clocks"), pads=platform.request("rgmii_pads"),
                tx_delay=float(cfg.get("phy_tx_delay", 2e-9)),
                rx_delay=float(cfg.get("phy_rx_delay", 2e-9)),
                with_hw_init_reset=False)
        else:
            raise ValueError(f"phy: {phy!r}: gmii_model or ecp5_rgmii")
        self.ethphy = ethphy
        # LiteEth 2024.12's receive path with an 8-bit PHY and an 8-bit core never drives
        # last_be (LiteEthMACRXLastBE, which sets it from last, is only added when the core is
        # wider), and its CRC checker flags an error only on a byte lane last_be enables: a frame
        # with a bad FCS would pass as good. The PHY's last byte is its last lane.
        self.comb += ethphy.source.last_be.eq(ethphy.source.last)

        mac_address = platform.request("mac_address")
        ip_address = platform.request("ip_address")
        FilteringMACCrossbar.hw_mac = mac_address
        MaskedUDPCrossbar.mask = platform.request("udp_rx_port_mask")
        ip_multicast = platform.request("ip_multicast")
        take_group = Signal()                   # LiteEth's "broadcast" switch, made a signal
        dw = int(cfg.get("data_width", 8))
        # the UDP layer and port: on a clock of their own ("port": port_clock, port_reset) or
        # on the core's
        cd = "sys"
        if cfg.get("port_clock", False):
            cd = "port"
            self.cd_port = ClockDomain("port")
            self.comb += [self.cd_port.clk.eq(platform.request("port_clock")),
                          self.cd_port.rst.eq(platform.request("port_reset"))]
        self.core = LiteEthIPCore(
            ethphy, mac_address=mac_address, ip_address=ip_address,
            clk_freq=int(float(cfg["clk_freq"])), dw=dw,
            arp_entries=int(cfg.get("arp_entries", 1)),
            with_icmp=bool(cfg.get("with_icmp", True)),
            with_ip_broadcast=take_group,
            with_sys_datapath=bool(cfg.get("with_sys_datapath", False)),
            tx_cdc_depth=int(cfg.get("tx_cdc_depth", 32)),
            tx_cdc_buffered=bool(cfg.get("tx_cdc_buffered", False)),
            rx_cdc_depth=int(cfg.get("rx_cdc_depth", 32)), rx_cdc_buffered=False)
        # LiteEth's send path on the PHY's clock: its FIFO's read side, the 32-to-8 converter,
        # padding, CRC, preamble, gap: one combinational ready chain from the CRC back to the
        # FIFO's read pointer and memory (the PHY clock's critical path at 8 and at 32 bits).
        # A register both ways (LiteX's Buffer) after the FIFO cuts it; its Pipeline is made at
        # finalize time from this list.
        tx_path = self.core.mac.core.tx_datapath.pipeline
        (at,) = [k for k, m in enumerate(tx_path) if isinstance(m, stream.ClockDomainCrossing)]
        tx_buffer = ClockDomainsRenamer("eth_tx")(stream.Buffer(
            eth_phy_description(dw), pipe_valid=True, pipe_ready=True))
        self.core.mac.core.tx_datapath.tx_buffer = tx_buffer
        tx_path.insert(at + 1, tx_buffer)
        # Its receive path on the PHY's clock: the CRC checker's error (the CRC of the byte in,
        # compared with the residue) went on through the padding checker into the 8-to-32
        # converter's register, the PHY clock's critical path (118 MHz): a register after it.
        rx_path = self.core.mac.core.rx_datapath.pipeline
        (at,) = [k for k, m in enumerate(rx_path) if isinstance(m, LiteEthMACCRC32Checker)]
        rx_buffer = ClockDomainsRenamer("eth_rx")(stream.Buffer(
            eth_phy_description(len(ethphy.source.data)), pipe_valid=True))
        self.core.mac.core.rx_datapath.rx_buffer = rx_buffer
        rx_path.insert(at + 1, rx_buffer)
        self.core.udp = PortUDP(self.core.ip, ip_address, dw, cd,
                                rx_depth=int(cfg.get("port_rx_cdc_depth", 16)),
                                tx_depth=int(cfg.get("port_tx_cdc_depth", 16)))

        target = self.core.ip.rx.depacketizer.source.target_ip
        self.comb += take_group.eq(target == ip_multicast)
        ip_rx, udp_rx = self.core.ip.rx, self.core.udp.rx
        # the drop pulses: the MAC's and IPv4's in sys, the UDP layer's in cd: each side's
        # merged, sys's crossed to cd (a toggle: its pulses come a frame apart), then merged
        for name, core_pulses, port_pulses in (
                ("rx_drop_header",
                 [self.core.mac.depacketizer.cut, ip_rx.depacketizer.cut, ip_rx.drop_header],
                 [udp_rx.depacketizer.cut, udp_rx.drop_header]),
                ("rx_drop_other",
                 [self.core.mac.crossbar.dropped, ip_rx.drop_other,
                  self.core.ip.crossbar.dropped],
                 [self.core.udp.crossbar.dropped])):
            core_merge = PulseMerge(core_pulses)
            setattr(self, f"{name}_core", core_merge)
            crossed = core_merge.o
            if cd != "sys":
                sync = PulseSynchronizer("sys", cd)
                setattr(self, f"{name}_cdc", sync)
                self.comb += sync.i.eq(core_merge.o)
                crossed = sync.o
            port_merge = ClockDomainsRenamer(cd)(PulseMerge([crossed, *port_pulses]))
            setattr(self, f"{name}_port", port_merge)
            self.comb += platform.request(name).eq(port_merge.o)
        rx_port = platform.request("udp_rx_port")
        platform.add_extension(get_udp_raw_port_ios("udp", data_width=8))
        pads = platform.request("udp")
        port = self.core.udp.crossbar.get_port(rx_port, dw=8)
        self.comb += [
            port.sink.valid.eq(pads.sink_valid), port.sink.last.eq(pads.sink_last),
            port.sink.dst_port.eq(pads.sink_dst_port), port.sink.src_port.eq(pads.sink_src_port),
            port.sink.ip_address.eq(pads.sink_ip_address), port.sink.length.eq(pads.sink_length),
            pads.sink_ready.eq(port.sink.ready), port.sink.data.eq(pads.sink_data),
            port.sink.last_be.eq(pads.sink_last_be),
            pads.source_valid.eq(port.source.valid), pads.source_last.eq(port.source.last),
            pads.source_dst_port.eq(port.source.dst_port),
            pads.source_src_port.eq(port.source.src_port),
            pads.source_ip_address.eq(port.source.ip_address),
            pads.source_length.eq(port.source.length), port.source.ready.eq(pads.source_ready),
            pads.source_data.eq(port.source.data), pads.source_last_be.eq(port.source.last_be),
            pads.source_error.eq(port.source.error),
        ]


def main() -> None:
    """Generate the core a YAML file describes into the output folder (``NAME.v``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", help="YAML: name, phy, clk_freq, device (+ optional keys)")
    ap.add_argument("-o", "--output", required=True, help="folder for NAME.v")
    ap.add_argument("--build-dir", default="/tmp/liteeth_build")
    args = ap.parse_args()
    cfg = yaml.safe_load(Path(args.config).read_text())
    name = cfg["name"]
    liteeth.mac.LiteEthMACCrossbar = FilteringMACCrossbar   # before the core is built
    liteeth.packet.Depacketizer.__init__ = _cut_dropping_init
    liteeth.core.ip.LiteEthIPRX = CheckingIPRX
    liteeth.core.ip.LiteEthIPV4Crossbar = CountingIPCrossbar
    liteeth.phy.ecp5rgmii.LiteEthPHYRGMIIRX = ErrorRGMIIRX
    platform = LatticePlatform(cfg["device"], io=[], toolchain="trellis")
    platform.add_extension(_io)
    platform.add_extension(PADS)
    soc = UDPPortCore(platform, cfg)
    build_dir = Path(args.build_dir) / name
    builder = Builder(soc, output_dir=str(build_dir), compile_software=False,
                      compile_gateware=False, csr_csv=str(build_dir / "csr.csv"))
    builder.build(build_name=name)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    text = (build_dir / "gateware" / f"{name}.v").read_text()
    # The date LiteX writes would make every run a new file: the versions that made it instead.
    made = (f"// Made by   : tools/liteeth/gen_liteeth.py {Path(args.config).name} (liteeth "
            f"{version('liteeth')}, litex {version('litex')}, migen {version('migen')})")
    text = re.sub(r"^// Date .*$", made, text, count=1, flags=re.M)
    text = re.sub(r"^(//  Auto-Generated by LiteX) on .*$", r"\1.", text, flags=re.M)
    (out / f"{name}.v").write_text(text)
    print(out / f"{name}.v")


if __name__ == "__main__":
    main()
