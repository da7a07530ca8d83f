"""``rtl.fabricdemo``: notebook 12's run of the ROS 2 node in the fabric, and the dump shipped in
data/ (what it shows is right, and it is what the RTL makes now).

Expected bytes come from the lab's software (the RTPS builders, the CDR models, numpy's sliding
minimum, scapy's reading of the frames), never from the dump's own reading.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from scapy.layers.inet import IP, UDP
from scapy.layers.l2 import ARP, Ether

from tests.support.realros import require_rtl

from rosfpga_lab.hls.vectors import model_output_cdr
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.rtl.discrom import fabric_participant
from rosfpga_lab.rtl.fabricdemo import (
    DUMP_SIMULATOR, NODE_IP, NODE_MAC, PEER_IP, PEER_MAC, PREAMBLE, TIME, demo_config,
    demo_datagrams, demo_frames, demo_ranges, demo_sample, gmii_frames, run_fabric_demo,
    shipped_dump, stream_bytes,
)
from rosfpga_lab.rtl.vcd import read_vcd
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.entities import user_port
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES


def _expected_datagrams() -> tuple[bytes, list[bytes]]:
    """The new sample (the CDR models') and the two datagrams the lab's software writer sends it
    in: longer than one fragment, DATA_FRAGs of 1344 bytes (rtps.limits), the HEARTBEAT after
    the last."""
    config = demo_config()
    sample = b.pad_payload(demo_sample())
    records, why = model_output_cdr(cdr_layout_from_config(config), config.application.op,
                                    config.application.ksize,
                                    [struct.pack("<I", len(sample)) + sample])
    (n,) = struct.unpack("<I", records[:4])
    assert len(records) == 4 + n, why
    out = records[4:]
    part, _node, wid, _rid = fabric_participant(config)
    head = b.header(part.guid_prefix) + b.info_ts((TIME >> 32) + (TIME & 0xFFFFFFFF) / 2**32)
    padded = b.pad_payload(out)
    assert FRAGMENT_BYTES < len(padded) <= 2 * FRAGMENT_BYTES
    frags = [b.data_frag(0, wid, 1, n, FRAGMENT_BYTES, len(padded),
                         padded[(n - 1) * FRAGMENT_BYTES:n * FRAGMENT_BYTES], 1) for n in (1, 2)]
    return out, [head + frags[0], head + frags[1] + b.heartbeat(0, wid, 2, 1, 1)]


def test_the_demo_frames_are_ethernet_ipv4_udp_as_scapy_reads_them() -> None:
    for frame, datagram in zip(demo_frames(), demo_datagrams()):
        assert frame.startswith(PREAMBLE)
        eth = Ether(frame[len(PREAMBLE):-4])
        assert (eth.dst, eth.src, eth[IP].src, eth[IP].dst) == (NODE_MAC, PEER_MAC, PEER_IP,
                                                                 NODE_IP)
        fresh = eth[IP].copy()
        del fresh.chksum                                            # scapy computes it anew
        assert IP(bytes(fresh)).chksum == eth[IP].chksum
        assert eth[UDP].dport == user_port(0, 0)
        assert bytes(eth[UDP].payload)[:eth[UDP].len - 8] == datagram


def test_the_shipped_dump_carries_the_sample_through_every_stage() -> None:
    path = shipped_dump()
    assert path is not None and path.name == "fabric_demo.vcd"
    assert path.stat().st_size < 250_000
    wave = read_vcd(path, clock="clk")
    sample = b.pad_payload(demo_sample())
    rx = gmii_frames(wave, "rx")
    assert [f for _c, f in rx[:2]] == demo_frames()                 # the peer's two frames
    assert Ether(rx[2][1][8:-4])[ARP].op == 2                       # then its ARP reply
    assert stream_bytes(wave, "p_rx")[1] == b"".join(demo_datagrams())
    assert stream_bytes(wave, "rx")[1] == sample                    # RTPS taken off
    rec = stream_bytes(wave, "rec")[1]
    assert rec == struct.pack("<I", len(sample)) + sample
    out, dgs = _expected_datagrams()
    pub = stream_bytes(wave, "pub")[1]
    assert pub == struct.pack("<I", len(out)) + out
    # the ranges out are numpy's sliding minimum over 5 beams of the ranges in
    raw = demo_ranges().astype("<f4").tobytes()
    n = len(raw) // 4
    at = sample.find(struct.pack("<I", n) + raw) + 4
    r = np.frombuffer(raw, "<f4")
    want = np.array([r[max(0, k - 2):k + 3].min() for k in range(n)], "<f4").tobytes()
    assert out[at:at + 4 * n] == want and out[:at] == sample[:at]
    both = b"".join(dgs)
    assert stream_bytes(wave, "tx")[1] == both == stream_bytes(wave, "le_tx")[1][-len(both):]
    sent = [Ether(f[8:-4]) for _c, f in gmii_frames(wave, "tx")]
    data = [f for f in sent if f.haslayer(UDP) and f[IP].dst == PEER_IP]
    assert [f.dst for f in data] == [PEER_MAC] * 2
    assert [bytes(f[UDP].payload)[:f[UDP].len - 8] for f in data] == dgs
    assert any(f.haslayer(ARP) and f[ARP].op == 1 for f in sent)   # it asked for the peer
    decided = wave.values("status_valid").astype(bool)
    assert wave.values("status")[decided].tolist() == [0]          # SUB_OK, once


@pytest.mark.rtl
@pytest.mark.timeout(900)
def test_the_shipped_dump_is_what_the_rtl_makes_today(tmp_path: Path) -> None:
    """Verilator's build of the top (LiteEth included) some 40 s here, the run a second."""
    require_rtl(DUMP_SIMULATOR)
    fresh = run_fabric_demo(tmp_path / "fabric_demo.vcd")
    old, new = read_vcd(shipped_dump(), clock="clk"), read_vcd(fresh, clock="clk")
    assert old.signals == new.signals, "signals changed: run python data/make_fabric_dump.py"
    assert old.cycles == new.cycles, "clock count changed: run python data/make_fabric_dump.py"
    for name in old.signals:
        assert np.array_equal(old.values(name), new.values(name)), (
            f"{name} differs from the RTL's: run python data/make_fabric_dump.py and review")


def test_the_rx_state_names_are_rfl_rtps_rx_s() -> None:
    """``fabricdemo.RX_STATES`` (the notebook names ``rx_state`` with it) is the Verilog's
    numbering."""
    import re

    from rosfpga_lab.rtl.fabricdemo import RX_STATES

    text = (Path(__file__).resolve().parents[2] / "rosfpga_lab" / "rtl" / "fabric" /
            "rfl_rtps_rx.v").read_text()
    numbered = {int(n): name for name, n in re.findall(r"(S_[A-Z0-9]+) = 4'd(\d+)", text)}
    assert [numbered[k] for k in range(len(numbered))] == list(RX_STATES)
