#!/usr/bin/env python3
"""Capture data/cyclone_sedp_dispose.pcapng: what a lab ROS 2 node receives from Cyclone DDS
(PyPI cyclonedds, the DDS under rmw_cyclonedds_cpp) while a Cyclone writer appears, is matched
with the node's reader, and is deleted: SPDP, the SEDP announcement of the writer, and the SEDP
"disposed and unregistered" of that writer (a DATA with the K flag and PID_STATUS_INFO inline).

    python data/capture_cyclone_sedp_dispose.py [--domain N] [-o data/cyclone_sedp_dispose.pcapng]

The node records (Ros2Node.record); the datagrams sent to its ports are written as UDP packets
on loopback (pcapng, scapy), in the order they came, which Wireshark and
``rosfpga_lab.graph.capture_read.udp_datagrams`` read back. The first packet's comment names
the node's GUID prefix (the submessages are addressed to it with INFO_DST). Cyclone runs on
loopback without multicast, as rmw_cyclonedds_cpp users configure it; it stops after --timeout.
"""
# no "from __future__ import annotations": cyclonedds reads the field types at class creation

import argparse
import gc
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

TOPIC, ROS_TYPE = "/chatter", "std_msgs/String"


def write_pcapng(path: Path, datagrams: "list[tuple[float, str, str, bytes]]", comment: str) -> None:
    """``(time, "src:port", "dst:port", payload)`` as IPv4/UDP packets in a pcapng file."""
    from scapy.layers.inet import IP, UDP
    from scapy.layers.l2 import Ether
    from scapy.packet import Raw
    from scapy.utils import PcapNgWriter

    writer = PcapNgWriter(str(path))
    try:
        for k, (t, src, dst, payload) in enumerate(datagrams):
            (sh, sp), (dh, dp) = (s.rsplit(":", 1) for s in (src, dst))
            pkt = (Ether(src="00:00:00:00:00:00", dst="00:00:00:00:00:00")
                   / IP(src=sh, dst=dh, ttl=64) / UDP(sport=int(sp), dport=int(dp)) / Raw(payload))
            pkt.time = t
            if k == 0:
                pkt.comments = [comment.encode()]
            writer.write(pkt)
    finally:
        writer.close()


def main(argv: "list[str] | None" = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--domain", type=int, default=79, help="DDS domain to use (default 79)")
    ap.add_argument("--timeout", type=float, default=15.0, help="seconds to wait (default 15)")
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent / "cyclone_sedp_dispose.pcapng")
    args = ap.parse_args(argv)
    from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri

    os.environ["CYCLONEDDS_URI"] = cyclone_loopback_uri()
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from rosfpga_lab.graph.ros2 import Ros2Node
    from rosfpga_lab.rtps.build import dds_topic, dds_type

    @dataclass
    class String_(IdlStruct, typename=dds_type(ROS_TYPE)):
        data: str

    node = Ros2Node("capture", args.domain)
    try:
        node.record()
        sub = node.create_subscriber(TOPIC, ROS_TYPE, lambda payload, sample: None)
        deadline = time.monotonic() + args.timeout
        dp = DomainParticipant(args.domain)
        writer = DataWriter(dp, Topic(dp, dds_topic(TOPIC), String_))
        while not sub.matched() and time.monotonic() < deadline:
            time.sleep(0.05)
        if not sub.matched():
            print("the Cyclone writer was not matched within the timeout", file=sys.stderr)
            return 1
        time.sleep(0.5)                         # SEDP acknowledged both ways
        del writer
        gc.collect()                            # deletes the Cyclone writer: SEDP dispose
        while sub.matched() and time.monotonic() < deadline:
            time.sleep(0.05)
        if sub.matched():
            print("the Cyclone writer's dispose did not arrive within the timeout", file=sys.stderr)
            return 1
        rec = node.recorded()
        mine = {f"{a}:{p}" for a, p in (node.participant.meta, node.participant.user)}
        received = [d for d in rec.datagrams if d[2] in mine]
        write_pcapng(args.output, received, f"received by the lab participant "
                     f"{node.participant.guid_prefix.hex()}")
        print(f"{args.output}: {len(received)} datagrams")
        return 0
    finally:
        node.close()


if __name__ == "__main__":
    sys.exit(main())
