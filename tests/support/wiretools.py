"""Helpers for tests that check capture files with Wireshark's tshark (Debian's ``tshark``).

Without tshark those tests skip with a reason; with ``ROSFPGA_REQUIRE_WIRE=1`` (set by
``.ci/run`` under CI) they fail instead, so CI can never skip them.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from tests.support.realros import skip_or_fail

REQUIRE = "ROSFPGA_REQUIRE_WIRE"


def require_tshark() -> str:
    """The tshark executable, or skip (fail under CI)."""
    exe = shutil.which("tshark")
    if exe is None:
        skip_or_fail("no tshark on this machine (apt-get install tshark)", REQUIRE)
    return exe


def tshark_fields(capture: Path, fields: list[str], *, display_filter: str = "",
                  options: list[str] = ()) -> list[list[str]]:
    """Rows of ``-T fields`` output of tshark on ``capture`` (one list per packet)."""
    cmd = [require_tshark(), "-r", str(capture), *options, "-T", "fields", "-E", "occurrence=a",
           "-E", "aggregator=|"]
    if display_filter:
        cmd += ["-Y", display_filter]
    for f in fields:
        cmd += ["-e", f]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    return [line.split("\t") for line in run.stdout.splitlines()]


def require_capture() -> str:
    """dumpcap, when this process may capture on loopback (root), or skip (fail under CI)."""
    require_tshark()
    exe = shutil.which("dumpcap") or "/usr/bin/dumpcap"
    if not Path(exe).exists():
        skip_or_fail("no dumpcap on this machine (apt-get install tshark)", REQUIRE)
    if os.geteuid() != 0:
        skip_or_fail("capturing on loopback needs root", REQUIRE)
    return exe


def require_cyclonedds() -> None:
    """Skip (fail under CI) unless PyPI's cyclonedds imports."""
    try:
        import cyclonedds.domain  # noqa: F401
    except ImportError as exc:
        skip_or_fail(f"cyclonedds does not import ({exc}); pip install cyclonedds", REQUIRE)


def sequence_numbers(sub: object) -> list[int]:
    """The sequence numbers tshark shows as rtps.sm.seqNumber for one submessage, in its order."""
    from rosfpga_lab.rtps import AckNack, Data, DataFrag, Gap, Heartbeat, HeartbeatFrag

    if isinstance(sub, Heartbeat):
        return [sub.first, sub.last]
    if isinstance(sub, AckNack):
        return [sub.base]
    if isinstance(sub, Gap):
        return [sub.start, sub.list_base]
    if isinstance(sub, (Data, DataFrag, HeartbeatFrag)):
        return [sub.seq]
    return []


def assert_rtps_agrees_with_tshark(capture: Path) -> int:
    """Decode every RTPS datagram of ``capture`` with the lab and with tshark; they must agree
    on submessage kinds, writer ids, sequence numbers and fragment numbers. Returns the count."""
    from rosfpga_lab.graph.capture_read import udp_datagrams
    from rosfpga_lab.rtps import DataFrag, parse_message

    messages = [parse_message(d[3]) for d in udp_datagrams(capture) if d[3][:4] == b"RTPS"]
    rows = tshark_fields(capture, ["rtps.sm.id", "rtps.sm.wrEntityId", "rtps.sm.seqNumber",
                                   "rtps.data_frag.number"], display_filter="rtps")
    assert len(rows) == len(messages) > 0
    for row, msg in zip(rows, messages):
        ids, writers, seqs, frags = (r.split("|") if r else [] for r in row)
        subs = msg.submessages
        assert [f"0x{s.kind:02x}" for s in subs] == ids
        assert [f"0x{s.writer_id:08x}" for s in subs if hasattr(s, "writer_id")] == writers
        assert [str(n) for s in subs for n in sequence_numbers(s)] == seqs
        assert [str(s.frag_start) for s in subs if isinstance(s, DataFrag)] == frags
    return len(messages)
