"""Benchmark: the RTPS participant under attack, next to a Cyclone DDS participant (issue 30).

Each attack runs twice, once against the lab's participant (``rosfpga_lab.graph.ros2.Ros2Node``,
the sans-IO ``rtps.participant`` on sockets) and once against a Cyclone DDS participant (PyPI
``cyclonedds``), in the same setting, and the figures are printed side by side:

* acknack:  the side's writer sends 30 Hz frames (RELIABLE KEEP_LAST 10) to a reader; meanwhile
            ACKNACKs in that reader's name (its GUID, rising counts) ask for every sample the
            writer holds, ``--rate`` a second for ``--seconds``. Figures: legitimate frames exact,
            bytes the writer sent again per byte of ACKNACK (counted at the reader: DATA and
            DATA_FRAG bytes of a sample, or fragment, it had already received). The reader is a
            lab participant on both sides (there the bytes are counted).
* flood:    ``--flood`` SPDP announcements from random GUID prefixes (300 s leases) to the side's
            discovery port, then a Cyclone DDS peer with a writer of the side's topic starts.
            Figures: seconds until the side's reader is matched with it, the process's RSS growth.
* goodbye:  a Cyclone camera sends 30 Hz frames to the side's reader; one SPDP dispose in the
            camera's name (from the attacker's own socket) goes to the side's discovery port.
            Figures: the longest time without a frame after it (recovery), frames lost.
* goodbye2: as goodbye, but the camera is a lab participant and the goodbye comes from its own
            socket while it goes on sending (what a spoofer of the source address too, with a
            raw socket, sends): the goodbye looks real.
* gap:      as goodbye, but the attack is a GAP in the camera writer's name for its next 30
            samples, not yet written. Figures: frames lost.
* slow:     the side's writer (RELIABLE KEEP_LAST 10) sends 30 Hz frames to a Cyclone KEEP_ALL
            RELIABLE reader (max_samples 10) that takes one sample every 0.2 s. Figures: the
            longest write() call (does the writer block?), frames the reader got, in order.

Every row runs in a child process of its own (``--child ROW SIDE``) in a DDS domain of its own
(from the pid), on 127.0.0.1 only, bounded in datagrams and seconds; no files are written. The
side's participant is the first of its domain (participant index 0: the attacker knows its
ports). The cameras, late peers and slow reader run in a process of their own
(``--peer``): Cyclone DDS joins the participants of one process into one instance that matches
them without the network. The lab's participant runs in Python threads of the child, sharing
its GIL with the attacker. Times are from the attack (or the late peer's creation) to the
figure, as the child's clock sees them.
Run:  PYTHONPATH=. .venv/bin/python tests/benchmarks/bench_rtps_attacks.py [--only acknack,gap]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
sys.path.insert(0, str(HERE.parents[2]))   # the root: tests.support

ROWS = ("acknack", "flood", "goodbye", "goodbye2", "gap", "slow")
SIDES = ("lab", "cyclone")
TOPIC, ROS_TOPIC, ROS_TYPE = "rt/bench", "/bench", "sensor_msgs/Image"
PERIOD = 1 / 30


# ------------------------------------------------------------------------------ the child side
class World:
    """What one child row shares: the domain, Cyclone's types, frames and where they went."""

    def __init__(self, args: argparse.Namespace) -> None:
        from tests.support.ros2tools import cyclone, qos

        self.dds = cyclone()              # sets CYCLONEDDS_URI (loopback, no multicast)
        self.qos = qos
        self.args = args
        self.domain = 1 + os.getpid() % 97 if args.domain is None else args.domain
        self.w, self.h = args.width, args.height
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.attack_bytes = 0
        self.got: list[tuple[float, int, bool]] = []       # (time, frame number, exact)
        self.lock = threading.Lock()

    # ports of participant index 0 (the side's participant is the first in its domain)
    def meta0(self) -> tuple[str, int]:
        from rosfpga_lab.rtps.entities import discovery_port
        return ("127.0.0.1", discovery_port(self.domain, 0))

    def user0(self) -> tuple[str, int]:
        from rosfpga_lab.rtps.entities import user_port
        return ("127.0.0.1", user_port(self.domain, 0))

    def data(self, k: int) -> bytes:
        return k.to_bytes(4, "big") * (self.w * self.h)

    def frame(self, k: int) -> Any:
        d = self.dds
        return d.Image_(d.Header_(d.Time_(k, 0), "camera"), self.h, self.w, "rgba8", 0,
                        self.w * 4, self.data(k))

    def arrived(self, img: Any) -> None:
        k = img.header.stamp.sec
        with self.lock:
            self.got.append((time.monotonic(), k, bytes(img.data) == self.data(k)))

    def send(self, datagram: bytes, dst: tuple[str, int]) -> None:
        try:
            self.sock.sendto(datagram, dst)
        except OSError:
            return
        self.attack_bytes += len(datagram)


class LabWriter:
    def __init__(self, world: World, name: str = "camera") -> None:
        from rosfpga_lab.graph.ros2 import Ros2Node
        self.world, self.node = world, Ros2Node(name, domain=world.domain)
        self.pub = self.node.create_publisher(ROS_TOPIC, ROS_TYPE)
        self.prefix, self.eid = self.node.participant.guid_prefix, self.pub.writer_id

    def write(self, k: int) -> None:
        self.pub.publish(self.world.frame(k).serialize())

    def matched(self) -> int:
        return self.pub.matched()

    def close(self) -> None:
        self.node.close()


class CycloneWriter:
    def __init__(self, world: World, dp: Any = None) -> None:
        d = world.dds
        self.world = world
        self.dp = dp or d.DomainParticipant(world.domain)
        self.writer = d.DataWriter(self.dp, d.Topic(self.dp, TOPIC, d.Image_), qos=world.qos(d))
        guid = self.writer.guid.bytes
        self.prefix, self.eid = guid[:12], int.from_bytes(guid[12:], "big")

    def write(self, k: int) -> None:
        self.writer.write(self.world.frame(k))

    def matched(self) -> int:
        return len(self.writer.get_matched_subscriptions())

    def close(self) -> None:
        pass


class LabReader:
    def __init__(self, world: World, name: str = "sink", count_for: bytes = b"") -> None:
        from rosfpga_lab.graph.ros2 import Ros2Node
        self.world = world
        self.node = Ros2Node(name, domain=world.domain)
        self.sub = self.node.create_subscriber(
            ROS_TOPIC, ROS_TYPE, lambda payload, s: world.arrived(world.dds.Image_.deserialize(payload)))
        self.prefix, self.eid = self.node.participant.guid_prefix, self.sub.reader_id
        self.resent = 0
        self._seen: set[tuple[int, int]] = set()

    def count_resent(self, writer_prefix: bytes, writer_eid: int) -> None:
        """From now on, count DATA/DATA_FRAG bytes of that writer already received once."""
        from rosfpga_lab.rtps import parse_message
        from rosfpga_lab.rtps.errors import RtpsError
        from rosfpga_lab.rtps.message import Data, DataFrag
        part = self.node.participant
        orig = part.receive

        def receive(datagram: bytes, source: tuple[str, int], now: float) -> list:
            try:
                msg = parse_message(datagram)
            except RtpsError:
                return orig(datagram, source, now)
            if msg.header.guid_prefix == writer_prefix:
                for sub in msg.submessages:
                    if isinstance(sub, (Data, DataFrag)) and sub.writer_id == writer_eid:
                        key = (sub.seq, sub.frag_start if isinstance(sub, DataFrag) else 0)
                        if key in self._seen:
                            self.resent += len(sub.payload)
                        else:
                            self._seen.add(key)
            return orig(datagram, source, now)

        part.receive = receive  # type: ignore[method-assign]

    def matched(self) -> int:
        return self.sub.matched()

    def writer_locator(self, prefix: bytes, eid: int) -> tuple[str, int]:
        with self.node._lock:
            return self.node.participant.remote[prefix + eid.to_bytes(4, "big")].locator

    def close(self) -> None:
        self.node.close()


class CycloneReader:
    def __init__(self, world: World, qos: Any = None, take_every: float = 0.0) -> None:
        d = world.dds
        self.world = world
        self.dp = d.DomainParticipant(world.domain)
        self.reader = d.DataReader(self.dp, d.Topic(self.dp, TOPIC, d.Image_), qos=qos or world.qos(d))
        guid = self.reader.guid.bytes
        self.prefix, self.eid = guid[:12], int.from_bytes(guid[12:], "big")
        self.stop = threading.Event()
        self.take_every = take_every
        self.thread = threading.Thread(target=self._loop, daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        while not self.stop.is_set():
            for s in self.reader.take(1 if self.take_every else 32):
                if isinstance(s, self.world.dds.Image_):
                    self.world.arrived(s)
            time.sleep(self.take_every or 0.002)

    def drain(self, seconds: float) -> None:
        self.take_every = 0.0
        time.sleep(seconds)

    def matched(self) -> int:
        return len(self.reader.get_matched_publications())

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2)


class Peer:
    """A Cyclone DDS participant in a process of its own (this script with ``--peer ROLE``):
    Cyclone DDS joins the participants of one process into one instance that matches them
    without the network, so the side's Cyclone participant and its Cyclone peers must live in
    different processes. Talks line by line over its stdin and stdout."""

    def __init__(self, world: World, role: str) -> None:
        a = world.args
        self.proc = subprocess.Popen(
            [sys.executable, str(HERE), "--peer", role, f"--domain={world.domain}",
             f"--width={a.width}", f"--height={a.height}", f"--seconds={a.seconds}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        line = self.ask("")
        if not line.startswith("READY "):
            self.stop()
            raise RuntimeError(f"peer {role} did not start: {line!r}")
        _, prefix, eid = line.split()
        self.prefix, self.eid = bytes.fromhex(prefix), int(eid)

    def ask(self, command: str) -> str:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        if command:
            self.proc.stdin.write(command + "\n")
            self.proc.stdin.flush()
        return self.proc.stdout.readline().strip()

    def stop(self) -> None:
        try:
            assert self.proc.stdin is not None
            self.proc.stdin.close()
            self.proc.wait(10)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait()


def peer_main(role: str, args: argparse.Namespace) -> None:
    """The ``--peer`` process: a Cyclone camera, a late peer or a slow KEEP_ALL reader."""
    world = World(args)
    d = world.dds
    if role == "slowreader":
        P = d.Policy
        keep_all = d.Qos(P.Reliability.Reliable(1_000_000_000), P.History.KeepAll,
                         P.ResourceLimits(max_samples=10), P.Durability.Volatile,
                         P.DataRepresentation(use_cdrv0_representation=True))
        reader = CycloneReader(world, keep_all, take_every=0.2)
        print(f"READY {reader.prefix.hex()} {reader.eid}", flush=True)
        for line in sys.stdin:
            if line.strip() == "drain":
                reader.drain(2.0)
                with world.lock:
                    print(json.dumps([(k, ok) for _, k, ok in world.got]), flush=True)
        os._exit(0)
    if role == "late":          # its participant starts on "go" (process start not timed)
        print("READY 00 0", flush=True)
        for line in sys.stdin:
            if line.strip() == "go":
                late = CycloneWriter(world)
                print(f"{late.prefix.hex()} {late.eid}", flush=True)
        os._exit(0)
    writer: Any = LabWriter(world) if role == "labcamera" else CycloneWriter(world)
    print(f"READY {writer.prefix.hex()} {writer.eid}", flush=True)
    cam: Camera | None = None
    for line in sys.stdin:
        command = line.strip()
        if command.startswith("bye ") and role == "labcamera":
            # its own goodbye, from its own socket, while it goes on: what a spoofer of both
            # GUID prefix and source address (a raw socket) sends
            host, port = command.split()[1:]
            writer.node._user.sendto(goodbye_datagram(writer.prefix), (host, int(port)))
            print("sent", flush=True)
        elif command == "start":
            cam = Camera(writer, 120.0)
            print("started", flush=True)
        elif command == "count":
            print(cam.written if cam else 0, flush=True)
        elif command == "stop" and cam is not None:
            cam.finish()
            print(cam.written, flush=True)
    os._exit(0)


def wait(cond: Any, timeout: float) -> float | None:
    """Seconds until ``cond()`` holds, or None after ``timeout``."""
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            return None
        time.sleep(0.002)
    return time.monotonic() - t0


class Camera:
    """Writes frames 0, 1, 2 ... at 30 Hz on its own thread until stopped (or ``limit`` s)."""

    def __init__(self, writer: Any, limit: float) -> None:
        self.writer, self.limit = writer, limit
        self.written = 0
        self.longest_write = 0.0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        t0 = time.monotonic()
        while not self.stop.is_set() and time.monotonic() - t0 < self.limit:
            t = time.monotonic()
            self.writer.write(self.written)
            self.longest_write = max(self.longest_write, time.monotonic() - t)
            self.written += 1
            time.sleep(max(0.0, t0 + self.written * PERIOD - time.monotonic()))

    def finish(self) -> None:
        self.stop.set()
        self.thread.join(self.limit + 5)


def exact(world: World, first: int, last: int) -> tuple[int, int]:
    """Frames first..last-1 received exactly once, in order and intact; and how many were due."""
    ks = [k for _, k, ok in world.got if first <= k < last and ok]
    return (len(set(ks)) if ks == sorted(set(ks)) else 0), max(0, last - first)


def rss() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def spdp_datagram(prefix: bytes, domain: int, lease: float = 300.0) -> bytes:
    from rosfpga_lab.rtps import build as b
    from rosfpga_lab.rtps.entities import SPDP_READER, SPDP_WRITER
    payload = b.spdp_payload(prefix, b.Locator("127.0.0.1", 9), b.Locator("127.0.0.1", 9), lease,
                             "flood", b"", domain)
    return b.header(prefix) + b.data(SPDP_READER, SPDP_WRITER, 1, payload)


def goodbye_datagram(prefix: bytes) -> bytes:
    """What a participant sends when it leaves (rtps.spdp's goodbye): SPDP disposed, unregistered."""
    from rosfpga_lab.rtps import build as b
    from rosfpga_lab.rtps.entities import PARTICIPANT_ENTITY, SPDP_READER, SPDP_WRITER
    guid = prefix + PARTICIPANT_ENTITY.to_bytes(4, "big")
    qos = b.inline_qos([(b.PID_KEY_HASH, guid), (b.PID_STATUS_INFO, b"\x00\x00\x00\x03")])
    key = b.param_list([(b.PID_PARTICIPANT_GUID, guid)])
    return b.header(prefix) + b.info_ts(time.time()) + b.data(SPDP_READER, SPDP_WRITER, 1 << 20, key, qos)


def row_acknack(world: World, side: str) -> dict:
    from rosfpga_lab.rtps import build as b
    args = world.args
    writer = LabWriter(world) if side == "lab" else CycloneWriter(world)
    reader = LabReader(world)
    if wait(lambda: writer.matched() and reader.matched(), 15) is None:
        return {"error": "writer and reader never matched"}
    reader.count_resent(writer.prefix, writer.eid)
    dst = reader.writer_locator(writer.prefix, writer.eid)
    cam = Camera(writer, args.seconds + 1.5)
    time.sleep(0.5)
    t0, k = time.monotonic(), 0
    while time.monotonic() - t0 < args.seconds:
        k += 1
        top = max(1, cam.written)
        base = max(1, top - 40)
        world.send(b.header(reader.prefix) + b.info_dst(writer.prefix)
                   + b.acknack(reader.eid, writer.eid, base, range(base, top + 1), 10_000 + k), dst)
        time.sleep(max(0.0, t0 + k / args.rate - time.monotonic()))
    cam.finish()
    time.sleep(1.0)
    good, due = exact(world, 0, cam.written)
    out = {"frames": f"{good}/{due}", "acknacks": k, "attack_bytes": world.attack_bytes,
           "resent_bytes": reader.resent,
           "ratio": reader.resent / max(1, world.attack_bytes)}
    reader.close()
    writer.close()
    return out


def row_flood(world: World, side: str) -> dict:
    args = world.args
    if side == "lab":
        target: Any = LabReader(world, "target")
    else:
        target = CycloneReader(world)
    time.sleep(0.3)
    rss0 = rss()
    rng = random.Random(30)
    t0 = time.monotonic()
    for k in range(args.flood):
        world.send(spdp_datagram(bytes(rng.randrange(256) for _ in range(12)), world.domain),
                   world.meta0())
        time.sleep(max(0.0, t0 + (k + 1) / args.flood_rate - time.monotonic()))
    time.sleep(0.5)
    grown = rss() - rss0
    table = len(target.node.participant.participants) if side == "lab" else None
    times: list[float | None] = []
    for _ in range(args.repeat):          # legitimate peers, one after the other, after the flood
        late = Peer(world, "late")
        before = target.matched()         # (those before stay matched until their lease ends)
        t_go = time.monotonic()
        late.ask("go")
        found = wait(lambda: target.matched() > before, args.wait)
        times.append(None if found is None else time.monotonic() - t_go)
        late.stop()
        if found is None:
            break
    out = {"flood": args.flood, "flood_seconds": round(time.monotonic() - t0, 1),
           "discovery_s": times, "rss_growth": grown, "table": table}
    target.close()
    return out


def camera_and_target(world: World, side: str, role: str = "camera") -> tuple[Any, Peer]:
    """The side's reader (first in the domain: index 0) and a camera peer (Cyclone's, or the
    lab's for ``labcamera``), matched."""
    target: Any = LabReader(world, "target") if side == "lab" else CycloneReader(world)
    time.sleep(0.3)
    camera = Peer(world, role)
    if wait(lambda: target.matched(), 15) is None:
        camera.stop()
        raise RuntimeError("camera and target never matched")
    camera.ask("start")
    return target, camera


def row_goodbye(world: World, side: str, from_camera: bool = False) -> dict:
    args = world.args
    target, camera = camera_and_target(world, side, "labcamera" if from_camera else "camera")
    time.sleep(1.0)
    tg = time.monotonic()
    first = int(camera.ask("count"))
    if from_camera:
        camera.ask("bye %s %d" % world.meta0())
    else:
        world.send(goodbye_datagram(camera.prefix), world.meta0())
    # until frames have flowed for 1.5 s after the longest outage so far, or --wait
    while time.monotonic() - tg < args.wait:
        time.sleep(0.1)
        _, back = outage(world, tg, time.monotonic())
        if back < 1e9 and time.monotonic() - tg > back + 1.5:
            break
    written = int(camera.ask("stop"))
    until = time.monotonic()
    time.sleep(0.5)
    camera.stop()
    gap, back = outage(world, tg, until)
    good, due = exact(world, first, written)
    forgotten = None
    if side == "lab":
        forgotten = any("said goodbye" in n for n in target.node.notes())
    elif gap > 0.5:
        forgotten = True
    target.close()
    return {"longest_gap_s": gap, "recovered": back < 1e9, "frames": f"{good}/{due}",
            "forgotten": forgotten}


def outage(world: World, since: float, until: float) -> tuple[float, float]:
    """The longest time without a frame between ``since`` and ``until``, and when it ended
    (seconds after ``since``; 1e9 if no frame came after it)."""
    with world.lock:
        times = [t for t, _, _ in world.got if since <= t <= until]
    prev, longest, end = since, 0.0, 0.0
    for t in times:
        if t - prev > longest:
            longest, end = t - prev, t - since
        prev = t
    if until - prev > max(longest, 0.5):
        return until - prev, 1e9
    return longest, end


def row_gap(world: World, side: str) -> dict:
    from rosfpga_lab.rtps import build as b
    args = world.args
    target, camera = camera_and_target(world, side)
    time.sleep(1.0)
    first = int(camera.ask("count"))
    nxt = first + 1                 # the camera's next sequence number (Cyclone counts from 1)
    dst = target.node.participant.user if side == "lab" else world.user0()
    world.send(b.header(camera.prefix) + b.info_dst(target.prefix)
               + b.gap(target.eid, camera.eid, nxt, nxt + 30), dst)
    time.sleep(args.seconds)
    written = int(camera.ask("stop"))
    time.sleep(1.0)
    camera.stop()
    good, due = exact(world, first, written)
    target.close()
    return {"frames": f"{good}/{due}", "lost": due - good}


def row_slow(world: World, side: str) -> dict:
    args = world.args
    writer = LabWriter(world) if side == "lab" else CycloneWriter(world)
    time.sleep(0.3)
    reader = Peer(world, "slowreader")
    if wait(lambda: writer.matched(), 15) is None:
        reader.stop()
        return {"error": "writer and reader never matched"}
    rss0 = rss()
    cam = Camera(writer, args.seconds)
    time.sleep(args.seconds)
    cam.finish()
    got = json.loads(reader.ask("drain"))
    reader.stop()
    ks = [k for k, ok in got if ok]
    out = {"written": cam.written, "got": len(ks), "in_order": ks == sorted(set(ks)),
           "longest_write_s": cam.longest_write, "rss_growth": rss() - rss0}
    writer.close()
    return out


def child_main(row: str, side: str, args: argparse.Namespace) -> None:
    world = World(args)
    fn = {"acknack": row_acknack, "flood": row_flood, "goodbye": row_goodbye,
          "goodbye2": lambda w, s: row_goodbye(w, s, from_camera=True), "gap": row_gap,
          "slow": row_slow}[row]
    try:
        out = fn(world, side)
    except Exception as exc:      # a row that cannot run says why; the others go on
        out = {"error": f"{type(exc).__name__}: {exc}"}
    out["domain"] = world.domain
    print("RESULT " + json.dumps(out), flush=True)
    os._exit(0)          # Cyclone's threads and the nodes' daemon threads end with the process


# ------------------------------------------------------------------------------ the parent side
def run_child(row: str, side: str, argv: list[str], timeout: float) -> dict:
    cmd = [sys.executable, str(HERE), "--child", row, side, *argv]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"no result in {timeout:.0f} s"}
    for line in proc.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return {"error": (proc.stderr.strip().splitlines() or ["no output"])[-1][:120]}


def disc(times: list[float | None], wait: float) -> str:
    if not times or None in times:
        return f"never (>{wait:g} s)"
    ts = sorted(t for t in times if t is not None)
    return f"{ts[len(ts) // 2]:.3f} ({ts[-1]:.3f}) s x{len(ts)}"


def cells(row: str, r: dict, args: argparse.Namespace) -> list[tuple[str, str]]:
    if "error" in r:
        return [("error", r["error"])]
    if row == "acknack":
        return [("legitimate frames exact", r["frames"]),
                ("ACKNACKs sent / bytes", f"{r['acknacks']} / {r['attack_bytes']:,}"),
                ("bytes resent to the reader", f"{r['resent_bytes']:,}"),
                ("bytes resent per byte received", f"{r['ratio']:.2f}")]
    if row == "flood":
        return [("SPDP flood (random prefixes)", f"{r['flood']} in {r['flood_seconds']} s"),
                ("discovery time of a late peer, median (max)", disc(r["discovery_s"], args.wait)),
                ("RSS growth during the flood", f"{r['rss_growth'] / 2**20:.1f} MiB"),
                ("participant table after it", "-" if r["table"] is None else str(r["table"]))]
    if row in ("goodbye", "goodbye2"):
        rec = f"{r['longest_gap_s']:.3f} s" if r["recovered"] else f"none in {args.wait:g} s"
        return [("longest time without a frame (recovery)", rec),
                ("legitimate frames exact", r["frames"]),
                ("camera forgotten", "-" if r["forgotten"] is None else str(r["forgotten"]))]
    if row == "gap":
        return [("legitimate frames exact", r["frames"]), ("frames lost", str(r["lost"]))]
    return [("frames written / got by the slow reader", f"{r['written']} / {r['got']}"),
            ("got in order, intact", str(r["in_order"])),
            ("longest write() call", f"{r['longest_write_s'] * 1000:.1f} ms"),
            ("RSS growth while writing", f"{r['rss_growth'] / 2**20:.1f} MiB")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog="Rows: " + ", ".join(ROWS) + ". See the module docstring.")
    ap.add_argument("--only", default=",".join(ROWS), help="rows to run, comma-separated")
    ap.add_argument("--sides", default=",".join(SIDES), help="lab, cyclone or both")
    ap.add_argument("--seconds", type=float, default=4.0, help="length of an attack (default 4)")
    ap.add_argument("--rate", type=float, default=1000.0, help="ACKNACKs a second (default 1000)")
    ap.add_argument("--flood", type=int, default=10000, help="SPDP announcements (default 10000)")
    ap.add_argument("--flood-rate", type=float, default=5000.0,
                    help="SPDP announcements a second (default 5000)")
    ap.add_argument("--repeat", type=int, default=5,
                    help="late peers started one after the other after the flood (default 5)")
    ap.add_argument("--wait", type=float, default=15.0,
                    help="longest wait for a late peer or a recovery, s (default 15)")
    ap.add_argument("--width", type=int, default=160, help="frame width, rgba8 (default 160)")
    ap.add_argument("--height", type=int, default=120, help="frame height (default 120: 76.8 KB)")
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: from the pid)")
    ap.add_argument("--child", nargs=2, metavar=("ROW", "SIDE"), help=argparse.SUPPRESS)
    ap.add_argument("--peer", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child_main(args.child[0], args.child[1], args)
        return
    if args.peer:
        peer_main(args.peer, args)
        return
    rows = [r for r in args.only.split(",") if r]
    sides = [s for s in args.sides.split(",") if s]
    bad = [r for r in rows if r not in ROWS] + [s for s in sides if s not in SIDES]
    if bad:
        ap.error(f"unknown row or side {bad}: rows {ROWS}, sides {SIDES}")
    argv = [f"--seconds={args.seconds}", f"--rate={args.rate}", f"--flood={args.flood}",
            f"--flood-rate={args.flood_rate}", f"--wait={args.wait}", f"--repeat={args.repeat}",
            f"--width={args.width}",
            f"--height={args.height}"] + ([f"--domain={args.domain}"] if args.domain is not None else [])
    timeout = 30 + args.seconds + args.wait * (1 + args.repeat) + args.flood / args.flood_rate
    print(f"frames {args.width}x{args.height} rgba8 ({args.width * args.height * 4:,} bytes) at "
          f"30 Hz, attacks {args.seconds:g} s, on 127.0.0.1")
    print(f"{'row':8} {'figure':42} " + " ".join(f"{s:>22}" for s in sides))
    for row in rows:
        results = {side: run_child(row, side, argv, timeout) for side in sides}
        table = {side: cells(row, results[side], args) for side in sides}
        names = [n for n, _ in table[sides[0]]]
        for s in sides[1:]:
            names += [n for n, _ in table[s] if n not in names]
        for i, name in enumerate(names):
            vals = [dict(table[s]).get(name, "") for s in sides]
            print(f"{row if i == 0 else '':8} {name:42} " + " ".join(f"{v:>22}" for v in vals))


if __name__ == "__main__":
    main()
