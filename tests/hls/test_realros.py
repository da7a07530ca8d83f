"""The generated circuit on the wire with real ROS 1 (rosmaster, rospy), through C simulation.

Subscriber side: the generated subscriber's connection header (as the C simulation writes it)
is sent to a real rospy publisher; rospy accepts it and streams ``sensor_msgs/Image`` frames,
one of which, taken off the socket byte for byte, goes through the C simulation and must come
out as the Python models and OpenCV say. Publisher side: a real rospy subscriber connects to a
socket that answers with the generated publisher's connection header and then the frame the
C simulation wrote; rospy must accept both and receive exactly that message.
Everything runs on loopback, bounded in time, and is cleaned up.
"""

from __future__ import annotations

import socket
import struct
import subprocess
import threading
import xmlrpc.client
import xmlrpc.server
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.support.realros import ROS_PYTHON, free_port, require_cxx, ros_env, stop_process
from rosfpga_lab.config import load_config
from rosfpga_lab.hls import build_csim, generate, run_csim
from tests.support.imagemodel import ImageModel
from rosfpga_lab.msg import default_registry, deserialize

pytestmark = [pytest.mark.ros, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "data" / "fpga_erode_mono8.yaml"  # /fpga_erode: /camera/image_mono -> /camera/image_eroded
TIMEOUT = 30.0

PUBLISHER = """
import rospy
from sensor_msgs.msg import Image
rospy.init_node('hls_test_camera')
pub = rospy.Publisher('/camera/image_mono', Image, queue_size=1)
m = Image()
m.header.frame_id = 'camera_optical'
m.height, m.width, m.encoding, m.step = 240, 320, 'mono8', 320
m.data = bytes(255 if (i * 7919) % 97 == 0 else (i * 7 + i // 320) % 64 for i in range(320 * 240))
print('ready', flush=True)
rate = rospy.Rate(20)
while not rospy.is_shutdown():
    m.header.stamp = rospy.Time(1700000000, 250)
    pub.publish(m)
    rate.sleep()
"""

SUBSCRIBER = """
import io, sys, rospy
from sensor_msgs.msg import Image
def got(m):
    buf = io.BytesIO()
    m.serialize(buf)
    print(buf.getvalue().hex(), flush=True)
    rospy.signal_shutdown('done')
rospy.init_node('hls_test_viewer')
rospy.Subscriber('/camera/image_eroded', Image, got)
rospy.spin()
"""


def _recv_exact(sock: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError(f"connection closed after {len(data)} of {n} bytes")
        data += chunk
    return data


def _recv_prefixed(sock: socket.socket) -> bytes:
    head = _recv_exact(sock, 4)
    return head + _recv_exact(sock, struct.unpack("<I", head)[0])


def _fields(header: bytes) -> dict[str, str]:
    out, pos = {}, 4
    while pos < len(header):
        (n,) = struct.unpack_from("<I", header, pos)
        key, _, value = header[pos + 4:pos + 4 + n].decode().partition("=")
        out[key] = value
        pos += 4 + n
    return out


@pytest.fixture(scope="module")
def project(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    require_cxx()
    out = tmp_path_factory.mktemp("realros") / "proj"
    generate(load_config(CONFIG), out)
    return out, build_csim(out)


def test_real_rospy_publisher_accepts_the_generated_subscriber(
        rosmaster_uri: str, tmp_path: Path, project: tuple[Path, Path]) -> None:
    proj, binary = project
    env = ros_env(rosmaster_uri, tmp_path)
    pub = subprocess.Popen([ROS_PYTHON, "-c", PUBLISHER], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE)
    try:
        assert pub.stdout is not None and pub.stdout.readline().strip() == b"ready"
        master = xmlrpc.client.ServerProxy(rosmaster_uri)
        code, _, node_uri = master.lookupNode("/fpga_erode", "/hls_test_camera")
        assert code == 1, node_uri
        code, msg, proto = xmlrpc.client.ServerProxy(node_uri).requestTopic(
            "/fpga_erode", "/camera/image_mono", [["TCPROS"]])
        assert code == 1, msg
        # The header bytes as the circuit sends them (C simulation of the generated code).
        sim = run_csim(proj, b"", binary=binary)
        with socket.create_connection((proto[1], proto[2]), timeout=TIMEOUT) as sock:
            sock.sendall(sim.subscriber_header)
            answer = _fields(_recv_prefixed(sock))
            assert "error" not in answer, answer
            assert answer["md5sum"] == "060021388200f6f0f447d0fcd9c64743"
            assert answer["type"] == "sensor_msgs/Image" and answer["callerid"] == "/hls_test_camera"
            frame = _recv_prefixed(sock)  # one TCPROS frame, straight off the wire
    finally:
        stop_process(pub)
        pub.stdout.close()  # type: ignore[union-attr]
        pub.stderr.close()  # type: ignore[union-attr]
    got = run_csim(proj, frame, binary=binary)
    model = ImageModel(load_config(CONFIG)).process(frame)
    assert got.status == ((0, "SUB_OK"),)
    assert got.input_beats == model.input_beats and got.output_beats == model.output_beats
    assert got.output == model.output_frame
    received = deserialize(default_registry(), "sensor_msgs/Image", frame[4:])
    image = np.frombuffer(bytes(received["data"]), np.uint8).reshape(240, 320)
    out = deserialize(default_registry(), "sensor_msgs/Image", got.output[4:])
    assert np.array_equal(np.frombuffer(bytes(out["data"]), np.uint8).reshape(240, 320),
                          cv2.erode(image, np.ones((5, 5), np.uint8)))
    assert out["header"]["frame_id"] == "camera_optical"


class _Slave:
    """Just enough of a node's XML-RPC slave API for rospy to find our TCPROS socket."""

    def __init__(self, tcpros_port: int) -> None:
        self.server = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False,
                                                       allow_none=True)
        self.server.register_function(
            lambda caller, topic, protocols: [1, "ok", ["TCPROS", "127.0.0.1", tcpros_port]],
            "requestTopic")
        self.server.register_function(lambda caller: [1, "ok", 0], "getPid")
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()
        self.thread.join(5)


def test_real_rospy_subscriber_accepts_the_generated_publisher(
        rosmaster_uri: str, tmp_path: Path, project: tuple[Path, Path]) -> None:
    proj, binary = project
    sim = run_csim(proj, (proj / "tb_input.bin").read_bytes(), binary=binary)
    assert sim.status == ((0, "SUB_OK"),)
    listener = socket.create_server(("127.0.0.1", free_port()))
    listener.settimeout(TIMEOUT)
    slave = _Slave(listener.getsockname()[1])
    seen: dict[str, str] = {}
    errors: list[BaseException] = []

    def serve() -> None:
        try:
            conn, _ = listener.accept()
            with conn:
                conn.settimeout(TIMEOUT)
                seen.update(_fields(_recv_prefixed(conn)))
                conn.sendall(sim.publisher_header + sim.output)
                conn.recv(1)  # wait until rospy hangs up
        except BaseException as exc:  # noqa: BLE001 - reported by the test below
            errors.append(exc)

    server = threading.Thread(target=serve, daemon=True)
    server.start()
    sub = None
    try:
        master = xmlrpc.client.ServerProxy(rosmaster_uri)
        code, msg, _ = master.registerPublisher("/fpga_erode", "/camera/image_eroded",
                                                "sensor_msgs/Image", slave.uri)
        assert code == 1, msg
        sub = subprocess.Popen([ROS_PYTHON, "-c", SUBSCRIBER], env=ros_env(rosmaster_uri, tmp_path),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        out, err = sub.communicate(timeout=TIMEOUT)
        assert sub.returncode == 0, err.decode(errors="replace")
        body = bytes.fromhex(out.decode().strip())
        assert body == sim.output[4:]  # rospy received exactly the circuit's message
        assert seen["topic"] == "/camera/image_eroded" and seen["md5sum"] == "060021388200f6f0f447d0fcd9c64743"
        master.unregisterPublisher("/fpga_erode", "/camera/image_eroded", slave.uri)
    finally:
        if sub is not None:
            stop_process(sub)
        server.join(TIMEOUT)
        listener.close()
        slave.close()
    assert not errors, errors
