"""The RTL run that notebook 08 shows and ``rosfpga-lab rtl demo`` prints: a configuration's
generated top, a few frames, and the dump shipped in data/.

One owner for what the notebook, the command, the script that made ``data/rtl_demo.vcd`` and the
test that regenerates it share: the circuit (by default a 16x8 ``rgba8`` 3x3 dilate), the input
frames, the simulator settings (random input gaps and 40 % output backpressure, a fixed seed)
and the signals kept in the dump. With a simulator the notebook runs this live; without one it
reads the shipped dump, made by Icarus Verilog::

    python data/make_rtl_demo_dump.py            # rewrites data/rtl_demo.vcd (needs iverilog)

How this works: every configuration runs its generated top (:func:`demo_design`, what
``rosfpga-lab generate`` writes into ``rtl/``), ``sensor_msgs/Image`` on TCPROS included, with
the same testbench and dump. Its frames (:func:`demo_inputs`) are, for Image on TCPROS, one 15
pixels wide (refused: width) and the sample picture (:func:`demo_frames`); for any other
configuration generate's test frames (``hls.vectors``: a good one, a refused one, another good
one; records of a sample length and a CDR payload on ``wire: cdr``). :func:`demo_report` sets
beside each input frame the subscriber's decision, the bytes the circuit sent for it and the
bytes the Python models publish for it (:func:`rosfpga_lab.rtl.project.model_output`: the
layout's ``MessagePipeline`` or ``CdrPipeline``, Image included).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.config.vocabulary import CDR_WIRE
from rosfpga_lab.hls import sample_image
from rosfpga_lab.hls.errors import HlsError
from rosfpga_lab.hls.generic import GenericSpec
from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.sim import RtlResult, build, design_from_config, run, status_table

#: The circuit of the demo: the paper's dilate on a frame small enough to read clock by clock.
DEMO_YAML = """\
node: {name: /fpga_rtl_demo}
subscriber: {topic: /image_raw}
publisher: {topic: /image_dilated}
image: {width: 16, height: 8, encoding: rgba8}
application: {op: dilate, ksize: 3}
fifo: {input_depth: 64, output_depth: 64, axis_depth: 4}
"""
#: Input gaps and output backpressure (per mille of clocks) and the testbench's seed.
DEMO_GAP, DEMO_BP, DEMO_SEED = 100, 400, 7
#: Width of the refused first frame (the circuit is built for 16).
REFUSED_WIDTH = 15
#: File name of the shipped dump in the repository's ``data/``.
DUMP_NAME = "rtl_demo.vcd"
#: The simulator that made the shipped dump (its dumps are what the drift test compares).
DUMP_SIMULATOR = "iverilog"
#: The subscriber's name for an accepted frame (code 0 of every status table).
ACCEPTED = "SUB_OK"


def demo_config() -> NodeConfig:
    """The demo's node configuration."""
    return parse_config(DEMO_YAML, source="rosfpga_lab.rtl.demo")


def demo_frames(config: NodeConfig | None = None) -> tuple[bytes, bytes]:
    """The two TCPROS frames of an Image configuration: one 15 pixels wide (refused: width), then
    the sample picture."""
    config = config or demo_config()
    picture = sample_image(config)
    refused = image_frame(picture[:, :REFUSED_WIDTH], config.image.encoding, seq=1,
                          stamp=(1_700_000_000, 0), frame_id="camera")
    good = image_frame(picture, config.image.encoding, seq=2, stamp=(1_700_000_000, 33_000_000),
                       frame_id="camera")
    return refused, good


def demo_inputs(config: NodeConfig | None = None) -> list[bytes]:
    """The frames the demo feeds ``config``'s circuit (see the module docstring), each a
    4-byte length and its body (a TCPROS frame, or on ``wire: cdr`` a CDR record)."""
    from rosfpga_lab.hls import sample_frames

    config = config or demo_config()
    if config.is_image and config.wire != CDR_WIRE:
        return list(demo_frames(config))
    return split_records(sample_frames(config)[0])


def split_records(data: bytes) -> list[bytes]:
    """``data`` cut into its whole length-prefixed frames (TCPROS frames and CDR records are
    framed alike: a 4-byte little-endian length, then that many bytes), prefixes kept."""
    from rosfpga_lab.tcpros.frame import FrameDecoder, encode_frame

    return [encode_frame(body) for body in FrameDecoder().feed(data)]


def demo_design(config: NodeConfig | None = None) -> GenericSpec:
    """The generated top the demo simulates for ``config``, ``sensor_msgs/Image`` on TCPROS too
    (built from :func:`~rosfpga_lab.hls.generic.spec_from_config` whatever
    :func:`~rosfpga_lab.rtl.sim.design_from_config` picks for it).

    Raises:
        RtlError: ``op: custom`` (no RTL) or a configuration the generator refuses.
    """
    from rosfpga_lab.hls.generic import spec_from_config

    config = config or demo_config()
    design = design_from_config(config)      # its refusals name the configuration
    if isinstance(design, GenericSpec):
        return design
    try:
        return spec_from_config(config)
    except HlsError as exc:
        where = str(config.path) if config.path else "the configuration"
        raise RtlError(f"{where}: no generated circuit to simulate: {exc}") from None


def run_demo(vcd: str | Path | None = None, *, simulator: str | None = None,
             config: NodeConfig | None = None, gap: int = DEMO_GAP, bp: int = DEMO_BP,
             seed: int = DEMO_SEED, cache: bool = True) -> RtlResult:
    """Build and simulate ``config``'s generated top (the demo circuit by default) on
    :func:`demo_inputs`, optionally dumping a VCD.

    Raises:
        SimulatorMissingError: no simulator; RtlError: the configuration has no RTL
        (:func:`demo_design`) or the simulation failed.
    """
    config = config or demo_config()
    sim = build(demo_design(config), simulator=simulator, trace=vcd is not None, cache=cache)
    return run(sim, b"".join(demo_inputs(config)), gap=gap, bp=bp, seed=seed, vcd=vcd)


@dataclass(frozen=True)
class DemoFrame:
    """One input frame of a demo run beside the models.

    Attributes:
        offset: where it starts in the input stream.
        size: its bytes (length prefix included).
        status: the subscriber's decision (a name of the status table; ``""`` when it decided
            nothing: the input ended inside the frame).
        field: the field that status is about (``"frame accepted"`` for ``SUB_OK``).
        output: what the circuit sent for it (empty when it refused it).
        expected: what the Python models publish for it (empty when they refuse it).
    """

    offset: int
    size: int
    status: str
    field: str
    output: bytes
    expected: bytes

    @property
    def exact(self) -> bool:
        """The circuit and the models agree on this frame, byte for byte (both refusing counts)."""
        return self.output == self.expected


def demo_report(config: NodeConfig, frames: list[bytes], result: RtlResult) -> list[DemoFrame]:
    """Each of ``frames`` with the circuit's decision and output (``result``, a run on them back
    to back) beside the models' output for it, given the frames before it (the Image model
    numbers ``header.seq`` as the circuit does).

    Raises:
        PipelineConfigError: ``op: custom`` (no model of the user's C++).
    """
    from rosfpga_lab.rtl.project import model_output

    fields = dict(status_table(demo_design(config)))
    decided = dict(result.status)
    sent = iter(split_records(result.output))
    report: list[DemoFrame] = []
    offset, before = 0, b""
    for frame in frames:
        status = decided.get(offset, "")
        upto = model_output(config, b"".join(frames[:len(report) + 1]))
        report.append(DemoFrame(offset, len(frame), status, fields.get(status, "?"),
                                next(sent, b"") if status == ACCEPTED else b"",
                                upto[len(before):]))
        before, offset = upto, offset + len(frame)
    return report


def format_demo(report: list[DemoFrame]) -> str:
    """One line per frame: where it was, what the subscriber decided, what came out beside the
    models."""
    lines = []
    for k, f in enumerate(report, 1):
        said = (f"{f.status} ({f.field})" if f.status else "no decision (cut short)")
        if f.output or f.expected:
            what = (f"{len(f.output):,} bytes out, equal to the models'" if f.exact else
                    f"{len(f.output):,} bytes out, the models {len(f.expected):,}: DIFFERENT")
        else:
            what = "nothing out, the models refuse it too"
        lines.append(f"frame {k} at byte {f.offset:,} ({f.size:,} bytes): {said}; {what}")
    return "\n".join(lines)


def shipped_dump() -> Path | None:
    """``data/rtl_demo.vcd`` of the checkout the lab runs from, or None when it is not there."""
    here = Path(__file__).resolve()
    for root in (here.parents[2], Path.cwd(), Path.cwd().parent):
        path = root / "data" / DUMP_NAME
        if path.is_file():
            return path
    return None
