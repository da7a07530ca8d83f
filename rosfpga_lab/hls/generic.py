"""The generator of Figure 4 for any message layout: HLS C++ rendered from a :class:`Program`.

How this works: :func:`render_generic` renders the templates of ``templates/generic/`` (and the
Image project's ``connection_headers.cpp.j2``, which knows no field) from one
:class:`GenericSpec`: the node configuration's names, FIFO depths, part and clock, the walk
(:class:`~rosfpga_lab.hls.program.Program`, one instruction per field with its name and type)
and the application (operation, window, how elements are ordered). No template names a field
of any message type: every field-specific line comes from the program's instructions, with a
comment naming the field. The Image project keeps its own templates (the hand-written teaching
version, :mod:`rosfpga_lab.hls.generator`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import jinja2

from rosfpga_lab import __version__
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.generator import HEX_BYTES_PER_LINE, TEMPLATES_DIR, _header_context
from rosfpga_lab.hls.program import MAX_LOOP_DEPTH, Op, Program, Pub, Sub

GENERIC_DIR = TEMPLATES_DIR / "generic"
#: Output file -> template of a generic project (``stream_filter.cpp`` is the user's for custom).
GENERIC_FILES = {
    "layout.h": "generic/layout.h.j2",
    "ros_node.h": "generic/ros_node.h.j2",
    "subscriber.cpp": "generic/subscriber.cpp.j2",
    "publisher.cpp": "generic/publisher.cpp.j2",
    "connection_headers.cpp": "connection_headers.cpp.j2",
    "stream_filter.cpp": "generic/stream_filter.cpp.j2",
    "ros_fpga_node.cpp": "generic/ros_fpga_node.cpp.j2",
    "csim_testbench.cpp": "generic/csim_testbench.cpp.j2",
    "Makefile": "generic/Makefile.j2",
    "run_hls.tcl": "generic/run_hls.tcl.j2",
    "README.md": "generic/README.md.j2",
}
#: The C++ sources of a generic project's testbench, in the Makefile's order.
GENERIC_SOURCES = ("subscriber.cpp", "publisher.cpp", "stream_filter.cpp", "ros_fpga_node.cpp",
                   "connection_headers.cpp", "csim_testbench.cpp")
#: How each element kind is ordered, said in the application's comment.
KIND_NOTES = {
    "unsigned": "unsigned integers.",
    "signed": "two's-complement integers.",
    "float": "IEEE totalOrder (-inf < negatives < -0.0 < +0.0 < positives < +inf; a NaN with "
             "the sign clear ranks above +inf, one with it set below -inf).",
}


@dataclass(frozen=True)
class GenericSpec:
    """Everything a generic project is rendered from.

    Attributes:
        program: the walk (one instruction per field).
        node_name, sub_topic, pub_topic, master_uri, ip_address: the node's names.
        input_depth, output_depth, axis_depth: FIFO depths (bytes, bytes, beats).
        part, clock_mhz: the FPGA part and clock.
        op, ksize: the application (``dilate``, ``erode``, ``passthrough`` or ``custom``).
        kind: how elements are ordered: ``unsigned``, ``signed`` or ``float``.
        stream_name, stream_type: the streamed field, e.g. ``ranges``, ``float32[]``.
        subscriber_header, publisher_header: the connection-header fields of both sides.
        config_name: the configuration's file name (in the generated-file note).
        custom_source: ``op: custom``: the user's C++ file (its ``stream_filter()``).
    """

    program: Program
    node_name: str
    sub_topic: str
    pub_topic: str
    master_uri: str
    ip_address: str
    input_depth: int
    output_depth: int
    axis_depth: int
    part: str
    clock_mhz: float
    op: str
    ksize: int
    kind: str
    stream_name: str
    stream_type: str
    subscriber_header: dict[str, str]
    publisher_header: dict[str, str]
    config_name: str = "<string>"
    custom_source: Path | None = None


def _hex_rows(data: bytes) -> list[str]:
    return [", ".join(f"0x{b:02x}" for b in data[i:i + HEX_BYTES_PER_LINE]) + ","
            for i in range(0, len(data), HEX_BYTES_PER_LINE)]


_SUB_WORD = {Sub.SKIP: "skip", Sub.CARRY: "carry", Sub.CHECK: "check", Sub.STREAM: "stream"}
_PUB_WORD = {Pub.CARRY: "as received", Pub.CONST: "constant", Pub.COUNT: "message number",
             Pub.ZERO: "zero / empty", Pub.STREAM: "the application's output"}


def instruction_rows(prog: Program) -> list[dict[str, object]]:
    """One row per instruction for the templates: codes, offsets and a comment naming the field."""
    rows = []
    depth = 0
    for pc, ins in enumerate(prog.instrs):
        if ins.op == Op.END:
            depth -= 1
        indent = "  " * depth
        if ins.op == Op.DONE:
            comment = "end of the message: the frame must end here"
        elif ins.op == Op.END:
            comment = f"{indent}end of each element of {ins.name}"
        else:
            what = {Op.FIXED: f"{ins.size} byte(s)", Op.VAR: f"uint32 count + count x {ins.size} byte(s), "
                    f"{'exactly' if ins.sub == Sub.STREAM else 'at most'} {ins.count}",
                    Op.LOOP: (f"uint32 count, at most {ins.count} elements" if ins.variable
                              else f"{ins.count} elements")}[ins.op]
            check = ""
            if ins.sub == Sub.CHECK:
                check = f", must be {ins.const!r}"
            comment = (f"{indent}{ins.name} ({ins.type}): {what}; {_SUB_WORD[ins.sub]}{check}; "
                       f"out: {_PUB_WORD[ins.pub]}")
        if ins.op == Op.LOOP:
            depth += 1
        rows.append({
            "pc": pc, "op_c": f"OP_{ins.op.name}", "sub_c": f"SUB_{ins.sub.name}",
            "pub_c": f"PUB_{ins.pub.name}", "op": int(ins.op), "sub": int(ins.sub),
            "pub": int(ins.pub), "size": ins.size, "count": ins.count,
            "variable": ins.variable, "status": ins.status,
            "kaddr": prog.const_offsets[pc], "klen": len(ins.const), "jump": ins.jump,
            "comment": comment.replace("*/", "* /"), "name": ins.name, "type": ins.type,
            "sub_word": _SUB_WORD[ins.sub] if ins.op in (Op.FIXED, Op.VAR) else "-",
            "pub_word": _PUB_WORD[ins.pub] if ins.op in (Op.FIXED, Op.VAR) else "-",
        })
    return rows


def loop_depth(prog: Program) -> int:
    """The deepest nesting of loops of ``prog`` (at least 1, the size of the walkers' stacks)."""
    depth = best = 0
    for ins in prog.instrs:
        if ins.op == Op.LOOP:
            depth += 1
            best = max(best, depth)
        elif ins.op == Op.END:
            depth -= 1
    assert best <= MAX_LOOP_DEPTH
    return max(1, best)


def max_steps(prog: Program) -> int:
    """Instructions the walkers step through for the longest message (a loop trip count)."""
    total = 0
    mult = [1]
    for ins in prog.instrs:
        if ins.op == Op.LOOP:
            mult.append(mult[-1] * max(1, ins.count))
        total += mult[-1]
        if ins.op == Op.END:
            mult.pop()
    return total


def app_summary(spec: GenericSpec) -> str:
    """The application in a few words."""
    if spec.op == "custom":
        return (f"the user's stream_filter() from "
                f"{spec.custom_source.name if spec.custom_source else '?'}")
    if spec.op == "passthrough":
        return "pass-through, no processing"
    return f"{spec.op} over {spec.ksize} elements"


def context(spec: GenericSpec) -> dict[str, object]:
    """The template context of ``spec`` (shared with the Verilog renderer)."""
    prog = spec.program
    note = f"Generated by rosfpga-lab {__version__} from {spec.config_name} (do not edit: regenerate)."
    node = {"global_name": spec.node_name, "master_uri": spec.master_uri,
            "ip_address": spec.ip_address}
    return {
        "generated_note": note, "node": node,
        "sub": {"topic": spec.sub_topic, "type": prog.type_in},
        "pub": {"topic": spec.pub_topic, "type": prog.type_out},
        "prog": prog, "instrs": instruction_rows(prog), "statuses": list(prog.statuses),
        "consts": prog.const_table, "const_rows": _hex_rows(prog.const_table),
        "loop_depth": loop_depth(prog), "max_instr_steps": max_steps(prog),
        "carry_bytes": max(1, prog.carry_bytes),
        "fifo": {"input_depth": spec.input_depth, "output_depth": spec.output_depth},
        "axis_depth": spec.axis_depth, "part": spec.part, "clock_mhz": f"{spec.clock_mhz:g}",
        "clock_period_ns": f"{1000.0 / spec.clock_mhz:g}",
        "op": spec.op, "ksize": spec.ksize if spec.op in ("dilate", "erode") else 1,
        "kind": spec.kind, "kind_note": KIND_NOTES[spec.kind],
        "stream_name": spec.stream_name, "stream_type": spec.stream_type,
        "app_summary": app_summary(spec),
        "tb_input": "tb_input.bin", "tb_expected": "tb_expected.bin" if spec.op != "custom" else "",
        "cxxflags": ("-std=c++14", "-Wall", "-Werror", "-O2"), "rtl": spec.op != "custom",
        "csim_sources": GENERIC_SOURCES,
        "design_sources": [s for s in GENERIC_SOURCES if s != "csim_testbench.cpp"],
        "headers": [
            _header_context(f"Subscriber: sent to each publisher of {spec.sub_topic}",
                            "SUBSCRIBER_HEADER", "subscriber_connection_header",
                            spec.subscriber_header),
            _header_context(f"Publisher: the answer to each subscriber of {spec.pub_topic}",
                            "PUBLISHER_HEADER", "publisher_connection_header",
                            spec.publisher_header),
        ],
    }


def environment() -> jinja2.Environment:
    """The Jinja2 environment of the lab's templates (strict: an unknown name is an error)."""
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES_DIR)), undefined=jinja2.StrictUndefined,
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True, autoescape=False)


def render_generic(spec: GenericSpec) -> dict[str, str]:
    """Render every HLS C++ file of a generic project (nothing is written).

    Returns:
        ``{file name: text}``.

    Raises:
        GenerateError: the custom application file cannot be read.
    """
    ctx = context(spec)
    env = environment()
    out: dict[str, str] = {}
    for target, template in GENERIC_FILES.items():
        if target == "stream_filter.cpp" and spec.op == "custom":
            if spec.custom_source is None:
                raise GenerateError("application.op is custom but no source file is named")
            try:
                out[target] = spec.custom_source.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise GenerateError(f"cannot read the application file {spec.custom_source}: "
                                    f"{exc}") from None
            continue
        out[target] = env.get_template(template).render(ctx)
    return out
