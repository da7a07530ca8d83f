"""The FPGA component on the lab's own graph: frames through, figures, bad input and faults.

Every output is compared with OpenCV run on the input (never with the lab's own circuit
models). Everything runs on loopback against an embedded master on a free port.
"""

from __future__ import annotations

import logging
import re
import socket
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from rosfpga_lab.component import ComponentConfigError, FpgaComponent
from rosfpga_lab.graph import EmbeddedMaster, Node
from rosfpga_lab.config import load_config, parse_config
from rosfpga_lab.hw import image_frame
from rosfpga_lab.msg import default_registry
from rosfpga_lab.tcpros import encode_header

CONFIG = """\
node: {{name: /fpga_test}}
subscriber: {{topic: /cam, type: sensor_msgs/Image}}
publisher: {{topic: /cam_out, type: sensor_msgs/Image}}
image: {{width: {w}, height: {h}, encoding: {enc}}}
application: {{op: {op}, ksize: {k}}}
"""


def config(w: int = 64, h: int = 48, enc: str = "rgba8", op: str = "dilate", k: int = 3):
    return parse_config(CONFIG.format(w=w, h=h, enc=enc, op=op, k=k))


def picture(k: int, h: int = 48, w: int = 64, c: int = 4) -> np.ndarray:
    rng = np.random.default_rng(k)
    return rng.integers(0, 256, (h, w, c), dtype=np.uint8)


def cv2_dilate(img: np.ndarray, k: int = 3) -> np.ndarray:
    return cv2.dilate(img, np.ones((k, k), np.uint8)).reshape(img.shape)


class Collector:
    """A lab subscriber that keeps every output frame's body."""

    def __init__(self, master: EmbeddedMaster, topic: str = "/cam_out", name: str = "/collector",
                 **kw) -> None:
        self.bodies: list[bytes] = []
        self.cond = threading.Condition()
        self.node = Node(name, master=master)
        self.sub = self.node.subscribe(topic, "sensor_msgs/Image", self._cb, raw=True,
                                       queue_size=0, **kw)

    def _cb(self, body, info) -> None:
        with self.cond:
            self.bodies.append(bytes(body))
            self.cond.notify_all()

    def wait(self, n: int, timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        with self.cond:
            while len(self.bodies) < n:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self.cond.wait(left)
        return True

    def images(self, shape: tuple[int, ...]) -> list[np.ndarray]:
        size = int(np.prod(shape))
        return [np.frombuffer(b[-size:], np.uint8).reshape(shape) for b in self.bodies]


@pytest.fixture
def master():
    with EmbeddedMaster(port=0) as m:
        yield m


@pytest.fixture
def rig(master):
    """A started component (64x48 rgba8 dilate 3x3), a publisher node and a collector."""
    # an output queue deeper than any test's run: the collector may lag on a loaded machine, and
    # these tests check the outputs, not the queue policy (test_slow_subscriber_... does that)
    comp = FpgaComponent.from_config(config(), master=master, output_queue=64).start()
    src = Node("/source", master=master)
    pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
    out = Collector(master)
    assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
    yield comp, pub, out
    out.node.shutdown()
    src.shutdown()
    comp.stop()


def send(pub, img: np.ndarray, k: int, encoding: str = "rgba8") -> None:
    pub.publish_body(image_frame(img, encoding, seq=k, stamp=(100 + k, k), frame_id="cam")[4:])


def test_every_output_is_opencvs_dilation_and_header_is_carried(rig) -> None:
    comp, pub, out = rig
    sent = [picture(k) for k in range(20)]
    for k, img in enumerate(sent):
        send(pub, img, k)
        assert comp.wait_for(k + 1, 10)
    assert out.wait(20), comp.stats.report()
    reg = default_registry()
    from rosfpga_lab.msg import deserialize

    for k, (img, body) in enumerate(zip(sent, out.bodies)):
        msg = deserialize(reg, "sensor_msgs/Image", body)
        got = np.asarray(msg["data"], np.uint8).reshape(img.shape)
        assert np.array_equal(got, cv2_dilate(img)), f"frame {k}"
        assert (msg["header"]["stamp"][0], msg["header"]["stamp"][1]) == (100 + k, k)
        assert msg["header"]["frame_id"] == "cam"
        assert (msg["height"], msg["width"], msg["encoding"], msg["step"]) == (48, 64, "rgba8", 256)
    st = comp.stats
    assert (st.received, st.processed, st.published, st.refused, st.dropped) == (20, 20, 20, 0, 0)
    assert st.latency.count == 20 and 0 < st.latency.median < 1.0
    assert st.since_stamp.count == 0  # stamps of 1970 are not a camera's capture time
    # cycle figures of a 64x48 rgba8 frame: every byte through the byte-wide walkers, a pixel
    # per clock through the 3x3 window plus its reach (one row and one pixel)
    frame_bytes = len(image_frame(sent[-1], "rgba8", frame_id="cam"))
    assert st.cycles == {"subscriber": frame_bytes, "application": 64 * 48 + 64 + 1,
                         "publisher": frame_bytes}
    assert st.fifo_high_water == {}     # the walkers' model has no FIFO levels
    assert st.subscribers == 1 and st.publishers == 1


def test_wrong_size_and_encoding_are_refused_counted_and_next_frame_is_right(rig, caplog) -> None:
    comp, pub, out = rig
    caplog.set_level(logging.WARNING, logger="rosfpga_lab.component")
    send(pub, picture(1, h=24, w=32), 0)                         # wrong size
    assert comp.wait_for(1, 10)
    send(pub, picture(2, c=3), 1, encoding="rgb8")               # wrong encoding
    assert comp.wait_for(2, 10)
    send(pub, picture(3, c=1), 2, encoding="mono8")              # wrong encoding
    assert comp.wait_for(3, 10)
    # a frame whose data is one byte short of height*step (a broken publisher)
    short = bytearray(image_frame(picture(4), "rgba8", seq=3, stamp=(9, 9))[4:])
    pub.publish_body(bytes(short[:-1]))
    assert comp.wait_for(4, 10)
    good = picture(5)
    send(pub, good, 4)
    assert comp.wait_for(5, 10)
    assert out.wait(1)
    time.sleep(0.1)
    assert len(out.bodies) == 1
    assert np.array_equal(out.images(good.shape)[0], cv2_dilate(good))
    st = comp.stats
    assert st.refused == 4 and st.published == 1 and comp.running
    built_for = "not what the circuit was built for"
    assert st.refused_reasons[f"height: {built_for}"] == 1
    assert st.refused_reasons[f"encoding: {built_for}"] == 2      # rgb8 and mono8: one kind
    assert "'rgb8'" in st.refused_examples[f"encoding: {built_for}"]   # the first one's text
    assert sum(st.refused_reasons.values()) == 4
    assert f"refused x2: encoding: {built_for} (first: " in st.report()
    logged = [r.getMessage() for r in caplog.records if "refused frame" in r.getMessage()]
    assert len(logged) == 4 and any("circuit was built for" in m for m in logged)
    recs = list(comp.recent)
    assert [r.error != "" for r in recs] == [True, True, True, False]  # history 4: last four
    assert recs[-1].result is not None and recs[-1].latency >= 0


def test_refusals_count_by_kind_whatever_the_values(rig) -> None:
    """Reasons carry field values; 30 frames of 30 wrong widths are one kind, not 30 texts
    (with a cap on distinct texts, everything after the 20th was once counted as "other")."""
    comp, pub, _out = rig
    for k in range(30):   # one at a time: the input queue is 2 deep
        send(pub, picture(k, w=8 + k), k)
        assert comp.wait_for(k + 1, 10)
    send(pub, picture(99, c=3), 30, encoding="rgb8")
    assert comp.wait_for(31, 10)
    st = comp.stats
    width = "width: not what the circuit was built for"
    assert st.refused_reasons == {width: 30, "encoding: not what the circuit was built for": 1}
    assert "8 but the circuit was built for 64" in st.refused_examples[width]
    assert f"refused x30: {width} (first: " in st.report()
    assert "other" not in st.report()


def test_observers_see_frames_and_a_raising_observer_does_not_stop_the_path(rig) -> None:
    comp, pub, out = rig
    seen = []

    def bad(_rec):
        raise RuntimeError("observer bug")

    comp.add_observer(seen.append)
    comp.add_observer(bad)
    for k in range(3):
        send(pub, picture(k), k)
        assert comp.wait_for(k + 1, 10)
    assert out.wait(3)
    assert comp.wait_for(3)
    time.sleep(0.05)
    assert [r.index for r in seen] == [0, 1, 2]
    assert np.array_equal(seen[0].output_image, cv2_dilate(picture(0)))
    assert comp.stats.observer_errors == 3
    comp.remove_observer(bad)
    send(pub, picture(9), 9)
    assert out.wait(4)
    assert comp.stats.observer_errors == 3


def test_busy_circuit_drops_oldest_input_and_says_so(master, caplog) -> None:
    caplog.set_level(logging.INFO, logger="rosfpga_lab.component")
    comp = FpgaComponent.from_config(config(), master=master, input_queue=1).start()
    gate, inside = threading.Event(), threading.Event()

    def stall(_rec) -> None:  # the circuit stalls on its first frame
        inside.set()
        gate.wait(5)

    comp.add_observer(stall)
    src = Node("/source", master=master)
    pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
    out = Collector(master)
    try:
        assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
        send(pub, picture(0), 0)
        assert inside.wait(5)
        for k in range(1, 6):
            send(pub, picture(k), k)
        deadline = time.monotonic() + 5
        while comp.stats.received < 6 and time.monotonic() < deadline:
            time.sleep(0.01)
        gate.set()
        assert out.wait(2)
        time.sleep(0.2)
        st = comp.stats
        # first frame in the circuit, one waiting (queue 1): the other four were dropped
        assert (st.received, st.dropped_input, st.published) == (6, 4, 2), st.report()
        assert "input queue full" in st.report()
        def logged_drops() -> int:  # the monitor logs drops once a second
            found = [re.search(r"dropped (\d+) input frame", r.getMessage()) for r in caplog.records]
            return sum(int(m.group(1)) for m in found if m)

        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and logged_drops() < 4:
            time.sleep(0.05)
        assert logged_drops() == 4
        got = out.images((48, 64, 4))
        assert np.array_equal(got[-1], cv2_dilate(picture(5)))  # the newest frame survived
    finally:
        out.node.shutdown()
        src.shutdown()
        comp.stop()


def test_slow_subscriber_loses_frames_by_queue_policy_others_do_not(rig, master, caplog) -> None:
    caplog.set_level(logging.INFO, logger="rosfpga_lab.component")
    comp, pub, out = rig
    big = FpgaComponent.from_config(config(640, 480), master=master, name="/fpga_big",
                                    output_queue=2)
    # topics of its own so the two components do not meet
    big.input_topic, big.output_topic = "/big_in", "/big_out"
    big.start()
    src = Node("/big_source", master=master)
    bpub = src.advertise("/big_in", "sensor_msgs/Image", queue_size=0)
    fast = Collector(master, "/big_out", "/fast_reader")
    # the slow subscriber: handshakes, then never reads (tiny receive buffer)
    slow = socket.socket()
    slow.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    slow.connect(("127.0.0.1", big.node.tcpros_port))
    slow.sendall(encode_header({"callerid": "/slow_reader", "topic": "/big_out",
                                "md5sum": default_registry().md5("sensor_msgs/Image"),
                                "type": "sensor_msgs/Image"}))
    try:
        assert big.wait_for_subscribers(2, 10) and bpub.wait_for_subscribers(1, 10)
        img = picture(7, 480, 640)
        for k in range(12):  # in lock step with the fast reader: only the slow one may lose
            send(bpub, img, k)
            assert big.wait_for(k + 1, 10)
            assert fast.wait(k + 1, 20), big.stats.report()
        assert big.wait_for(12, 10)
        time.sleep(0.3)
        st = big.stats
        assert st.dropped_output > 0 and st.dropped_output_by_peer.keys() == {"/slow_reader"}
        assert "output queue full for subscriber /slow_reader" in st.report()
        deadline = time.monotonic() + 3                # the monitor says so in the log too
        while time.monotonic() < deadline and not any(
                "for subscriber /slow_reader" in r.getMessage() for r in caplog.records):
            time.sleep(0.05)
        assert any("too slow for the rate" in r.getMessage() for r in caplog.records)
        assert st.published == 12 and st.dropped_input == 0
        assert all(np.array_equal(g, cv2_dilate(img)) for g in fast.images(img.shape))
    finally:
        slow.close()
        fast.node.shutdown()
        src.shutdown()
        big.stop()


def test_input_publisher_dies_and_returns(rig, master) -> None:
    comp, pub, out = rig
    send(pub, picture(0), 0)
    assert out.wait(1)
    pub.unregister()                          # the publisher goes away (unregisters)
    time.sleep(0.3)
    assert comp.stats.publishers == 0 and comp.running
    again = Node("/source", master=master)    # and comes back under the same name
    try:
        pub2 = again.advertise("/cam", "sensor_msgs/Image", queue_size=0)
        assert pub2.wait_for_subscribers(1, 10)
        send(pub2, picture(1), 1)
        assert out.wait(2)
        assert np.array_equal(out.images((48, 64, 4))[1], cv2_dilate(picture(1)))
    finally:
        again.shutdown()


def test_master_restart_component_registers_again(master) -> None:
    port = master.port
    comp = FpgaComponent.from_config(config(), master_uri=master.uri).start()
    out = Collector(master)
    try:
        assert comp.wait_for_subscribers(1, 10)
        master.stop()
        time.sleep(1.5)                                   # a watchdog round sees no master
        assert not comp.stats.master_ok
        with EmbeddedMaster(port=port) as master2:        # the master comes back, empty
            deadline = time.monotonic() + 5
            while comp.stats.master_reregistrations == 0 and time.monotonic() < deadline:
                time.sleep(0.05)
            st = comp.stats
            assert st.master_reregistrations == 1 and st.master_ok
            # a publisher that starts after the restart finds the component through the new master
            src = Node("/late_source", master=master2)
            try:
                pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
                assert pub.wait_for_subscribers(1, 10)
                send(pub, picture(3), 3)
                assert out.wait(1, 10)                    # the old output connection still works
                assert np.array_equal(out.images((48, 64, 4))[0], cv2_dilate(picture(3)))
            finally:
                src.shutdown()
            assert "registered again with the master 1 time" in comp.stats.report()
    finally:
        out.node.shutdown()
        comp.stop()


def test_master_restart_keeps_frames_flowing(master) -> None:
    """A master restart while a camera streams: the component registers again and keeps the
    camera's connection (as roscpp does); it used to apply the new master's empty publisher
    list and cut its input, with no output until the camera registered again (this one never
    does, like rospy and roscpp nodes). A publisher list from the new master that does not name
    the camera does not cut it either; when the camera goes, its link is not retried."""
    port = master.port
    comp = FpgaComponent.from_config(config(), master_uri=master.uri).start()
    out = Collector(master)
    src = Node("/source", master=master)
    stop = threading.Event()
    try:
        pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
        assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
        link_before = dict(comp._sub._links)

        def stream() -> None:
            k = 0
            while not stop.wait(0.05):
                send(pub, picture(k % 4), k)
                k += 1

        threading.Thread(target=stream, daemon=True).start()
        assert out.wait(3, 10)
        master.stop()
        deadline = time.monotonic() + 10
        while comp.stats.master_ok and time.monotonic() < deadline:
            time.sleep(0.05)
        with EmbeddedMaster(port=port) as master2:        # back, and empty
            deadline = time.monotonic() + 10
            while comp.stats.master_reregistrations == 0 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert comp.stats.master_reregistrations == 1
            seen = len(out.bodies)
            assert out.wait(seen + 5, 10), "no output after the component registered again"
            assert comp._sub._links == link_before        # the same link, never reconnected
            assert comp.stats.publishers == 1
            late = Node("/late_source", master=master2)  # the new master's list: late only
            try:
                late_pub = late.advertise("/cam", "sensor_msgs/Image", queue_size=0)
                assert late_pub.wait_for_subscribers(1, 10)
                assert comp.wait_for_publishers(2, 10)
                seen = len(out.bodies)
                assert out.wait(seen + 5, 10)             # the camera still streams
                assert set(link_before) <= set(comp._sub._links)
            finally:
                late.shutdown()
            stop.set()
            src.shutdown()                                # the camera goes: no retries
            deadline = time.monotonic() + 10
            while comp._sub._links and time.monotonic() < deadline:
                time.sleep(0.05)
            assert comp._sub._links == {} and comp.stats.publishers == 0   # none retrying
    finally:
        stop.set()
        src.shutdown()
        out.node.shutdown()
        comp.stop()


def test_stop_is_clean_and_idempotent(master) -> None:
    before = {t.ident for t in threading.enumerate()}
    comp = FpgaComponent.from_config(config(), master=master).start()
    assert comp.running and "running" in repr(comp)
    comp.stop()
    comp.stop()
    assert not comp.running
    time.sleep(0.1)
    left = [t.name for t in threading.enumerate() if t.ident not in before and t.is_alive()]
    assert left == []
    reply = master.getSystemState("/t")
    assert all("/fpga_test" not in nodes for _topic, nodes in reply[2][0] + reply[2][1])


def test_started_from_the_generator_config_file(master) -> None:
    path = Path(__file__).resolve().parents[2] / "data" / "fpga_erode_mono8.yaml"
    cfg = load_config(path)
    comp = FpgaComponent.from_config(path, master=master)
    assert comp.name == cfg.node.global_name == "/fpga_erode"
    assert (comp.input_topic, comp.output_topic) == ("/camera/image_mono", "/camera/image_eroded")
    video = comp.pipeline.layout.video
    assert (video.width, video.height, video.encoding) == (320, 240, "mono8")
    assert (comp.pipeline.op, comp.pipeline.ksize) == ("erode", 5)
    assert comp.master_uri == master.uri
    assert FpgaComponent.from_config(cfg).master_uri == "http://127.0.0.1:11311/"


def test_custom_application_cannot_be_emulated(tmp_path) -> None:
    src = tmp_path / "f.cpp"
    src.write_text("void stream_filter() {}\n")
    cfg = parse_config(CONFIG.format(w=8, h=8, enc="mono8", op="custom", k=3).replace(
        "ksize: 3}", f"ksize: 3, source: {src}}}"), base_dir=tmp_path)
    with pytest.raises(ComponentConfigError, match="custom"):
        FpgaComponent(cfg)
    with pytest.raises(ComponentConfigError, match="at least 1"):
        FpgaComponent(config(), input_queue=0)


def test_reference_model_gives_the_same_bytes(master) -> None:
    comp = FpgaComponent.from_config(config(16, 12), master=master, model="reference").start()
    src = Node("/source", master=master)
    pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
    out = Collector(master)
    try:
        assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
        img = picture(11, 12, 16)
        send(pub, img, 0)
        assert out.wait(1, 20)
        assert np.array_equal(out.images(img.shape)[0], cv2_dilate(img))
        assert comp.stats.cycles["application"] == 16 * 12 + 16 + 1   # a pixel per clock
    finally:
        out.node.shutdown()
        src.shutdown()
        comp.stop()


def test_a_newer_node_with_the_same_name_wins(master) -> None:
    """ROS's rule: the master shuts the older node down; the older never registers again."""
    old = FpgaComponent.from_config(config(), master=master).start()
    new = FpgaComponent.from_config(config(), master=master).start()
    try:
        deadline = time.monotonic() + 5
        while old.running and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not old.running and new.running
        time.sleep(1.5)  # a monitor round of each
        assert master.lookupNode("/t", "/fpga_test")[2] == new.node.uri
        assert new.stats.master_reregistrations == 0
    finally:
        new.stop()
        old.stop()


def test_a_publisher_of_another_type_is_refused_at_the_handshake_and_reported(rig, master,
                                                                             caplog) -> None:
    caplog.set_level(logging.WARNING, logger="rosfpga_lab.component")
    comp, pub, out = rig
    wrong = Node("/string_talker", master=master)
    try:
        wrong.advertise("/cam", "std_msgs/String", queue_size=0)
        deadline = time.monotonic() + 5
        while not comp.stats.connection_errors and time.monotonic() < deadline:
            time.sleep(0.05)
        problems = " ".join(comp.stats.connection_errors)
        assert "std_msgs/String" in problems and "sensor_msgs/Image" in problems, problems
        assert "input connection problem" in comp.stats.report()
        send(pub, picture(1), 1)                   # the right publisher still gets through
        assert out.wait(1)
        assert np.array_equal(out.images((48, 64, 4))[0], cv2_dilate(picture(1)))
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and not any(
                "input connection problem" in r.getMessage() for r in caplog.records):
            time.sleep(0.05)
        assert any("input connection problem" in r.getMessage() for r in caplog.records)
    finally:
        wrong.shutdown()


@pytest.mark.parametrize("enc,channels,op,k", [("bgr8", 3, "dilate", 5), ("mono8", 1, "erode", 3),
                                               ("bgra8", 4, "erode", 7), ("rgb8", 3, "passthrough", 3)])
def test_other_circuits_match_opencv(master, enc, channels, op, k) -> None:
    comp = FpgaComponent.from_config(config(40, 30, enc, op, k), master=master).start()
    src = Node("/source", master=master)
    pub = src.advertise("/cam", "sensor_msgs/Image", queue_size=0)
    out = Collector(master)
    try:
        assert pub.wait_for_subscribers(1, 10) and comp.wait_for_subscribers(1, 10)
        sent = [picture(k * 10 + j, 30, 40, channels) for j in range(3)]
        for j, img in enumerate(sent):
            send(pub, img, j, encoding=enc)
            assert comp.wait_for(j + 1, 10)
            # one frame in flight: with the output queue 2 deep, a loaded machine's slow
            # collector would otherwise lose the oldest (counted) frame, by design
            assert out.wait(j + 1)
        kernel = np.ones((k, k), np.uint8)
        fn = {"dilate": cv2.dilate, "erode": cv2.erode, "passthrough": lambda i, _k: i}[op]
        for img, got in zip(sent, out.images(sent[0].shape)):
            assert np.array_equal(got, fn(img, kernel).reshape(img.shape))
    finally:
        out.node.shutdown()
        src.shutdown()
        comp.stop()


def test_a_remote_shutdown_while_starting_is_a_typed_ending_and_leaves_nothing(
        master, monkeypatch: pytest.MonkeyPatch) -> None:
    """`rosnode kill` between the component's registrations (its output advertised, its input
    not yet subscribed) made start() raise a bare GraphError and `node` exit 1 with a
    traceback; now it is ComponentShutDown with the reason, and nothing stays registered."""
    from rosfpga_lab.component import ComponentShutDown
    from rosfpga_lab.graph import call

    real_subscribe = Node.subscribe

    def killed_first(self, *args, **kw):           # the slave API's shutdown, as rosnode sends
        call(self.uri, "shutdown", "/rosnode", "kill")
        return real_subscribe(self, *args, **kw)

    monkeypatch.setattr(Node, "subscribe", killed_first)
    comp = FpgaComponent.from_config(config(), master=master)
    with pytest.raises(ComponentShutDown, match="shut down from outside") as info:
        comp.start()
    assert "kill" in info.value.reason
    state = call(master.uri, "getSystemState", "/t")[2]
    assert not [n for _topic, nodes in state[0] + state[1] for n in nodes if n == comp.name], state
