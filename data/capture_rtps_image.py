#!/usr/bin/env python3
"""Make data/rtps_image.pcapng: Cyclone DDS sending a ROS 2-style Image over loopback.

Rerun as root (dumpcap needs it) from the lab's checkout, with the lab's environment:
    sudo .venv/bin/python data/capture_rtps_image.py [--out FILE]
It needs Debian's tshark (for dumpcap) and PyPI's cyclonedds (in the lab's [test] extra).

A subscriber and a publisher (two processes, DDS domain 0) find each other by SPDP/SEDP over
127.0.0.1 only (no multicast: the peer list is 127.0.0.1), then the publisher sends FRAMES
640x480 rgb8 images on the ROS 2 topic /image_raw, i.e. DDS topic "rt/image_raw" of type
"sensor_msgs::msg::dds_::Image_", as rmw_cyclonedds_cpp names them. Each 921,600-byte sample
is far larger than a UDP datagram, so it travels as DATA_FRAG submessages.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "rtps_image.pcapng"
FRAMES = 2
WIDTH, HEIGHT = 640, 480
CONFIG = """<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface name="lo"/>
</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><Peers>
<Peer address="127.0.0.1"/></Peers><ParticipantIndex>auto</ParticipantIndex>
<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex></Discovery></Domain></CycloneDDS>"""

TYPES = '''
from dataclasses import dataclass
from cyclonedds.idl import IdlStruct
import cyclonedds.idl.types as t

@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32

@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_
    frame_id: str

@dataclass
class Image_(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header_
    height: t.uint32
    width: t.uint32
    encoding: str
    is_bigendian: t.uint8
    step: t.uint32
    data: t.sequence[t.uint8]
'''

PUBLISHER = TYPES + f'''
import time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.pub import DataWriter
from cyclonedds.core import Qos, Policy
dp = DomainParticipant(0)
writer = DataWriter(dp, Topic(dp, "rt/image_raw", Image_),
                    qos=Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.History.KeepLast(1)))
deadline = time.time() + 10
while not writer.get_matched_subscriptions() and time.time() < deadline:
    time.sleep(0.05)
time.sleep(0.5)
for i in range({FRAMES}):
    pixels = bytes((x * 7 + i) % 256 for x in range({WIDTH} * {HEIGHT} * 3))
    writer.write(Image_(Header_(Time_(1700000000 + i, 500), "camera"), {HEIGHT}, {WIDTH}, "rgb8",
                        0, {WIDTH} * 3, list(pixels)))
    time.sleep(0.3)
time.sleep(1.0)
'''

SUBSCRIBER = TYPES + '''
import sys, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.sub import DataReader
from cyclonedds.core import Qos, Policy
dp = DomainParticipant(0)
reader = DataReader(dp, Topic(dp, "rt/image_raw", Image_),
                    qos=Qos(Policy.Reliability.Reliable(1_000_000_000), Policy.History.KeepLast(5)))
got = 0
deadline = time.time() + 20
while got < int(sys.argv[1]) and time.time() < deadline:
    for s in reader.take(10):
        got += 1
        print("got", s.width, s.height, s.encoding, len(s.data), flush=True)
    time.sleep(0.02)
sys.exit(0 if got >= int(sys.argv[1]) else 1)
'''


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT, help=f"capture to write (default: {OUT})")
    out = parser.parse_args().out
    dumpcap = shutil.which("dumpcap") or "/usr/bin/dumpcap"
    if os.geteuid() != 0:
        print("run as root (dumpcap on lo)", file=sys.stderr)
        return 2
    work = Path(tempfile.mkdtemp(prefix="rosfpga-rtps-"))
    (work / "cyclonedds.xml").write_text(CONFIG)
    env = dict(os.environ, CYCLONEDDS_URI=f"file://{work / 'cyclonedds.xml'}")
    cap = subprocess.Popen([dumpcap, "-q", "-i", "lo", "-f", "udp portrange 7400-7999", "-w", str(work / "raw.pcapng")])
    time.sleep(2.0)
    try:
        sub = subprocess.Popen([sys.executable, "-c", SUBSCRIBER, str(FRAMES)], env=env)
        time.sleep(1.0)
        pub = subprocess.run([sys.executable, "-c", PUBLISHER], env=env, timeout=60)
        sub_rc = sub.wait(timeout=30)
        time.sleep(1.0)
    finally:
        cap.terminate()
        cap.wait(timeout=10)
    if pub.returncode or sub_rc:
        print(f"publisher exit {pub.returncode}, subscriber exit {sub_rc}", file=sys.stderr)
        return 1
    shutil.copy(work / "raw.pcapng", out)
    out.chmod(0o644)
    print(f"wrote {out} ({out.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
