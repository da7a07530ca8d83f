"""The node in the fabric on the network as the lab's fast Verilator model (issue #31 item 3):
``rosfpga_lab.rtl.fabricsim`` (``rfl_fabric_top``'s GMII variant and the C++ main
``harness/rfl_fabric_sim.cpp``, whole Ethernet frames through a pipe) given the frames
tests/rtl/test_fabric_top.py's cocotb peer sends, answering the circuit's ARP request as that peer
does: the same frames out, checked by that test's own expectations (the lab's software only), the
same counters. The build is cached (some 15-30 s the first time); the run a fraction of a second.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.fabricsim import FabricConfig, FabricSim, build_fabric_sim
from tests.rtl.test_fabric_rtps_cdr import CONFIG
from tests.rtl.test_fabric_top import MAX_CLOCKS, PERIOD, check_sent, scenario
from tests.support.rtltools import require_fabric_sim

pytestmark = pytest.mark.rtl

PREAMBLE = "55" * 7 + "d5"
ETHERTYPE_ARP = bytes.fromhex("0806")


@pytest.mark.timeout(300)
def test_the_fast_model_sends_what_the_cocotb_bench_expects(tmp_path: Path) -> None:
    require_fabric_sim()
    sc = scenario(tmp_path)
    build = build_fabric_sim(load_config(CONFIG), sc.rom, period=PERIOD)
    assert {**build.params, "MAX_BYTES": sc.params["MAX_BYTES"]} == sc.params
    case: dict[str, Any] = sc.case
    config = FabricConfig(int(case["node_mac"], 16), _dotted(case["node_ip"]),
                          _dotted(case["peer_ip"]), case["peer_meta_port"],
                          case["peer_user_port"], case["reader"], case["writer"], case["time"])
    sim = FabricSim(build, config, rate=0, max_clocks=MAX_CLOCKS)
    peer_ip = bytes.fromhex(case["peer_ip"])
    sent: list[bytes] = []
    try:
        for raw in case["frames"]:
            sim.send_frame(bytes.fromhex(raw))
        deadline = time.monotonic() + 60
        while sim.running() and time.monotonic() < deadline:
            for frame in sim.read(0.05).frames:
                sent.append(frame)
                if frame[12:14] == ETHERTYPE_ARP and frame[20:22] == b"\x00\x01" \
                        and frame[38:42] == peer_ip:
                    sim.send_frame(bytes.fromhex(case["arp_reply"]))
    finally:
        report = sim.close()
    sent += report.frames
    assert report.clocks >= MAX_CLOCKS, report.clocks   # it ran to its bound
    counters = {k: v for k, v in report.counters.items()
                if k not in ("credit", "judged", "refused", "last_refusal")}
    assert (report.counters["judged"], report.counters["refused"]) == (1, 0)
    check_sent(sc, [PREAMBLE + f.hex() for f in sent], counters)


def _dotted(hexed: str) -> str:
    return ".".join(str(b) for b in bytes.fromhex(hexed))
