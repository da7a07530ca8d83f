"""Place and route every shipped example's generated top at its clock, at several seeds (prints
figures; not a test).

For each ``data/fpga_*.yaml`` (Image on TCPROS and CDR, LaserScan and the custom message on both
wires): ``rtl.timing.place_and_route`` (Yosys ``synth_ecp5``, nextpnr-ecp5, the lab's device) of
the generated top, as ``rosfpga-lab rtl timing CONFIG --seed N`` runs it, one row per seed:
Fmax against the configuration's clock, LUT4, flip-flops, block RAMs, multipliers, and the clocks
of the example's first test frame by the circuit record (``circuit_of(config).frame_clocks``,
which tests/rtl/test_cycles.py holds equal to the RTL). ``--random N`` adds N message definitions
drawn as the property test draws them (tests/hw/test_walker.py ``definitions``, small maxima as
tests/rtl/test_timing.py takes them), placed at 100 MHz; ``--pick K`` places only the K-th of
them (1-based, repeatable: ``--random 4 --pick 2``). The tools' versions are printed first.

Usage: ``python tests/benchmarks/bench_timing_examples.py [--seeds 1 2 3] [--only laserscan]
[--random N [--pick K ...]] [--no-examples]``
"""

from __future__ import annotations

import argparse
import struct
import sys
import tempfile
import time
from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hls.vectors import sample_frames
from rosfpga_lab.rtl.errors import TimingError
from rosfpga_lab.rtl.timing import choose_tools, format_timing, place_and_route, place_and_route_dir

ROOT = Path(__file__).resolve().parents[2]
HEADER = (f"{'configuration':<30}{'type':<22}{'wire':<8}{'seed':>5}{'Fmax':>8}{'clock':>7}"
          f"{'met':>5}{'LUT4':>7}{'FF':>7}{'BRAM':>5}{'DSP':>4}{'clocks/frame':>14}")


def row(name: str, type_name: str, wire: str, seed: int, report, clocks: str) -> str:
    return (f"{name:<30}{type_name:<22}{wire:<8}{seed:>5}{report.fmax_mhz:>8.1f}"
            f"{report.clock_mhz:>7g}{'yes' if report.met else 'NO':>5}"
            f"{report.used('TRELLIS_COMB'):>7,}{report.used('TRELLIS_FF'):>7,}"
            f"{report.used('DP16KD'):>5}{report.used('MULT18X18D'):>4}{clocks:>14}")


def examples(only: str | None) -> list[Path]:
    paths = sorted((ROOT / "data").glob("fpga_*.yaml"))
    return [p for p in paths if only is None or only in p.stem]


def first_frame_clocks(config) -> str:
    """Clocks of the example's first test frame (a TCPROS frame or a CDR record, both a 4-byte
    little-endian length first), from its first byte in to its last byte out (the circuit
    record's cycle model)."""
    frames, _expected = sample_frames(config)
    first = frames[:4 + struct.unpack_from("<I", frames)[0]]
    return f"{circuit_of(config).frame_clocks(first).total:,}"


def random_tops(count: int, seeds: list[int], pick: list[int] | None = None) -> None:
    """Place and route ``count`` generated tops of message definitions the property test draws
    (only the ``pick``-th ones, 1-based, when given)."""
    from hypothesis import HealthCheck, Phase, given, settings

    from rosfpga_lab.hls.generic import spec_from_layout
    from rosfpga_lab.hw.layout import Action, StepKind, derive_layout
    from rosfpga_lab.rtl.generic import generic_rtl_files

    sys.path.insert(0, str(ROOT))  # run as a script: the suite's strategy lives in tests/
    from tests.hw.test_walker import definitions

    drawn: list = []  # derandomized, as the suite draws them: the same N every run

    @settings(max_examples=count, derandomize=True, database=None, deadline=None,
              phases=[Phase.generate], suppress_health_check=list(HealthCheck))
    @given(definitions())
    def collect(definition) -> None:
        drawn.append(definition)

    collect()
    for k, (reg, type_name, stream) in enumerate(drawn[:count]):
        if pick and k + 1 not in pick:
            continue
        layout = derive_layout(reg, type_name, stream=stream, stream_length=3)
        small = {s.path: 3 for s in layout.steps[1:] if s.kind is StepKind.LENGTH
                 and s.action is not Action.STREAM and not s.label.endswith("[] length")}
        layout = derive_layout(reg, type_name, stream=stream, stream_length=3, limits_=small)
        with tempfile.TemporaryDirectory(prefix="rosfpga-timing-random-") as work:
            for name, text in generic_rtl_files(spec_from_layout(layout, reg, op="dilate",
                                                                 ksize=3)).items():
                (Path(work) / name).write_bytes(text)
            for seed in seeds:
                report = place_and_route_dir(work, 100.0, seed=seed)
                print(row(f"random #{k + 1}", type_name[-21:], "tcpros", seed, report, "-"),
                      flush=True)
                if not report.met:
                    path = [line for line in format_timing(report).splitlines()
                            if line.startswith(("critical path", "  through"))]
                    print("\n".join(f"    {line.strip()}" for line in path), flush=True)
            print(f"    {type_name}: {len(layout.steps)} layout steps, stream {stream}",
                  flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--only", help="only the examples whose file name contains this")
    parser.add_argument("--examples", action=argparse.BooleanOptionalAction, default=True,
                        help="place the shipped examples (default); --no-examples: only --random")
    parser.add_argument("--random", type=int, default=0, metavar="N",
                        help="also N random message definitions (property test's strategy)")
    parser.add_argument("--pick", type=int, action="append", metavar="K",
                        help="only the K-th of the --random definitions (1-based; repeatable)")
    args = parser.parse_args(argv)
    if args.pick and not all(1 <= k <= args.random for k in args.pick):
        parser.error(f"--pick takes 1 to --random N (got {args.pick} with --random {args.random})")
    yosys, nextpnr = choose_tools()
    print(f"tools: {yosys.describe()}; {nextpnr.describe()}", flush=True)
    print(HEADER, flush=True)
    start = time.perf_counter()
    for path in examples(args.only) if args.examples else []:
        config = load_config(path)
        clocks = first_frame_clocks(config)
        for seed in args.seeds:
            try:
                report = place_and_route(config, seed=seed)
            except TimingError as exc:  # e.g. a whole 640x480 frame buffered does not fit
                print(f"{path.stem:<30}{config.subscriber.type:<22}{config.wire:<8}{seed:>5}  "
                      f"not placed: {str(exc).split(';')[0]}", flush=True)
                break
            print(row(path.stem, config.subscriber.type, config.wire, seed, report, clocks),
                  flush=True)
    if args.random:
        random_tops(args.random, args.seeds, args.pick)
    print(f"{time.perf_counter() - start:.0f} s in all", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
