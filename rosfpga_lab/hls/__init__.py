"""The design flow of Figure 4: node configuration -> generated HLS C++ -> C simulation.

The developer provides (a) the ROS message definition (from :mod:`rosfpga_lab.msg`), (b) the
node configuration (a YAML file, :func:`load_config`) and (c) the application; the generator
emits (d) the subscriber and (e) the publisher in HLS C++, with the application top, the top
level, a testbench, a Makefile for C simulation with g++ (against the lab's stand-ins for
Xilinx's HLS headers, ``include/``) and a Vivado HLS project script::

    from rosfpga_lab.hls import load_config, generate, run_csim, count_sloc
    config = load_config("data/fpga_dilate_rgba8.yaml")
    generate(config, "build/fpga_dilate")             # rosfpga-lab generate CONFIG -o DIR
    result = run_csim("build/fpga_dilate", frames)    # make + run the testbench
    count_sloc("build/fpga_dilate")                   # rosfpga-lab sloc DIR (Table 1)
"""

from rosfpga_lab.hls.config import (
    ENCODINGS, OPS, ApplicationConfig, FifoConfig, ImageConfig, NodeConfig, NodeSection,
    TopicConfig, load_config, parse_config, ros_name_problem,
)
from rosfpga_lab.hls.csim import CsimResult, build_csim, run_csim
from rosfpga_lab.hls.errors import ConfigError, CsimError, GenerateError, HlsError
from rosfpga_lab.hls.generator import (
    GenerationResult, generate, pipeline_for, publisher_header_fields, render, sample_frames,
    sample_image, subscriber_header_fields,
)
from rosfpga_lab.hls.sloc import PAPER_TABLE1, SlocTable, count_sloc, format_table, sloc

__all__ = [
    "ENCODINGS", "OPS", "PAPER_TABLE1", "ApplicationConfig", "ConfigError", "CsimError",
    "CsimResult", "FifoConfig", "GenerateError", "GenerationResult", "HlsError", "ImageConfig",
    "NodeConfig", "NodeSection", "SlocTable", "TopicConfig", "build_csim", "count_sloc",
    "format_table", "generate", "load_config", "parse_config", "pipeline_for",
    "publisher_header_fields", "render", "ros_name_problem", "run_csim", "sample_frames",
    "sample_image", "sloc", "subscriber_header_fields",
]
