"""The design flow of Figure 4: node configuration -> generated HLS C++ -> C simulation.

The developer provides (a) the ROS message definition (from :mod:`rosfpga_lab.msg`), (b) the
node configuration (a YAML file, :func:`rosfpga_lab.config.load_config`) and (c) the application; the generator
emits (d) the subscriber and (e) the publisher in HLS C++, with the application top, the top
level, a testbench, a Makefile for C simulation with g++ (against the lab's stand-ins for
Xilinx's HLS headers, ``include/``) and an HLS project script: for Vitis HLS by default, for
the paper's Vivado HLS with ``hls: {flavour: vivado}`` (:data:`generator.HLS_TOOLS`)::

    from rosfpga_lab.config import load_config
    from rosfpga_lab.hls import generate, run_csim, count_sloc
    config = load_config("data/fpga_dilate_rgba8.yaml")
    generate(config, "build/fpga_dilate")             # rosfpga-lab generate CONFIG -o DIR
    result = run_csim("build/fpga_dilate", frames)    # make + run the testbench
    count_sloc("build/fpga_dilate")                   # rosfpga-lab sloc DIR (Table 1)
"""

from rosfpga_lab.hls.csim import CsimResult, build_csim, run_csim
from rosfpga_lab.hls.errors import CsimError, GenerateError, HlsError
from rosfpga_lab.hls.generator import (
    GenerationResult, generate, publisher_header_fields, render, sample_frames,
    sample_image, subscriber_header_fields,
)
from rosfpga_lab.hls.sloc import PAPER_TABLE1, SlocTable, count_sloc, format_table, sloc

__all__ = [
    "PAPER_TABLE1", "CsimError", "CsimResult", "GenerateError", "GenerationResult", "HlsError",
    "SlocTable", "build_csim", "count_sloc", "format_table", "generate", "publisher_header_fields",
    "render", "run_csim", "sample_frames", "sample_image", "sloc", "subscriber_header_fields",
]
