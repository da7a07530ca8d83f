"""The seam ``rfl_rtps_to_cdr`` (rtl/fabric) alone under cocotb
(tests/rtl/bench_rfl_rtps_to_cdr_seam.py): sample packets in, records (a length, LE32, then the
sample) out, against a model written here from the seam's contract, not from its RTL: a packet
that ends with TUSER is dropped, one longer than MAX_BYTES is refused, every other one becomes a
record, in order.

Its ring of 2 x 2**clog2(MAX_BYTES) bytes: samples back to back with the output always ready go
through with the input waiting at most 4 clocks a kept sample (the seam writes its length), any
mix of lengths -- the one-buffer seam waited the whole record, its length + 5 clocks; with the
output stopped, one good sample, an overlong one and a dropped one, and a second good one go in
without waiting but for those 4 clocks (the discarded ones' bytes never stall), and the next
waits; random samples, gaps and backpressure come out exact.
"""

from __future__ import annotations

import json
import random
import struct
from pathlib import Path

import pytest

from tests.support.rtltools import TB_DIR, require_cocotb, run_bench

pytestmark = pytest.mark.rtl

SEAM = Path(__file__).resolve().parents[2] / "rosfpga_lab" / "rtl" / "fabric" / "rfl_rtps_to_cdr.v"
#: the input's wait per kept sample the seam's header states (it writes the record's 4 length
#: bytes)
WAIT_PER_SAMPLE = 4


def model(packets: list[tuple[bytes, bool]],
          max_bytes: int) -> tuple[bytes, dict[str, int], list[bool]]:
    """The records the seam must send, its counters and which packets it keeps, from its
    contract."""
    out = bytearray()
    counts = {"samples": 0, "dropped": 0, "too_long": 0}
    kept = []
    for data, user in packets:
        if user:
            counts["dropped"] += 1
        elif len(data) > max_bytes:
            counts["too_long"] += 1
        else:
            out += struct.pack("<I", len(data)) + data
            counts["samples"] += 1
        kept.append(not user and len(data) <= max_bytes)
    return bytes(out), counts, kept


def run_seam(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, max_bytes: int,
             packets: list[tuple[bytes, bool]], *, seed: int = 1, gap: int = 0, bp: int = 0,
             max_wait: int | None = None, hold: int = 0, hold_clocks: int = 0) -> None:
    """Build the seam with ``max_bytes`` and run the bench on ``packets``."""
    sim = require_cocotb()
    monkeypatch.syspath_prepend(str(TB_DIR))
    from cocotb_tools.runner import get_runner

    output, counts, kept = model(packets, max_bytes)
    case = {"seed": seed, "gap": gap, "bp": bp, "max_wait": max_wait, "hold": hold,
            "hold_clocks": hold_clocks, "grace": WAIT_PER_SAMPLE, "output": output.hex(),
            "counts": counts, "packets": [{"data": d.hex(), "user": int(u), "kept": k}
                                          for (d, u), k in zip(packets, kept)]}
    (tmp_path / "case.json").write_text(json.dumps(case))
    runner = get_runner(sim)
    runner.build(sources=[SEAM], hdl_toplevel="rfl_rtps_to_cdr", build_dir=tmp_path / "build",
                 parameters={"MAX_BYTES": max_bytes, "COUNT_BITS": 16},
                 timescale=("1ns", "1ps"), log_file=tmp_path / "build.log")
    run_bench(runner, "bench_rfl_rtps_to_cdr_seam", "rfl_rtps_to_cdr", tmp_path / "build",
              tmp_path, {"SEAM_CASE": str(tmp_path / "case.json")})


def _bytes(rng: random.Random, n: int) -> bytes:
    return bytes(rng.getrandbits(8) for _ in range(n))


# 9: the smallest MAX_BYTES whose ring (32 bytes) holds a record going out and the next sample
@pytest.mark.parametrize("max_bytes", [9, 64, 100])
def test_samples_back_to_back_wait_only_for_the_length_bytes(
        max_bytes: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    rng = random.Random(max_bytes)
    sizes = [1, 2, 3, 4, max_bytes, max_bytes, 5, 1, 1, 2] + \
        [rng.randint(1, max_bytes) for _ in range(30)]
    packets = [(_bytes(rng, n), False) for n in sizes]
    bound = WAIT_PER_SAMPLE * len(sizes)
    # the one-buffer seam: each sample after the first waits its record, len + 5 clocks
    assert bound < sum(n + 5 for n in sizes[:-1]) // 2
    run_seam(tmp_path, monkeypatch, max_bytes, packets, max_wait=bound)


def test_discarded_samples_never_wait_while_a_record_is_held(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Output stopped, MAX_BYTES 60 (a ring of 128 bytes, two records of 60): a good sample of
    60 bytes goes in; an overlong one (3 x MAX_BYTES), a dropped one and a second good one of
    60 go in too, without waiting but for the 4 clocks after each good one; the next waits 200
    clocks while the ring is full, then all come out."""
    rng = random.Random(7)
    packets = [(_bytes(rng, 60), False), (_bytes(rng, 180), False), (_bytes(rng, 50), True),
               (_bytes(rng, 60), False), (_bytes(rng, 9), False), (_bytes(rng, 61), False),
               (_bytes(rng, 3), False)]
    run_seam(tmp_path, monkeypatch, 60, packets, hold=4, hold_clocks=200)


@pytest.mark.parametrize("seed,gap,bp", [(3, 300, 400), (4, 0, 700), (5, 600, 0)])
def test_random_samples_gaps_and_backpressure_come_out_exact(
        seed: int, gap: int, bp: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    rng = random.Random(seed)
    max_bytes = 100
    packets = []
    for _ in range(60):
        kind = rng.random()
        n = rng.randint(1, max_bytes) if kind < 0.7 else rng.choice(
            [1, max_bytes, max_bytes + 1, rng.randint(max_bytes + 1, 3 * max_bytes)])
        packets.append((_bytes(rng, n), rng.random() < 0.15))
    _, counts, _ = model(packets, max_bytes)
    assert min(counts.values()) >= 3
    run_seam(tmp_path, monkeypatch, max_bytes, packets, seed=seed, gap=gap, bp=bp)
