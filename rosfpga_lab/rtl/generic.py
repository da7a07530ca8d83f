"""Verilog of generated projects for any message type, ``sensor_msgs/Image`` included (every RTL
tool runs it; the hand-written Image circuit, ``verilog/``, is the exhibit beside Table 1).

How this works: the modules of ``generic/`` are written once and parameterized:
``rfl_gsubscriber`` and ``rfl_gpublisher`` walk a frame by stepping through a program, one
instruction per field, that is generated for each configuration into ``rfl_layout.vh`` (from
:class:`rosfpga_lab.hls.program.Program`, the same program as the HLS C++'s ``layout.h``, with a
comment per field naming it); ``rfl_elem_pack`` turns the streamed array's bytes into AXI4-Stream
beats of one element (TUSER first, TLAST last), ``rfl_window1d`` is the 1-D application (sliding
max/min over KSIZE elements, pass-through) and ``rfl_elem_unpack`` turns beats back into bytes;
``rfl_gtop`` joins them with the lab's ``rfl_fifo`` and ``rfl_slice``. ``rfl_node.v`` sets the
parameters of one configuration, with the ports of the hand circuit's ``rfl_node`` (so the lab's
testbench ``rfl_tb.v`` and its fast harness run either top unchanged). The same
walkers read and write CDR (``wire: cdr``): the program's alignment, ``OP_ENCAP`` and strings
with their NUL (:mod:`rosfpga_lab.hls.program`). A stream with a video shape
(:attr:`GenericSpec.video`) is packed a pixel per beat with TLAST ending each line, and
``rfl_gtop`` (``VIDEO``) runs the video project's 2-D ``rfl_morph`` instead of ``rfl_window1d``.

Timing (``rosfpga-lab rtl timing`` places and routes the generated top for an ECP5 at the
configuration's clock): the walkers have no multiplier (an array's bytes are its count shifted
by log2 of its element size, which the program word carries; an array of messages' fewest
bytes are added up bit by bit), hold the current instruction in a register, keep the bytes left
as registers and settle each decision's arithmetic into registers for two clocks before
deciding; ``rfl_window1d`` keeps its fold as it goes (one comparison per clock); a register
slice sits between the publisher and the tx FIFO. Bodies still move a byte per clock; a field
costs a few clocks more than before (S_FCHK, S_DECODE, S_COUNTED and S_FINISH take three clocks
each, one before; an array of messages 1 + bits(elem_min) more).
"""

from __future__ import annotations

from pathlib import Path

import jinja2

from rosfpga_lab.hls.generic import GenericSpec, beat_shape, context, environment
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.tools import NODE_FILE, TB_DIR, VERILOG_DIR

GENERIC_VERILOG_DIR = Path(__file__).resolve().parent / "generic"
#: ``rfl_window1d``'s OP parameter per operation.
OP_CODES_1D = {"dilate": 0, "erode": 1, "passthrough": 2}
#: ``rfl_window1d``'s KIND parameter per element kind (how elements are ordered).
KIND_CODES = {"unsigned": 0, "signed": 1, "float": 2}
#: The static Verilog of every generic project (``generic/``), in data-path order.
GENERIC_MODULES = ("rfl_gsubscriber.v", "rfl_elem_pack.v", "rfl_window1d.v", "rfl_elem_unpack.v",
                   "rfl_gpublisher.v", "rfl_gtop.v")
#: The lab's modules every generic project takes from ``verilog/`` (FIFO, register slice).
LAB_MODULES = ("rfl_fifo.v", "rfl_slice.v")
#: The application of a video stream (the video project's), beside ``GENERIC_MODULES``.
VIDEO_APP = "rfl_morph.v"
#: The generated include holding the walk (one instruction per field).
LAYOUT_INCLUDE = "rfl_layout.vh"
TEMPLATES = Path(__file__).resolve().parent / "templates"


def out_depth(spec: GenericSpec) -> int:
    """Beats of ``rfl_gtop``'s FIFO after the application: a whole stream (and 2) when the
    publisher starts a frame only once the subscriber has read all of it, ``axis_depth`` with
    streaming early release (:attr:`rosfpga_lab.hls.program.Program.stream_early`). Back to back
    the next frame's stream queues behind it and flows as the publisher takes this one's (the
    subscriber then waits only if the publisher reaches its stream later than the subscriber
    did: ``hls.program.stream_clocks`` assumes it does not)."""
    if spec.program.stream_early is not None:
        return max(2, spec.axis_depth)
    return max(spec.axis_depth, beat_shape(spec)["count"] + 2)


def generic_params(spec: GenericSpec) -> dict[str, int]:
    """``rfl_gtop``'s parameters for a generic project (with a video stream: a beat per pixel,
    ``VIDEO``, ``WIDTH`` and ``HEIGHT``; :func:`rosfpga_lab.hls.generic.beat_shape`)."""
    prog = spec.program
    beat = beat_shape(spec)
    carry = max(1, prog.carry_bytes)
    video = {} if spec.video is None else {"VIDEO": 1, "WIDTH": spec.video.width,
                                           "HEIGHT": spec.video.height}
    return {
        "EBYTES": beat["bytes"], "LENGTH": beat["count"],
        "KSIZE": spec.ksize if spec.op in ("dilate", "erode") else 1,
        "OP": OP_CODES_1D[spec.op], "KIND": KIND_CODES[spec.kind],
        "CARRY_BYTES": carry, "CW": max(1, (carry - 1).bit_length()),
        "MIN_BODY": prog.min_body, "MAX_FRAME": prog.max_frame,
        "RX_DEPTH": spec.input_depth, "TX_DEPTH": spec.output_depth,
        "AXIS_DEPTH": spec.axis_depth, "OUT_DEPTH": out_depth(spec),
        "SEQ_START": prog.seq_start, "EARLY": int(prog.stream_early is not None), **video,
    }


def node_wrapper(spec: GenericSpec, note: str) -> str:
    """``rfl_node.v``: ``rfl_gtop`` with the configuration's parameters (the testbench's DUT)."""
    params = generic_params(spec)
    body = ",\n".join(f"        .{k}({v})" for k, v in params.items())
    return (f"// rfl_node -- rfl_gtop with the parameters of one node configuration "
            f"({spec.program.type_in}, stream {spec.stream_name}).\n// {note}\n"
            "module rfl_node (\n"
            "    input clk, input rst_n,\n"
            "    input [7:0] s_tdata, input s_tvalid, output s_tready,\n"
            "    output [7:0] m_tdata, output m_tvalid, input m_tready,\n"
            "    output frame_start, output status_valid, output [7:0] status, output busy,\n"
            "    output [7:0] framing);\n"
            "    // no framing flags: the walkers frame each array themselves (the port is the\n"
            "    // hand circuit's, so that one testbench and one harness take either top)\n"
            "    assign framing = 8'd0;\n"
            f"    rfl_gtop #(\n{body}\n    ) u_top (\n"
            "        .clk(clk), .rst_n(rst_n),\n"
            "        .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),\n"
            "        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),\n"
            "        .frame_start(frame_start), .status_valid(status_valid), .status(status),\n"
            "        .busy(busy));\nendmodule\n")


def testbench() -> str:
    """The lab's file-based testbench ``rfl_tb.v``: the generic ``rfl_node`` has the hand
    circuit's ports (an 8-bit status, framing flags tied to 0), so it is taken as it is."""
    return (TB_DIR / "rfl_tb.v").read_text(encoding="utf-8")


def generic_rtl_files(spec: GenericSpec) -> dict[str, bytes]:
    """``{file name: bytes}`` of a generic project's ``rtl/`` (empty for ``op: custom``)."""
    if spec.op == "custom":
        return {}
    ctx = context(spec)
    env = environment()
    env.loader = jinja2.FileSystemLoader(str(TEMPLATES))
    files = {LAYOUT_INCLUDE: env.get_template(f"{LAYOUT_INCLUDE}.j2").render(ctx).encode()}
    for name in GENERIC_MODULES:
        files[name] = (GENERIC_VERILOG_DIR / name).read_bytes()
    if spec.video is not None:  # the video project's 2-D application
        files[VIDEO_APP] = (VERILOG_DIR / VIDEO_APP).read_bytes()
    for name in LAB_MODULES:
        files[name] = (VERILOG_DIR / name).read_bytes()
    files[NODE_FILE] = node_wrapper(spec, str(ctx["generated_note"])).encode()
    files["rfl_tb.v"] = testbench().encode()
    return files


def project_files(spec: GenericSpec) -> dict[str, bytes]:
    """Every file of a generic project but the test frames: the HLS C++, ``hls_include/`` and
    ``rtl/`` with the lab's fast harness (what ``rosfpga-lab generate`` writes for a
    configuration, for a bare layout)."""
    from rosfpga_lab.hls.csim import HLS_HEADERS, INCLUDE_DIR
    from rosfpga_lab.hls.generic import render_generic
    from rosfpga_lab.hls.rtlbuild import HARNESS_FILES
    from rosfpga_lab.rtl.tools import HARNESS_DIR

    files = {name: text.encode() for name, text in render_generic(spec).items()}
    for header in HLS_HEADERS:
        files[f"hls_include/{header}"] = (INCLUDE_DIR / header).read_bytes()
    rtl = generic_rtl_files(spec)
    for name, data in rtl.items():
        files[f"rtl/{name}"] = data
    for name in HARNESS_FILES if rtl else ():
        files[f"rtl/{name}"] = (HARNESS_DIR / name).read_bytes()
    return files


def simulate_project(project_dir: str | Path, frames: bytes, *, target: str = "rtlsim",
                     simulator: str | None = None, gap: int = 0, bp: int = 0, seed: int = 1,
                     out: str = "sim_out") -> tuple[bytes, list[str]]:
    """Run a generic project's ``make csim`` or ``make rtlsim`` on ``frames`` (the real flow,
    as a student types it) and read back its output bytes and a status name per frame.

    Args:
        project_dir: a project written by ``rosfpga-lab generate`` (not TCPROS Image's).
        frames: TCPROS frames, or for a ``wire: cdr`` project CDR records (each a 4-byte sample
            length and the payload).
        target: ``csim`` or ``rtlsim``.
        simulator: rtlsim: ``iverilog`` or ``verilator`` (default: the first installed).
        gap, bp, seed: rtlsim: random input gaps and output backpressure (per mille), seed.
        out: the output folder inside the project.

    Raises:
        RtlError: the build or the simulation failed, or no simulator is installed.
    """
    import re
    import shutil
    import subprocess

    from rosfpga_lab.rtl.limits import RUN_TIMEOUT
    from rosfpga_lab.rtl.tools import find_simulator, find_tool

    project = Path(project_dir)
    if shutil.which("make") is None:
        raise RtlError("no make on this machine (apt-get install make)")
    (project / out).mkdir(parents=True, exist_ok=True)
    (project / out / "input.bin").write_bytes(frames)
    cmd = ["make", "-s", target, f"INPUT={out}/input.bin", f"OUT={out}", "EXPECTED="]
    if target == "rtlsim":
        sim = find_simulator(simulator)
        cmd += [f"SIM={sim}", f"GAP={gap}", f"BP={bp}", f"SEED={seed}"]
        if sim == "verilator":
            cmd.append(f"VERILATOR={find_tool('verilator') or find_tool('verilator-cli')}")
    try:
        proc = subprocess.run(cmd, cwd=project, capture_output=True, text=True,
                              timeout=RUN_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise RtlError(f"make {target} ran longer than {RUN_TIMEOUT:g} s") from None
    if proc.returncode != 0:
        raise RtlError(f"make {target} in {project} failed:\n{proc.stdout}{proc.stderr}")
    names = re.findall(r"localparam \[7:0\] (SUB_\w+) = 8'd(\d+)",
                       (project / "rtl" / LAYOUT_INCLUDE).read_text()) if target == "rtlsim" else []
    by_code = {"0": "SUB_OK", "1": "SUB_BAD_FRAME_LENGTH", **{c: n for n, c in names}}
    statuses = [by_code.get(word, word) for word in
                (project / out / "status.txt").read_text().split()[1::2]]
    return (project / out / "output.bin").read_bytes(), statuses
