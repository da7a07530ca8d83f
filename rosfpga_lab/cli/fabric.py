"""``rosfpga-lab fabric sim CONFIG``: the ROS 2 node in the fabric, simulated whole in Verilator
and bridged to the host's network, for real ROS 2 peers (issue 31 item 3)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from rosfpga_lab.cli._args import positive_int
from rosfpga_lab.cli._signals import StopSignals

if TYPE_CHECKING:
    from rosfpga_lab.component.fabricsim import ShimBridge, TapBridge


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``fabric`` sub-command (and its ``sim``)."""
    parser = subparsers.add_parser(
        "fabric", help="the ROS 2 node in the fabric: simulate the network-attached top",
        description="The ROS 2 node in the fabric (rtl/fabric/rfl_fabric_top.v: LiteEth's "
        "UDP/IP core, RTPS and the generated CDR circuit). 'fabric sim CONFIG' runs it; "
        "'fabric counters' reads its counters over the network (a board, or fabric sim).")
    sub = parser.add_subparsers(dest="fabric_command", metavar="ACTION")
    p = sub.add_parser(
        "sim", help="run the whole network-attached top in Verilator, bridged to the host",
        description="Build (once; cached) the Verilator model of the node in the fabric for "
        "CONFIG (wire: cdr), its GMII side exchanging whole Ethernet frames with this "
        "process, and bridge it to the host: through a TAP interface (--tap) or, by "
        "default, a shim. --shim (the default; no root needed): the node's "
        "metatraffic and user-data UDP ports are bound on 127.0.0.1 (participant index 0 of "
        "--domain: 7410 and 7411 for domain 0); each datagram a peer sends there goes to the "
        "circuit as an Ethernet/IPv4/UDP frame, each frame the circuit sends comes back as a "
        "datagram (its SPDP to the unicast discovery ports of indices 0-9, as Cyclone DDS "
        "does on loopback); the bridge answers the circuit's ARP. The circuit learns its one "
        "peer from the participants' SPDP itself (the first one heard, until it is silent for "
        "its lease) and sends it its SEDP data (--bridge-peer: the bridge sets the peer's "
        "registers and asks for SEDP instead, the old way). Peers: ROS 2 on this host with Cyclone DDS configured for loopback "
        "(ParticipantIndex auto, peer localhost, no multicast) and MaxMessageSize 1472B (one "
        "Ethernet frame: the circuit does not reassemble IP fragments); one peer participant "
        "at a time. The clock runs at most --rate clocks per second, SPDP every --period "
        "clocks (the board's is 125 million at 125 MHz; scaled down here). Stops after "
        "--seconds or on Ctrl-C (SIGINT or SIGTERM), and prints the circuit's counters (the "
        "top's, then the RTPS stages' inside the node: rfl_rtps_rx, the seam rfl_rtps_to_cdr, "
        "rfl_rtps_tx, rfl_rtps_ctrl) and the bridge's; SIGUSR1 prints them while it runs "
        "(kill -USR1 PID). "
        "Example: rosfpga-lab fabric sim data/fpga_laserscan_min_cdr.yaml --seconds 60")
    p.add_argument("config", type=Path, metavar="CONFIG",
                   help="the node configuration (YAML, wire: cdr)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--shim", action="store_true",
                      help="bridge through UDP ports on 127.0.0.1 (the default; no root)")
    mode.add_argument("--tap", action="store_true",
                      help="bridge through a Linux TAP interface rfltap0 (root, "
                      "/dev/net/tun): the host is 10.31.0.1/24 on it, the node 10.31.0.2; "
                      "peers bind that interface (Cyclone DDS: NetworkInterface name rfltap0, "
                      "MaxMessageSize 1472B); the interface goes when the command ends")
    p.add_argument("--seconds", type=float, default=60.0, metavar="N",
                   help="run for N seconds (default 60)")
    p.add_argument("--domain", type=int, default=0, metavar="ID",
                   help="the DDS domain (ROS_DOMAIN_ID; default 0)")
    p.add_argument("--rate", type=int, default=None, metavar="CLOCKS",
                   help="at most CLOCKS clocks per second of wall time (default 400000; 0: as "
                   "fast as the model runs)")
    p.add_argument("--period", type=positive_int, default=None, metavar="CLOCKS",
                   help="clocks between SPDP announcements (default 400000: about a second "
                   "at the default rate)")
    p.add_argument("--max-bytes", type=positive_int, default=None, metavar="N",
                   help="the longest sample the circuit takes (its store-and-forward buffer; "
                   "default 2048, the board's): longer ones are dropped and counted; a 64x48 "
                   "rgba8 Image needs 16384")
    p.add_argument("--bridge-peer", action="store_true",
                   help="the bridge sets the circuit's peer (cfg_peer_* registers, send_sedp) "
                   "from the SPDP it reads, instead of the circuit learning it (cfg_learn)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the counters")
    p.set_defaults(func=run_sim)
    c = sub.add_parser(
        "counters", help="read the circuit's counters over UDP (a board, or fabric sim)",
        description="Ask the node in the fabric for its counters: one UDP datagram to its "
        "counter readout's port, one back with every counter (the top's, the RTPS stages', the "
        "readout's own; rtl/fabric/rfl_counter_readout.v), printed by name. Works on a board "
        "and against 'fabric sim' (--tap: the node is 10.31.0.2; the shim: 127.0.0.1). The "
        "readout answers at most 1000 requests a second and only well-formed ones; all others "
        "are dropped and counted. Example: rosfpga-lab fabric counters --host 10.31.0.2")
    c.add_argument("--host", default=None, metavar="IP",
                   help="the node's address (default 10.31.0.2: the board's and fabric sim "
                   "--tap's)")
    c.add_argument("--port", type=positive_int, default=None, metavar="P",
                   help="its counters port (default: the one of --domain, 7408 in domain 0)")
    c.add_argument("--domain", type=int, default=0, metavar="ID",
                   help="the DDS domain the node is in (gives the default --port; default 0)")
    c.add_argument("--timeout", type=float, default=1.0, metavar="S",
                   help="seconds to wait for the answer (default 1)")
    c.add_argument("--json", action="store_true", help="print them as one JSON object")
    c.set_defaults(func=run_counters)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


def run_counters(args: argparse.Namespace) -> int:
    """Ask for the counters, print them (name value a line, or JSON); 1 on no answer."""
    import json

    from rosfpga_lab.component.fabricsim import TAP_NODE_ADDRESS
    from rosfpga_lab.errors import LabError
    from rosfpga_lab.rtl.discrom import counters_port
    from rosfpga_lab.rtl.fabriccounters import read_counters
    from rosfpga_lab.rtps.entities import check_domain

    if args.timeout <= 0:
        print("rosfpga-lab fabric counters: error: --timeout must be positive", file=sys.stderr)
        return 2
    check_domain(args.domain)
    host = args.host or TAP_NODE_ADDRESS
    port = args.port or counters_port(args.domain)
    try:
        values = read_counters(host, port, args.timeout)
    except LabError as exc:
        print(f"rosfpga-lab fabric counters: error: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(values))
    else:
        width = max(map(len, values))
        for key, value in values.items():
            print(f"{key:<{width}}  {value}")
    return 0


def run_sim(args: argparse.Namespace) -> int:
    """Build, start, bridge for --seconds, print the counters."""
    from rosfpga_lab.component.fabricsim import TAP_HOST_CIDR, TAP_NAME, start_fabric
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.fabricsim import SIM_PERIOD, SIM_RATE
    from rosfpga_lab.rtps.entities import check_domain

    def say(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    if args.tap:
        from rosfpga_lab.graph.tap import tap_missing_reason

        reason = tap_missing_reason()
        if reason:
            print(f"rosfpga-lab fabric sim: error: --tap: {reason}", file=sys.stderr)
            return 2
    if args.seconds <= 0:
        print("rosfpga-lab fabric sim: error: --seconds must be positive", file=sys.stderr)
        return 2
    if args.rate is not None and args.rate < 0:
        print("rosfpga-lab fabric sim: error: --rate must be 0 or more", file=sys.stderr)
        return 2
    check_domain(args.domain)
    config = load_config(args.config)
    say(f"building (or taking from the cache) the Verilator model of {args.config} ...")
    bridge = start_fabric(config, domain=args.domain, tap=args.tap,
                          period=args.period or SIM_PERIOD,
                          rate=SIM_RATE if args.rate is None else args.rate,
                          max_bytes=args.max_bytes, bridge_peer=args.bridge_peer, log=say)
    started = time.monotonic()
    try:
        bridge.start()
        where = (f"TAP interface {TAP_NAME} (the host {TAP_HOST_CIDR})" if args.tap else
                 "127.0.0.1 through the shim")
        say(f"ready: the node is participant 0 of domain {args.domain} at "
            f"{bridge.rom.address}, UDP ports {bridge.meta} (metatraffic) and {bridge.user} "
            f"(user data), counters on {bridge.counters} (rosfpga-lab fabric counters --host "
            f"{bridge.rom.address}), on {where}; running {args.seconds:g} s (Ctrl-C stops)")
        with StopSignals(raise_interrupt=False) as stop:   # SIGINT, SIGTERM: counters, then out
            _bridge(bridge, args.seconds, lambda: stop.fired is not None, started)
        if stop.fired is not None:
            say("stopped by a signal")
    finally:
        bridge.close()
        report = bridge.sim.close()
    _print_counters(report.clocks, time.monotonic() - started, report.counters,
                    report.node_counters, bridge.counts.lines())
    err = bridge.sim.stderr().strip()
    if err:
        print(f"simulation's stderr: {err}", file=sys.stderr)
    return 0


def _print_counters(clocks: int, seconds: float, counters: Mapping[str, int],
                    node_counters: Mapping[str, int], bridge_lines: list[str]) -> None:
    """The circuit's counters (the top's, then the RTPS stages' a line a stage) and the
    bridge's, on stdout."""
    from rosfpga_lab.rtl.fabriccounters import stage_lines

    print(f"fabric sim: {clocks} clocks in {seconds:.1f} s "
          f"({clocks / max(seconds, 1e-9):,.0f} clocks/s)")
    print("circuit: " + ", ".join(f"{k} {v}" for k, v in counters.items()))
    for line in stage_lines(node_counters):
        print(line)
    for line in bridge_lines:
        print("bridge: " + line)
    sys.stdout.flush()


def _bridge(bridge: ShimBridge | TapBridge, seconds: float, stopped: Callable[[], bool],
            started: float) -> None:
    """Bridge for ``seconds`` or until ``stopped()``; on SIGUSR1 (main thread only) ask the
    simulation for its counters and print them when they come (at most a second's wait)."""
    asked = threading.Event()
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGUSR1, lambda _n, _f: asked.set()) if main else None
    try:
        end = time.monotonic() + seconds
        while not stopped() and bridge.sim.running() and time.monotonic() < end:
            bridge.run(end - time.monotonic(), stop=lambda: stopped() or asked.is_set())
            if asked.is_set():
                asked.clear()
                before = bridge.sim.node_counters
                bridge.sim.ask_counters()       # its 'N' report comes after the 'K' one
                bridge.run(min(1.0, max(end - time.monotonic(), 0.0)),
                           stop=lambda: stopped() or bridge.sim.node_counters is not before)
                _print_counters(bridge.sim.clocks, time.monotonic() - started,
                                bridge.sim.counters, bridge.sim.node_counters,
                                bridge.counts.lines())
    finally:
        if main:
            signal.signal(signal.SIGUSR1, signal.SIG_DFL if previous is None else previous)
