"""``rosfpga-lab generate``'s RTL part: the Verilog beside the HLS C++ in ``DIR/rtl/``.

:func:`generate_project` runs the HLS generator (:func:`rosfpga_lab.hls.generate`) and hands it
the RTL files to write under the same manifest: the lab's Verilog, the status include, the
file-based testbench and ``rfl_node.v`` with the configuration's parameters. The generated
Makefile's ``make rtlsim`` compiles them with Icarus Verilog or Verilator.
"""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.config import CUSTOM, NodeConfig
from rosfpga_lab.config.vocabulary import CDR_WIRE
from rosfpga_lab.hls import GenerationResult, generate
from rosfpga_lab.hls.generator import Progress
from rosfpga_lab.hls.generic import render_generic, spec_from_config
from rosfpga_lab.hls.vectors import sample_frames
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.generic import generic_rtl_files
from rosfpga_lab.rtl.sim import source_files

#: The RTL's folder inside a generated project.
RTL_DIR = "rtl"


def node_sources(config: NodeConfig) -> dict[str, bytes]:
    """``{file name: bytes}`` of the node's Verilog for any configuration: what ``rtl synth`` and
    ``rtl timing`` read (from ``rfl_node``): the generated top ``rosfpga-lab generate`` writes
    into ``rtl/`` (:func:`~rosfpga_lab.rtl.generic.generic_rtl_files`), every type and wire,
    ``sensor_msgs/Image`` on TCPROS included.

    Raises:
        RtlError: ``op: custom`` (the application is the user's C++: no Verilog).
        GenerateError: the generic walk cannot be generated for this configuration.
    """
    if config.application.op == CUSTOM:
        raise RtlError("a custom application has no RTL: the lab's Verilog holds dilate, erode "
                       "and passthrough only")
    return generic_rtl_files(spec_from_config(config))


def generate_project(config: NodeConfig, out_dir: str | Path, *, force: bool = False,
                     progress: Progress | None = None) -> GenerationResult:
    """The HLS C++ project of ``config`` with its RTL in ``rtl/`` (see the module docstring):
    every type, ``sensor_msgs/Image`` included, on either wire, rendered from its circuit layout
    (:mod:`rosfpga_lab.hls.generic`, :mod:`rosfpga_lab.rtl.generic`; a video stream framed as
    video for the 2-D application), for the configured HLS flavour.

    Raises:
        GenerateError: as :func:`rosfpga_lab.hls.generate` and
            :func:`~rosfpga_lab.hls.generic.spec_from_config`.
    """
    say = progress or (lambda _msg: None)
    spec = spec_from_config(config)
    say(f"rendering the walk of {spec.program.type_in}: {len(spec.program.instrs)} instructions")
    texts = render_generic(spec)
    # the generated Verilog and the lab's fast harness around it (make rtlsim on Verilator)
    rtl = {f"{RTL_DIR}/{k}": v for k, v in source_files(spec).items()} if spec.op != CUSTOM else {}
    say("computing the test frames and the Python models' output")
    return generate(config, out_dir, force=force, progress=progress, extra_files=rtl,
                    texts=texts, frames=sample_frames(config))


def model_output(config: NodeConfig, frames: bytes) -> bytes:
    """What the Python models publish for ``frames`` (back to back, each behind its 4-byte
    length; a refused one gives nothing): the configuration's circuit record
    (:func:`~rosfpga_lab.hls.circuit.circuit_of`) walked by ``MessagePipeline`` (TCPROS, Image
    included) or ``CdrPipeline`` (CDR).

    Raises:
        PipelineConfigError: ``op: custom`` (no model of the user's C++).
    """
    import struct

    from rosfpga_lab.hls.circuit import circuit_of
    from rosfpga_lab.hw.errors import PipelineError

    circuit = circuit_of(config)
    if config.wire == CDR_WIRE:
        cdr = circuit.cdr_model()
        run = lambda frame: cdr.run_record(frame).output_record   # noqa: E731
    else:
        pipe = circuit.model()
        run = lambda frame: pipe.process(frame).output_frame      # noqa: E731
    out, at = bytearray(), 0
    while at + 4 <= len(frames):
        frame = frames[at:at + 4 + struct.unpack_from("<I", frames, at)[0]]
        at += len(frame)
        try:
            out += run(frame)
        except PipelineError:
            pass
    return bytes(out)
