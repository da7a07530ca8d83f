"""``rosfpga-lab fabric sim``'s refusals, before anything is built: a ROS 1 configuration, a
bad duration or domain, a missing file; each one line and a non-zero exit (no tools needed)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[2] / "data"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rosfpga_lab", "fabric", "sim", *args],
                          capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("args,code,says", [
    ((str(DATA / "fpga_laserscan_min.yaml"),), 1, "wire is 'tcpros'"),
    ((str(DATA / "fpga_laserscan_min_cdr.yaml"), "--seconds", "0"), 2, "--seconds must be"),
    ((str(DATA / "fpga_laserscan_min_cdr.yaml"), "--domain", "233"), 1, "domain 233 out of range"),
    (("nothere.yaml",), 1, "cannot read the configuration"),
    ((str(DATA / "fpga_laserscan_min_cdr.yaml"), "--tap", "--shim"), 2, "not allowed with"),
], ids=["ros1-config", "seconds", "domain", "missing", "tap-and-shim"])
def test_fabric_sim_refuses_clearly(args: tuple[str, ...], code: int, says: str) -> None:
    proc = _run(*args)
    assert proc.returncode == code, proc.stderr
    assert says in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


def _counters_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rosfpga_lab", "fabric", "counters", *args],
                          capture_output=True, text=True, timeout=60)


def test_fabric_counters_prints_the_answer_by_name_and_says_when_none_comes() -> None:
    """Against a stand-in readout on 127.0.0.1 (a UDP socket answering as the circuit does:
    ``rtl.fabriccounters``' format): every counter by name, or as JSON; a stand-in that keeps
    quiet: the error names the address and the wait, exit 1; a wrong answer: said so."""
    import json
    import socket
    import struct
    import threading

    from rosfpga_lab.rtl.fabriccounters import FABRIC_COUNTERS, MAGIC, request

    values = list(range(101, 101 + len(FABRIC_COUNTERS)))
    answer = struct.pack(f">II{len(values)}I", MAGIC, len(values), *values)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as readout:
        readout.bind(("127.0.0.1", 0))
        port = readout.getsockname()[1]
        replies = [answer, answer, b"RFC\x09" + answer[4:], None]

        def serve() -> None:
            for reply in replies:
                data, peer = readout.recvfrom(2048)
                assert data == request()
                if reply is not None:
                    readout.sendto(reply, peer)

        server = threading.Thread(target=serve, daemon=True)
        server.start()
        text = _counters_cli("--host", "127.0.0.1", "--port", str(port))
        as_json = _counters_cli("--host", "127.0.0.1", "--port", str(port), "--json")
        wrong = _counters_cli("--host", "127.0.0.1", "--port", str(port))
        quiet = _counters_cli("--host", "127.0.0.1", "--port", str(port), "--timeout", "0.5")
        server.join(5)
    assert text.returncode == 0, text.stderr
    lines = [line.split() for line in text.stdout.splitlines()]
    assert lines == [[c.key, str(v)] for c, v in zip(FABRIC_COUNTERS, values)]
    assert json.loads(as_json.stdout) == {c.key: v for c, v in zip(FABRIC_COUNTERS, values)}
    assert wrong.returncode == 1 and "starting 0x52464309" in wrong.stderr, wrong.stderr
    assert quiet.returncode == 1, quiet.stderr
    assert (f"no answer from 127.0.0.1:{port} within 0.5 s: is the board up / fabric sim "
            "running?") in quiet.stderr
