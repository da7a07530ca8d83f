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
