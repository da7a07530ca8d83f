"""``rfl_rtps_rx`` (``rosfpga_lab/rtl/fabric``, issue #31's first stage): random RTPS datagrams
built with the lab's encoders (``rtps.build``; big-endian submessages by swapping their fields,
checked with the lab's decoder), well-formed and damaged, through the Verilog under cocotb with
random input gaps and output backpressure; the samples out must be the reference's.

The reference is the lab's decoder, ``rtps.parse_message(keep_valid=True)`` and
``RtpsMessage.routed`` (source, destination, what a malformed submessage drops), with the
walker's contract on top (:func:`reference`): DATA (flag D) and DATA_FRAG for our reader (or
ENTITYID_UNKNOWN) from our writer, writerSN >= 1, destination ours or any; fragments streamed
in order only (a sample whose fragments come out of order or with one missing is dropped, as
is the sample in progress when another one starts); a DATA_FRAG repeating fragments already
taken (of the sample in progress, or past the first of the fragmented sample sent last) is
skipped and counted, the sample going on; every fragmented sample it puts together is also what the
participant's ``FragmentAssembler`` puts together from the same fragments.
"""

from __future__ import annotations

import dataclasses
import json
import random
import re
import struct
import subprocess
from pathlib import Path

import pytest

from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps.discovery import FragmentAssembler
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.message import (
    ANY_PARTICIPANT, HEADER_SIZE, Data, DataFrag, InfoTs, parse_message,
)
from rosfpga_lab.rtl.proofs import PROOFS, RTPS_RX, prove
from tests.support.rtltools import (
    run_bench,
    TB_DIR, require_cocotb, require_formal, require_iverilog, require_verilator, require_yosys,
)

pytestmark = pytest.mark.rtl

FABRIC = Path(__file__).resolve().parents[2] / "rosfpga_lab" / "rtl" / "fabric"
SOURCE = FABRIC / "rfl_rtps_rx.v"
SOURCES = [FABRIC / m for m in RTPS_RX]   # with the walk it instantiates
LOCAL = bytes.fromhex("010f4a5b00112233445566aa")
REMOTES = (bytes.fromhex("010fcafe0000000100000001"), bytes.fromhex("0110beef0000000200000007"))
OTHER_DST = bytes.fromhex("010f000000000000000000ff")
WRITER, OTHER_WRITER = 0x00001203, 0x00001303
READER, OTHER_READER = 0x00001204, 0x00001304
DATA_FIELDS, FRAG_FIELDS = 20, 32      # body bytes of their fixed fields


# ---- big-endian submessages: the lab's little-endian ones with every field swapped --------
def _swap(sub: bytes) -> bytes:
    kind, flags = sub[0], sub[1]
    (length,) = struct.unpack("<H", sub[2:4])
    body = bytearray(sub[4:])

    def sw(at: int, n: int) -> None:
        body[at:at + n] = body[at:at + n][::-1]

    if kind == b.INFO_TS and not flags & 0x02:
        sw(0, 4)
        sw(4, 4)
    elif kind in (b.DATA, b.DATA_FRAG):
        (to_qos,) = struct.unpack("<H", body[2:4])
        for at, n in ((0, 2), (2, 2), (12, 4), (16, 4)):
            sw(at, n)
        if kind == b.DATA_FRAG:
            for at, n in ((20, 4), (24, 2), (26, 2), (28, 4)):
                sw(at, n)
        pos = 4 + to_qos
        while flags & 0x02:
            pid, plen = struct.unpack("<HH", body[pos:pos + 4])
            sw(pos, 2)
            sw(pos + 2, 2)
            pos += 4 + plen
            if pid == b.PID_SENTINEL:
                break
    elif kind == b.HEARTBEAT:
        for at in (8, 12, 16, 20, 24):
            sw(at, 4)
    elif kind in (b.GAP, b.ACKNACK):
        first = (8, 12, 16, 20) if kind == b.GAP else (8, 12)
        for at in first:
            sw(at, 4)
        at = first[-1] + 4
        (bits,) = struct.unpack("<I", body[at:at + 4])
        for k in range(1 + (bits + 31) // 32 + (kind == b.ACKNACK)):
            sw(at + 4 * k, 4)
    return bytes([kind, flags & 0xFE]) + struct.pack(">H", length) + bytes(body)


def _order(sub: bytes, big: bool) -> bytes:
    return _swap(sub) if big else sub


def test_the_big_endian_submessages_decode_as_the_little_endian_ones() -> None:
    rng = random.Random(3)
    for sub in [b.data(READER, WRITER, 7, b.CDR_LE + b"abcde", _qos(rng)),
                b.data_frag(0, WRITER, 2**33 + 5, 3, 7, 40, bytes(range(14)), 2),
                b.info_ts(1234.5), b.heartbeat(0, WRITER, 1, 9, 4),
                b.gap(READER, WRITER, 3, 5, [6, 9, 40]), b.acknack(READER, WRITER, 4, [5, 70], 2),
                b.info_dst(LOCAL)]:
        le = parse_message(b.header(REMOTES[0]) + sub).submessages[0]
        be = parse_message(b.header(REMOTES[0]) + _swap(sub)).submessages[0]
        assert not be.little_endian
        same = {"flags": le.flags}
        if isinstance(le, Data):                 # the parameter list's own byte order
            assert len(be.inline_qos) == len(le.inline_qos)
            same["inline_qos"] = le.inline_qos
        assert dataclasses.replace(be, **same) == le


def _qos(rng: random.Random) -> bytes:
    """An inline QoS parameter list (PID_STATUS_INFO, maybe a key hash), PL_CDR_LE."""
    params = struct.pack("<HH", b.PID_STATUS_INFO, 4) + bytes(4)
    if rng.random() < 0.5:
        params += struct.pack("<HH", b.PID_KEY_HASH, 16) + rng.randbytes(16)
    return params + struct.pack("<HH", b.PID_SENTINEL, 0)


# ---- random traffic ---------------------------------------------------------------------
def _payload(rng: random.Random) -> bytes:
    body = rng.randbytes(rng.choice([0, 1, 3, 4, rng.randint(1, 90)]))
    pay = (b.CDR_LE if rng.random() < 0.5 else b"\x00\x00\x00\x00") + body
    return b.pad_payload(pay) if rng.random() < 0.5 else pay


def _control(rng: random.Random) -> bytes:
    """A submessage the walker skips (or a vendor's unknown one)."""
    pick = rng.randrange(6)
    w = rng.choice([WRITER, OTHER_WRITER])
    if pick == 0:
        sub = b.heartbeat(rng.choice([0, READER]), w, 1, rng.randint(1, 99), rng.randint(1, 9),
                          final=rng.random() < 0.5)
    elif pick == 1:
        sub = b.gap(READER, w, 2, 5, [7, 9])
    elif pick == 2:
        sub = b.acknack(READER, w, 3, [4, 6, 40], 1)
    elif pick == 3:
        sub = struct.pack("<BBH", b.PAD, 1, 0)
    elif pick == 4:
        sub = struct.pack("<BBH", 0x80 + rng.randrange(0x7F), 1, 8) + rng.randbytes(8)
    else:
        sub = b.nack_frag(READER, w, 3, [2, 5], 1)
    return _order(sub, rng.random() < 0.3) if pick < 3 else sub


def _sample_items(rng: random.Random, seq: int) -> list[tuple[bytes, bytes]]:
    """(source, submessage) of one sample: a DATA, or DATA_FRAGs, now and then damaged."""
    src = REMOTES[0] if rng.random() < 0.8 else REMOTES[1]
    writer = WRITER if rng.random() < 0.85 else OTHER_WRITER
    reader = rng.choice([0, READER, READER, READER, OTHER_READER])
    big = rng.random() < 0.4
    if rng.random() < 0.08:
        seq = 0                                  # invalid: never taken
    if rng.random() < 0.45:
        qos = _qos(rng) if rng.random() < 0.3 else b""
        sub = b.data(reader, writer, seq, _payload(rng), qos)
        if rng.random() < 0.05:
            sub = sub[:1] + bytes([sub[1] & ~0x04]) + sub[2:]   # no payload (flag D clear)
        return [(src, _order(sub, big))]
    sample = _payload(rng) + rng.randbytes(rng.randint(1, 120))
    fsize = rng.randint(1, 24)
    total = -(-len(sample) // fsize)
    chunks = []
    n = 1
    while n <= total:
        count = min(rng.randint(1, 3), total - n + 1)
        chunks.append((n, count))
        n += count
    fault = rng.random()
    if fault < 0.08 and len(chunks) > 1:
        del chunks[rng.randrange(1, len(chunks))]            # a fragment missing
    elif fault < 0.16 and len(chunks) > 2:
        k = rng.randrange(len(chunks) - 1)
        chunks[k], chunks[k + 1] = chunks[k + 1], chunks[k]  # out of order
    elif fault < 0.22:
        chunks.insert(rng.randrange(len(chunks) + 1), chunks[0])   # a resent first one
    elif fault < 0.30:
        chunks = [c for c in chunks for _ in range(2)]             # each twice (Fast DDS)
    elif fault < 0.36 and len(chunks) > 2:
        k = rng.randrange(1, len(chunks) - 1)
        chunks.insert(rng.randrange(k + 2, len(chunks) + 1), chunks[k])   # one again, later
    out = []
    for start, count in chunks:
        part = sample[(start - 1) * fsize:(start - 1 + count) * fsize]
        sub = b.data_frag(reader, writer, seq, start, fsize, len(sample), part, count)
        out.append((src, _order(sub, big)))
    return out


def _subs(dg: bytes) -> list[tuple[int, int, bool]]:
    """(offset, length, little endian) of the submessages a datagram's lengths walk through."""
    found, pos = [], HEADER_SIZE
    while pos + 4 <= len(dg):
        le = bool(dg[pos + 1] & 1)
        (length,) = struct.unpack("<H" if le else ">H", dg[pos + 2:pos + 4])
        found.append((pos, length, le))
        if length == 0 and dg[pos] not in (b.PAD, b.INFO_TS):
            break                                  # to the end of the message
        pos += 4 + length
    return found


def _set_length(dg: bytearray, at: int, le: bool, length: int) -> None:
    dg[at + 2:at + 4] = struct.pack("<H" if le else ">H", length)


def _damage(rng: random.Random, dg: bytes) -> bytes:
    """One of the ways a datagram can be malformed."""
    out = bytearray(dg)
    subs = _subs(dg)
    kind = rng.randrange(9)
    if kind == 0:
        out[rng.randrange(4)] ^= 1 << rng.randrange(8)          # bad magic
    elif kind == 1:
        out[4] = rng.choice([1, 3])                             # another major version
    elif kind == 2:
        return bytes(out[:rng.randrange(1, HEADER_SIZE)])       # shorter than a header
    elif kind in (3, 4) and len(out) > HEADER_SIZE + 1:
        return bytes(out[:rng.randrange(HEADER_SIZE + 1, len(out))])   # cut short
    elif kind == 5 and subs:
        at, length, le = rng.choice(subs)
        _set_length(out, at, le, len(dg) - at + 4 * rng.randint(0, 40))  # beyond the packet
    elif kind == 6 and len(subs) > 1:
        at, length, le = rng.choice(subs[:-1])
        _set_length(out, at, le, length + rng.choice([1, 2, 3]))       # not a multiple of 4
    elif kind == 7:
        datas = [s for s in subs if dg[s[0]] == b.DATA]
        if datas:
            at = rng.choice(datas)[0]
            out[at + 1] |= 0x0C                                 # D and K
    elif kind == 8:
        datas = [s for s in subs if dg[s[0]] in (b.DATA, b.DATA_FRAG)]
        if datas:
            at, _, le = rng.choice(datas)
            out[at + 6:at + 8] = struct.pack("<H" if le else ">H", 0x7FF0)   # QoS far away
    return bytes(out)


def random_datagrams(seed: int, samples: int) -> list[bytes]:
    rng = random.Random(seed)
    items: list[tuple[bytes, bytes]] = []
    for seq in range(1, samples + 1):
        items += _sample_items(rng, seq)
    datagrams = []
    while items:
        src = items[0][0]
        dg = b.header(src)
        if rng.random() < 0.5:
            dg += _order(b.info_ts(rng.uniform(0, 2e9)), rng.random() < 0.4)
        elif rng.random() < 0.1:
            dg += struct.pack("<BBH", b.INFO_TS, 0x03, 0)        # invalidated
        for _ in range(rng.randint(1, 4)):
            if not items:
                break
            if items[0][0] != src:
                if rng.random() < 0.5:
                    break
                src = items[0][0]
                dg += b.info_src(src)
            r = rng.random()
            if r < 0.12:
                dg += b.info_dst(OTHER_DST)
            elif r < 0.24:
                dg += b.info_dst(rng.choice([LOCAL, ANY_PARTICIPANT]))
            if rng.random() < 0.3:
                dg += _control(rng)
            dg += items.pop(0)[1]
        if rng.random() < 0.3:
            dg += _control(rng)
        if rng.random() < 0.15:                                  # the last one "to the end"
            at, _, le = _subs(dg)[-1]
            if dg[at] not in (b.PAD, b.INFO_TS):
                dg = bytearray(dg)
                _set_length(dg, at, le, 0)
                dg = bytes(dg)
        elif rng.random() < 0.15:
            dg = _damage(rng, dg)
        datagrams.append(dg)
        if rng.random() < 0.03:
            datagrams.append(b.header(LOCAL) + b.data(0, WRITER, 1, b.CDR_LE + b"own"))
    return datagrams


# ---- the reference --------------------------------------------------------------------------
def _fields(dg: bytes, at: int, le: bool) -> tuple[int, int, int]:
    o = "<" if le else ">"
    reader, writer = struct.unpack(">II", dg[at + 8:at + 16])
    high, low = struct.unpack(o + "iI", dg[at + 16:at + 24])
    return reader, writer, (high << 32) | low


def _frag_fields(dg: bytes, at: int, le: bool) -> tuple[int, int, int, int]:
    """fragmentStartingNum, fragmentsInSubmessage, fragmentSize, sampleSize of a DATA_FRAG."""
    return struct.unpack(("<" if le else ">") + "IHHI", dg[at + 24:at + 36])


def reference(datagrams: list[bytes], local: bytes = LOCAL, reader: int = READER,
              writer: int = WRITER) -> tuple[list[dict], dict[str, int]]:
    """The samples the walker must send whole, and its counters (dropped: not predicted)."""
    samples: list[dict] = []
    counts = {"packets": len(datagrams), "bad_header": 0, "malformed": 0, "samples": 0,
              "repeated": 0}
    act: dict | None = None
    done: tuple | None = None                   # the fragmented sample sent last whole
    assembler = FragmentAssembler()

    def wanted(dst: bytes, rd: int, wr: int, seq: int) -> bool:
        return dst in (local, ANY_PARTICIPANT) and rd in (0, reader) and \
            writer in (0, wr) and seq >= 1

    def repeats(key: tuple, start: int, valid: bool) -> bool:
        """Fragments already taken: of the sample in progress, or past the first of the one
        sent last (its fragment 1 starts it again: no history of writerSNs)."""
        return valid and start >= 1 and ((key == done and start >= 2) or (
            act is not None and act["key"] == key and start < act["next"]))

    for dg in datagrams:
        try:
            msg = parse_message(dg, keep_valid=True)
        except RtpsError:
            counts["bad_header"] += 1
            continue
        if dg[4] != 2:
            counts["bad_header"] += 1
            continue
        if msg.header.guid_prefix == local:
            continue
        ts, src, dst = None, msg.header.guid_prefix, ANY_PARTICIPANT
        for src, dst, sub in msg.routed():
            if isinstance(sub, InfoTs):           # {seconds, fraction} as the walker keeps it
                ts = None
                if not sub.flags & 0x02:
                    sec, frac = struct.unpack("<iI" if sub.little_endian else ">iI",
                                              dg[sub.offset + 4:sub.offset + 12])
                    ts = ((sec & 0xFFFFFFFF) << 32) | frac
            if not isinstance(sub, (Data, DataFrag)) or \
                    not wanted(dst, sub.reader_id, sub.writer_id, sub.seq):
                continue
            meta = {"guid": (src + sub.writer_id.to_bytes(4, "big")).hex(), "seq": sub.seq,
                    "ts": ts}
            if isinstance(sub, Data):
                if sub.flags & 0x0C != 0x04:
                    continue
                act = done = None
                if sub.payload:
                    samples.append(dict(meta, data=sub.payload.hex()))
                continue
            key = (src, sub.writer_id, sub.seq, sub.frag_size, sub.sample_size)
            valid = bool(sub.frag_size and sub.frag_count and sub.sample_size)
            if repeats(key, sub.frag_start, valid):
                counts["repeated"] += 1
                continue
            if not (act and valid and act["key"] == key and sub.frag_start == act["next"]):
                act = None
                if sub.frag_start != 1 or not valid:
                    continue
                act = {"key": key, "next": 1, "data": b"", "meta": meta}
                done = None
            need = min(sub.frag_count * sub.frag_size, sub.sample_size - len(act["data"]))
            whole = assembler.add(src, sub)
            if len(sub.payload) < need:
                act = None
                continue
            act["data"] += sub.payload[:need]
            act["next"] += sub.frag_count
            if len(act["data"]) == sub.sample_size:
                assert whole == act["data"], "the participant's assembler puts it otherwise"
                samples.append(dict(act["meta"], data=act["data"].hex()))
                act, done = None, key
        if msg.error is not None:
            counts["malformed"] += 1
            last = msg.submessages[-1] if msg.submessages else None
            at = last.offset + last.size if last else HEADER_SIZE
            if at + 4 > len(dg):
                continue                           # a submessage header cut short
            kind, le = dg[at], bool(dg[at + 1] & 1)
            (length,) = struct.unpack("<H" if le else ">H", dg[at + 2:at + 4])
            end = len(dg) if length == 0 else min(len(dg), at + 4 + length)
            need = DATA_FIELDS if kind == b.DATA else FRAG_FIELDS
            # a DATA / DATA_FRAG for us whose fields are all there drops the sample in progress,
            # unless it repeats fragments already taken
            if kind in (b.DATA, b.DATA_FRAG) and end - at - 4 >= need and \
                    (kind == b.DATA_FRAG or dg[at + 1] & 0x0C == 0x04) and \
                    wanted(dst, *_fields(dg, at, le)):
                if kind == b.DATA:
                    act = done = None
                    continue
                start, count, fsize, ssize = _frag_fields(dg, at, le)
                key = (src, _fields(dg, at, le)[1], _fields(dg, at, le)[2], fsize, ssize)
                valid = bool(fsize and count and ssize)
                if repeats(key, start, valid):
                    counts["repeated"] += 1
                    continue
                act = None
                if start == 1 and valid:
                    done = None                    # it started a sample, then broke it
    counts["samples"] = len(samples)
    return samples, counts


def test_the_reference_sees_samples_and_damage() -> None:
    """The random traffic is not trivial: whole samples of both kinds and both byte orders,
    damaged datagrams of each counter, repeated fragments."""
    datagrams = random_datagrams(11, 60)
    samples, counts = reference(datagrams)
    assert len(samples) > 15 and counts["malformed"] > 0 and counts["bad_header"] > 0
    # the co-simulated seeds repeat fragments
    assert all(reference(random_datagrams(seed, 70))[1]["repeated"] >= 3 for seed in (1, 2))
    assert any(dg[HEADER_SIZE:].find(bytes([b.DATA_FRAG, 0])) >= 0 for dg in datagrams)


# ---- repeated fragments, written by hand -----------------------------------------------------
def _frag_datagram(seq: int, sample: bytes, starts: list[int], fsize: int = 8) -> bytes:
    """One datagram of DATA_FRAGs (a fragment each) of ``sample`` from REMOTES[0]'s WRITER."""
    dg = b.header(REMOTES[0]) + b.info_dst(LOCAL)
    for n in starts:
        part = sample[(n - 1) * fsize:n * fsize]
        dg += b.data_frag(READER, WRITER, seq, n, fsize, len(sample), part, 1)
    return dg


def repeated_fragments_case() -> tuple[list[bytes], list[dict], dict[str, int]]:
    """Datagrams with repeated fragments, and what the walker must do with them: samples 1, 2
    and 5 whole (1: each datagram twice, as Fast DDS sends them; 2: fragment 1 again after 2,
    2 again after 3; 5: the copies in one datagram, 3's across two), 3 (fragment 2 missing)
    and 4 (fragments 1, 3, 2, 4) dropped and counted."""
    sample = {seq: bytes([seq]) * 4 + bytes(range(seq * 16, seq * 16 + 26)) for seq in range(1, 6)}
    order = {1: [1, 1, 2, 2, 3, 3, 4, 4], 2: [1, 2, 1, 3, 2, 4], 3: [1, 3, 4], 4: [1, 3, 2, 4]}
    datagrams = [_frag_datagram(seq, sample[seq], [n]) for seq in (1, 2, 3, 4) for n in order[seq]]
    datagrams += [_frag_datagram(5, sample[5], [1, 1]), _frag_datagram(5, sample[5], [2, 2, 3]),
                  _frag_datagram(5, sample[5], [3, 4, 4])]
    guid = (REMOTES[0] + WRITER.to_bytes(4, "big")).hex()
    want = [{"guid": guid, "seq": seq, "ts": None, "data": sample[seq].hex()} for seq in (1, 2, 5)]
    # repeated: the second copies (1: four, the last after the sample went out; 2: two; 5:
    # four); dropped: 3 at its fragment 3 (the sample, then the fragment alone) and its 4
    # alone, 4 likewise at its 3, then its 2 and 4 alone
    counts = {"packets": len(datagrams), "bad_header": 0, "malformed": 0, "samples": 3,
              "repeated": 4 + 2 + 4, "dropped": 3 + 4}
    return datagrams, want, counts


def test_the_repeated_fragments_case_is_what_the_reference_says() -> None:
    datagrams, want, counts = repeated_fragments_case()
    assert reference(datagrams) == (want, {k: v for k, v in counts.items() if k != "dropped"})


# ---- the Verilog -----------------------------------------------------------------------------
def cosimulate(tmp_path: Path, seed: int, gap: int, bp: int, datagrams: list[bytes],
               want: list[dict], counts: dict[str, int | None]) -> None:
    sim = require_cocotb()
    from cocotb_tools.runner import get_runner

    case = {"seed": seed, "gap": gap, "bp": bp, "local": LOCAL.hex(), "reader": READER,
            "writer": WRITER, "datagrams": [d.hex() for d in datagrams], "samples": want,
            "counts": counts}
    (tmp_path / "case.json").write_text(json.dumps(case))
    runner = get_runner(sim)
    runner.build(sources=SOURCES, includes=[FABRIC], hdl_toplevel="rfl_rtps_rx",
                 build_dir=tmp_path / "build",
                 timescale=("1ns", "1ps"), log_file=tmp_path / "build.log")
    run_bench(runner, "bench_rfl_rtps_rx", "rfl_rtps_rx", tmp_path / "build", tmp_path,
              {"RTPS_RX_CASE": str(tmp_path / "case.json"),
               "RTPS_RX_OUT": str(tmp_path / "out.json")})


@pytest.mark.parametrize("seed,samples,gap,bp", [(1, 70, 200, 300), (2, 70, 0, 0)],
                         ids=["gaps-backpressure", "full-rate"])
def test_rtps_rx_streams_the_references_samples(seed: int, samples: int, gap: int, bp: int,
                                               tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(TB_DIR))
    datagrams = random_datagrams(seed, samples)
    want, counts = reference(datagrams)
    cosimulate(tmp_path, seed, gap, bp, datagrams, want, dict(counts, dropped=None))


@pytest.mark.parametrize("gap,bp", [(200, 300), (0, 0)], ids=["gaps-backpressure", "full-rate"])
def test_rtps_rx_skips_repeated_fragments(gap: int, bp: int, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """Repeated fragments (Fast DDS sends each twice) leave the sample whole; a fragment
    missing or out of order still drops it, counted."""
    monkeypatch.syspath_prepend(str(TB_DIR))
    datagrams, want, counts = repeated_fragments_case()
    cosimulate(tmp_path, 5, gap, bp, datagrams, want, counts)


def test_verilator_wall_has_no_warning(tmp_path: Path) -> None:
    """Verilator -Wall is silent (the parameter contract is tests/rtl/test_house_rules.py's)."""
    verilator = require_verilator()
    done = subprocess.run([verilator, "--lint-only", "-Wall", f"-I{FABRIC}", "--top-module",
                           "rfl_rtps_rx", *map(str, SOURCES)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "%Warning" not in done.stderr, done.stderr[-3000:]


def test_iverilog_wall_and_yosys_check_are_silent(tmp_path: Path) -> None:
    """Icarus -Wall says nothing; Yosys finds no latch, loop, multiple or missing driver."""
    iverilog = require_iverilog()
    done = subprocess.run([iverilog, "-g2005", "-Wall", f"-I{FABRIC}", "-o", "m.vvp",
                           "-s", "rfl_rtps_rx", *map(str, SOURCES)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout + done.stderr == "", done.stdout + done.stderr
    require_yosys()
    from rosfpga_lab.rtl.synth import yosys_command

    yosys = yosys_command()
    assert yosys is not None
    (tmp_path / "check.ys").write_text(
        f"read_verilog -I{FABRIC} {' '.join(map(str, SOURCES))}\n"
        "hierarchy -check -top rfl_rtps_rx\nproc\n"
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$sr\ncheck -assert\n")
    done = subprocess.run([*yosys, "-q", "check.ys"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]


def test_a_planted_bug_fails_the_proof(tmp_path: Path) -> None:
    """The proof is not vacuous: an output beat dropped while the sink stalls is caught."""
    require_formal()
    text = SOURCE.read_text()
    good = "if (m_axis_tready) o_valid <= 1'b0;"
    assert text.count(good) == 1
    buggy = tmp_path / "rfl_rtps_rx.v"
    buggy.write_text(text.replace(good, "o_valid <= 1'b0;"))
    proof = next(p for p in PROOFS if p.name == "rtps_rx")
    result = prove(proof, replace={"rfl_rtps_rx.v": buggy})
    # from reset no beat comes out within the depth: the induction step is what fails
    assert result.status in ("FAIL", "UNKNOWN"), result.log[-3000:]
    assert re.search(r"Assert(ion)? failed.*fv_rtps_rx\.sv", result.log), result.log[-3000:]
