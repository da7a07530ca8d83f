"""The run notebook 12 shows: one ``sensor_msgs/LaserScan`` sample through the ROS 2 node in the
fabric (``fabric/rfl_fabric_top.v``, GMII variant), from the Ethernet preamble in to the RTPS
DATA_FRAGs out, and the dump shipped in data/.

One owner for what the notebook, the script that made ``data/fabric_demo.vcd`` and the test that
regenerates it share: the circuit (:data:`DEMO_YAML`, the 330-beam variant of
``data/fpga_laserscan_min_cdr.yaml``: its new sample goes back in two DATA_FRAGs, as the peer's
came in, and the dump stays small), the addresses, the
sample (:func:`demo_sample`), how the peer sends it (:func:`demo_datagrams`: two DATA_FRAG
datagrams, fragments of :data:`FRAGMENT` bytes, in Ethernet/IPv4/UDP frames, :func:`demo_frames`), the
signals kept in the dump (:data:`DUMP_SIGNALS`) and the simulator. No simulation runs at
notebook time: the notebook reads the shipped dump (with :func:`stream_bytes`,
:func:`gmii_frames` and :func:`frame_layers`), made by Verilator (Icarus Verilog loops at
time 0 in LiteX's generated Verilog)::

    python data/make_fabric_dump.py          # rewrites data/fabric_demo.vcd (needs Verilator, g++)

How this works: :func:`run_fabric_demo` writes the generated top of the configuration
(:func:`rosfpga_lab.rtl.project.node_sources`), the discovery ROM (:mod:`rosfpga_lab.rtl.discrom`),
the frames as a ``$readmemh`` memory and the parameters into a folder, compiles them with
``tb/rfl_fabric_demo_tb.v`` (which plays the frames on the GMII receive side and answers the
node's ARP request) and runs it. Every parameter comes from the owners the cocotb test of the top
(tests/rtl/test_fabric_top.py) uses.
"""

from __future__ import annotations

import ipaddress
import struct
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.graph import ethframe
from rosfpga_lab.graph.ethframe import ArpRequest, mac_bytes
from rosfpga_lab.rtl.discrom import (
    fabric_participant, fabric_top_literals, render_rom, write_rom,
)
from rosfpga_lab.rtl.errors import RtlError, SimulatorMissingError
from rosfpga_lab.rtl.limits import BUILD_TIMEOUT, FABRIC_DEMO_MAX_CLOCKS, RUN_TIMEOUT
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_TOP_GMII
from rosfpga_lab.rtl.vcd import Waveform
from rosfpga_lab.rtl.tools import TB_DIR, _verilator, simulator_missing_reason
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import discovery_port, user_port
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES

#: The scan's beams: enough that the new sample (1380 bytes) is longer than rfl_rtps_tx's
#: DATA_FRAG fragment (FRAG_BYTES, 1344: it goes back as two DATA_FRAGs), few enough that the
#: dump stays under 250 KB (360 would make it some 260 KB).
BEAMS = 330
#: The circuit: data/fpga_laserscan_min_cdr.yaml with :data:`BEAMS` beams instead of 360.
DEMO_YAML = f"""\
node: {{name: /fpga_scan_min}}
subscriber: {{topic: /scan, type: sensor_msgs/LaserScan}}
publisher: {{topic: /scan_min}}
stream: {{field: ranges, length: {BEAMS}}}
checks:
  range_max: {{max: 1000.0}}
limits:
  header.frame_id: 64
  intensities: {BEAMS}
application: {{op: erode, ksize: 5}}
wire: cdr
"""
NODE_MAC, NODE_IP = "02:52:46:4c:00:02", "192.168.10.2"
PEER_MAC, PEER_IP = "02:00:00:00:00:01", "192.168.10.1"
#: The peer's GUID prefix, its participant index and its writer's entity id.
PEER_PREFIX = bytes.fromhex("010fcafe0000000100000001")
PEER_INDEX = 1
PEER_WRITER = 0x00001103
#: The peer's source port (any: the node answers on the RTPS mapping's ports).
PEER_SPORT = 40000
#: The peer's DATA_FRAG fragment size, the lab's software writer's: the sample goes in two
#: datagrams.
FRAGMENT = FRAGMENT_BYTES
#: The node's INFO_TS (``cfg_time``: seconds, then 2**-32 s).
TIME = (1_700_000_000 << 32) | 0x8000_0000
PREAMBLE = bytes.fromhex("55555555555555d5")
#: The beams that see the post (the notebook shows the minimum widen it by two each side).
POST = slice(160, 164)
#: Idle clocks between the frames the peer sends, and after the last frame out.
GAP, HOLD = 40, 60
PERIOD = 1_000_000                          # one SPDP announcement (at reset) in the run
#: One compilation unit: the PyPI wheel's split build fails on its precompiled headers
#: (:data:`rosfpga_lab.hls.rtlbuild.HARNESS_MAKEFLAGS` says how).
MAKEFLAGS = "OPT_FAST=-O1 OPT_GLOBAL=-O1 VM_PARALLEL_BUILDS=0"
DUMP_NAME = "fabric_demo.vcd"
DUMP_SIMULATOR = "verilator"
#: The dump's time unit and precision: whole nanoseconds (a clock is 8 ns) keep its timestamps,
#: half its bytes at picoseconds, short.
DUMP_TIMESCALE = "1ns/1ns"
#: The signals in the dump, stage by stage (tb/rfl_fabric_demo_tb.v declares them, in its scope).
DUMP_SIGNALS = (
    "clk", "rst_n", "rxd", "rx_dv",                               # GMII in (the PHY's bytes)
    "le_rx_data", "le_rx_valid", "le_rx_ready", "le_rx_last",     # LiteEth's UDP payload out
    "p_rx_tdata", "p_rx_tvalid", "p_rx_tready", "p_rx_tlast",     # rfl_udp_port, whole datagrams
    "rx_state",                                                   # rfl_rtps_rx's walk
    "rx_tdata", "rx_tvalid", "rx_tready", "rx_tlast",             # the sample's bytes
    "rec_tdata", "rec_tvalid", "rec_tready",                      # the CDR subscriber's input
    "pub_tdata", "pub_tvalid", "pub_tready",                      # the CDR publisher's output
    "status_valid", "status",                                     # the subscriber's decision
    "tx_tdata", "tx_tvalid", "tx_tready", "tx_tlast",             # rfl_rtps_tx: RTPS out
    "le_tx_data", "le_tx_valid", "le_tx_ready", "le_tx_last",     # to LiteEth
    "txd", "tx_en",                                               # GMII out
)
#: rfl_rtps_rx's states (its ``st``), as rfl_rtps_rx.v numbers them.
RX_STATES = ("S_HDR", "S_SUBHDR", "S_FIELDS", "S_D1", "S_D2", "S_GAP", "S_QOS", "S_PAY",
             "S_SKIP", "S_DROP")


def demo_config() -> NodeConfig:
    """The demo's node configuration."""
    return parse_config(DEMO_YAML, source="rosfpga_lab.rtl.fabricdemo")


def demo_ranges() -> np.ndarray:
    """The sample's :data:`BEAMS` ranges (float32, metres): a wall at 2 m with a post at 1.2 m
    (beams :data:`POST`) and one beam that saw nothing (inf, beam 280)."""
    ranges = np.full(BEAMS, 2.0, np.float32)
    ranges[POST] = 1.2
    ranges[280] = np.inf
    return ranges


def demo_sample() -> bytes:
    """The LaserScan sample the peer publishes, as the lab's CDR writer serializes it
    (encapsulation included)."""
    from rosfpga_lab.msg.cdr import serialize_cdr

    return serialize_cdr(None, "sensor_msgs/LaserScan", {
        "header": {"stamp": {"sec": 12, "nanosec": 34}, "frame_id": "laser"},
        "angle_min": -0.785, "angle_max": 0.785, "angle_increment": 0.0175,
        "time_increment": 0.0, "scan_time": 0.1, "range_min": 0.05, "range_max": 30.0,
        "ranges": [float(r) for r in demo_ranges()], "intensities": []})


def _ids(config: NodeConfig) -> tuple[int, int]:
    """The fabric participant's output writer and input reader entity ids."""
    _p, _node, wid, rid = fabric_participant(config)
    return wid, rid


def demo_datagrams(config: NodeConfig | None = None) -> list[bytes]:
    """The peer's two RTPS datagrams: header, INFO_TS and DATA_FRAG 1; header and DATA_FRAG 2."""
    config = config or demo_config()
    _wid, rid = _ids(config)
    sample = b.pad_payload(demo_sample())
    parts = [sample[k:k + FRAGMENT] for k in range(0, len(sample), FRAGMENT)]
    if len(parts) != 2:
        raise RtlError(f"the demo sample is {len(sample)} bytes: not two fragments of {FRAGMENT}")
    hdr = b.header(PEER_PREFIX)
    return [hdr + b.info_ts(1_700_000_000.25) +
            b.data_frag(rid, PEER_WRITER, 1, 1, FRAGMENT, len(sample), parts[0], 1),
            hdr + b.data_frag(rid, PEER_WRITER, 1, 2, FRAGMENT, len(sample), parts[1], 1)]


def udp_frame(payload: bytes, dport: int, *, sport: int = PEER_SPORT, ident: int = 1) -> bytes:
    """The peer's Ethernet II frame to the node around ``payload`` (IPv4, UDP without a
    checksum, padded, FCS: :func:`rosfpga_lab.graph.ethframe.udp_frame`); no preamble."""
    return ethframe.udp_frame(payload, src_mac=mac_bytes(PEER_MAC), dst_mac=mac_bytes(NODE_MAC),
                              src_ip=PEER_IP, dst_ip=NODE_IP, src_port=sport, dst_port=dport,
                              ident=ident)


def arp_reply() -> bytes:
    """The peer's ARP reply to the node (its MAC for its IP), with FCS; no preamble."""
    return ethframe.arp_reply(ArpRequest(mac_bytes(NODE_MAC), NODE_IP, PEER_IP),
                              mac_bytes(PEER_MAC))


def demo_frames(config: NodeConfig | None = None) -> list[bytes]:
    """The two frames the peer sends, as the PHY carries them: preamble and SFD, then the frame
    (to the node's user-data port, RTPS port mapping)."""
    return [PREAMBLE + udp_frame(d, user_port(0, 0), ident=k)
            for k, d in enumerate(demo_datagrams(config), 1)]


def _params(config: NodeConfig, where: Path) -> tuple[dict[str, str], int]:
    rom = render_rom(config)
    write_rom(rom, where)
    params = dict(fabric_top_literals(rom, period=PERIOD), MAX_BYTES="2048")
    return params, 3       # out: the SPDP announcement, then the new sample's two DATA_FRAGs


def run_fabric_demo(vcd: str | Path, *, config: NodeConfig | None = None,
                    simulator: str = DUMP_SIMULATOR) -> Path:
    """Simulate the demo with Verilator, dumping :data:`DUMP_SIGNALS` into ``vcd`` (the build
    some 30 s, the run a few).

    Raises:
        RtlError: no Verilator or C++ compiler, or the simulation failed or did not finish.
    """
    from rosfpga_lab.rtl.project import node_sources

    if simulator != "verilator":
        raise RtlError(f"the fabric demo runs on Verilator, not {simulator!r}")
    why = simulator_missing_reason("verilator")
    if why:
        raise SimulatorMissingError(why)
    config = config or demo_config()
    vcd = Path(vcd).resolve()
    with tempfile.TemporaryDirectory(prefix="rfl-fabric-demo-") as tmp:
        where = Path(tmp)
        for name, data in node_sources(config).items():
            if name != "rfl_tb.v":
                (where / name).write_bytes(data)
        params, expect = _params(config, where)
        frames = [PREAMBLE + arp_reply(), *demo_frames(config)]
        (where / "rfl_fabric_demo_rx.hex").write_text(
            "\n".join(f"{x:02x}" for x in b"".join(frames)) + "\n")
        (where / "rfl_fabric_demo_len.hex").write_text(
            "\n".join(f"{len(f):04x}" for f in frames) + "\n")
        defines = {"RFL_DEMO_PARAMS": ", ".join(f".{k}({v})" for k, v in params.items()),
                   "RFL_DEMO_MAC": f"48'h{NODE_MAC.replace(':', '')}",
                   "RFL_DEMO_IP": f"32'h{ipaddress.IPv4Address(NODE_IP).packed.hex()}",
                   "RFL_DEMO_PEER_IP": f"32'h{ipaddress.IPv4Address(PEER_IP).packed.hex()}",
                   "RFL_DEMO_PEER_META": str(discovery_port(0, PEER_INDEX)),
                   "RFL_DEMO_PEER_USER": str(user_port(0, PEER_INDEX)),
                   "RFL_DEMO_READER": f"32'h{_ids(config)[1]:08x}",
                   "RFL_DEMO_WRITER": f"32'h{PEER_WRITER:08x}",
                   "RFL_DEMO_TIME": f"64'h{TIME:016x}",
                   "RFL_DEMO_BYTES": str(sum(map(len, frames))),
                   "RFL_DEMO_FRAMES": str(len(frames)),
                   "RFL_DEMO_GAP": str(GAP), "RFL_DEMO_HOLD": str(HOLD),
                   "RFL_DEMO_EXPECT": str(expect),
                   "RFL_DEMO_MAX_CLOCKS": str(FABRIC_DEMO_MAX_CLOCKS),
                   "RFL_DEMO_VCD": f'"{vcd}"'}
        (where / "rfl_fabric_demo_params.vh").write_text(
            "".join(f"`define {k} {v}\n" for k, v in defines.items()))
        sources = [*(FABRIC_DIR / m for m in FABRIC_TOP_GMII),
                   *sorted(p for p in where.glob("*.v")), TB_DIR / "rfl_fabric_demo_tb.v"]
        cmd = [_verilator() or "verilator", "--binary", "--timing", "-O1", "--trace",
               "--timescale-override", DUMP_TIMESCALE,
               "--trace-depth", "1", "-Wno-fatal", "-Wno-lint", "-Wno-style", "-Wno-UNOPTFLAT",
               f"-I{where}", f"-I{FABRIC_DIR}", "--top-module", "tb", "-Mdir", str(where / "obj_dir"), "-o",
               "rfl_sim", "-MAKEFLAGS", MAKEFLAGS, *map(str, sources)]
        done = subprocess.run(cmd, cwd=where, capture_output=True, text=True,
                              timeout=BUILD_TIMEOUT)
        if done.returncode:
            raise RtlError(f"Verilator failed:\n{done.stdout[-1500:]}{done.stderr[-3000:]}")
        done = subprocess.run([str(where / "obj_dir" / "rfl_sim")], cwd=where,
                              capture_output=True, text=True, timeout=RUN_TIMEOUT)
        if done.returncode or "RFL_DEMO_DONE" not in done.stdout:
            raise RtlError(f"the fabric demo did not finish:\n{done.stdout[-2000:]}"
                           f"{done.stderr[-2000:]}")
        if f"ipv4={expect}" not in done.stdout:
            raise RtlError(f"the fabric demo sent other than {expect} IPv4 frames: "
                           f"{done.stdout.strip()[-300:]}")
    return vcd


def shipped_dump() -> Path | None:
    """``data/fabric_demo.vcd`` of the checkout the lab runs from, or None when it is not
    there."""
    here = Path(__file__).resolve()
    for root in (here.parents[2], Path.cwd(), Path.cwd().parent):
        path = root / "data" / DUMP_NAME
        if path.is_file():
            return path
    return None


#: The byte streams of the dump, in the order a sample crosses them: (name in the dump, what it
#: carries). LiteEth's ports are named ``_data``/``_valid``/``_ready``, the lab's ``_t*``.
STAGES = (
    ("le_rx", "LiteEth's UDP payload out (a datagram as the frame's bytes arrive)"),
    ("p_rx", "rfl_udp_port: a whole datagram, once its FCS was good"),
    ("rx", "rfl_rtps_rx: the sample's bytes, the RTPS around them taken off"),
    ("rec", "rfl_rtps_to_cdr: the sample's length, then the sample, into the CDR subscriber"),
    ("pub", "the CDR publisher's output: the sample's length, then the new sample"),
    ("tx", "rfl_rtps_tx: the RTPS datagram around the new sample"),
    ("le_tx", "into LiteEth: the datagram it sends as Ethernet/IPv4/UDP"),
)


def _part(wave: Waveform, stage: str, part: str) -> np.ndarray:
    lab = stage not in ("le_rx", "le_tx")
    return wave.values(f"{stage}_{'t' if lab else ''}{part}")


def stream_bytes(wave: Waveform, stage: str) -> tuple[np.ndarray, bytes]:
    """The clocks at which ``stage`` (a name of :data:`STAGES`) moved a byte (valid and ready
    both 1) and those bytes, in order."""
    fire = _part(wave, stage, "valid").astype(bool) & _part(wave, stage, "ready").astype(bool)
    return np.flatnonzero(fire), _part(wave, stage, "data")[fire].astype(np.uint8).tobytes()


def gmii_frames(wave: Waveform, side: str) -> list[tuple[int, bytes]]:
    """The frames on the GMII ``"rx"`` (into the node) or ``"tx"`` side: each its first clock
    and its bytes (preamble, SFD and FCS included)."""
    enable = wave.values("rx_dv" if side == "rx" else "tx_en").astype(np.int8)
    data = wave.values("rxd" if side == "rx" else "txd").astype(np.uint8)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], enable, [0]))))
    return [(int(a), data[a:z].tobytes()) for a, z in zip(edges[::2], edges[1::2])]


def frame_layers(frame: bytes) -> list[tuple[str, int, int, str]]:
    """A GMII frame carrying IPv4/UDP (preamble first, FCS last) cut into its layers: each
    ``(layer, first byte, end, what its fields say)``; the RTPS message is one layer here
    (``rtps.parse_message`` reads it); padding up to Ethernet's minimum only when there is some.

    Raises:
        RtlError: not preamble + Ethernet II + IPv4 + UDP.
    """
    p = len(PREAMBLE)
    if frame[:p] != PREAMBLE or frame[p + 12:p + 14] != b"\x08\x00" or frame[p + 23] != 17:
        raise RtlError("not a GMII frame of IPv4/UDP (preamble, Ethernet II, IPv4, UDP)")
    e, ihl = p + 14, 4 * (frame[p + 14] & 0x0F)
    u = e + ihl
    total, ident, ttl, _proto, csum = struct.unpack(">2xHH2xBBH", frame[e:e + 12])
    sport, dport, ulen, ucsum = struct.unpack(">HHHH", frame[u:u + 8])

    def mac(b: bytes) -> str:
        return ":".join(f"{x:02x}" for x in b)

    layers = [
        ("preamble+SFD", 0, p, "7 x 0x55, then 0xd5: the receiver locks on, the frame starts"),
        ("Ethernet", p, e, f"to {mac(frame[p:p + 6])} from {mac(frame[p + 6:p + 12])}, "
                           "EtherType 0x0800 (IPv4)"),
        ("IPv4", e, u, f"{ipaddress.IPv4Address(frame[e + 12:e + 16])} -> "
                       f"{ipaddress.IPv4Address(frame[e + 16:e + 20])}, {total} bytes, id {ident}, "
                       f"TTL {ttl}, protocol 17 (UDP), checksum 0x{csum:04x}"),
        ("UDP", u, u + 8, f"port {sport} -> {dport}, {ulen} bytes, checksum 0x{ucsum:04x}"
                          f"{' (none)' if ucsum == 0 else ''}"),
        ("RTPS", u + 8, u + ulen, f"{ulen - 8} bytes: header and submessages"),
        ("padding", u + ulen, len(frame) - 4, "up to Ethernet's 60-byte minimum"),
        ("FCS", len(frame) - 4, len(frame), f"CRC-32 0x{int.from_bytes(frame[-4:], 'little'):08x}"),
    ]
    return [layer for layer in layers if layer[2] > layer[1]]     # no padding: none listed
