"""The RTL run that notebook 08 shows: a small circuit, two frames, and the dump shipped in data/.

One owner for what the notebook, the script that made ``data/rtl_demo.vcd`` and the test that
regenerates it share: the circuit (a 16x8 ``rgba8`` 3x3 dilate), the two input frames (the
first refused for its width, the second good), the simulator settings (random input gaps and
40 % output backpressure, a fixed seed) and the signals kept in the dump. With a simulator the
notebook runs this live; without one it reads the shipped dump, made by Icarus Verilog::

    python data/make_rtl_demo_dump.py            # rewrites data/rtl_demo.vcd (needs iverilog)

:func:`run_demo` takes any other configuration too: its circuit is
:func:`~rosfpga_lab.rtl.sim.design_from_config`'s (a generated top for any type but Image on
TCPROS) and its frames generate's test frames (a good one, a refused one, another good one),
with the same testbench and dump.
"""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.hls import sample_image
from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl.params import RtlParams
from rosfpga_lab.rtl.sim import RtlResult, build, design_from_config, run

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


def demo_config() -> NodeConfig:
    """The demo's node configuration."""
    return parse_config(DEMO_YAML, source="rosfpga_lab.rtl.demo")


def demo_frames(config: NodeConfig | None = None) -> tuple[bytes, bytes]:
    """The two TCPROS frames: one 15 pixels wide (refused: width), then the sample picture."""
    config = config or demo_config()
    picture = sample_image(config)
    refused = image_frame(picture[:, :REFUSED_WIDTH], config.image.encoding, seq=1,
                          stamp=(1_700_000_000, 0), frame_id="camera")
    good = image_frame(picture, config.image.encoding, seq=2, stamp=(1_700_000_000, 33_000_000),
                       frame_id="camera")
    return refused, good


def run_demo(vcd: str | Path | None = None, *, simulator: str | None = None,
             config: NodeConfig | None = None, gap: int = DEMO_GAP, bp: int = DEMO_BP,
             seed: int = DEMO_SEED) -> RtlResult:
    """Build and simulate the demo circuit on :func:`demo_frames` (another configuration's
    circuit on its test frames, see the module docstring), optionally dumping a VCD.

    Raises:
        SimulatorMissingError: no simulator; RtlError: the configuration has no RTL
        (:func:`~rosfpga_lab.rtl.sim.design_from_config`) or the simulation failed.
    """
    from rosfpga_lab.hls import sample_frames

    config = config or demo_config()
    design = design_from_config(config)
    sim = build(design, simulator=simulator, trace=vcd is not None)
    if isinstance(design, RtlParams):
        refused, good = demo_frames(config)
        frames = refused + good
    else:
        frames = sample_frames(config)[0]
    return run(sim, frames, gap=gap, bp=bp, seed=seed, vcd=vcd)


def shipped_dump() -> Path | None:
    """``data/rtl_demo.vcd`` of the checkout the lab runs from, or None when it is not there."""
    here = Path(__file__).resolve()
    for root in (here.parents[2], Path.cwd(), Path.cwd().parent):
        path = root / "data" / DUMP_NAME
        if path.is_file():
            return path
    return None
