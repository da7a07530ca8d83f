"""``rosfpga-lab generate CONFIG -o DIR``: the HLS C++ of one component (Figure 4's flow)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``generate`` sub-command."""
    parser = subparsers.add_parser(
        "generate",
        help="generate the HLS C++ subscriber, publisher, testbench and Makefile from a node config",
        description="Generate, from a node configuration (YAML), the HLS C++ of a ROS-compliant "
        "FPGA component: subscriber, publisher, connection headers, application, top level, "
        "a C-simulation testbench with a test frame and the Python models' expected output, a "
        "Makefile ('make csim' builds and runs it with g++; 'make rtlsim' simulates the same "
        "circuit's Verilog, written into DIR/rtl/) and an HLS Tcl script (vitis_hls -f "
        "run_hls.tcl; the paper's vivado_hls with 'hls: {flavour: vivado}' in CONFIG). "
        "Examples: data/fpga_dilate_rgba8.yaml, data/fpga_erode_mono8.yaml, "
        "data/fpga_passthrough_rgb8.yaml (sensor_msgs/Image), data/fpga_laserscan_min.yaml, "
        "data/fpga_samples_dilate.yaml (every type: a project rendered from the message's "
        "circuit layout, one instruction per field); "
        "data/fpga_laserscan_min_cdr.yaml, data/fpga_samples_dilate_cdr.yaml, "
        "data/fpga_dilate_rgba8_cdr.yaml (wire: cdr: the same circuits on ROS 2's CDR samples; "
        "Image's pixels framed as video for its 2-D application).",
    )
    parser.add_argument("config", type=Path, metavar="CONFIG", help="the node configuration file (YAML)")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="directory to write into (created if missing; must be empty or "
                        "hold an earlier generation, see --force)")
    parser.add_argument("--force", action="store_true",
                        help="replace an earlier generation in DIR: delete the files its "
                        "manifest lists (and 'make csim' output) first; other files are kept")
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    parser.add_argument("--target", choices=("project", "fabric"), default="project",
                        help="what to write: 'project' (default) the HLS C++ and Verilog project; "
                        "'fabric' the discovery ROM of the ROS 2 node in the fabric (wire: cdr "
                        "only): its SPDP, SEDP and ros_discovery_info datagrams as $readmemh "
                        "files, the ROM and message table rtl/fabric/rfl_rtps_disc_rom.v reads, "
                        "the answer ROM and table rtl/fabric/rfl_rtps_disc_answer.v reads "
                        "(resends and HEARTBEATs of the reliable built-in writers), "
                        "and an index (offsets, lengths, destinations, run-time patch points, "
                        "answer slots), with the board build of a Colorlight 5A-75B v8.0 "
                        "(board/: its Verilog, pins and parameters; 'make bitstream' in the "
                        "output directory runs Yosys, nextpnr-ecp5 and ecppack)")
    parser.add_argument("--domain", type=int, default=0, metavar="ID",
                        help="--target fabric: the DDS domain (ROS_DOMAIN_ID; default 0)")
    parser.add_argument("--participant-index", type=int, default=0, metavar="N",
                        help="--target fabric: the participant index, which sets the node's "
                        "UDP ports (RTPS port mapping; default 0)")
    parser.add_argument("--address", default=None, metavar="IPV4",
                        help="--target fabric: the board's address on its link, which the node "
                        "announces (default 10.31.0.2, the node's address under 'fabric sim "
                        "--tap': one host set-up, 10.31.0.1/24, serves both)")
    parser.add_argument("--guid-prefix", metavar="HEX",
                        help="--target fabric: the participant's GUID prefix, 24 hex digits "
                        "(default: the lab's fixed fabric prefix; give each board of one DDS "
                        "domain its own)")
    parser.add_argument("--mac", default=None, metavar="MAC",
                        help="--target fabric: the board's MAC address (default "
                        "02:52:46:4c:00:02, locally administered)")
    parser.add_argument("--peer-ip", default=None, metavar="IPV4",
                        help="--target fabric: the host's address on the board's link, for the "
                        "board's README (the board learns its peer from SPDP; default: "
                        "--address with the last number 1, or 2 when that is the node)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Validate the configuration, then generate (errors are LabErrors, printed by the CLI)."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.project import generate_project

    def say(message: str) -> None:
        if not args.quiet:
            print(f"generate: {message}", file=sys.stderr)

    config = load_config(args.config)
    if args.target == "fabric":
        return _fabric(args, config)
    result = generate_project(config, args.output, force=args.force, progress=say)
    if result.kept:
        say(f"left alone {len(result.kept)} files not written by the generator: "
            + ", ".join(result.kept[:5]) + (" ..." if len(result.kept) > 5 else ""))
    if not args.quiet:
        print(f"wrote {len(result.files)} files into {result.out_dir}; "
              f"next: make -C {result.out_dir} csim"
              + (f" (or rtlsim)" if config.application.op != "custom" else ""))
    return 0


def _fabric(args: argparse.Namespace, config: object) -> int:
    """``--target fabric``: the discovery ROM's files into the output directory."""
    from rosfpga_lab.rtl.board import DEFAULT_MAC, default_peer, write_board
    from rosfpga_lab.rtl.discrom import DEFAULT_FABRIC_PREFIX, render_rom, write_rom
    from rosfpga_lab.rtl.errors import RtlError

    prefix = DEFAULT_FABRIC_PREFIX
    if args.guid_prefix is not None:
        try:
            prefix = bytes.fromhex(args.guid_prefix)
        except ValueError:
            raise RtlError(f"--guid-prefix {args.guid_prefix!r} is not hex digits") from None
    from rosfpga_lab.component.fabricsim import TAP_NODE_ADDRESS

    address = args.address or TAP_NODE_ADDRESS
    rom = render_rom(config, domain=args.domain, index=args.participant_index,  # type: ignore[arg-type]
                     address=address, guid_prefix=prefix)
    paths = write_rom(rom, args.output)
    peer_ip = args.peer_ip or default_peer(address)
    paths += write_board(config, rom, args.output, peer_ip=peer_ip,  # type: ignore[arg-type]
                         mac=args.mac or DEFAULT_MAC)
    if not args.quiet:
        sizes = ", ".join(f"{m.name} {len(m.data)}" for m in rom.messages)
        print(f"wrote {len(paths)} files into {args.output}: discovery ROM of "
              f"{len(rom.image())} bytes ({sizes}); 'make bitstream' there builds the "
              "board's bitstream")
    return 0
