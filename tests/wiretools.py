"""Helpers for tests that check capture files with Wireshark's tshark (Debian's ``tshark``).

Without tshark those tests skip with a reason; with ``ROSFPGA_REQUIRE_WIRE=1`` (set by
``.ci/run`` under CI) they fail instead, so CI can never skip them.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from realros import skip_or_fail

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
