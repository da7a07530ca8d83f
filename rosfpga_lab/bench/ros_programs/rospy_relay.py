"""A rospy relay: forwards IN to OUT without deserializing (rospy.AnyMsg), like topic_tools relay.

Run by /usr/bin/python3 with Debian's rospy: rospy_relay.py IN OUT [QUEUE]. Prints READY once
registered. The subscriber asks for a 16 MiB buffer (rospy's documented advice for images).
"""

import sys

import rospy
from sensor_msgs.msg import Image


def main():
    inp, out = sys.argv[1], sys.argv[2]
    queue = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    rospy.init_node("rospy_relay", disable_signals=True)
    pub = rospy.Publisher(out, Image, queue_size=queue, tcp_nodelay=True)
    rospy.Subscriber(inp, rospy.AnyMsg, pub.publish, queue_size=queue, buff_size=1 << 24,
                     tcp_nodelay=True)
    print("READY", flush=True)
    try:
        rospy.spin()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
