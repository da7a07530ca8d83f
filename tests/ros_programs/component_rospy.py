"""rospy side of the FPGA component's real-ROS tests (run by /usr/bin/python3 with Debian's ROS).

Usage:
  component_rospy.py pub TOPIC COUNT WIDTH HEIGHT ENCODING OUTFILE [RATE] [TIMEOUT]
      wait for a subscriber, publish COUNT sensor_msgs/Image frames of pseudo-random pixels
      (seeded by the frame number, so each differs) at RATE per second (COUNT 0: until
      TIMEOUT); write every message as genpy serialized it (uint32 length + bytes) to OUTFILE,
      flushed after each.
  component_rospy.py sub TOPIC COUNT OUTFILE [TIMEOUT]
      subscribe with the real sensor_msgs/Image class; write every message received,
      re-serialized by genpy, to OUTFILE; exit after COUNT messages (or TIMEOUT).
Prints READY once registered, DONE at the end.
"""

import io
import random
import struct
import sys
import time

import rospy
from sensor_msgs.msg import Image

CHANNELS = {"mono8": 1, "rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4}


def body(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def make(k, width, height, encoding):
    step = width * CHANNELS[encoding]
    rng = random.Random(1000 + k)
    img = Image(height=height, width=width, encoding=encoding, is_bigendian=0, step=step)
    img.header.frame_id = "rospy_cam"
    img.header.stamp = rospy.Time(2000 + k, 1000 * k + 7)
    img.data = bytes(rng.getrandbits(8) for _ in range(4096)) * (height * step // 4096) + bytes(
        rng.getrandbits(8) for _ in range(height * step % 4096))
    return img


def main():
    mode, topic, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
    rospy.init_node("component_rospy_" + mode, disable_signals=True)
    if mode == "sub":
        outfile = sys.argv[4]
        timeout = float(sys.argv[5]) if len(sys.argv) > 5 else 60.0
        got = []
        rospy.Subscriber(topic, Image, lambda m: got.append(body(m)), queue_size=100,
                         buff_size=1 << 24)
        print("READY", flush=True)
        deadline = time.time() + timeout
        while len(got) < count and time.time() < deadline:
            time.sleep(0.01)
        with open(outfile, "wb") as out:
            for b in got:
                out.write(struct.pack("<I", len(b)) + b)
    else:
        width, height, encoding, outfile = int(sys.argv[4]), int(sys.argv[5]), sys.argv[6], sys.argv[7]
        rate = float(sys.argv[8]) if len(sys.argv) > 8 else 10.0
        timeout = float(sys.argv[9]) if len(sys.argv) > 9 else 60.0
        pub = rospy.Publisher(topic, Image, queue_size=100)
        print("READY", flush=True)
        deadline = time.time() + timeout
        while pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.3)
        with open(outfile, "wb") as out:
            k = 0
            while (count == 0 or k < count) and time.time() < deadline:
                msg = make(k, width, height, encoding)
                pub.publish(msg)
                b = body(msg)
                out.write(struct.pack("<I", len(b)) + b)
                out.flush()
                k += 1
                time.sleep(1.0 / rate)
        time.sleep(1.0)
    print("DONE", flush=True)
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    main()
