"""A real ROS 2 Jazzy peer (rclpy, rmw_fastrtps_cpp) for tests/flow/test_ros2_realros2.py.

Run by the tests as a subprocess of the venv's Python (never rclpy.init in pytest's process),
with ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and ROS_LOG_DIR set by the test.
Each mode ends by itself (bounded by --timeout) and prints one JSON line on stdout as its
last line; frames received are written as raw files into --out.

  relay IN OUT W H N      publish N random rgba8 W x H pictures (numpy seed k) on IN, receive on OUT
                          (prints "matched", then waits for a line on stdin before publishing)
  scans IN OUT FILE       publish the LaserScans FILE describes (a JSON list, the float32 fields
                          as little-endian hex) on IN, receive on OUT (as relay: "matched", a
                          line on stdin, then one at a time); what came back in the same form
  listen TOPIC N          receive N images
  talk TOPIC W H N        publish N pictures once a subscriber is matched
  graph NODE NS TOPIC...  what the ROS 2 graph API says about node NS/NODE and the topics
  best_effort TOPIC       a BEST_EFFORT publisher: matched subscriptions, incompatible QoS events
"""

import argparse
import array
import json
import sys
import time
from pathlib import Path

import numpy as np
import rclpy
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Image, LaserScan


def picture(k: int, h: int, w: int) -> np.ndarray:
    return np.random.default_rng(k).integers(0, 256, (h, w, 4), dtype=np.uint8)


def image(k: int, h: int, w: int) -> Image:
    msg = Image()
    msg.header.stamp.sec, msg.header.stamp.nanosec = 1700000000 + k, 500
    msg.header.frame_id = "rclpy"
    msg.height, msg.width, msg.encoding, msg.is_bigendian, msg.step = h, w, "rgba8", 0, 4 * w
    msg.data = picture(k, h, w).tobytes()
    return msg


class Sink:
    """Keeps what arrives on a topic: header and geometry per sample, data into files."""

    def __init__(self, node, topic: str, out: Path) -> None:
        self.got: list[dict] = []
        self.out = out
        self.sub = node.create_subscription(Image, topic, self.on_image, 10)

    def on_image(self, msg: Image) -> None:
        n = len(self.got)
        (self.out / f"{n}.bin").write_bytes(bytes(msg.data))
        self.got.append({"sec": msg.header.stamp.sec, "nanosec": msg.header.stamp.nanosec,
                         "frame_id": msg.header.frame_id, "width": msg.width,
                         "height": msg.height, "encoding": msg.encoding, "step": msg.step})


#: LaserScan's float32 fields besides the two arrays.
SCAN_FLOATS = ("angle_min", "angle_max", "angle_increment", "time_increment", "scan_time",
               "range_min", "range_max")


def scan(d: dict) -> LaserScan:
    """A LaserScan from its description (float32 fields as little-endian hex: bit exact)."""
    msg = LaserScan()
    msg.header.stamp.sec, msg.header.stamp.nanosec = d["sec"], d["nanosec"]
    msg.header.frame_id = d["frame_id"]
    for name in SCAN_FLOATS:
        setattr(msg, name, float(np.frombuffer(bytes.fromhex(d[name]), "<f4")[0]))
    msg.ranges = array.array("f", bytes.fromhex(d["ranges"]))
    msg.intensities = array.array("f", bytes.fromhex(d["intensities"]))
    return msg


def scan_description(msg: LaserScan) -> dict:
    out = {"sec": msg.header.stamp.sec, "nanosec": msg.header.stamp.nanosec,
           "frame_id": msg.header.frame_id}
    for name in SCAN_FLOATS:
        out[name] = np.float32(getattr(msg, name)).astype("<f4").tobytes().hex()
    out["ranges"] = np.asarray(msg.ranges, "<f4").tobytes().hex()
    out["intensities"] = np.asarray(msg.intensities, "<f4").tobytes().hex()
    return out


def spin_until(node, cond, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            return False
        rclpy.spin_once(node, timeout_sec=0.02)
    return True


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode")
    ap.add_argument("args", nargs="*")
    ap.add_argument("--out", type=Path, default=Path("."))
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--node", action="append", default=[],
                    help="graph: NS/NAME of another node to wait for too")
    opt = ap.parse_args()
    rclpy.init()
    node = rclpy.create_node("rclpy_peer")
    report: dict = {}
    try:
        a = opt.args
        if opt.mode == "relay":
            topic_in, topic_out, w, h, n = a[0], a[1], int(a[2]), int(a[3]), int(a[4])
            pub = node.create_publisher(Image, topic_in, 10)      # RELIABLE KEEP_LAST 10
            sink = Sink(node, topic_out, opt.out)
            report["matched"] = spin_until(
                node, lambda: pub.get_subscription_count() >= 1 and
                sink.sub.get_publisher_count() >= 1, opt.timeout)
            # the test says when the lab has matched our writer too (rclpy cannot see that)
            print("matched" if report["matched"] else "unmatched", flush=True)
            sys.stdin.readline()
            for k in range(n):
                pub.publish(image(k, h, w))
                spin_until(node, lambda: len(sink.got) > k, 2.0)   # paced: one at a time
            spin_until(node, lambda: len(sink.got) >= n, opt.timeout)
            report["got"] = sink.got
        elif opt.mode == "scans":
            topic_in, topic_out, scans = a[0], a[1], json.loads(Path(a[2]).read_text())
            pub = node.create_publisher(LaserScan, topic_in, 10)   # RELIABLE KEEP_LAST 10
            got: list[dict] = []
            sub = node.create_subscription(LaserScan, topic_out,
                                           lambda m: got.append(scan_description(m)), 10)
            report["matched"] = spin_until(
                node, lambda: pub.get_subscription_count() >= 1 and
                sub.get_publisher_count() >= 1, opt.timeout)
            print("matched" if report["matched"] else "unmatched", flush=True)
            sys.stdin.readline()
            for k, d in enumerate(scans):
                pub.publish(scan(d))
                spin_until(node, lambda: len(got) > k, 2.0)        # paced: one at a time
            spin_until(node, lambda: len(got) >= len(scans), opt.timeout)
            report["got"] = got
        elif opt.mode == "listen":
            sink = Sink(node, a[0], opt.out)
            spin_until(node, lambda: len(sink.got) >= int(a[1]), opt.timeout)
            report["got"] = sink.got
        elif opt.mode == "talk":
            topic, w, h, n = a[0], int(a[1]), int(a[2]), int(a[3])
            pub = node.create_publisher(Image, topic, 10)
            report["matched"] = spin_until(node, lambda: pub.get_subscription_count() >= 1,
                                           opt.timeout)
            spin_until(node, lambda: False, 0.5)   # the lab matches our writer (SEDP) too
            for k in range(n):
                pub.publish(image(k, h, w))
                spin_until(node, lambda: False, 0.1)
            report["sent"] = n
            spin_until(node, lambda: False, 1.0)   # RELIABLE: answer the reader's ACKNACKs
        elif opt.mode == "graph":
            name, ns, topics = a[0], a[1], a[2:]
            others = [tuple(reversed(n.rsplit("/", 1))) for n in opt.node]   # (name, ns)
            others = [(n, ns or "/") for n, ns in others]
            spin_until(node, lambda: {(name, ns), *others} <= set(node.get_node_names_and_namespaces())
                       and all(node.count_publishers(t) + node.count_subscribers(t) for t in topics),
                       opt.timeout)
            report["nodes"] = node.get_node_names_and_namespaces()
            report["publishers"] = node.get_publisher_names_and_types_by_node(name, ns)
            report["subscribers"] = node.get_subscriber_names_and_types_by_node(name, ns)
            report["topics"] = node.get_topic_names_and_types()
            infos = {}
            for t in topics:
                infos[t] = [{"node": i.node_name, "ns": i.node_namespace, "type": i.topic_type,
                             "kind": i.endpoint_type.name, "reliability": i.qos_profile.reliability.name,
                             "durability": i.qos_profile.durability.name, "depth": i.qos_profile.depth,
                             "type_hash": str(i.topic_type_hash)}
                            for i in node.get_publishers_info_by_topic(t)
                            + node.get_subscriptions_info_by_topic(t)]
            report["infos"] = infos
        elif opt.mode == "best_effort":
            events: list[str] = []
            cbs = PublisherEventCallbacks(
                incompatible_qos=lambda e: events.append(str(e.last_policy_kind)))
            pub = node.create_publisher(Image, a[0], QoSProfile(
                depth=10, reliability=ReliabilityPolicy.BEST_EFFORT), event_callbacks=cbs)
            spin_until(node, lambda: bool(events) and node.count_subscribers(a[0]) >= 1, opt.timeout)
            pub.publish(image(0, 8, 16))
            spin_until(node, lambda: False, 0.3)
            report["subscribers_seen"] = node.count_subscribers(a[0])
            report["matched"] = pub.get_subscription_count()
            report["incompatible"] = events
        else:
            print(f"unknown mode {opt.mode}", file=sys.stderr)
            return 2
    finally:
        node.destroy_node()
        rclpy.shutdown()
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
