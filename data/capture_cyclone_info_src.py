#!/usr/bin/env python3
"""Capture data/cyclone_info_src_spdp.bin: one datagram in which Cyclone DDS (PyPI cyclonedds,
the DDS under rmw_cyclonedds_cpp) announces two participants of one process, the second after
an INFO_SRC submessage.

    python data/capture_cyclone_info_src.py [--domain N] [-o data/cyclone_info_src_spdp.bin]

Two Cyclone participants start in this process (as a ROS 2 process with two contexts, or the
camera and viewer of notebook 11, has them), configured for loopback without multicast as
rmw_cyclonedds_cpp users configure it. They share one UDP socket, so Cyclone packs their
submessages into one datagram: the RTPS header names the first participant, an INFO_SRC
submessage switches the source to the second (RTPS 2.3 8.3.7.9). A lab ROS 2 node on the same
domain records what it receives; the first datagram whose SPDP announcement follows an
INFO_SRC is kept. Loopback only; it stops after --timeout seconds.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path



def spdp_after_info_src(datagram: bytes) -> bool:
    """Whether an SPDP announcement in ``datagram`` comes from the participant an INFO_SRC names."""
    from rosfpga_lab.rtps import Data, RtpsError, parse_message
    from rosfpga_lab.rtps.entities import SPDP_WRITER

    try:
        msg = parse_message(datagram)
    except RtpsError:
        return False
    return any(isinstance(sub, Data) and sub.writer_id == SPDP_WRITER and sub.payload
               and source != msg.header.guid_prefix for source, _dst, sub in msg.routed())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--domain", type=int, default=78, help="DDS domain to use (default 78)")
    ap.add_argument("--timeout", type=float, default=15.0, help="seconds to wait (default 15)")
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent / "cyclone_info_src_spdp.bin")
    args = ap.parse_args(argv)
    from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri

    os.environ["CYCLONEDDS_URI"] = cyclone_loopback_uri()
    from cyclonedds.domain import DomainParticipant

    from rosfpga_lab.graph.ros2 import Ros2Node

    node = Ros2Node("capture", args.domain)
    peers: list[DomainParticipant] = []
    try:
        node.record()
        peers += [DomainParticipant(args.domain), DomainParticipant(args.domain)]
        deadline = time.monotonic() + args.timeout
        while time.monotonic() < deadline:
            for _t, _src, dst, payload in node.recorded().datagrams:
                if dst.endswith(f":{node.participant.meta[1]}") and spdp_after_info_src(payload):
                    args.output.write_bytes(payload)
                    print(f"{args.output}: {len(payload)} bytes")
                    return 0
            time.sleep(0.1)
        print("no SPDP after an INFO_SRC within the timeout", file=sys.stderr)
        return 1
    finally:
        peers.clear()
        node.close()


if __name__ == "__main__":
    sys.exit(main())
