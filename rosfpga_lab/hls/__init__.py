"""The design flow of Figure 4: node configuration -> generated HLS C++ -> C simulation.

The developer provides (a) the ROS message definition (from :mod:`rosfpga_lab.msg`), (b) the
node configuration (a YAML file, :func:`rosfpga_lab.config.load_config`) and (c) the application; the generator
emits (d) the subscriber and (e) the publisher in HLS C++, with the application, the top
level, a testbench, a Makefile for C simulation with g++ (against the lab's stand-ins for
Xilinx's HLS headers, ``include/``) and an HLS project script: for Vitis HLS by default, for
the paper's Vivado HLS with ``hls: {flavour: vivado}`` (:data:`generic.HLS_TOOLS`)::

    from rosfpga_lab.config import load_config
    from rosfpga_lab.hls import generate, run_csim, count_sloc
    config = load_config("data/fpga_dilate_rgba8.yaml")
    generate(config, "build/fpga_dilate")             # rosfpga-lab generate CONFIG -o DIR
    result = run_csim("build/fpga_dilate", frames)    # make + run the testbench
    count_sloc("build/fpga_dilate")                   # rosfpga-lab sloc DIR (Table 1)

On the shell: ``rosfpga-lab generate CONFIG -o DIR``, then ``make -C DIR csim`` (g++:
"csim: PASS: output equals tb_expected.bin"; ``make csim INPUT=frames.bin [EXPECTED=file]``
writes output bytes and AXI4-Stream beats to ``csim_out/``), ``make -C DIR rtlsim``, ``synth``
(:mod:`rosfpga_lab.rtl`). A bad configuration is refused with ``file:line: key: problem``
before anything is written; regenerating into a used directory needs ``--force``, which
deletes only what the previous generation wrote. The application is the lab's dilate / erode
(its own line buffer and window) or your ``stream_filter()`` with ``application: {op: custom,
source: my_filter.cpp}``. ``include/`` holds the lab's g++ stand-ins for ``ap_int.h``,
``ap_axi_sdata.h``, ``hls_stream.h``; the tool versions each flavour is for are
:data:`generic.HLS_TOOLS` (neither tried here: the lab has no Xilinx tools).

One engine for every message type (issue 19, 28): the configuration names the type, the array
the application processes and, optionally, checks, maxima and the user's ``.msg`` folders (the
keys: :mod:`rosfpga_lab.config.schema`); ``hw.layout.layout_from_config(config)`` derives the
one walk over the frame. The modules, in the flow's order: ``compiler`` compiles the layout to
the walkers' program (``program``); ``generic`` renders the project from it (the templates of
``templates/``); ``circuit`` keeps one record per configuration (``circuit_of(config)``: its
layouts, spec, program, clocks and Python models, derived once, what the component and the
tools take); ``vectors`` makes the test frames and the models' output; ``generator`` writes
it all; ``csim`` builds and runs the testbench; ``sloc`` counts lines. ``wire: cdr`` writes the
same walkers for ROS 2's CDR samples; ``sensor_msgs/Image`` is one type among the others, its
``data`` framed as video for the 2-D application. The shipped examples are mapped in
``data/README.md``. Golden files of the generated code are in ``tests/golden/hls/``; after a
deliberate template change run ``ROSFPGA_UPDATE_GOLDEN=1 python -m pytest
tests/hls/test_generate.py -k golden`` and review ``git diff tests/golden/hls``.
"""

from rosfpga_lab.hls.csim import CsimResult, build_csim, run_csim
from rosfpga_lab.hls.errors import CsimError, GenerateError, HlsError
from rosfpga_lab.hls.generator import GenerationResult, generate
from rosfpga_lab.hls.generic import publisher_header_fields, render, subscriber_header_fields
from rosfpga_lab.hls.sloc import PAPER_TABLE1, SlocTable, count_sloc, format_table, sloc
from rosfpga_lab.hls.vectors import sample_frames, sample_image

__all__ = [
    "PAPER_TABLE1", "CsimError", "CsimResult", "GenerateError", "GenerationResult", "HlsError",
    "SlocTable", "build_csim", "count_sloc", "format_table", "generate", "publisher_header_fields",
    "render", "run_csim", "sample_frames", "sample_image", "sloc", "subscriber_header_fields",
]
