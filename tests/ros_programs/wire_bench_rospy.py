"""rospy side of tests/benchmarks/bench_transport.py (run by /usr/bin/python3).

  wire_bench_rospy.py sub TOPIC NLAT NTHR   -> prints one JSON line with the results
  wire_bench_rospy.py pub TOPIC NLAT NTHR   -> NLAT frames at 10 Hz ("lat"), then NTHR back to back ("thr")
Frames are 640x480 rgba8 sensor_msgs/Image; header.stamp is the wall time at publish.
"""

import json
import sys
import time

import rospy
from sensor_msgs.msg import Image


def main():
    mode, topic, nlat, nthr = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    rospy.init_node("wire_bench_rospy_" + mode, disable_signals=True)
    deadline = time.time() + 120
    if mode == "sub":
        lat, arrivals = [], []

        def cb(m):
            now = time.time()
            if m.header.frame_id == "lat":
                lat.append((now - m.header.stamp.to_sec()) * 1000.0)
            else:
                arrivals.append(now)

        rospy.Subscriber(topic, Image, cb, queue_size=None, buff_size=1 << 24)
        print("READY", flush=True)
        while (len(lat) < nlat or len(arrivals) < nthr) and time.time() < deadline:
            time.sleep(0.01)
        span = arrivals[-1] - arrivals[0] if len(arrivals) > 1 else float("nan")
        print(json.dumps({"lat_ms": lat, "thr_frames": len(arrivals), "thr_seconds": span}), flush=True)
    else:
        pub = rospy.Publisher(topic, Image, queue_size=nthr + 10)
        print("READY", flush=True)
        while pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)
        img = Image(height=480, width=640, encoding="rgba8", is_bigendian=0, step=2560)
        img.data = bytes(range(256)) * (640 * 480 * 4 // 256)
        for phase, n, gap in (("lat", nlat, 0.1), ("thr", nthr, 0.0)):
            img.header.frame_id = phase
            for _ in range(n):
                img.header.stamp = rospy.Time.from_sec(time.time())
                pub.publish(img)
                if gap:
                    time.sleep(gap)
        time.sleep(5.0)
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    main()
