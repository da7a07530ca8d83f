"""The FPGA component as a ROS 2 node against real Cyclone DDS peers (PyPI ``cyclonedds``).

A Cyclone writer of ``sensor_msgs::msg::dds_::Image_`` -> the lab's component -> a Cyclone reader
with ROS 2's default QoS (RELIABLE KEEP_LAST 10). Every output is compared with OpenCV run on
the input (never with the lab's own models). Skips without cyclonedds; fails under
ROSFPGA_REQUIRE_WIRE=1 (CI).
"""

from __future__ import annotations

import logging
import time

import cv2
import numpy as np
import pytest

from rosfpga_lab.component.ros2 import Ros2Component
from rosfpga_lab.config import parse_config
from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri
from rosfpga_lab.rtps.participant import Qos
from tests.support.ros2tools import DOMAIN, cyclone, image, qos, wait

pytestmark = pytest.mark.timeout(60)

CONFIG = """\
node: {{name: /fpga_ros2}}
subscriber: {{topic: /cam, type: sensor_msgs/Image}}
publisher: {{topic: /cam_out, type: sensor_msgs/Image}}
image: {{width: {w}, height: {h}, encoding: rgba8}}
application: {{op: dilate, ksize: 3}}
"""


def picture(k: int, h: int = 48, w: int = 64) -> np.ndarray:
    return np.random.default_rng(k).integers(0, 256, (h, w, 4), dtype=np.uint8)


def cv2_dilate(img: np.ndarray) -> np.ndarray:
    return cv2.dilate(img, np.ones((3, 3), np.uint8)).reshape(img.shape)


def run_through(n: int, h: int, w: int, writer_reliable: bool, qos_in: Qos,
                qos_out: Qos = Qos(), reader_reliable: bool = True) -> list:
    """n pictures from a Cyclone writer through the component; the Cyclone reader's samples."""
    dds = cyclone()
    comp = Ros2Component(parse_config(CONFIG.format(w=w, h=h)), domain=DOMAIN, qos_in=qos_in,
                         qos_out=qos_out)
    with comp:
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds, writer_reliable))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_),
                                qos=qos(dds, reader_reliable))
        assert comp.wait_for_peers(10), comp.notes()
        assert wait(lambda: writer.get_matched_subscriptions() and reader.get_matched_publications())
        for k in range(n):
            writer.write(image(dds, picture(k, h, w), "rgba8", sec=1700000000 + k))
        assert comp.wait_for(n, 20), (comp.counts, comp.notes())
        got: list = []
        assert wait(lambda: got.extend(reader.take(10)) or len(got) >= n, 20), len(got)
        assert comp.counts == {"seen": n, "published": n, "refused": 0}
        return got


@pytest.mark.parametrize("writer_reliable,reader_reliable", [(True, True), (True, False),
                                                             (False, False)])
def test_cyclone_images_through_the_component_exact(writer_reliable: bool,
                                                    reader_reliable: bool) -> None:
    got = run_through(5, 48, 64, writer_reliable, Qos(reader_reliable, 10))
    for k, s in enumerate(got):
        assert (s.width, s.height, s.encoding, s.step) == (64, 48, "rgba8", 256)
        assert (s.header.stamp.sec, s.header.stamp.nanosec, s.header.frame_id) == \
            (1700000000 + k, 500, "camera")
        out = np.frombuffer(bytes(s.data), np.uint8).reshape(48, 64, 4)
        assert np.array_equal(out, cv2_dilate(picture(k, 48, 64))), f"sample {k}"


@pytest.mark.parametrize("out_reliable,reader_reliable", [(True, False), (False, False)])
def test_the_component_output_to_cyclone_readers_of_other_qos(out_reliable: bool,
                                                              reader_reliable: bool) -> None:
    got = run_through(3, 48, 64, True, Qos(True), Qos(out_reliable), reader_reliable)
    for k, s in enumerate(got):
        out = np.frombuffer(bytes(s.data), np.uint8).reshape(48, 64, 4)
        assert np.array_equal(out, cv2_dilate(picture(k, 48, 64))), f"sample {k}"


@pytest.mark.parametrize("writer_reliable", [True, False])
def test_a_640x480_frame_fragmented_both_ways_exact(writer_reliable: bool) -> None:
    # best effort: one lost fragment loses the sample; loopback with 8 MiB socket buffers keeps them
    got = run_through(1, 480, 640, writer_reliable, Qos(writer_reliable, 10))
    out = np.frombuffer(bytes(got[0].data), np.uint8).reshape(480, 640, 4)
    assert np.array_equal(out, cv2_dilate(picture(0, 480, 640)))


def test_best_effort_writer_never_matches_reliable_reader(caplog: pytest.LogCaptureFixture) -> None:
    dds = cyclone()
    caplog.set_level(logging.INFO, logger="rosfpga_lab.graph.ros2")
    comp = Ros2Component(parse_config(CONFIG.format(w=64, h=48)), domain=DOMAIN,
                         qos_in=Qos(True, 10), qos_out=Qos(False, 10))
    with comp:
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds, False))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds, True))
        why = "a BEST_EFFORT writer never matches a RELIABLE reader"
        assert wait(lambda: any(why in n and "reader /cam" not in n and "rt/cam " in n
                                for n in comp.notes()), 10), comp.notes()
        # the lab's best-effort writer and Cyclone's reliable reader: Cyclone refuses it too
        assert wait(lambda: any(why in n and "rt/cam_out" in n for n in comp.notes()), 10)
        writer.write(image(dds, picture(0), "rgba8"))
        assert not wait(lambda: comp.counts["seen"] > 0, 0.5)
        assert reader.get_matched_publications() == []
        assert writer.get_matched_subscriptions() == []
    logged = [r.getMessage() for r in caplog.records if why in r.getMessage()]
    assert len(logged) == 2, logged       # once each, however often SEDP repeats


def test_a_late_reader_and_a_peer_that_leaves_and_comes_back() -> None:
    dds = cyclone()
    comp = Ros2Component(parse_config(CONFIG.format(w=16, h=8)), domain=DOMAIN)
    with comp:
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
        early = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds))
        assert comp.wait_for_peers(10)
        assert wait(lambda: writer.get_matched_subscriptions() and early.get_matched_publications())
        for k in range(2):
            writer.write(image(dds, picture(k, 8, 16), "rgba8", sec=k))
        assert comp.wait_for(2, 10)
        got_early: list = []
        got_late: list = []
        # Cyclone's participants of one process share their proxy of the component's writer: a
        # reader made there matches at once and is handed what that proxy has not delivered
        # yet (a race of Cyclone's receive thread, not the component's). The late reader comes
        # only after the early one has its samples.
        assert wait(lambda: got_early.extend(early.take(10)) or len(got_early) >= 2)
        dp2 = dds.DomainParticipant(DOMAIN)
        late = dds.DataReader(dp2, dds.Topic(dp2, "rt/cam_out", dds.Image_), qos=qos(dds))
        assert wait(lambda: late.get_matched_publications() and len(comp._pub.node.participant
                                                                     .matched(comp._pub.writer_id)) >= 2)
        for k in range(2, 4):
            writer.write(image(dds, picture(k, 8, 16), "rgba8", sec=k))
        assert comp.wait_for(4, 10)
        assert wait(lambda: got_early.extend(early.take(10)) or len(got_early) >= 4)
        assert wait(lambda: got_late.extend(late.take(10)) or len(got_late) >= 2)
        assert [s.header.stamp.sec for s in got_early] == [0, 1, 2, 3]
        assert [s.header.stamp.sec for s in got_late] == [2, 3]     # VOLATILE: only what came after
        # the first peer leaves (its participant is deleted): the lab forgets it
        prefix_count = len(comp.node.participant.participants)
        dp.__del__()
        assert wait(lambda: len(comp.node.participant.participants) == prefix_count - 1, 10), \
            comp.notes()
        assert wait(lambda: not comp.node._subs[next(iter(comp.node._subs))].matched())
        # ... and comes back as a new participant: matched again, frames flow again
        dp3 = dds.DomainParticipant(DOMAIN)
        writer3 = dds.DataWriter(dp3, dds.Topic(dp3, "rt/cam", dds.Image_), qos=qos(dds))
        assert wait(lambda: writer3.get_matched_subscriptions())
        writer3.write(image(dds, picture(9, 8, 16), "rgba8", sec=9))
        assert comp.wait_for(5, 10)
        assert wait(lambda: got_late.extend(late.take(10)) or len(got_late) >= 3)
        out = np.frombuffer(bytes(got_late[2].data), np.uint8).reshape(8, 16, 4)
        assert got_late[2].header.stamp.sec == 9
        assert np.array_equal(out, cv2_dilate(picture(9, 8, 16)))


def test_cli_node_ros2_serves_cyclone_peers(tmp_path) -> None:
    """The ``node --ros2`` command between a best-effort Cyclone camera and a Cyclone viewer.

    Best effort has no retransmission: a sample written after Cyclone matched the node's reader
    but before the node has read Cyclone's own SEDP announcement of the writer is lost, as on a
    real camera. So the camera here keeps sending, as cameras do, until three frames came out;
    each output must be the exact dilation of the frame with its stamp, and the node's summary
    must count every frame it saw as published, none refused."""
    import os
    import re
    import signal
    import subprocess
    import sys

    dds = cyclone()
    cfg = tmp_path / "node.yaml"
    cfg.write_text(CONFIG.format(w=32, h=16))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    # its log goes to files, never to a pipe nobody reads (a full pipe would stall the node)
    with open(tmp_path / "out.txt", "w") as out_file, open(tmp_path / "err.txt", "w") as err_file:
        proc = subprocess.Popen([sys.executable, "-m", "rosfpga_lab", "node", str(cfg), "--ros2",
                                 "--domain", str(DOMAIN), "--duration", "60",
                                 "--best-effort-input"],
                                stdout=out_file, stderr=err_file, text=True, env=env)
        try:
            dp = dds.DomainParticipant(DOMAIN)
            # a best-effort camera (sensor-data QoS): only --best-effort-input matches it
            writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds, False))
            reader = dds.DataReader(dp, dds.Topic(dp, "rt/cam_out", dds.Image_), qos=qos(dds))
            assert wait(lambda: writer.get_matched_subscriptions()
                        and reader.get_matched_publications(), 30)
            got: list = []
            sent = 0
            deadline = time.monotonic() + 20
            while len(got) < 3 and time.monotonic() < deadline:
                writer.write(image(dds, picture(sent, 16, 32), "rgba8", sec=sent))
                sent += 1
                wait(lambda: got.extend(reader.take(10)) or len(got) >= 3, 0.2)
            assert len(got) >= 3, f"{len(got)} outputs for {sent} frames sent"
            for s in got:
                out = np.frombuffer(bytes(s.data), np.uint8).reshape(16, 32, 4)
                assert np.array_equal(out, cv2_dilate(picture(s.header.stamp.sec, 16, 32)))
            assert len({s.header.stamp.sec for s in got}) == len(got)     # none twice
            proc.send_signal(signal.SIGINT)          # Ctrl-C: stops cleanly with a summary
            proc.wait(timeout=15)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    out_text = (tmp_path / "out.txt").read_text()
    err = (tmp_path / "err.txt").read_text()
    assert proc.returncode == 0, err
    assert "DDS domain" in out_text and "input BEST_EFFORT" in out_text
    summary = re.search(r"(\d+) samples seen, (\d+) published, (\d+) refused", out_text)
    assert summary, out_text
    seen, published, refused = map(int, summary.groups())
    assert len(got) <= seen == published <= sent and refused == 0, (summary[0], len(got), sent)


def test_transient_local_writer_serves_a_late_cyclone_reader_its_history() -> None:
    from rosfpga_lab.graph.ros2 import Ros2Node
    from rosfpga_lab.msg import serialize_cdr

    dds = cyclone()

    def sample(k: int) -> bytes:
        return serialize_cdr(None, "sensor_msgs/Image", {
            "header": {"stamp": {"sec": k, "nanosec": 0}, "frame_id": "f"}, "height": 1,
            "width": 2, "encoding": "mono8", "is_bigendian": 0, "step": 2, "data": bytes([k, k])})

    with Ros2Node("latched", DOMAIN) as node:
        pub = node.create_publisher("/latched", "sensor_msgs/Image", Qos(True, 3, transient_local=True))
        for k in range(5):
            pub.publish(sample(k))
        dp = dds.DomainParticipant(DOMAIN)
        P = dds.Policy
        tl = dds.Qos(P.Reliability.Reliable(1_000_000_000), P.History.KeepLast(10),
                     P.Durability.TransientLocal, P.DataRepresentation(use_cdrv0_representation=True))
        late = dds.DataReader(dp, dds.Topic(dp, "rt/latched", dds.Image_), qos=tl)
        got: list = []
        assert wait(lambda: got.extend(late.take(10)) or len(got) >= 3, 10)
        assert [s.header.stamp.sec for s in got] == [2, 3, 4]      # KEEP_LAST 3 of 5
        # the VOLATILE reader only after that: Cyclone (one network stack per domain and
        # process) hands a writer's samples to all its in-sync readers there, so history sent
        # for a TRANSIENT_LOCAL reader meanwhile would reach it too
        volatile = dds.DataReader(dp, dds.Topic(dp, "rt/latched", dds.Image_), qos=qos(dds))
        assert wait(lambda: volatile.get_matched_publications(), 5)
        pub.publish(sample(5))
        more: list = []
        assert wait(lambda: more.extend(volatile.take(10)) or len(more) >= 1, 5)
        assert [s.header.stamp.sec for s in more] == [5]           # VOLATILE: only the new one


def test_camera_component_viewer_all_on_ros2() -> None:
    """The one-command pieces on ROS 2 (no Cyclone needed): camera -> component -> viewer."""
    import time

    from rosfpga_lab.component import Camera, Viewer

    domain = (DOMAIN + 7) % 233
    with Ros2Component(parse_config(CONFIG.format(w=32, h=16)), domain=domain) as comp, \
            Viewer("/cam_out", name="/viewer", domain=domain) as viewer, \
            Camera("/cam", width=32, height=16, encoding="rgba8", rate=50, name="/camera",
                   domain=domain) as cam:
        assert wait(lambda: cam.publisher.get_num_connections() == 1 and comp.wait_for_peers(0.1))
        sent = [cam.publish_one() for _ in range(3)]
        assert viewer.wait_for(3, 10), comp.notes()
        time.sleep(0.1)
        assert viewer.received == 3
        assert viewer.last is not None and viewer.last.header["frame_id"] == "camera"
        assert np.array_equal(viewer.last.image, cv2_dilate(sent[-1].image))


def test_ros_discovery_info_names_the_node_and_its_endpoints() -> None:
    """What ``ros2 node list`` reads: rmw_dds_common/ParticipantEntitiesInfo on ros_discovery_info
    (TRANSIENT_LOCAL), here read by a Cyclone reader typed from rmw_dds_common's .msg files."""
    dds = cyclone()
    comp = Ros2Component(parse_config(CONFIG.format(w=8, h=4)), domain=DOMAIN,
                         name="/lab/fpga_ros2")
    with comp:
        dp = dds.DomainParticipant(DOMAIN)
        P = dds.Policy
        tl = dds.Qos(P.Reliability.Reliable(1_000_000_000), P.History.KeepLast(1),
                     P.Durability.TransientLocal, P.DataRepresentation(use_cdrv0_representation=True))
        reader = dds.DataReader(dp, dds.Topic(dp, "ros_discovery_info", dds.ParticipantEntitiesInfo_),
                                qos=tl)
        got: list = []
        assert wait(lambda: got.extend(s for s in reader.take(10)
                                       if isinstance(s, dds.ParticipantEntitiesInfo_)) or got, 10)
        info = got[-1]
        prefix = comp.node.participant.guid_prefix if comp.node else b""
        assert bytes(info.gid.data) == prefix + b"\x00\x00\x01\xc1"
        (node,) = info.node_entities_info_seq
        assert (node.node_namespace, node.node_name) == ("/lab", "fpga_ros2")
        readers = [bytes(g.data) for g in node.reader_gid_seq]
        writers = [bytes(g.data) for g in node.writer_gid_seq]
        assert len(readers) == len(writers) == 1
        assert readers[0][:12] == writers[0][:12] == prefix
        assert comp._pub is not None and writers[0][12:] == comp._pub.writer_id.to_bytes(4, "big")


def test_a_cyclone_peer_that_dies_is_forgotten_when_its_lease_runs_out(tmp_path) -> None:
    """SIGKILL: no goodbye on the wire; only the lease (1 s here) tells."""
    import os
    import signal
    import subprocess
    import sys
    import time

    cyclone()
    cfg = cyclone_loopback_uri(lease_seconds=1)
    code = ("import time\nfrom cyclonedds.domain import DomainParticipant\n"
            f"dp = DomainParticipant({DOMAIN})\nprint('up', flush=True)\ntime.sleep(60)\n")
    with Ros2Component(parse_config(CONFIG.format(w=8, h=4)), domain=DOMAIN) as comp:
        assert comp.node is not None
        before = set(comp.node.participant.participants)
        proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                                env=dict(os.environ, CYCLONEDDS_URI=cfg))
        try:
            assert proc.stdout is not None and proc.stdout.readline().strip() == "up"
            parts = comp.node.participant.participants

            def short_lease() -> list[bytes]:   # the subprocess's (earlier peers: Cyclone's 10 s)
                return [k for k, p in list(parts.items()) if k not in before and p.lease < 5]

            assert wait(short_lease, 10)
            (peer,) = short_lease()
            lease = parts[peer].lease
            assert lease == pytest.approx(1.0)
            proc.send_signal(signal.SIGKILL)
            proc.wait(5)
            t0 = time.monotonic()
            assert wait(lambda: peer not in comp.node.participant.participants, 10)
            assert time.monotonic() - t0 < lease + 1.0
            assert any("lease" in n and peer.hex() in n for n in comp.notes())
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def test_the_labs_own_message_through_the_ros2_component() -> None:
    """lab_msgs/Samples (a nested message, a float64 array: 8-byte CDR alignment, a sequence of
    messages) from a Cyclone writer through the component's CDR circuit: the int32 array dilated
    (sliding maximum over 3), every other field carried as the writer sent it."""
    from pathlib import Path

    from rosfpga_lab.config import load_config

    cyclone()
    from tests.support import cdrtypes as T

    dds = cyclone()
    cfg = load_config(Path(__file__).resolve().parents[2] / "data" / "fpga_samples_dilate.yaml")
    rng = np.random.default_rng(4)
    values = rng.integers(-2**31, 2**31, 64, dtype=np.int64).astype(np.int32)
    cal = T.Calibration_("lidar", [0.5, -1.25, 3.0], 2)
    msg = T.Samples_(T.Header_(T.Time_(7, 9), "array"), cal, "burst", [1, -2, 3, -4],
                     values.tolist(), T.Duration_(0, 500), [cal, T.Calibration_("x", [0, 0, 1], 2)],
                     True)
    with Ros2Component(cfg, domain=DOMAIN) as comp:
        dp = dds.DomainParticipant(DOMAIN)
        writer = dds.DataWriter(dp, dds.Topic(dp, "rt/samples", T.Samples_), qos=qos(dds))
        reader = dds.DataReader(dp, dds.Topic(dp, "rt/samples_dilated", T.Samples_), qos=qos(dds))
        assert comp.wait_for_peers(10), comp.notes()
        assert wait(lambda: writer.get_matched_subscriptions() and reader.get_matched_publications())
        writer.write(msg)
        got: list = []
        assert wait(lambda: got.extend(reader.take(10)) or got, 10), (comp.counts, comp.notes())
    out = got[0]
    padded = np.concatenate(([np.iinfo(np.int32).min], values, [np.iinfo(np.int32).min]))
    want = np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:])
    assert list(out.samples) == want.tolist()
    assert (out.label, list(out.thresholds), out.valid, out.period.nanosec) == ("burst", [1, -2, 3, -4], True, 500)
    assert out.calibration == cal and list(out.history) == list(msg.history)
    assert (out.header.stamp.sec, out.header.frame_id) == (7, "array")


def test_demo_ros2_command_is_bit_exact(tmp_path) -> None:
    import os
    import subprocess
    import sys

    cfg = tmp_path / "node.yaml"
    cfg.write_text(CONFIG.format(w=32, h=16))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    run = subprocess.run([sys.executable, "-m", "rosfpga_lab", "demo", "--ros2", "--config",
                          str(cfg), "--domain", str((DOMAIN + 21) % 233), "--frames", "6",
                          "--source", "synthetic", "--rate", "50"],
                         capture_output=True, text=True, timeout=60, env=env)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "frames sent 6, received 6, bit-exact against OpenCV 6" in run.stdout


def test_cyclone_forgets_the_lab_node_at_once_when_it_stops() -> None:
    """The node says goodbye (SPDP disposed/unregistered): Cyclone unmatches at once, not when
    the 10 s lease runs out."""
    import time

    dds = cyclone()
    # a domain of its own: a lab reader of rt/cam that an earlier test left without a goodbye
    # (a killed process) would stay matched here until its lease ran out
    domain = (DOMAIN + 37) % 233
    comp = Ros2Component(parse_config(CONFIG.format(w=8, h=4)), domain=domain).start()
    dp = dds.DomainParticipant(domain)
    writer = dds.DataWriter(dp, dds.Topic(dp, "rt/cam", dds.Image_), qos=qos(dds))
    assert wait(lambda: writer.get_matched_subscriptions(), 10)
    comp.stop()
    t0 = time.monotonic()
    assert wait(lambda: not writer.get_matched_subscriptions(), 6)
    assert time.monotonic() - t0 < 6.0     # the lease is 10 s: only the goodbye is this quick
