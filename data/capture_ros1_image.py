#!/usr/bin/env python3
"""Make data/ros1_image.pcapng: real rosmaster, rospy and roscpp exchanging a small Image.

Rerun as root (dumpcap needs it) from the lab's checkout:
    sudo .venv/bin/python data/capture_ros1_image.py [--out FILE]
It needs Debian's ROS 1 Noetic (rosmaster, python3-rospy, python3-sensor-msgs,
libroscpp-dev, libsensor-msgs-dev), g++ and tshark (for dumpcap), as the lab's real-ROS
tests do.

A rosmaster on a free loopback port, a rospy node publishing FRAMES 64x48 rgb8 images on
/image_raw and a roscpp node subscribing to it: the XML-RPC registration, the master's
publisherUpdate, requestTopic, the TCPROS connection headers and the frames, all on
127.0.0.1. The capture is cut down to the connections of these three programs (their ports),
so other loopback traffic on the machine stays out. The script itself asks the master once
(``lookupNode``, as ``/capture``) for the roscpp node's port; that call is in the capture too.
"""

from __future__ import annotations

import argparse
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import xmlrpc.client
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "ros1_image.pcapng"
FRAMES = 4
WIDTH, HEIGHT = 64, 48
ROS_PYTHON = "/usr/bin/python3"

PUBLISHER = f'''
import sys, time, rospy
from sensor_msgs.msg import Image
rospy.init_node("rospy_camera", disable_signals=True, xmlrpc_port=int(sys.argv[1]),
                tcpros_port=int(sys.argv[2]))
pub = rospy.Publisher("/image_raw", Image, queue_size=10)
deadline = time.time() + 20
while pub.get_num_connections() == 0 and time.time() < deadline:
    time.sleep(0.05)
print("CONNECTED", flush=True)
time.sleep(0.3)
for k in range({FRAMES}):
    img = Image(height={HEIGHT}, width={WIDTH}, encoding="rgb8", is_bigendian=0, step={WIDTH * 3})
    img.header.seq = k
    img.header.stamp = rospy.Time(1700000000 + k, 1000 * k)
    img.header.frame_id = "camera"
    img.data = bytes((x * 3 + k * 40) % 256 for x in range({WIDTH * HEIGHT * 3}))
    pub.publish(img)
    time.sleep(0.2)
time.sleep(1.0)
print("DONE", flush=True)
'''

SUBSCRIBER_CPP = r'''
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <cstdio>
static int got = 0;
static void on_image(const sensor_msgs::Image::ConstPtr& m) {
  printf("got %u %ux%u %s\n", m->header.seq, m->width, m->height, m->encoding.c_str());
  fflush(stdout);
  ++got;
}
int main(int argc, char** argv) {
  ros::init(argc, argv, "roscpp_viewer", ros::init_options::NoSigintHandler);
  int count = atoi(argv[1]);
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe("/image_raw", 10, on_image);
  printf("READY\n");
  fflush(stdout);
  ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && got < count && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  return got < count;
}
'''
LIBS = ["-lroscpp", "-lrosconsole", "-lroscpp_serialization", "-lrostime", "-lxmlrpcpp",
        "-lcpp_common", "-lboost_system"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT, help=f"capture to write (default: {OUT})")
    out = parser.parse_args().out
    if os.geteuid() != 0:
        print("run as root (dumpcap on lo)", file=sys.stderr)
        return 2
    work = Path(tempfile.mkdtemp(prefix="rosfpga-ros1cap-"))
    exe = work / "roscpp_viewer"
    subprocess.run(["g++", "-O1", "-o", str(exe), "-x", "c++", "-", "-I/usr/include"] + LIBS,
                   input=SUBSCRIBER_CPP.encode(), check=True)
    master_port, pub_xmlrpc, pub_tcpros = free_port(), free_port(), free_port()
    master_uri = f"http://127.0.0.1:{master_port}/"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "PYTHON"))}
    env.update(ROS_MASTER_URI=master_uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(work),
               PYTHONUNBUFFERED="1")
    raw = work / "raw.pcapng"
    dumpcap = shutil.which("dumpcap") or "/usr/bin/dumpcap"
    procs = [subprocess.Popen(["rosmaster", "--core", "-p", str(master_port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    master = xmlrpc.client.ServerProxy(master_uri)
    for _ in range(100):
        try:
            master.getUri("/capture")
            break
        except OSError:
            time.sleep(0.1)
    # a large capture buffer (-B, MiB): other loopback traffic must not make the kernel drop ours
    cap = subprocess.Popen([dumpcap, "-q", "-B", "64", "-i", "lo", "-f", "tcp", "-w", str(raw)])
    try:
        time.sleep(2.0)
        sub = subprocess.Popen([str(exe), str(FRAMES)], env=env, stdout=subprocess.PIPE)
        procs.append(sub)
        assert sub.stdout.readline().strip() == b"READY"
        pub = subprocess.Popen([ROS_PYTHON, "-c", PUBLISHER, str(pub_xmlrpc), str(pub_tcpros)],
                               env=env, stdout=subprocess.PIPE)
        procs.append(pub)
        assert pub.stdout.readline().strip() == b"CONNECTED"
        code, _, sub_uri = master.lookupNode("/capture", "/roscpp_viewer")
        assert code == 1, sub_uri
        sub_xmlrpc = int(sub_uri.rstrip("/").rsplit(":", 1)[1])
        printed, _ = sub.communicate(timeout=60)
        print(printed.decode(), end="")
        pub.wait(timeout=30)
        time.sleep(1.0)
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                p.terminate()
                p.wait(timeout=10)
        time.sleep(1.0)
        cap.terminate()
        cap.wait(timeout=10)
    if sub.returncode:
        print("the roscpp subscriber did not get every frame", file=sys.stderr)
        return 1
    ports = ", ".join(str(p) for p in (master_port, pub_xmlrpc, pub_tcpros, sub_xmlrpc))
    subprocess.run(["tshark", "-r", str(raw), "-Y", f"tcp.port in {{{ports}}}", "-w", str(out)],
                   check=True, stderr=subprocess.DEVNULL)
    out.chmod(0o644)
    print(f"wrote {out} ({out.stat().st_size} bytes); ports master {master_port}, rospy "
          f"XML-RPC {pub_xmlrpc}, TCPROS {pub_tcpros}, roscpp XML-RPC {sub_xmlrpc}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
