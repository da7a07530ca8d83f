"""Benchmark: the lab's servers under hostile peers (issue 10), as figures to compare.

Runs each attack over loopback against the code it imports (this checkout, or another one put
first on ``PYTHONPATH``: run it once on main's code and once on a branch for before/after) and,
where cheap, against Debian's real ``rosmaster``:

* body:   RSS growth of a master after 20 XML-RPC requests of ~8 MiB, 16 of them concurrent
          (the trace used to keep every request body);
* frame:  RSS growth of a subscribing node after 8 fake publishers each declared a 60 MiB
          frame and sent 1 MiB of it;
* slow:   legitimate XML-RPC calls served while 200 sockets drip one byte per second, and new
          subscribers connected while 80 idle sockets (reopened as the node closes them) sit on a
          publisher's TCPROS port;
* notify: seconds until a subscriber connects to a new publisher while a silent node (accepts,
          never answers) subscribes to 5 busy topics;
* slope:  RSS per 100,000 frames over 1,000,000 frames through a subscriber handshake machine
          and a ``topic hz`` rate meter.

Every attack is bounded in sockets and seconds and stops by itself; child processes are ended.
Run:  .venv/bin/python tests/benchmarks/bench_hardening.py [--only body,frame,...] [--no-ros]
Before: git worktree add /tmp/h-main main && PYTHONPATH=/tmp/h-main .venv/bin/python
        tests/benchmarks/bench_hardening.py
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import os
import select
import shutil
import socket
import struct
import subprocess
import sys
import threading
import time
import xmlrpc.client
import xmlrpc.server
from pathlib import Path

ATTACKS = ("body", "frame", "slow", "notify", "slope")
HERE = Path(__file__).resolve()


# ------------------------------------------------------------------------------ helpers
def rss(pid: int) -> int:
    """Resident set size of ``pid`` in bytes (Linux /proc)."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def mib(n: float) -> str:
    return f"{n / (1 << 20):8.1f} MiB"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port(port: int, timeout: float = 15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            return True
        except OSError:
            time.sleep(0.1)
    return False


def xml_call(method: str, *params) -> bytes:
    return xmlrpc.client.dumps(params, methodname=method).encode()


def post(port: int, body: bytes, timeout: float = 10.0) -> bytes:
    head = b"POST / HTTP/1.0\r\nContent-Type: text/xml\r\nContent-Length: %d\r\n\r\n" % len(body)
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(head + body)
        out = bytearray()
        while chunk := s.recv(65536):
            out += chunk
    return bytes(out)


class Child:
    """This script in ``--child ROLE`` mode: a master or a node in its own process."""

    def __init__(self, role: str, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, str(HERE), "--child", role, *args],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline().strip()
        if not line.startswith("READY "):
            self.stop()
            raise RuntimeError(f"child {role} did not start: {line!r}")
        self.info = line.split()[1:]

    def trimmed_rss(self) -> int:
        """The child's RSS after gc and glibc's malloc_trim (memory the code still holds)."""
        self.proc.stdin.write("trim\n")
        self.proc.stdin.flush()
        return int(self.proc.stdout.readline())

    def stop(self) -> None:
        try:
            self.proc.stdin.close()
            self.proc.wait(15)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait()


def child_main(role: str, args: list[str]) -> None:
    from rosfpga_lab.graph import EmbeddedMaster, Node

    master = EmbeddedMaster(port=0).start()
    extra = []
    node = None
    if role == "subscriber":
        node = Node("/victim", master=master)
        node.subscribe("/attack", "std_msgs/String", lambda body, info: None, raw=True)
        extra = [node.uri]
    print("READY", master.port, *extra, flush=True)
    for line in sys.stdin:  # until the parent closes our stdin
        if line.strip() == "trim":  # what the allocator keeps vs what the code keeps
            gc.collect()
            try:
                ctypes.CDLL("libc.so.6").malloc_trim(0)
            except OSError:
                pass
            print(rss(os.getpid()), flush=True)
    if node is not None:
        node.shutdown()
    master.stop()


class RealMaster:
    """Debian's rosmaster on a free port, or None-like when it is not installed."""

    def __init__(self) -> None:
        self.port = free_port()
        self.proc = subprocess.Popen(["rosmaster", "--core", "-p", str(self.port)],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     env={**os.environ, "ROS_HOME": os.path.join(
                                         os.environ.get("TMPDIR", "/tmp"), f"bench-hardening-{os.getpid()}")})
        if not wait_port(self.port):
            self.stop()
            raise RuntimeError("rosmaster did not start")

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def real_master() -> RealMaster | None:
    if shutil.which("rosmaster") is None:
        return None
    try:
        return RealMaster()
    except RuntimeError:
        return None


# ------------------------------------------------------------------------------ attacks
def body_attack(port: int, pid: int) -> tuple[int, int]:
    """20 requests of ~8 MiB (4 alone, then 16 at once); returns (RSS before, RSS after)."""
    payload = "b" * ((8 << 20) - 4096)
    body = xml_call("getPid", "/bench_attacker", payload)
    before = rss(pid)

    def one() -> None:
        try:
            post(port, body, timeout=60)
        except OSError:
            pass

    for _ in range(4):
        one()
    threads = [threading.Thread(target=one) for _ in range(16)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    time.sleep(1.0)
    return before, rss(pid)


def run_body(ros: bool) -> None:
    print("\n[body] 20 XML-RPC requests of ~8 MiB (16 concurrent): master RSS growth after")
    child = Child("master")
    try:
        before, after = body_attack(int(child.info[0]), child.proc.pid)
        trimmed = child.trimmed_rss()
        print(f"  lab master          {mib(after - before)}  (RSS {mib(after)}; after gc + "
              f"malloc_trim: {mib(trimmed - before)})")
    finally:
        child.stop()
    if ros and (rm := real_master()):
        try:
            before, after = body_attack(rm.port, rm.proc.pid)
            print(f"  real rosmaster      {mib(after - before)}  (RSS {mib(after)})")
        finally:
            rm.stop()


def _header(fields: dict[str, str]) -> bytes:
    out = b""
    for k, v in fields.items():
        f = f"{k}={v}".encode()
        out += struct.pack("<I", len(f)) + f
    return struct.pack("<I", len(out)) + out


class FakePublisher:
    """Answers requestTopic, accepts one subscriber, declares a big frame, sends part of it."""

    def __init__(self, i: int, declared: int, sent: int) -> None:
        self.declared, self.sent = declared, sent
        self.done = threading.Event()
        self.tcp = socket.socket()
        self.tcp.bind(("127.0.0.1", 0))
        self.tcp.listen(4)
        port = self.tcp.getsockname()[1]
        self.rpc = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
        self.rpc.register_function(lambda caller, topic, protos: [1, "", ["TCPROS", "127.0.0.1", port]],
                                   "requestTopic")
        self.uri = f"http://127.0.0.1:{self.rpc.server_address[1]}/"
        self.conns: list[socket.socket] = []
        threading.Thread(target=self.rpc.serve_forever, daemon=True).start()
        threading.Thread(target=self._serve, args=(i,), daemon=True).start()

    def _serve(self, i: int) -> None:
        try:
            conn, _ = self.tcp.accept()
        except OSError:
            return
        self.conns.append(conn)
        conn.settimeout(10)
        try:
            n = struct.unpack("<I", conn.recv(4, socket.MSG_WAITALL))[0]
            conn.recv(n, socket.MSG_WAITALL)
            conn.sendall(_header({"callerid": f"/fake{i}", "latching": "0", "md5sum": "*",
                                  "topic": "/attack", "type": "std_msgs/String"}))
            conn.sendall(struct.pack("<I", self.declared) + b"\xab" * self.sent)
        except OSError:
            pass
        self.done.set()

    def close(self) -> None:
        self.rpc.shutdown()
        self.rpc.server_close()
        for c in self.conns:
            c.close()
        self.tcp.close()


def run_frame() -> None:
    print("\n[frame] 8 fake publishers declare a 60 MiB frame and send 1 MiB of it: subscriber RSS growth")
    child = Child("subscriber")
    fakes = [FakePublisher(i, 60 << 20, 1 << 20) for i in range(8)]
    try:
        time.sleep(0.5)
        before = rss(child.proc.pid)
        node_uri = child.info[1]
        reply = xmlrpc.client.ServerProxy(node_uri).publisherUpdate("/master", "/attack",
                                                                    [f.uri for f in fakes])
        ok = all(f.done.wait(20) for f in fakes)
        time.sleep(1.0)
        after = rss(child.proc.pid)
        print(f"  lab subscriber      {mib(after - before)}  (8 MiB received; all sent: {ok}; "
              f"publisherUpdate {reply[0]}; after gc + malloc_trim: "
              f"{mib(child.trimmed_rss() - before)})")
    finally:
        for f in fakes:
            f.close()
        child.stop()


def slow_xmlrpc(port: int, seconds: float = 6.0) -> tuple[int, int]:
    """200 sockets dripping one byte per second; legit getPid calls meanwhile: (served, tried)."""
    drips: list[socket.socket] = []
    stop = threading.Event()
    for _ in range(200):
        try:
            drips.append(socket.create_connection(("127.0.0.1", port), timeout=5))
        except OSError:
            break
    text = b"POST / HTTP/1.1\r\nContent-Length: 100\r\n\r\n" + b"x" * 100

    def drip() -> None:
        i = 0
        while not stop.wait(1.0) and i < len(text):
            for s in list(drips):
                try:
                    s.send(text[i:i + 1])
                except OSError:
                    drips.remove(s)
            i += 1

    t = threading.Thread(target=drip, daemon=True)
    t.start()
    time.sleep(1.5)
    served = tried = 0
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        tried += 1
        try:
            reply = post(port, xml_call("getPid", "/legit"), timeout=2)
            if b" 200 " in reply.split(b"\r\n", 1)[0]:
                served += 1
        except OSError:
            pass
        time.sleep(0.1)
    stop.set()
    t.join(5)
    for s in drips:
        s.close()
    return served, tried


def slow_tcpros(tries: int = 10) -> tuple[int, int]:
    from rosfpga_lab.graph import EmbeddedMaster, Node

    master = EmbeddedMaster(port=0).start()
    pub_node = Node("/held", master=master)
    pub_node.advertise("/h", "std_msgs/String")
    port = pub_node.tcpros_port
    idle = [socket.create_connection(("127.0.0.1", port), timeout=5) for _ in range(80)]
    stop = threading.Event()

    def keep_holding() -> None:  # the attacker reopens every socket the node closes
        while not stop.wait(0.05):
            readable, _, _ = select.select(idle, [], [], 0)
            for s in readable:
                idle.remove(s)
                s.close()
                try:
                    idle.append(socket.create_connection(("127.0.0.1", port), timeout=5))
                except OSError:
                    pass

    holder = threading.Thread(target=keep_holding, daemon=True)
    holder.start()
    connected = 0
    try:
        time.sleep(0.3)
        for i in range(tries):
            n = Node(f"/newcomer{i}", master=master)
            try:
                if n.subscribe("/h", "std_msgs/String").wait_for_connection(1, 2.0):
                    connected += 1
            finally:
                n.shutdown()
    finally:
        stop.set()
        holder.join(5)
        for s in idle:
            s.close()
        pub_node.shutdown()
        master.stop()
    return connected, tries


def run_slow(ros: bool) -> None:
    print("\n[slow] legit XML-RPC calls served while 200 sockets drip 1 byte/s (6 s, one call per 0.1 s)")
    child = Child("master")
    try:
        served, tried = slow_xmlrpc(int(child.info[0]))
        print(f"  lab master          {served}/{tried} served")
    finally:
        child.stop()
    if ros and (rm := real_master()):
        try:
            served, tried = slow_xmlrpc(rm.port)
            print(f"  real rosmaster      {served}/{tried} served")
        finally:
            rm.stop()
    print("[slow] new subscribers connected within 2 s while 80 idle sockets (kept open: reopened when "
          "closed) sit on the TCPROS port")
    connected, tries = slow_tcpros()
    print(f"  lab publisher       {connected}/{tries} connected")


def notify_time(master_uri: str, limit: float = 40.0) -> float:
    """Silent node subscribed to 5 topics, each gets a publisher; then time a legit pair."""
    from rosfpga_lab.graph import Node

    proxy = xmlrpc.client.ServerProxy(master_uri)
    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen(64)
    api = f"http://127.0.0.1:{silent.getsockname()[1]}/"
    listener = talker = None
    try:
        for t in range(5):
            proxy.registerSubscriber("/silent", f"/busy{t}", "std_msgs/String", api)
        for t in range(5):
            proxy.registerPublisher("/busy_talker", f"/busy{t}", "std_msgs/String", "http://127.0.0.1:9/")
        listener = Node("/listener", master_uri=master_uri)
        talker = Node("/talker", master_uri=master_uri)
        sub = listener.subscribe("/legit", "std_msgs/String")
        t0 = time.monotonic()
        talker.advertise("/legit", "std_msgs/String")
        if not sub.wait_for_connection(1, limit):
            return float("inf")
        return time.monotonic() - t0
    finally:
        silent.close()
        for n in (listener, talker):
            if n is not None:
                n.shutdown()


def run_notify(ros: bool) -> None:
    from rosfpga_lab.graph import EmbeddedMaster

    print("\n[notify] seconds until a new publisher reaches its subscriber, one silent node in the graph "
          "(5 updates queued for it; capped at 40 s: inf = never)")
    master = EmbeddedMaster(port=0).start()
    try:
        print(f"  lab master          {notify_time(master.uri):7.3f} s")
    finally:
        master.stop()
    if ros and (rm := real_master()):
        try:
            print(f"  real rosmaster      {notify_time(f'http://127.0.0.1:{rm.port}/'):7.3f} s")
        finally:
            rm.stop()


def run_slope() -> None:
    print("\n[slope] RSS over 1,000,000 frames through a subscriber handshake machine + topic hz meter")
    out = subprocess.run([sys.executable, str(HERE), "--child", "slope"], capture_output=True,
                         text=True, timeout=600)
    print(out.stdout.rstrip() or out.stderr[-2000:])


def slope_child() -> None:
    from rosfpga_lab.graph.tools import RateMeter
    from rosfpga_lab.tcpros import SubscriberHandshake, encode_frame, encode_header

    hs = SubscriberHandshake(callerid="/hz", topic="/t", md5sum="*", type_name="*")
    hs.initiate()
    hs.receive_data(encode_header({"callerid": "/p", "md5sum": "*", "type": "std_msgs/String",
                                   "topic": "/t", "latching": "0"}))
    meter = RateMeter()
    chunk = encode_frame(b"\x05\x00\x00\x00hello") * 1000
    samples = []
    t0 = time.monotonic()
    for i in range(1, 1001):
        for _ in hs.receive_data(chunk):
            meter.tick()
        if i % 100 == 0:
            samples.append(rss(os.getpid()))
    n = len(samples)
    xs = range(n)
    mx, my = (n - 1) / 2, sum(samples) / n
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, samples)) / sum((x - mx) ** 2 for x in xs)
    print(f"  lab                 {slope / 1024:8.1f} KiB per 100,000 frames "
          f"(RSS {mib(samples[0])} -> {mib(samples[-1])}, {time.monotonic() - t0:.0f} s, "
          f"history {len(hs.history)} entries)")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], epilog=__doc__.split("\n\n", 1)[1],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", default=",".join(ATTACKS),
                   help=f"comma-separated attacks to run (default: all of {','.join(ATTACKS)})")
    p.add_argument("--no-ros", action="store_true", help="skip the real rosmaster rows")
    p.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        if args.child[0] == "slope":
            slope_child()
        else:
            child_main(args.child[0], args.child[1:])
        return 0
    import rosfpga_lab

    wanted = [a.strip() for a in args.only.split(",") if a.strip()]
    bad = [a for a in wanted if a not in ATTACKS]
    if bad:
        p.error(f"unknown attack(s) {bad}; choose from {','.join(ATTACKS)}")
    ros = not args.no_ros
    print(f"code under test: {Path(rosfpga_lab.__file__).parent}; real rosmaster: "
          f"{'yes' if ros and shutil.which('rosmaster') else 'no'}")
    runs = {"body": lambda: run_body(ros), "frame": run_frame, "slow": lambda: run_slow(ros),
            "notify": lambda: run_notify(ros), "slope": run_slope}
    for name in wanted:
        runs[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main())
