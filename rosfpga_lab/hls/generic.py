"""Render a node's HLS C++ project from its walk: every message type, both wires, both HLS tools.

How this works: a configuration gives one :class:`GenericSpec` (:func:`spec_from_config`): the
node's names, FIFO depths, part and clock, the walk (:class:`~rosfpga_lab.hls.program.Program`,
one instruction per field with its name and type, compiled by :mod:`rosfpga_lab.hls.compiler`),
the application (operation, window, how elements are ordered), the wire and the HLS flavour.
:func:`context` turns it into one template context (shared with the Verilog renderer,
:mod:`rosfpga_lab.rtl.generic`) and :func:`render_generic` renders every template of
``templates/`` into ``{file name: text}``; :func:`render` does both for a configuration. No
template names a field of any message type: every field-specific line comes from the program's
instructions, with a comment naming the field. A stream with a video shape (``sensor_msgs/Image``'s
``data``, from the layout: no field named) travels as pixels, TUSER on the first and TLAST ending
each line, into the 2-D application (``video_filter.cpp.j2``), on TCPROS as on CDR.

The two flavours (``hls.flavour``, :data:`HLS_TOOLS`) are the same C++ but for the directive that
packs the metadata word, and their own ``run_hls.tcl``. The paper's Vivado HLS flavour once used
the HLS video library (``hls_video.h``); the application's own line buffer is plain C++ both tools
synthesize, so the library (and the lab's g++ stand-in for it) is gone.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import jinja2
import numpy as np

from rosfpga_lab import __version__
from rosfpga_lab.config import CUSTOM, NodeConfig
from rosfpga_lab.config.vocabulary import CDR_WIRE, DEFAULT_HLS_FLAVOUR, TCPROS_WIRE
from rosfpga_lab.hls import rtlbuild
from rosfpga_lab.hls.csim import BINARY, CXXFLAGS, HLS_HEADERS, SOURCES, TB_EXPECTED, TB_INPUT
from rosfpga_lab.hls.compiler import program_from_cdr, program_from_layout
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.program import (
    ALIGN_ORIGIN, ENCAP_PAD_MASK, MAX_LOOP_DEPTH, RECORDS, Op, Program, Pub, Sub,
    stream_latency,
)
from rosfpga_lab.hw import limits as hw_limits
from rosfpga_lab.hw.cdrlayout import END_ALIGN
# NUMBERED_FIELD: the field a TCPROS Image's publisher numbers itself (1, 2, 3 ...), as rospy and
# the live node's model do; its owner is hw.circuit (numbered_field says for which
# configurations). (The one Image rule left: a configuration key for it is issue 28's.)
from rosfpga_lab.hw.circuit import NUMBERED_FIELD, CircuitLayouts, circuit_layouts
from rosfpga_lab.hw.layout import Layout, VideoShape
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.tcpros import TopicSpec, encode_header, publisher_reply_fields, subscriber_request_fields

#: The templates of a project (Jinja2, strict: an unknown name is an error).
TEMPLATES_DIR = Path(__file__).resolve().parent / "templates"
#: Output file -> template (``stream_filter.cpp`` is the user's file for ``op: custom``).
GENERIC_FILES = {
    "layout.h": "layout.h.j2",
    "ros_node.h": "ros_node.h.j2",
    "subscriber.cpp": "subscriber.cpp.j2",
    "publisher.cpp": "publisher.cpp.j2",
    "connection_headers.cpp": "connection_headers.cpp.j2",
    "stream_filter.cpp": "stream_filter.cpp.j2",
    "ros_fpga_node.cpp": "ros_fpga_node.cpp.j2",
    "csim_testbench.cpp": "csim_testbench.cpp.j2",
    "Makefile": "Makefile.j2",
    "run_hls.tcl": "run_hls.tcl.j2",
    "README.md": "README.md.j2",
}
#: The file the user writes for ``op: custom`` (its function ``stream_filter()``).
CUSTOM_FILE = "stream_filter.cpp"
#: Bytes per line of the hexadecimal arrays in connection_headers.cpp.
HEX_BYTES_PER_LINE = 16
#: The C++ name of a morphological operation (the application's comment).
_OP_CPP = {"dilate": "Dilate", "erode": "Erode"}


@dataclass(frozen=True)
class HlsTool:
    """What one flavour of the generated C++ (``hls.flavour``) is written for.

    Attributes:
        name: the tool's name.
        versions: the releases the flavour is for (said in the generated README and scripts).
        command: how to run ``run_hls.tcl`` with it.
        pack: the directive that makes the metadata struct one FIFO word.
        what: one line on how the flavour's C++ and script differ.
    """

    name: str
    versions: str
    command: str
    pack: str
    what: str


#: Flavour (:data:`rosfpga_lab.config.vocabulary.HLS_FLAVOURS`) -> its tool.
HLS_TOOLS: dict[str, HlsTool] = {
    "vitis": HlsTool(
        "Vitis HLS", "Vitis HLS 2020.2 and later", "vitis_hls -f run_hls.tcl", "HLS aggregate",
        "`#pragma HLS aggregate` on the metadata FIFO; each solution opened with `-flow_target "
        "vivado` and no AXI4-Lite adapter by default."),
    "vivado": HlsTool(
        "Vivado HLS", "Vivado HLS 2016.x to 2019.2", "vivado_hls -f run_hls.tcl", "HLS DATA_PACK",
        "The paper's tool. `#pragma HLS DATA_PACK` on the metadata FIFO (Vitis HLS removed it); "
        "the same C++ otherwise: the application's own line buffer, not the HLS video library "
        "(`hls_video.h`, which Vitis HLS no longer ships), so one application serves both tools."),
}


#: How each element kind is ordered, said in the application's comment.
KIND_NOTES = {
    "unsigned": "unsigned integers",
    "signed": "two's-complement integers",
    "float": "IEEE floats by value: -0.0 equals +0.0, so of two zeros the later wins; a window "
             "with a NaN gives its first NaN, bits unchanged",
}


@dataclass(frozen=True)
class GenericSpec:
    """Everything a project is rendered from (any message type, either wire).

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
        wire: ``tcpros`` (frames) or ``cdr`` (ROS 2 samples, each behind a sample length).
        video: the stream's video shape, or ``None``: with one, the streamed bytes go to the
            application as pixels of ``bytes_per_pixel`` bytes (TUSER on the first, TLAST ending
            each line of ``width``) and the application is the 2-D window over ``height``
            lines (``video_filter.cpp.j2``, ``rfl_morph.v``).
        flavour: ``hls.flavour``, the HLS tool ``run_hls.tcl`` and the directives are for.
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
    wire: str = TCPROS_WIRE
    video: VideoShape | None = None
    flavour: str = DEFAULT_HLS_FLAVOUR


def meta_fields(prog: Program) -> tuple[tuple[str, int, str], ...]:
    """The fields of the subscriber's one metadata FIFO word per frame (``struct frame_meta``),
    with their widths in bits and what each holds; the carried bytes go on a byte FIFO."""
    return (("out_len", 32, "the publisher's frame length"),
            ("carried", max(1, prog.carry_bytes).bit_length(), "bytes this frame put on the carry FIFO"),
            ("streamed", 1, "the stream went to the application"),
            ("drop", 1, "refused after that: the publisher drops the frame"))


def _hex_rows(data: bytes) -> list[str]:
    """``data`` as rows of a C array initializer, :data:`HEX_BYTES_PER_LINE` bytes a row."""
    return [", ".join(f"0x{b:02x}" for b in data[i:i + HEX_BYTES_PER_LINE]) + ","
            for i in range(0, len(data), HEX_BYTES_PER_LINE)]


def _header_context(title: str, array: str, function: str,
                    fields: Mapping[str, str]) -> dict[str, object]:
    """One connection header of ``connection_headers.cpp``: its bytes as C rows and its fields
    as a comment (a long or multi-line value, the message definition, shown by its length)."""
    data = encode_header(dict(fields))
    shown = []
    for key in sorted(fields):
        value = fields[key]
        if "\n" in value or len(value) > 60:
            value = f"<{len(value.encode())} bytes: the full text of the message definition>"
        shown.append((key, value))
    return {"title": title, "array": array, "function": function, "length": len(data),
            "rows": _hex_rows(data), "fields": shown}


_SUB_WORD = {Sub.SKIP: "skip", Sub.CARRY: "carry", Sub.CHECK: "check", Sub.STREAM: "stream",
             Sub.RANGE: "carry, check bounds"}
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
        elif ins.op == Op.ENCAP:
            comment = ("CDR encapsulation header: must start 00 01 (CDR little-endian); options & 3: "
                       "padding bytes at the end of the payload; out: 00 01 00 00")
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
            elif ins.sub == Sub.RANGE:
                check = f" {ins.const[:ins.size].hex()}..{ins.const[ins.size:].hex()} (LE hex)"
            if ins.nul:
                what += ", NUL counted and checked"
            aligned = "".join(f"; align {a}{' (elements)' if k else ''}" for k, a in
                              enumerate((ins.align, ins.elem_align)) if a > 1)
            comment = (f"{indent}{ins.name} ({ins.type}): {what}; {_SUB_WORD[ins.sub]}{check}; "
                       f"out: {_PUB_WORD[ins.pub]}{aligned}")
        if ins.op == Op.LOOP:
            depth += 1
        rows.append({
            "pc": pc, "op_c": f"OP_{ins.op.name}", "sub_c": f"SUB_{ins.sub.name}",
            "pub_c": f"PUB_{ins.pub.name}", "op": int(ins.op), "sub": int(ins.sub),
            "pub": int(ins.pub), "size": ins.size, "count": ins.count,
            "variable": ins.variable, "status": ins.status, "status2": ins.status2,
            "kind": ins.kind, "fixed_after": ins.fixed_after, "elem_min": ins.elem_min,
            "lsize": ins.size.bit_length() - 1 if ins.op == Op.VAR else 0,
            "kaddr": prog.const_offsets[pc], "klen": len(ins.const), "jump": ins.jump,
            "align": ins.align, "elem_align": ins.elem_align, "nul": ins.nul,
            "status3": ins.status3,
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
    if spec.video is not None:
        v = spec.video
        return (f"{spec.op} over {spec.ksize}x{spec.ksize} pixels of {v.width}x{v.height} "
                f"{v.encoding} video")
    return f"{spec.op} over {spec.ksize} elements"


def beat_shape(spec: GenericSpec) -> dict[str, int]:
    """How the streamed bytes travel as AXI4-Stream beats: ``bytes`` per beat, ``count`` beats
    per array, ``line`` beats per line (TLAST), ``bits`` of TDATA. Without a video shape a beat
    is one element and the array one line; with one, a beat is a pixel (32-bit TDATA, unused
    lanes zero, as the video project packs it) and a line ``width`` pixels."""
    prog = spec.program
    if spec.video is None:
        return {"bytes": prog.stream_bytes, "count": prog.stream_length,
                "line": prog.stream_length, "bits": 8 * prog.stream_bytes}
    v = spec.video
    if prog.stream_bytes * prog.stream_length != v.width * v.height * v.bytes_per_pixel:
        raise GenerateError(f"the stream has {prog.stream_bytes * prog.stream_length} bytes, "
                            f"not the {v.width}x{v.height} pixels of {v.bytes_per_pixel} bytes "
                            "of its video shape")
    return {"bytes": v.bytes_per_pixel, "count": v.width * v.height, "line": v.width,
            "bits": hw_limits.TDATA_BITS}


def stream_path(spec: GenericSpec) -> int:
    """Clocks of the stream's path through the generated top's application, for the cycle
    model of a walk with streaming early release (:func:`rosfpga_lab.hls.program.stream_latency`,
    the ``latency`` of :func:`~rosfpga_lab.hls.program.frame_clocks`)."""
    beat = beat_shape(spec)
    ksize = spec.ksize if spec.op in ("dilate", "erode") else 1
    if spec.video is None:
        return stream_latency(beat["bytes"], ksize, length=beat["count"])
    return stream_latency(beat["bytes"], ksize, beat["line"])


def context(spec: GenericSpec) -> dict[str, object]:
    """The template context of ``spec`` (shared with the Verilog renderer)."""
    from rosfpga_lab.hw.encodings import PIXEL_FORMATS

    prog = spec.program
    video = None
    if spec.video is not None:
        fmt = PIXEL_FORMATS[spec.video.encoding]
        video = {"width": spec.video.width, "height": spec.video.height,
                 "encoding": spec.video.encoding, "bpp": fmt.bytes_per_pixel,
                 "tkeep": fmt.tkeep, "pixel_mask": (1 << (8 * fmt.bytes_per_pixel)) - 1}
    note = f"Generated by rosfpga-lab {__version__} from {spec.config_name} (do not edit: regenerate)."
    node = {"global_name": spec.node_name, "master_uri": spec.master_uri,
            "ip_address": spec.ip_address}
    return {
        "generated_note": note, "node": node,
        "sub": {"topic": spec.sub_topic, "type": prog.type_in},
        "pub": {"topic": spec.pub_topic, "type": prog.type_out},
        "prog": prog, "instrs": instruction_rows(prog),
        "cdr": spec.wire == CDR_WIRE, "wire": spec.wire,
        "align_origin": ALIGN_ORIGIN, "encap_pad_mask": ENCAP_PAD_MASK, "end_align": END_ALIGN,
        "frame": "CDR sample" if spec.wire == CDR_WIRE else "TCPROS frame", "statuses": list(prog.statuses),
        "consts": prog.const_table, "const_rows": _hex_rows(prog.const_table),
        "loop_depth": loop_depth(prog), "max_instr_steps": max_steps(prog),
        "stream_early": prog.stream_early,
        "carry_bytes": max(1, prog.carry_bytes), "records": RECORDS,
        "meta_fields": meta_fields(prog), "meta_bits": sum(f[1] for f in meta_fields(prog)),
        "carry_count_bits": meta_fields(prog)[1][1],
        "flavour": spec.flavour, "tool": HLS_TOOLS[spec.flavour],
        "flavours": list(HLS_TOOLS.items()), "hls_headers": HLS_HEADERS,
        "harness": rtlbuild.makefile_context(),
        "cores": ("subscriber", "fifo2axi", "stream_filter", "axi2fifo", "publisher"),
        "fifo": {"input_depth": spec.input_depth, "output_depth": spec.output_depth},
        "axis_depth": spec.axis_depth, "part": spec.part, "clock_mhz": f"{spec.clock_mhz:g}",
        "clock_period_ns": f"{1000.0 / spec.clock_mhz:g}",
        "op": spec.op, "ksize": spec.ksize if spec.op in ("dilate", "erode") else 1,
        "kind": spec.kind, "kind_note": KIND_NOTES[spec.kind],
        "stream_name": spec.stream_name, "stream_type": spec.stream_type,
        "app_summary": app_summary(spec),
        "beat": beat_shape(spec), "video": video, "filter_name": "stream_filter",
        "app": {"op": spec.op, "ksize": spec.ksize},
        "op_cpp": _OP_CPP.get(spec.op, ""),
        "tb_input": TB_INPUT, "tb_expected": TB_EXPECTED if spec.op != CUSTOM else "",
        "cxxflags": CXXFLAGS, "rtl": spec.op != CUSTOM, "csim_sources": SOURCES,
        "design_sources": [s for s in SOURCES if s != f"{BINARY}.cpp"],
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


def render(config: NodeConfig) -> dict[str, str]:
    """Render every text file of the HLS project of ``config`` (nothing is written):
    :func:`render_generic` of :func:`spec_from_config`.

    Raises:
        GenerateError: as :func:`spec_from_config` and :func:`render_generic`.
    """
    return render_generic(spec_from_config(config))


def subscriber_header_fields(config: NodeConfig) -> dict[str, str]:
    """Connection-header fields the node's subscriber sends to a publisher (sorted on the wire):
    callerid, md5sum, message_definition, tcp_nodelay, topic, type."""
    return dict(spec_from_config(config).subscriber_header)


def publisher_header_fields(config: NodeConfig) -> dict[str, str]:
    """Connection-header fields the node's publisher answers a subscriber with: callerid,
    latching, md5sum, message_definition, topic, type."""
    return dict(spec_from_config(config).publisher_header)


def render_generic(spec: GenericSpec) -> dict[str, str]:
    """Render every HLS C++ file of a project (nothing is written).

    Returns:
        ``{file name: text}``.

    Raises:
        GenerateError: the custom application file cannot be read.
    """
    ctx = context(spec)
    env = environment()
    out: dict[str, str] = {}
    for target, template in GENERIC_FILES.items():
        if target == CUSTOM_FILE and spec.op == CUSTOM:
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


#: ``kind`` of :class:`GenericSpec` per numpy dtype kind of the stream's elements.
_KIND_NAMES = {"u": "unsigned", "i": "signed", "f": "float"}


def spec_from_layout(layout: Layout, reg: MsgRegistry, *, node_name: str = "/fpga",
                     sub_topic: str = "/in", pub_topic: str = "/out",
                     master_uri: str = "http://127.0.0.1:11311", ip_address: str = "127.0.0.1",
                     input_depth: int = 2048, output_depth: int = 2048, axis_depth: int = 16,
                     part: str = "xc7z020clg400-1", clock_mhz: float = 100.0, op: str = "dilate",
                     ksize: int = 3, config_name: str = "<string>",
                     custom_source: Path | None = None,
                     program: Program | None = None, wire: str = TCPROS_WIRE,
                     video: VideoShape | None = None, flavour: str = DEFAULT_HLS_FLAVOUR) -> GenericSpec:
    """The generic project of a layout (its type in ``reg``), with the node's names and sizes
    (``program``: the layout's walk when the caller derived it itself; ``wire``: ``cdr`` for a
    CDR walk's ``layout`` with its ``program_from_cdr``; ``video``: the stream's video shape,
    to frame it as pixels and lines for a 2-D application, see :class:`GenericSpec`)."""
    prog = program or program_from_layout(layout)
    t = layout.type_name
    stream = layout.stream
    sub_header = subscriber_request_fields(
        callerid=node_name, topic=sub_topic, md5sum=reg.md5(t), type_name=t,
        message_definition=reg.full_text(t), tcp_nodelay=True)
    pub_header = publisher_reply_fields(node_name, TopicSpec(pub_topic, t, reg.md5(t),
                                                             reg.full_text(t)))
    return GenericSpec(
        program=prog, node_name=node_name, sub_topic=sub_topic, pub_topic=pub_topic,
        master_uri=master_uri, ip_address=ip_address, input_depth=input_depth,
        output_depth=output_depth, axis_depth=axis_depth, part=part, clock_mhz=clock_mhz,
        op=op, ksize=ksize, kind=_KIND_NAMES[np.dtype(stream.dtype).kind],
        stream_name=stream.label,
        stream_type=f"{stream.type}[]" if stream.count is None else f"{stream.type}[{stream.count}]",
        subscriber_header=sub_header, publisher_header=pub_header, config_name=config_name,
        custom_source=custom_source, wire=wire, video=video, flavour=flavour)


def spec_from_config(config: NodeConfig) -> GenericSpec:
    """The project of a node configuration: any type, either wire (a video stream, Image's
    ``data``, framed as video: :class:`GenericSpec`; a TCPROS Image's publisher numbers
    :data:`NUMBERED_FIELD`). Its layouts are derived once per configuration
    (:func:`~rosfpga_lab.hw.circuit.circuit_layouts`); the spec itself once per configuration
    with :func:`rosfpga_lab.hls.circuit.circuit_of` (``.spec``).

    Raises:
        GenerateError: the configuration's types differ (the generated publisher re-sends the
            subscribed type), or its layout cannot be compiled
            (:func:`~rosfpga_lab.hls.compiler.program_from_layout`).
    """
    _check_same_types(config)
    return spec_from_layouts(circuit_layouts(config))


def _check_same_types(config: NodeConfig) -> None:
    if config.publisher.type != config.subscriber.type:
        raise GenerateError(f"publisher.type {config.publisher.type} differs from subscriber.type "
                            f"{config.subscriber.type}: the generated circuit publishes the type "
                            "it subscribes to")


def spec_from_layouts(parts: CircuitLayouts) -> GenericSpec:
    """The project of a configuration's derived layouts (see :func:`spec_from_config`).

    Raises:
        GenerateError: as :func:`spec_from_config`.
    """
    config = parts.config
    _check_same_types(config)
    app = config.application
    layout = parts.layout
    program = None
    if config.wire == CDR_WIRE:
        layout, program = parts.cdr.layout, program_from_cdr(parts.cdr)
    elif parts.numbered is not None:  # the publisher numbers its messages (NUMBERED_FIELD)
        program = program_from_layout(layout, count=parts.numbered)
    return spec_from_layout(
        layout, parts.reg, node_name=config.node.global_name, program=program, wire=config.wire,
        sub_topic=config.subscriber.topic, pub_topic=config.publisher.topic,
        master_uri=config.node.master_uri, ip_address=config.node.ip_address,
        input_depth=config.fifo.input_depth, output_depth=config.fifo.output_depth,
        axis_depth=config.fifo.axis_depth, part=config.part, clock_mhz=config.clock_mhz,
        op=app.op, ksize=app.ksize, config_name=config.path.name if config.path else "<string>",
        custom_source=app.source, video=layout.video, flavour=config.hls.flavour)

