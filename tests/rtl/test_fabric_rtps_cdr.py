"""The fabric's receive path (issue #31): RTPS datagrams in, the generated application's
published CDR records out, in Verilog -- ``rfl_rtps_rx`` -> ``rfl_rtps_to_cdr`` -> the generated
top of ``data/fpga_laserscan_min_cdr.yaml`` (``rosfpga-lab generate``), under cocotb with random
input gaps and output backpressure (tests/rtl/rtps_cdr_top.v, tests/rtl/bench_rfl_rtps_to_cdr.py).

The datagrams are the lab's RTPS builders' (``rtps.build``: DATA, DATA_FRAG, INFO_TS, a DATA for
another reader) around sensor_msgs/LaserScan samples the lab's CDR writer serialized
(``msg.cdr``): whole samples, fragmented ones (one with end padding its encapsulation options
declare, which the subscriber skips), one with a fragment missing (dropped by the
walker, so the seam must discard it) followed by a good one, one the subscriber refuses
(range_max over its bound), one longer than the seam's buffer (refused and counted) and a good
one after each. Expected: the lab's decoder picks the samples the walker sends whole
(tests/rtl/test_fabric_rtps_rx.py's ``reference``), each becomes a record (its length, then the
payload), and the lab's CDR models (``hls.generic.model_output_cdr``) say what the circuit
publishes and which records it refuses; the good samples' output is held against numpy too
(the scan re-serialized with its ranges eroded by a sliding minimum).
"""

from __future__ import annotations

import json
import re
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.generictools import window_oracle
from rosfpga_lab.config import load_config
from rosfpga_lab.hls.vectors import model_output_cdr
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config
from rosfpga_lab.msg.cdr import serialize_cdr
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtl.proofs import PROOFS, RTPS_RX, prove
from tests.support.rtltools import TB_DIR, require_cocotb, require_formal, run_bench
from tests.hls.test_generic_project_cdr import statuses_of
from tests.rtl.test_fabric_rtps_rx import LOCAL, OTHER_READER, READER, REMOTES, WRITER, reference

pytestmark = pytest.mark.rtl

ROOT = Path(__file__).resolve().parents[2]
FABRIC = ROOT / "rosfpga_lab" / "rtl" / "fabric"
CONFIG = ROOT / "data" / "fpga_laserscan_min_cdr.yaml"
MAX_BYTES = 2048                        # the seam's buffer in tests/rtl/rtps_cdr_top.v


def scan(ranges: np.ndarray, intensities: int, frame_id: str, range_max: float = 30.0) -> bytes:
    """A sensor_msgs/LaserScan serialized by the lab's CDR writer (encapsulation included)."""
    return serialize_cdr(None, "sensor_msgs/LaserScan", {
        "header": {"stamp": {"sec": 12, "nanosec": 34}, "frame_id": frame_id},
        "angle_min": -1.5, "angle_max": 1.5, "angle_increment": 0.01, "time_increment": 0.0,
        "scan_time": 0.1, "range_min": 0.05, "range_max": range_max,
        "ranges": [float(r) for r in ranges],
        "intensities": [float(k) for k in range(intensities)]})


def frags(seq: int, sample: bytes, fsize: int, numbers: list[int], per: int = 2) -> list[bytes]:
    """DATA_FRAG submessages of ``sample`` (fragments ``numbers``, ``per`` to a submessage)."""
    out = []
    for k in range(0, len(numbers), per):
        group = numbers[k:k + per]
        if group != list(range(group[0], group[0] + len(group))):
            out += [b.data_frag(READER, WRITER, seq, n, fsize, len(sample),
                                sample[(n - 1) * fsize:n * fsize], 1) for n in group]
            continue
        part = sample[(group[0] - 1) * fsize:(group[-1]) * fsize]
        out.append(b.data_frag(READER, WRITER, seq, group[0], fsize, len(sample), part,
                               len(group)))
    return out


def case_of(seed: int) -> tuple[list[bytes], bytes, list[bytes]]:
    """The datagrams, the numpy oracle of the good samples' output, and the payloads the
    walker must send whole, in order."""
    rng = np.random.default_rng(seed)
    specials = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1.0, 2.5], np.float32)
    ranges = [rng.standard_normal(360).astype(np.float32) for _ in range(4)]
    ranges.append(rng.choice(specials, 360))
    good = {1: scan(ranges[0], 0, "laser"), 2: scan(ranges[1], 3, "l" * 13),
            4: scan(ranges[4], 7, "f" * 20), 7: scan(ranges[2], 1, ""),
            9: scan(ranges[3], 2, "x")}
    lost = scan(ranges[2], 0, "lost")                       # fragment 2 never comes
    refused = scan(ranges[3], 1, "laser", range_max=1000.5)
    too_long = scan(ranges[0], 360, "laser")                # 2.9 kB > MAX_BYTES
    assert len(too_long) > MAX_BYTES >= max(len(s) for s in good.values())
    hdr = b.header(REMOTES[0])
    s1, s2, s4 = b.pad_payload(good[1]), good[2], good[4]
    s9 = _padded(good[9], 3)            # end padding the options declare (sampleSize includes it)
    f2 = frags(2, s2, 512, [1, 2, 3, 4])
    datagrams = [
        hdr + b.info_ts(1.5e9) + b.data(READER, WRITER, 1, s1),
        hdr + b.info_ts(1.5e9 + 1) + f2[0],
        hdr + f2[1],
        hdr + b"".join(frags(3, lost, 600, [1, 3], per=1)),     # 2 missing: dropped
        hdr + b"".join(frags(4, s4, 1000, [1, 2])),
        hdr + b.data(READER, WRITER, 5, refused),
        hdr + b.data(READER, WRITER, 6, too_long),
        hdr + b.data(OTHER_READER, WRITER, 7, lost) + b.data(0, WRITER, 7, good[7]),
        hdr + b"".join(frags(9, s9, 700, [1, 2, 3], per=3)),
    ]
    oracle = b"".join(_record(_eroded(good[k], r)) for k, r in
                      zip(sorted(good), [ranges[0], ranges[1], ranges[4], ranges[2], ranges[3]]))
    return datagrams, oracle, [s1, s2, s4, refused, too_long, good[7], s9]


def _eroded(sample: bytes, ranges: np.ndarray) -> bytes:
    """The sample with its ranges replaced by numpy's sliding minimum over 5 beams."""
    raw = ranges.astype("<f4").tobytes()
    at = sample.find(struct.pack("<I", 360) + raw)
    assert at > 0 and sample.find(raw, at + 5) < 0
    eroded = window_oracle(raw, "<f4", 5, "erode")
    return sample[:at + 4] + eroded + sample[at + 4 + len(raw):]


def _padded(payload: bytes, pad: int) -> bytes:
    """The payload with ``pad`` zeros at its end, declared in the encapsulation options' low
    bits (``rtps.build.unpad_payload`` takes them off)."""
    out = payload[:3] + bytes([payload[3] | pad]) + payload[4:] + bytes(pad)
    assert b.unpad_payload(out) == payload
    return out


def _record(payload: bytes) -> bytes:
    return struct.pack("<I", len(payload)) + payload


def test_the_case_covers_fragments_a_drop_a_refusal_and_an_overlong_sample() -> None:
    datagrams, oracle, sent = case_of(5)
    walked, counts = reference(datagrams)
    records = [_record(bytes.fromhex(s["data"])) for s in walked]
    assert counts["samples"] == 7 and counts["malformed"] == counts["bad_header"] == 0
    assert sum(len(r) - 4 > MAX_BYTES for r in records) == 1
    cdr = cdr_layout_from_config(load_config(CONFIG))
    app = load_config(CONFIG).application
    kept = [r for r in records if len(r) - 4 <= MAX_BYTES]
    out, why = model_output_cdr(cdr, app.op, app.ksize, kept)
    assert out == oracle and [w != "" for w in why] == [False] * 3 + [True, False, False]
    assert [bytes.fromhex(s["data"]) for s in walked] == sent


@pytest.mark.parametrize("seed,gap,bp", [(5, 300, 400)])
def test_rtps_datagrams_through_the_seam_publish_the_models_records(
        seed: int, gap: int, bp: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    sim = require_cocotb()
    monkeypatch.syspath_prepend(str(TB_DIR))        # the cocotb module, for the simulator
    from cocotb_tools.runner import get_runner

    gen = tmp_path / "project"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(CONFIG), "-o",
                           str(gen), "-q"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    datagrams, oracle, _ = case_of(seed)
    walked, counts = reference(datagrams)
    records = [_record(bytes.fromhex(s["data"])) for s in walked]
    kept = [r for r in records if len(r) - 4 <= MAX_BYTES]
    cdr = cdr_layout_from_config(load_config(CONFIG))
    app = load_config(CONFIG).application
    expected, _why = model_output_cdr(cdr, app.op, app.ksize, kept)
    assert expected == oracle
    codes = dict(re.findall(r"localparam \[7:0\] (SUB_\w+) = 8'd(\d+)",
                            (gen / "rtl" / "rfl_layout.vh").read_text()), SUB_OK="0")
    statuses = [int(codes[name]) for name in statuses_of(cdr, kept)]
    case = {"seed": seed, "gap": gap, "bp": bp, "local": LOCAL.hex(), "reader": READER,
            "writer": WRITER, "datagrams": [d.hex() for d in datagrams], "output": expected.hex(),
            "statuses": statuses,
            "counts": {"rx_samples": counts["samples"], "samples": len(kept),
                       "dropped": 1, "too_long": len(records) - len(kept)}}
    (tmp_path / "case.json").write_text(json.dumps(case))
    rtl = sorted(p for p in (gen / "rtl").glob("*.v") if p.name != "rfl_tb.v")
    sources = [*(FABRIC / m for m in RTPS_RX), FABRIC / "rfl_rtps_to_cdr.v", *rtl,
               TB_DIR / "rtps_cdr_top.v"]
    runner = get_runner(sim)
    runner.build(sources=sources, includes=[gen / "rtl", FABRIC], hdl_toplevel="rtps_cdr_top",
                 build_dir=tmp_path / "build", timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    run_bench(runner, "bench_rfl_rtps_to_cdr", "rtps_cdr_top", tmp_path / "build", tmp_path,
              {"RTPS_CDR_CASE": str(tmp_path / "case.json"),
               "RTPS_CDR_OUT": str(tmp_path / "out.json")})


#: planted bugs the bounded proof must catch: (what is replaced, by what)
SEAM_BUGS = {
    # forwards a packet that ended with TUSER
    "forwards_dropped": ("wire keep = fin && !s_axis_tuser && !full;",
                         "wire keep = fin && !full;"),
    # the one-buffer seam's way: the input waits while a record goes out
    "waits_while_sending": ("assign s_axis_tready = !hdr && (room || full);",
                            "assign s_axis_tready = !hdr && (room || full) && !m_tvalid;"),
    # stalls on the bytes past MAX_BYTES of an overlong packet when the ring is full
    "stalls_on_overlong": ("assign s_axis_tready = !hdr && (room || full);",
                           "assign s_axis_tready = !hdr && room;"),
}


@pytest.mark.parametrize("bug", sorted(SEAM_BUGS))
def test_a_seam_with_a_planted_bug_fails_its_proof(bug: str, tmp_path: Path) -> None:
    """The bounded proof (tests/rtl/test_formal.py runs it) sees a record go out for a packet
    that ended with TUSER, or the input wait while a record goes out with room in the ring, or
    wait on a byte it would throw away."""
    require_formal()
    good = (FABRIC / "rfl_rtps_to_cdr.v").read_text()
    check, planted = SEAM_BUGS[bug]
    assert good.count(check) == 1
    buggy = tmp_path / "rfl_rtps_to_cdr.v"
    buggy.write_text(good.replace(check, planted))
    bmc = next(p for p in PROOFS if p.name == "rtps_to_cdr" and p.mode == "bmc")
    assert prove(bmc, replace={"rfl_rtps_to_cdr.v": buggy}).status == "FAIL"
