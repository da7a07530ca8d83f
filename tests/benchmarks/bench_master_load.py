"""Benchmark: the lab master beside Debian's rosmaster under a burst (issue 23, items 16 and 17).

* calls:  250 XML-RPC calls (``getUri``, one connection each) started at the same moment from
          250 threads, 3 rounds: slowest and median call, calls that failed;
* bodies: 64 XML-RPC requests with ~8 MiB bodies sent at once: the master's peak RSS (VmHWM)
          and how many were served or refused (the lab bounds all bodies in flight together:
          ``graph.limits.MAX_XMLRPC_BODIES_IN_FLIGHT``).

Runs the code it imports (this checkout, or another put first on ``PYTHONPATH``: run it on
main's code and on a branch for before/after); the lab master runs in a child process (see
bench_hardening.py), rosmaster as Debian's ``rosmaster --core``. Loopback only, bounded in
sockets and seconds. Run:  .venv/bin/python tests/benchmarks/bench_master_load.py
[--only calls,bodies] [--no-ros]
"""

from __future__ import annotations

import argparse
import shutil
import socket
import statistics
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_hardening as bh  # noqa: E402  (helpers: child master, rosmaster, rss)

CALLS = 250
ROUNDS = 3
BODIES = 64
BODY_BYTES = (8 << 20) - 4096


def peak_rss(pid: int) -> int:
    """Peak resident set size (VmHWM) of ``pid`` in bytes."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return 0


def burst(port: int, body: bytes, n: int, timeout: float) -> tuple[list[float], list[str]]:
    """``n`` threads post ``body`` at once; returns (seconds of each served call, failures)."""
    go = threading.Barrier(n)
    times: list[float] = []
    failures: list[str] = []
    lock = threading.Lock()

    def one() -> None:
        go.wait()
        t0 = time.monotonic()
        try:
            reply = bh.post(port, body, timeout=timeout)
            ok = reply.startswith(b"HTTP/1.0 200") or reply.startswith(b"HTTP/1.1 200")
            what = reply.split(b"\r\n", 1)[0].decode(errors="replace")
        except OSError as exc:
            ok, what = False, f"{type(exc).__name__}: {exc}"
        with lock:
            (times.append(time.monotonic() - t0) if ok else failures.append(what))

    threads = [threading.Thread(target=one) for _ in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout + 30)
    return times, failures


def calls_row(label: str, port: int) -> None:
    body = bh.xml_call("getUri", "/bench_burst")
    for r in range(ROUNDS):
        times, failures = burst(port, body, CALLS, 20.0)
        slowest = max(times) if times else float("nan")
        median = statistics.median(times) if times else float("nan")
        print(f"  {label:<16} round {r + 1}: slowest {slowest:6.3f} s, median {median:6.3f} s, "
              f"served {len(times)}/{CALLS}" + (f", failed: {sorted(set(failures))[:3]}" if failures else ""))
        time.sleep(0.5)


def run_calls(ros: bool) -> None:
    print(f"\n[calls] {CALLS} concurrent getUri calls (one connection each), {ROUNDS} rounds")
    child = bh.Child("master")
    try:
        calls_row("lab master", int(child.info[0]))
    finally:
        child.stop()
    if ros and (rm := bh.real_master()):
        try:
            calls_row("real rosmaster", rm.port)
        finally:
            rm.stop()


def bodies_row(label: str, port: int, pid: int) -> None:
    body = bh.xml_call("getPid", "/bench_bodies", "b" * BODY_BYTES)
    before = bh.rss(pid)
    times, failures = burst(port, body, BODIES, 120.0)
    refused = sorted({f for f in failures})
    print(f"  {label:<16} peak RSS {bh.mib(peak_rss(pid))} (before {bh.mib(before)}); served "
          f"{len(times)}/{BODIES}" + (f"; refused/failed {len(failures)}: {refused[:2]}" if failures else ""))


def run_bodies(ros: bool) -> None:
    print(f"\n[bodies] {BODIES} concurrent XML-RPC requests of ~8 MiB: master peak RSS")
    child = bh.Child("master")
    try:
        bodies_row("lab master", int(child.info[0]), child.proc.pid)
    finally:
        child.stop()
    if ros and (rm := bh.real_master()):
        try:
            bodies_row("real rosmaster", rm.port, rm.proc.pid)
        finally:
            rm.stop()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--only", default="calls,bodies")
    p.add_argument("--no-ros", action="store_true", help="skip the real rosmaster rows")
    a = p.parse_args()
    ros = not a.no_ros and shutil.which("rosmaster") is not None
    import rosfpga_lab

    print(f"code under test: {Path(rosfpga_lab.__file__).parent}; real rosmaster: {'yes' if ros else 'no'}; "
          f"somaxconn {Path('/proc/sys/net/core/somaxconn').read_text().strip()}")
    for what in a.only.split(","):
        {"calls": run_calls, "bodies": run_bodies}[what](ros)


if __name__ == "__main__":
    socket.setdefaulttimeout(None)
    main()
