"""``rfl_rtps_tx`` (``rosfpga_lab/rtl/fabric``, issue #31's transmit path): publisher records (a
length, then a serialized payload) of random sizes around the fragment boundaries, with a record
of length 0 and one over MAX_SAMPLE among them, through the Verilog under cocotb with random
input gaps and output backpressure (tests/rtl/bench_rfl_rtps_tx.py).

What must come out, checked with the lab's software, never with the circuit's own arithmetic:

* every datagram parses with ``rtps.parse_message``; its header is the fabric participant's
  (``rtl.discrom.fabric_participant``: the GUID prefix the discovery ROM announces), DATA_FRAGs
  put together by the participant's ``FragmentAssembler`` and DATAs give each sample, which is
  its input payload (``rtps.build.unpad_payload``), with writer GUID and writerSN 1, 2, ..;
  the HEARTBEAT after each sample says the writer holds nothing (first = writerSN + 1);
* byte for byte, each datagram is what the software builds for that sample (``rtps.build``:
  header, INFO_TS of the time the bench noted, DATA or DATA_FRAG, HEARTBEAT); with the
  participant's own fragment size, each DATA_FRAG is the participant's own
  (``_sample_subs`` with that fragment's number) and a DATA that fits is its DATA;
* bounded: a sample of L bytes sends at most (4 + L) (1 + HEAD / FRAG_BYTES) + HEAD + 32 bytes
  (HEAD: header, INFO_TS and DATA_FRAG's fields), a dropped record nothing.
"""

from __future__ import annotations

import json
import random
import re
import struct
import subprocess
from pathlib import Path

import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.discrom import (
    fabric_participant, render_rom, tx_parameters, verilog_parameters,
)
from rosfpga_lab.rtl.limits import FABRIC_MAX_DATAGRAM
from rosfpga_lab.rtl.proofs import PROOFS, prove
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.discovery import FragmentAssembler
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES
from rosfpga_lab.rtps.message import Data, DataFrag, Heartbeat, InfoTs, parse_message
from tests.support.rtltools import (
    run_bench,
    TB_DIR, require_cocotb, require_formal, require_iverilog, require_verilator, require_yosys,
)

pytestmark = pytest.mark.rtl

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "rosfpga_lab" / "rtl" / "fabric" / "rfl_rtps_tx.v"
CONFIG = ROOT / "data" / "fpga_laserscan_min_cdr.yaml"
HB_BYTES = 32


def params(frag: int, info_ts: bool, max_sample: int) -> dict[str, int]:
    """The module's parameters: the configuration's participant (tx_parameters), a fragment
    size, INFO_TS, the longest record."""
    out = tx_parameters(render_rom(CONFIG), frag_bytes=frag, info_ts=info_ts)
    return dict(out, MAX_SAMPLE=max_sample)


def head_bytes(info_ts: bool) -> int:
    """Header, INFO_TS and DATA_FRAG's fields before its payload: the software's sizes."""
    ts = len(b.info_ts(0.0)) if info_ts else 0
    return len(b.header(bytes(12))) + ts + len(b.data_frag(0, 0, 1, 1, 4, 4, b"", 1))


def sizes_for(frag: int, rng: random.Random) -> list[int]:
    """Record lengths around the fragment boundaries: 1..3 bytes (no options byte), around
    frag (DATA or two fragments after padding), 2 frag, several fragments; fewer for a large
    frag (a few seconds of simulation)."""
    if frag > 256:
        return [1, 3, 5, frag - 1, frag, frag + 1, 2 * frag + 2]
    return [1, 2, 3, 4, 5, 7, frag - 5, frag - 4, frag - 1, frag, frag + 1, frag + 3, frag + 4,
            2 * frag - 1, 2 * frag, 2 * frag + 2, 3 * frag + 7, rng.randint(5, 4 * frag)]


def records(seed: int, frag: int, max_sample: int) -> list[bytes]:
    """Payloads of :func:`sizes_for`, each a CDR encapsulation header and random bytes, in a
    random order, then a length 0 and one over max_sample among them."""
    rng = random.Random(seed)
    sizes = sizes_for(frag, rng)
    assert max(sizes) <= max_sample
    rng.shuffle(sizes)
    out = []
    for n in sizes:
        pay = (b.CDR_LE + rng.randbytes(n - 4)) if n >= 4 else rng.randbytes(n)
        out.append(pay)
    out.insert(rng.randrange(1, len(out)), b"")
    out.insert(rng.randrange(1, len(out)), rng.randbytes(max_sample + 1))
    return out


def expected(payloads: list[bytes], times: list[int], frag: int, info_ts: bool,
             max_sample: int, prefix: bytes, writer: int, reader: int) -> list[list[bytes]]:
    """Each record's datagrams as the lab's builders make them (none for a dropped record)."""
    out: list[list[bytes]] = []
    seq = 0
    for pay, t in zip(payloads, times):
        if not 1 <= len(pay) <= max_sample:
            out.append([])
            continue
        seq += 1
        head = b.header(prefix) + (b.info_ts((t >> 32) + (t & 0xFFFFFFFF) / 2**32)
                                   if info_ts else b"")
        hb = b.heartbeat(reader, writer, seq + 1, seq, seq)
        padded = b.pad_payload(pay)
        if len(padded) <= frag:
            out.append([head + b.data(reader, writer, seq, padded) + hb])
            continue
        total = -(-len(padded) // frag)
        out.append([head + b.data_frag(reader, writer, seq, n, frag, len(padded),
                                       padded[(n - 1) * frag:n * frag], 1)
                    + (hb if n == total else b"") for n in range(1, total + 1)])
    return out


def run(tmp_path: Path, seed: int, frag: int, info_ts: bool, max_sample: int, gap: int,
        bp: int) -> tuple[list[bytes], dict, dict[str, int]]:
    """The records through the Verilog: (payloads, the bench's output, the parameters)."""
    sim = require_cocotb()
    from cocotb_tools.runner import get_runner

    p = params(frag, info_ts, max_sample)
    payloads = records(seed, frag, max_sample)
    recs = [struct.pack("<I", len(x)) + x for x in payloads]
    case = {"seed": seed, "gap": gap, "bp": bp, "records": [r.hex() for r in recs]}
    (tmp_path / "case.json").write_text(json.dumps(case))
    runner = get_runner(sim)
    runner.build(sources=[SOURCE], includes=[SOURCE.parent], hdl_toplevel="rfl_rtps_tx",
                 build_dir=tmp_path / "build",
                 parameters=verilog_parameters(p), timescale=("1ns", "1ps"),
                 log_file=tmp_path / "build.log")
    run_bench(runner, "bench_rfl_rtps_tx", "rfl_rtps_tx", tmp_path / "build", tmp_path,
              {"RTPS_TX_CASE": str(tmp_path / "case.json"),
               "RTPS_TX_OUT": str(tmp_path / "out.json")})
    return payloads, json.loads((tmp_path / "out.json").read_text()), p


def check_parsed(datagrams: list[bytes], payloads: list[bytes], max_sample: int,
                 prefix: bytes, writer: int, reader: int, info_ts: bool) -> None:
    """The decoder's view: the right participant, writer and writerSNs, every sample equal to
    its payload (DATA_FRAGs through the participant's FragmentAssembler), a HEARTBEAT of an
    empty history after each sample."""
    assembler = FragmentAssembler()
    samples: list[tuple[int, bytes]] = []
    beats: list[tuple[int, int]] = []
    for dg in datagrams:
        msg = parse_message(dg)
        assert msg.header.guid_prefix == prefix and msg.header.version == b.PROTOCOL_VERSION
        kinds = [type(s) for s in msg.submessages]       # [INFO_TS], DATA(_FRAG), [HEARTBEAT]
        assert kinds[:int(info_ts)] == [InfoTs] * int(info_ts), kinds
        assert kinds[int(info_ts)] in (Data, DataFrag) and kinds[int(info_ts) + 1:] in \
            ([], [Heartbeat]), kinds
        for sub in msg.submessages:
            if isinstance(sub, (Data, DataFrag, Heartbeat)):
                assert (sub.writer_id, sub.reader_id) == (writer, reader)
            if isinstance(sub, Data):
                samples.append((sub.seq, b.unpad_payload(sub.payload)))
            elif isinstance(sub, DataFrag):
                assert sub.frag_count == 1
                whole = assembler.add(prefix, sub)
                if whole is not None:
                    samples.append((sub.seq, b.unpad_payload(whole)))
            elif isinstance(sub, Heartbeat):
                beats.append((sub.first, sub.last))
                assert not sub.final and sub.count == sub.last
    # a record of 1..3 bytes (no CDR sample: its encapsulation header alone has 4) comes as the
    # software's DATA carries it, zeros to the submessage's 4-byte alignment after it
    sent = [p.ljust(4, b"\0") for p in payloads if 1 <= len(p) <= max_sample]
    assert [s for _, s in samples] == sent
    assert [n for n, _ in samples] == list(range(1, len(sent) + 1))
    assert beats == [(n + 1, n) for n in range(1, len(sent) + 1)]


@pytest.mark.parametrize("seed,frag,info_ts,gap,bp", [
    (1, 64, False, 300, 400), (2, 32, True, 0, 0), (3, FRAGMENT_BYTES, True, 100, 500)],
    ids=["frag64-gaps-backpressure", "frag32-info_ts-full-rate", "participant-frag"])
def test_rtps_tx_sends_the_builders_datagrams(seed: int, frag: int, info_ts: bool, gap: int,
                                              bp: int, tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))
    max_sample = 4 * frag + 8 if frag <= 256 else 2 * frag + 8
    payloads, out, p = run(tmp_path, seed, frag, info_ts, max_sample, gap, bp)
    config = load_config(CONFIG)
    part, _node, wid, _rid = fabric_participant(config)
    prefix, reader = part.guid_prefix, 0
    assert (p["GUID_PREFIX"], p["WRITER_ID"]) == (int.from_bytes(prefix, "big"), wid)
    datagrams = [bytes.fromhex(d) for d in out["datagrams"]]
    check_parsed(datagrams, payloads, max_sample, prefix, wid, reader, info_ts)
    want = expected(payloads, out["times"], frag, info_ts, max_sample, prefix, wid, reader)
    assert len(out["times"]) == len(payloads)
    at = 0
    head = head_bytes(info_ts)
    for k, (pay, dgs) in enumerate(zip(payloads, want)):
        got = datagrams[at:at + len(dgs)]
        assert got == dgs, f"record {k} ({len(pay)} bytes): datagrams differ from the builders'"
        at += len(dgs)
        sent = sum(map(len, got))
        assert sent <= (4 + len(pay)) * (1 + head / frag) + head + HB_BYTES, (k, len(pay), sent)
        assert all(len(d) <= FABRIC_MAX_DATAGRAM for d in got)
    assert at == len(datagrams)
    samples = sum(1 for d in want if d)
    assert out["counts"] == {"samples": samples, "datagrams": len(datagrams), "dropped": 2}
    assert out["seq"] == samples + 1
    if frag == FRAGMENT_BYTES:       # the participant's own submessages, for the same sample
        seq = 0
        for pay, dgs in zip(payloads, want):
            if not dgs:
                continue
            seq += 1
            if len(dgs) == 1:
                own = part._sample_subs(reader, wid, seq, pay)
            else:
                own = [part._sample_subs(reader, wid, seq, pay, [n])[0]
                       for n in range(1, len(dgs) + 1)]
            for dg, sub in zip(dgs, own):
                start = len(b.header(prefix)) + (len(b.info_ts(0.0)) if info_ts else 0)
                assert dg[start:start + len(sub)] == sub


def test_the_verilog_defaults_are_the_participants() -> None:
    """One owner: the module's default parameters are tx_parameters of every shipped ROS 2
    configuration (the lab's fabric prefix, the output writer's id, the software participant's
    fragment size, the Ethernet-sized datagram), so the Verilog restates no fact of its own."""
    text = SOURCE.read_text()
    found = {m.group(1): int(m.group(3).replace("_", ""), 16 if m.group(2) == "h" else 10)
             for m in re.finditer(r"parameter (?:\[\d+:0\] )?(\w+) = (?:\d+'([hd]))?"
                                  r"([0-9a-fA-F_]+)", text)}
    for config in sorted((ROOT / "data").glob("fpga_*_cdr.yaml")):
        given = tx_parameters(render_rom(config))
        assert {k: found[k] for k in given} == given, config.name


def test_a_planted_bug_fails_the_proof(tmp_path: Path) -> None:
    """The proofs are not vacuous: an output beat dropped while the sink stalls fails the stream
    rules or the framing invariants (a beat lost breaks the byte count); a HEARTBEAT that
    forgets TLAST fails the framing (the datagram runs past MAX_DATAGRAM: the module's FORMAL
    block); a header with the version's bytes swapped fails the bounded header check."""
    require_formal()
    text = SOURCE.read_text()
    for k, (good, bad, mode, where) in enumerate((
            ("if (m_axis_tready) o_valid <= 1'b0;", "o_valid <= 1'b0;", "prove",
             ("fv_rtps_tx.sv", "rfl_rtps_tx.v")),
            ("emit(sh[SHW-1 -: 8], h1);", "emit(sh[SHW-1 -: 8], 1'b0);", "prove",
             "rfl_rtps_tx.v"),
            ("RTPS_VERSION, RTPS_VENDOR, GUID_PREFIX",
             "RTPS_VERSION[7:0], RTPS_VERSION[15:8], RTPS_VENDOR, GUID_PREFIX",
             "bmc", "fv_rtps_tx.sv"))):
        assert text.count(good) == 1
        buggy = tmp_path / str(k) / "rfl_rtps_tx.v"
        buggy.parent.mkdir()
        buggy.write_text(text.replace(good, bad))
        proof = next(p for p in PROOFS if p.name == "rtps_tx" and p.mode == mode)
        result = prove(proof, replace={"rfl_rtps_tx.v": buggy})
        # from reset the base case may not reach the bug within the depth: induction fails
        assert result.status in ("FAIL", "UNKNOWN"), result.log[-3000:]
        assert result.failed and all(f.startswith(where) for f in result.failed), result.failed
