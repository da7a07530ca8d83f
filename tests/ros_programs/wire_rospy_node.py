"""rospy side of the lab's TCPROS interop tests (run by /usr/bin/python3 with Debian's ROS).

Usage:
  wire_rospy_node.py sub TYPE TOPIC COUNT OUTFILE [TIMEOUT]
      subscribe with the real generated class; for every message received write its genpy
      re-serialization as uint32 length + bytes to OUTFILE; exit after COUNT messages.
  wire_rospy_node.py pub TYPE TOPIC COUNT OUTFILE [TIMEOUT]
      wait for a subscriber, publish COUNT deterministic messages (COUNT=0: forever at 20 Hz),
      write what was sent (serialized after publish, seq included) to OUTFILE.
TYPE is String, Int32 or Image. Prints READY once registered, DONE at the end.
"""

import io
import struct
import sys
import time

import rospy
from sensor_msgs.msg import Image
from std_msgs.msg import Int32, String

TYPES = {"String": String, "Int32": Int32, "Image": Image}


def make(kind, k):
    if kind == "String":
        return String(data="msg %d \u00e9" % k)
    if kind == "Int32":
        return Int32(data=k)
    img = Image(height=480, width=640, encoding="rgba8", is_bigendian=0, step=2560)
    img.header.frame_id = "rospy"
    img.header.stamp = rospy.Time(1000 + k, 17)
    img.data = bytes(((i * 7 + k * 13) & 0xFF) for i in range(256)) * (640 * 480 * 4 // 256)
    return img


def body(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def main():
    mode, kind, topic, count, outfile = sys.argv[1:6]
    count = int(count)
    timeout = float(sys.argv[6]) if len(sys.argv) > 6 else 30.0
    cls = TYPES[kind]
    rospy.init_node("wire_rospy_" + mode, anonymous=False, disable_signals=True)
    out = open(outfile, "wb")
    deadline = time.time() + timeout
    if mode == "sub":
        got = []
        rospy.Subscriber(topic, cls, lambda m: got.append(body(m)))
        print("READY", flush=True)
        while len(got) < count and time.time() < deadline:
            time.sleep(0.01)
        for b in got[:count]:
            out.write(struct.pack("<I", len(b)) + b)
    else:
        pub = rospy.Publisher(topic, cls, queue_size=100)
        print("READY", flush=True)
        while pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.2)
        k = 0
        while (count == 0 or k < count) and time.time() < deadline:
            msg = make(kind, k)
            pub.publish(msg)
            b = body(msg)
            out.write(struct.pack("<I", len(b)) + b)
            out.flush()
            k += 1
            time.sleep(0.05)
        time.sleep(1.0)
    out.close()
    print("DONE", flush=True)
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    main()
