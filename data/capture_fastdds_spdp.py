"""Capture data/fastdds_jazzy_spdp.bin: one SPDP datagram of a real ROS 2 Jazzy node (rclpy on
Fast DDS, the [ros2] extra's PyPI wheels) as it reaches a participant of this host.

    python data/capture_fastdds_spdp.py [--domain N] [-o data/fastdds_jazzy_spdp.bin]

An rclpy node starts in a subprocess with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, so Fast DDS
probes the discovery ports of participant indices on 127.0.0.1 (RTPS port mapping); this script
listens on the unicast discovery port of participant index 1 and keeps the first datagram
that starts with "RTPS" and carries an SPDP participant announcement (writer entity 0x000100c2).
Loopback only; it stops after --timeout seconds.
"""
from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SPDP_WRITER = bytes.fromhex("000100c2")
NODE = "import rclpy, time\nrclpy.init()\nn = rclpy.create_node('spdp_probe')\ntime.sleep({t})\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--domain", type=int, default=77, help="ROS_DOMAIN_ID to use (default 77)")
    ap.add_argument("--timeout", type=float, default=15.0, help="seconds to wait (default 15)")
    ap.add_argument("-o", "--output", type=Path,
                    default=Path(__file__).resolve().parent / "fastdds_jazzy_spdp.bin")
    args = ap.parse_args(argv)
    port = 7400 + 250 * args.domain + 10 + 2 * 1          # participant index 1's unicast port
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", port))
    sock.settimeout(0.5)
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, ROS_DOMAIN_ID=str(args.domain), ROS_HOME=home, ROS_LOG_DIR=home,
                   ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", RMW_IMPLEMENTATION="rmw_fastrtps_cpp")
        node = subprocess.Popen([sys.executable, "-c", NODE.format(t=args.timeout)], env=env)
        try:
            deadline = time.monotonic() + args.timeout
            while time.monotonic() < deadline:
                try:
                    dg, _ = sock.recvfrom(65536)
                except socket.timeout:
                    continue
                if dg.startswith(b"RTPS") and SPDP_WRITER in dg:
                    args.output.write_bytes(dg)
                    print(f"{args.output}: {len(dg)} bytes")
                    return 0
            print("no SPDP datagram from Fast DDS within the timeout", file=sys.stderr)
            return 1
        finally:
            node.kill()
            node.wait()


if __name__ == "__main__":
    sys.exit(main())
