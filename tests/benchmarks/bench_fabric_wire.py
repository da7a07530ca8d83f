"""The node in the fabric at gigabit line rate (issue #31 item 5; prints figures, not a test).

``rfl_fabric_top`` (GMII variant, 125 MHz, Verilator under cocotb: tests/rtl/bench_rfl_fabric_top_wire.py)
with the generated top of a ``wire: cdr`` configuration inside, fed at its GMII side with
samples back to back at line rate: a byte a clock, each frame behind its 8-byte preamble and
12-byte interframe gap, the samples as the lab's software writer sends them (DATA_FRAGs of
``rtps.limits.FRAGMENT_BYTES``, one a datagram, INFO_TS in each). Two cases: the LaserScan of
``data/fpga_laserscan_min_cdr.yaml`` (1.5 kB, 2 DATA_FRAGs) and the 3x3 dilation of
``data/fpga_dilate_rgba8_cdr.yaml`` at --image (default 64x48 rgba8, 12 kB, 10 DATA_FRAGs;
640x480 runs too, slowly). First one sample alone (after a warm-up sample: ARP and the SPDP
announcement out of the way) for the latencies: clocks from its first byte in (GMII rx, the
first preamble byte) to its output's first byte out (GMII tx), and from its last byte in to the
output's last byte out: RTL latency in the circuit, not wire latency (no PHY, no cable). Then
--samples back to back: samples in, samples out (the counters), samples/s sustained at 125 MHz
(the output's rate), the physical bound (wire bytes a sample in / 125 MB/s), and with --watch
(default) where the stream stalls: per stage, the clocks it held data its next stage did not
take. Beside them: the closed commercial RTPS core's 2.5 us (312 clocks at 125 MHz), which it
states for send/receive.

The simulated GMII top runs LiteEth's 32-bit core on the same 125 MHz clock as its 8-bit UDP
layer and the node (the board gives the core a clock of its own), so the figures are clocks of
that one clock, and do not depend on the machine's load (the wall time does).

Measured (2026-11-29, the 32-bit core, Verilator 5.048, cocotb 2.1, after the generated
subscriber's double buffering: the LaserScan at the output's line rate, 12 of 12; the 8-bit
core's latencies 13 to 14 clocks shorter): see the fabric docs
(rosfpga_lab/rtl/fabric/vendor/README.md, "At line rate"), printed by

    python tests/benchmarks/bench_fabric_wire.py [--image 64x48] [--samples 6] [--no-watch]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from scapy.layers.inet import IP, UDP  # noqa: E402
from scapy.layers.l2 import ARP, Ether  # noqa: E402

from rosfpga_lab.config import load_config  # noqa: E402
from rosfpga_lab.hls.vectors import model_output_cdr, sample_tokens  # noqa: E402
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config, cdr_marshal, to_cdr_tokens  # noqa: E402
from rosfpga_lab.rtl.discrom import fabric_participant, render_rom, tx_parameters, write_rom  # noqa: E402
from rosfpga_lab.rtps import build as b  # noqa: E402
from rosfpga_lab.rtps.entities import discovery_port, user_port  # noqa: E402
from rosfpga_lab.rtps.limits import FRAGMENT_BYTES  # noqa: E402
from tests.rtl.test_fabric_rtps_loop import TIME, split_records  # noqa: E402
from tests.rtl.test_fabric_rtps_rx import LOCAL, READER, WRITER  # noqa: E402
from tests.rtl.test_fabric_rtps_tx import expected  # noqa: E402
from tests.rtl.test_fabric_top import NODE_IP, NODE_MAC, PEER, PEER_INDEX, _ip  # noqa: E402
from tests.rtl.test_fabric_udp import PEER_IP, PEER_MAC, _fcs, _frames  # noqa: E402
from tests.support import fabrictop  # noqa: E402

CLOCK_NS = 8                                    # 125 MHz: a GMII byte a clock
PREAMBLE, IFG = 8, 12                           # wire bytes around each frame
CLOSED_CORE_CLOCKS = 312                        # 2.5 us at 125 MHz
PERIOD = 10_000_000                             # one SPDP announcement (at reset) in the run


def image_config(size: str, tmp: Path) -> Path:
    """data/fpga_dilate_rgba8_cdr.yaml at ``size`` (WxH)."""
    w, h = (int(x) for x in size.lower().split("x"))
    text = (ROOT / "data" / "fpga_dilate_rgba8_cdr.yaml").read_text()
    text = text.replace("width: 640", f"width: {w}").replace("height: 480", f"height: {h}")
    path = tmp / f"dilate_{w}x{h}_cdr.yaml"
    path.write_text(text)
    return path


def sample_of(config_path: Path) -> tuple[bytes, bytes]:
    """A sample the software writer would send (its payload) and the models' output for it."""
    config = load_config(config_path)
    cdr = cdr_layout_from_config(config)
    record = cdr_marshal(cdr, to_cdr_tokens(cdr, sample_tokens(cdr.base,
                                                               np.random.default_rng(7))))
    out, why = model_output_cdr(cdr, config.application.op, config.application.ksize, [record])
    assert why == [""], why
    (payload,) = split_records(out)
    return record[4:], payload


def datagrams_of(payload: bytes, seq: int) -> list[bytes]:
    """The software writer's datagrams of one sample: DATA_FRAGs of FRAGMENT_BYTES, one a
    datagram, each behind the header and INFO_TS."""
    padded = b.pad_payload(payload)
    head = b.header(PEER) + b.info_ts(1.5e9)
    total = -(-len(padded) // FRAGMENT_BYTES)
    return [head + b.data_frag(READER, WRITER, seq, n, FRAGMENT_BYTES, len(padded),
                               padded[(n - 1) * FRAGMENT_BYTES:n * FRAGMENT_BYTES], 1)
            for n in range(1, total + 1)]


def frame_of(payload: bytes) -> bytes:
    return _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) / IP(src=PEER_IP, dst=NODE_IP) /
                      UDP(sport=40000, dport=user_port(0, 0)) / payload))


def measure(config_path: Path, samples: int, watch: bool, work: Path) -> dict[str, Any]:
    """Run the case: the figures."""
    from cocotb_tools.runner import get_runner

    config = load_config(config_path)
    payload, out_payload = sample_of(config_path)
    rom = render_rom(config, guid_prefix=LOCAL)
    write_rom(rom, work)
    part, _node, wid, _rid = fabric_participant(config, guid_prefix=LOCAL)
    reader_id = tx_parameters(rom)["READER_ID"]
    max_bytes = 1 << max(11, (len(payload) + 4).bit_length())
    def frames(first: int, count: int) -> list[str]:
        """``count`` samples numbered from ``first`` (each its own writer sequence number, as a
        writer sends them: a fragment of a sample after a lost one is then not a repeat)."""
        return [frame_of(d).hex() for seq in range(first, first + count)
                for d in datagrams_of(payload, seq)]

    per_sample = [frame_of(d) for d in datagrams_of(payload, 1)]
    want = expected([out_payload] * 2, [TIME] * 2, FRAGMENT_BYTES, True, max_bytes,
                    part.guid_prefix, wid, reader_id)[1]         # the second sample's
    k = len(want)                                # datagrams out a sample
    reply = _fcs(bytes(Ether(dst=NODE_MAC, src=PEER_MAC) /
                       ARP(op=2, hwsrc=PEER_MAC, psrc=PEER_IP, hwdst=NODE_MAC, pdst=NODE_IP)))
    groups = [
        {"name": "warm-up", "frames": frames(1, 1), "gap": None,
         "expect": 1 + k, "samples": 1, "quiet": 2000},
        {"name": "alone", "frames": frames(2, 1), "gap": None,
         "expect": 1 + 2 * k, "samples": 2, "quiet": 2000},
        {"name": "line rate", "frames": frames(3, samples), "gap": None,
         "expect": 1 + (2 + samples) * k, "samples": 2 + samples, "quiet": 20_000},
    ]
    case = {"node_mac": NODE_MAC.replace(":", ""), "node_ip": _ip(NODE_IP),
            "peer_ip": _ip(PEER_IP), "peer_meta_port": discovery_port(0, PEER_INDEX),
            "peer_user_port": user_port(0, PEER_INDEX), "reader": READER, "writer": WRITER,
            "time": TIME, "arp_reply": reply.hex(), "groups": groups, "watch": watch,
            "max_clocks": 200 * len(payload) * (samples + 2) + 200_000,
            "idle_clocks": 4 * len(payload) + 20_000}          # a dropped sample: no wait
    gen = fabrictop.generate(config_path, work / "project")
    runner = get_runner("verilator")
    build = fabrictop.build(runner, gen, fabrictop.top_parameters_of(rom, max_bytes, PERIOD),
                            work)
    out = fabrictop.run(runner, build, "bench_rfl_fabric_top_wire", case, work, "FABRIC_WIRE_CASE",
                        "FABRIC_WIRE_OUT")

    frames = _frames([s["data"] for s in out["sent"]])
    user = [(s, Ether(f)) for s, f in zip(out["sent"], frames)
            if Ether(f).haslayer(UDP) and Ether(f)[UDP].dport == user_port(0, PEER_INDEX)]
    got = [bytes(e[UDP].payload)[:e[UDP].len - 8] for _, e in user]
    times = [(s["start"] // CLOCK_NS, s["end"] // CLOCK_NS - 1) for s, _ in user]
    alone_in = out["groups"][1]["in"]
    first_in, last_in = alone_in[0][0] // CLOCK_NS, alone_in[-1][1] // CLOCK_NS
    first_out, last_out = times[k][0], times[2 * k - 1][1]
    wire = sum(PREAMBLE + len(f) + IFG for f in per_sample)
    c0, c1 = out["groups"][1]["counters"], out["groups"][2]["counters"]
    delivered = c1["samples"] - c0["samples"]
    rate_in = out["groups"][2]["in"]
    span_in = (rate_in[-1][1] - rate_in[0][0]) / 1e9
    outs = times[2 * k:]
    starts = [outs[i][0] for i in range(0, len(outs), k)]
    sustained = ((len(starts) - 1) / ((starts[-1] - starts[0]) * CLOCK_NS / 1e9)
                 if len(starts) > 1 else 0.0)
    return {
        "config": config_path.name, "sample_bytes": len(payload), "out_bytes": len(out_payload),
        "frames_in": len(per_sample), "datagrams_out": k, "wire_bytes": wire,
        "exact": got[k:2 * k] == want,
        "first_to_first": first_out - first_in, "last_to_last": last_out - last_in,
        "samples": samples, "delivered": delivered, "offered_per_s": samples / span_in,
        "sustained_per_s": sustained, "bound_per_s": 125e6 / wire,
        "counters": {key: c1[key] - c0[key] for key in c1 if c1[key] != c0[key]},
        "stalls": out["stalls"]}


def report(r: dict[str, Any], watch: bool) -> None:
    print(f"== {r['config']}: sample {r['sample_bytes']} B in ({r['frames_in']} frames, "
          f"{r['wire_bytes']} wire bytes), {r['out_bytes']} B out ({r['datagrams_out']} "
          f"datagrams)")
    print(f"  latency, one sample alone (RTL, GMII rx to GMII tx, 125 MHz clocks):")
    print(f"    first byte in -> first byte out: {r['first_to_first']:7d} clocks "
          f"({r['first_to_first'] * CLOCK_NS / 1000:.2f} us)")
    print(f"    last byte in  -> last byte out:  {r['last_to_last']:7d} clocks "
          f"({r['last_to_last'] * CLOCK_NS / 1000:.2f} us)")
    print(f"    closed commercial core: {CLOSED_CORE_CLOCKS} clocks (2.5 us), send/receive")
    print(f"  line rate, {r['samples']} samples back to back: offered "
          f"{r['offered_per_s']:.0f}/s, {r['delivered']} of {r['samples']} out, sustained "
          f"{r['sustained_per_s']:.0f}/s; physical bound {r['bound_per_s']:.0f}/s "
          f"(wire bytes / 125 MB/s); keeps up: "
          f"{'yes' if r['delivered'] == r['samples'] else 'NO'}")
    print(f"  output exact (the models' sample as the software writer sends it): {r['exact']}")
    print(f"  counters moved: {r['counters']}")
    if watch:
        print("  stalls (clocks a stage held data its next stage did not take / clocks valid):")
        for name, s in r["stalls"].items():
            print(f"    {name:24s} {s['stalled']:8d} / {s['valid']:8d}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--image", default="64x48", help="the dilate Image's WxH (default 64x48)")
    ap.add_argument("--samples", type=int, default=6, help="samples back to back (default 6)")
    ap.add_argument("--no-watch", action="store_true", help="no per-stage stall count (faster)")
    ap.add_argument("--only", choices=["laserscan", "image"], help="one case only")
    args = ap.parse_args(argv)
    import pytest

    from tests.support.rtltools import TB_DIR, cocotb_verilator

    with pytest.MonkeyPatch.context() as mp, tempfile.TemporaryDirectory(
            prefix="rosfpga-wire-") as tmp:
        cocotb_verilator(mp)
        mp.syspath_prepend(str(TB_DIR))
        work = Path(tmp)
        cases = []
        if args.only in (None, "laserscan"):
            cases.append(ROOT / "data" / "fpga_laserscan_min_cdr.yaml")
        if args.only in (None, "image"):
            cases.append(image_config(args.image, work))
        for k, path in enumerate(cases):
            (work / str(k)).mkdir()
            report(measure(path, args.samples, not args.no_watch, work / str(k)),
                   not args.no_watch)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
