"""The circuit as a circuit: Verilog RTL of the data path, its simulation and synthesis.

The Verilog (``verilog/``, module prefix ``rfl_``) is the paper's conventional design of the
same circuit the HLS C++ describes: ``rfl_subscriber`` (TCPROS frame in, fields checked, pixel
bytes out), ``rfl_fifo2axi`` (Figure 7), the application ``rfl_morph``, ``rfl_axi2fifo``,
``rfl_publisher`` (TCPROS frame out) and ``rfl_fifo``, joined by ``rfl_top``. Parameters come
from the node configuration (:func:`rtl_params`); :func:`build` and :func:`run` simulate it with
Icarus Verilog or Verilator through the file-based testbench ``tb/rfl_tb.v``::

    from rosfpga_lab.rtl import build, load_config, rtl_params, run
    sim = build(rtl_params(load_config("data/fpga_dilate_rgba8.yaml")))
    result = run(sim, frames, gap=100, bp=500)   # result.output: the frames sent

:mod:`rosfpga_lab.rtl.vcd` reads waveform dumps into per-clock arrays,
:mod:`rosfpga_lab.rtl.synth` synthesizes the modules with Yosys,
:mod:`rosfpga_lab.rtl.timing` places and routes them with nextpnr-ecp5 (Fmax against the clock) and
:mod:`rosfpga_lab.rtl.sloc` counts their lines for the paper's Table 1. A message type other
than ``sensor_msgs/Image`` gets the generic circuit of :mod:`rosfpga_lab.rtl.generic` (walkers
stepping through a generated program, one instruction per field of the message), which
:func:`build` and :func:`run` simulate the same way (``build(design_from_config(config))``).
"""

from rosfpga_lab.rtl.errors import RtlError, SimulatorMissingError
from rosfpga_lab.rtl.params import OP_CODES, RtlParams, load_config, node_wrapper, rtl_params, status_header
from rosfpga_lab.config.vocabulary import SIMULATORS
from rosfpga_lab.rtl.sim import (
    STREAMS, Design, RtlBuild, RtlResult, StreamTiming, build, design_from_config,
    find_simulator, run, simulator_missing_reason, verilog_sources, write_sources,
)

__all__ = [
    "OP_CODES", "SIMULATORS", "STREAMS", "Design", "RtlBuild", "RtlError", "RtlParams",
    "RtlResult", "SimulatorMissingError", "StreamTiming", "build", "design_from_config",
    "find_simulator", "load_config", "node_wrapper", "rtl_params", "run",
    "simulator_missing_reason", "status_header", "verilog_sources", "write_sources",
]
