"""The generator of Figure 4 for any message layout: HLS C++ rendered from a :class:`Program`.

How this works: :func:`render_generic` renders the templates of ``templates/generic/`` (and the
Image project's ``connection_headers.cpp.j2``, which knows no field) from one
:class:`GenericSpec`: the node configuration's names, FIFO depths, part and clock, the walk
(:class:`~rosfpga_lab.hls.program.Program`, one instruction per field with its name and type)
and the application (operation, window, how elements are ordered). No template names a field
of any message type: every field-specific line comes from the program's instructions, with a
comment naming the field. A stream with a video shape (``GenericSpec.video``, from the layout:
no field named) travels as pixels, TUSER on the first and TLAST ending each line, into the video
application the Image project also renders (``video_filter.cpp.j2``): that is how Image on CDR is
generated. On TCPROS the Image project keeps its own templates (the hand-written teaching
version, :mod:`rosfpga_lab.hls.generator`).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path

import jinja2
import numpy as np

from rosfpga_lab import __version__
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.limits import MAX_CARRY_BYTES
from rosfpga_lab.hw import limits as hw_limits
from rosfpga_lab.hls.generator import _OP_CPP, HEX_BYTES_PER_LINE, HLS_TOOLS, TEMPLATES_DIR, _header_context
from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config.vocabulary import CDR_WIRE, DEFAULT_HLS_FLAVOUR, TCPROS_WIRE
from rosfpga_lab.hls.program import _replace
from rosfpga_lab.hls.program import (
    ALIGN_ORIGIN, ENCAP_BYTES, ENCAP_PAD_MASK, FRAME_LENGTH_STATUS, MAX_LOOP_DEPTH, Instr, Op, Program, Pub, Sub,
)
from rosfpga_lab.hw.cdrlayout import END_ALIGN, TAIL_LABEL, CdrLayout, cdr_length_rules
from rosfpga_lab.hw.layout import (
    Action, CheckOp, Layout, Step, StepKind, Token, VideoShape, length_rules, marshal,
)
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.tcpros import TopicSpec, publisher_reply_fields, subscriber_request_fields

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
    "unsigned": "unsigned integers",
    "signed": "two's-complement integers",
    "float": "IEEE floats by value: -0.0 equals +0.0, so of two zeros the later wins; a window "
             "with a NaN gives its first NaN, bits unchanged",
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
        wire: ``tcpros`` (frames) or ``cdr`` (ROS 2 samples, each behind a sample length).
        video: the stream's video shape, or ``None``: with one, the streamed bytes go to the
            application as pixels of ``bytes_per_pixel`` bytes (TUSER on the first, TLAST ending
            each line of ``width``) and the application is the 2-D window over ``height``
            lines (the video project's ``video_filter.cpp.j2``, ``rfl_morph.v``).
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
    return [", ".join(f"0x{b:02x}" for b in data[i:i + HEX_BYTES_PER_LINE]) + ","
            for i in range(0, len(data), HEX_BYTES_PER_LINE)]


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
        "carry_bytes": max(1, prog.carry_bytes),
        "meta_fields": meta_fields(prog), "meta_bits": sum(f[1] for f in meta_fields(prog)),
        "carry_count_bits": meta_fields(prog)[1][1],
        "flavour": spec.flavour, "tool": HLS_TOOLS[spec.flavour],
        "other_tools": [(key, tool) for key, tool in HLS_TOOLS.items() if key != spec.flavour],
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


# -- from the circuit layout (rosfpga_lab.hw.layout) to the walkers' program --------------------

def _kind_of(dtype: str) -> int:
    return {"u": 0, "b": 0, "i": 1, "f": 2}[np.dtype(dtype).kind]


def _scalar_bytes(step: Step, value: object) -> bytes:
    return struct.pack("<" + SCALARS[step.type].struct_char, value)


def _bounds(step: Step, low: object, high: object) -> bytes:
    dt = np.dtype(step.dtype)
    if dt.kind == "f":
        lo = -np.inf if low is None else low
        hi = np.inf if high is None else high
    else:
        info = np.iinfo(dt) if dt.kind in "iu" else np.iinfo(np.uint8)
        lo = info.min if low is None else low
        hi = info.max if high is None else high
    return _scalar_bytes(step, lo) + _scalar_bytes(step, hi)


def _scalar_instr(step: Step, code: dict[str, int], label: str) -> Instr:
    size, name, type_ = step.size, label, step.type
    if step.action is Action.SKIP:
        return Instr(Op.FIXED, Sub.SKIP, Pub.ZERO, size, name=name, type=type_)
    if step.action is not Action.CHECK or step.check is None:
        return Instr(Op.FIXED, Sub.CARRY, Pub.CARRY, size, name=name, type=type_)
    chk = step.check
    status = code[chk.status]
    kind = _kind_of(step.dtype)
    if chk.op is CheckOp.EQUAL and kind != 2:
        return Instr(Op.FIXED, Sub.CHECK, Pub.CONST, size, status=status,
                     const=_scalar_bytes(step, chk.value), name=name, type=type_)
    # a float's equality is the range [v, v] (so -0.0 == +0.0 and NaN equals nothing)
    low, high = (chk.value, chk.value) if chk.op is CheckOp.EQUAL else (chk.low, chk.high)
    return Instr(Op.FIXED, Sub.RANGE, Pub.CARRY, size, status=status, kind=kind,
                 const=_bounds(step, low, high), name=name, type=type_)


def program_from_layout(layout: Layout, *, max_frame: int | None = None,
                        count: str | None = None, video_as_bytes: bool = False,
                        cdr: CdrLayout | None = None) -> Program:
    """The walkers' program of a circuit layout (one instruction per field, names from it).

    A length prefix and the string or array it counts become one ``VAR`` instruction; an array
    of messages, strings or times a ``LOOP``/``END`` pair; the checks, maxima and statuses are
    the layout's. Skipped fields are written as zeros (empty strings and arrays).

    Args:
        layout: the circuit layout.
        max_frame: the longest frame length accepted (default: the layout's).
        count: the label of a uint32 field the publisher numbers itself (1, 2, 3 ...) instead of
            re-sending it (``header.seq`` of the Image project's publisher).
        video_as_bytes: take a video stream (``sensor_msgs/Image``'s ``data``) as a plain array of
            bytes (the TCPROS Image project has its own; this is for comparing the two). A CDR
            walk always does: its project frames the bytes as video (``GenericSpec.video``).
        cdr: the CDR walk whose ``layout`` this is (:func:`program_from_cdr`): the program
            reads and writes CDR samples (alignment, strings with their NUL, the header).

    Raises:
        GenerateError: the layout has no stream, or a video stream (Image keeps its own project).
    """
    if layout.stream_index is None:
        raise GenerateError(f"the layout of {layout.type_name} has no stream: nothing to generate")
    if layout.video is not None and not video_as_bytes and cdr is None:
        raise GenerateError("a video stream (sensor_msgs/Image) has its own project "
                            "(rosfpga_lab.hls.generator)")
    if layout.stream_length < 1:
        raise GenerateError(f"stream.length is {layout.stream_length}: the circuit streams at "
                            "least one element")
    rules = cdr_length_rules(cdr) if cdr is not None else length_rules(layout)  # the models' rule

    def align(step: int) -> int:
        return cdr.align[step] if cdr is not None else 1

    code = {name: i for i, (name, _label) in enumerate(layout.statuses)}
    steps = layout.steps
    frame = steps[0]
    assert frame.check is not None and code[frame.check.status] == FRAME_LENGTH_STATUS
    instrs: list[Instr] = []
    carry = 0
    mult = [1]
    i = 1
    while i < len(steps):
        s = steps[i]
        if s.kind is StepKind.ENCAPSULATION:
            assert s.check is not None
            instrs.append(Instr(Op.ENCAP, Sub.CHECK, Pub.CONST, len(ENCAP_BYTES),
                                status=code[s.check.status], const=ENCAP_BYTES, name=s.label,
                                type="uint8[4]"))
            i += 1
            continue
        if s.kind is StepKind.LENGTH:
            target = steps[s.partner] if s.partner is not None else None
            assert target is not None and s.check is not None
            status = code[s.check.status]
            keep = s.action in (Action.CARRY, Action.CHECK)
            fit = rules[s.index].fixed_after
            fixed_after = -1 if fit is None else fit
            elem_min = rules[s.index].element_min
            if target.kind is StepKind.LOOP:
                instrs.append(Instr(Op.LOOP, Sub.CARRY if keep else Sub.SKIP,
                                    Pub.CARRY if keep else Pub.ZERO, 0, target.max_count,
                                    variable=True, status=status, name=target.label,
                                    type=f"{target.type}[]", fixed_after=fixed_after,
                                    elem_min=elem_min, align=align(s.index)))
                carry += 4 * mult[-1] if keep else 0
                mult.append(mult[-1] * target.max_count)
                i = target.index + 1
                continue
            n = layout.stream_length if target.action is Action.STREAM else target.max_count
            if target.action is Action.STREAM:
                sub, pub = Sub.STREAM, Pub.STREAM
            elif target.action is Action.SKIP:
                sub, pub = Sub.SKIP, Pub.ZERO
            elif target.check is not None:
                sub, pub = Sub.CHECK, Pub.CONST
            else:
                sub, pub = Sub.CARRY, Pub.CARRY
            const = b""
            status2 = 0
            if sub == Sub.CHECK:
                assert target.check is not None and target.check.op is CheckOp.EQUAL
                const = str(target.check.value).encode("utf-8")
                status2 = code[target.check.status]
            # CDR: a string's count includes its NUL, checked by the NUL step after it
            nul = cdr is not None and target.kind is StepKind.STRING
            status3 = 0
            if nul:
                after = steps[target.index + 1]
                assert after.kind is StepKind.NUL and after.check is not None
                status3 = code[after.check.status]
                n += 1
            if sub == Sub.CARRY:
                carry += (4 + n * target.size) * mult[-1]
            instrs.append(Instr(Op.VAR, sub, pub, target.size, n, status=status, status2=status2,
                                const=const, name=target.label, fixed_after=fixed_after,
                                elem_min=elem_min, align=align(s.index),
                                elem_align=align(target.index), nul=nul, status3=status3,
                                type=target.type if target.kind is StepKind.STRING
                                else f"{target.type}[]"))
            i = target.index + (2 if nul else 1)
            continue
        if s.kind is StepKind.SCALAR and s.label == count and s.type == "uint32":
            instrs.append(Instr(Op.FIXED, Sub.SKIP, Pub.COUNT, 4, name=s.label, type=s.type))
        elif s.kind is StepKind.SCALAR:
            ins = _replace(_scalar_instr(s, code, s.label), align=align(i))
            carry += ins.size * mult[-1] if ins.sub in (Sub.CARRY, Sub.RANGE) else 0
            instrs.append(ins)
        elif s.kind is StepKind.ARRAY:  # a fixed-length array of numbers
            assert s.count is not None
            sub, pub = {Action.STREAM: (Sub.STREAM, Pub.STREAM), Action.SKIP: (Sub.SKIP, Pub.ZERO)
                        }.get(s.action, (Sub.CARRY, Pub.CARRY))
            carry += s.size * s.count * mult[-1] if sub == Sub.CARRY else 0
            instrs.append(Instr(Op.FIXED, sub, pub, s.size * s.count, name=s.label,
                                type=f"{s.type}[{s.count}]", align=align(i)))
        elif s.kind is StepKind.LOOP:  # fixed count (a variable one starts at its LENGTH)
            assert s.count is not None
            instrs.append(Instr(Op.LOOP, Sub.SKIP, Pub.CARRY, 0, s.count, name=s.label,
                                type=f"{s.type}[{s.count}]"))
            mult.append(mult[-1] * s.count)
        elif s.kind is StepKind.END:
            instrs.append(Instr(Op.END, name=s.label))
            mult.pop()
        else:
            raise GenerateError(f"step {i} ({s.kind} {s.label}) has no length step before it")
        i += 1
    if carry > MAX_CARRY_BYTES:
        raise GenerateError(f"{layout.type_name} keeps up to {carry} bytes of a frame for the "
                            f"publisher, over the {MAX_CARRY_BYTES} a generated circuit holds: "
                            "lower the maxima of its strings and arrays (limits: in the "
                            "configuration)")
    # CDR: the status of a non-zero byte in the unannounced end padding (the walk's own)
    tail = {label: c for c, (_name, label) in enumerate(layout.statuses)}.get(TAIL_LABEL, 0) \
        if cdr is not None else 0
    instrs.append(Instr(Op.DONE, status=FRAME_LENGTH_STATUS, status2=tail, name="", type=""))
    consts = sum(len(ins.const) for ins in instrs)
    for what, n, most in (("status codes", len(layout.statuses), 256),
                          ("instructions", len(instrs), 1 << 16),
                          ("constant bytes", consts, 1 << 16)):
        if n > most:  # the walkers' 8-bit status, 16-bit program counter and constant address
            raise GenerateError(f"the walk of {layout.type_name} needs {n} {what}; a generated "
                                f"circuit holds {most}")
    stream = layout.stream
    return Program.build(
        instrs, statuses=layout.statuses, min_body=int(frame.check.low),
        max_frame=int(max_frame if max_frame is not None else frame.check.high),
        seq_start=1, stream_bytes=stream.size, stream_length=layout.stream_length,
        carry_bytes=carry, type_in=layout.type_name, type_out=layout.type_name)


def program_from_cdr(cdr: CdrLayout, *, max_frame: int | None = None) -> Program:
    """The walkers' program of a CDR walk (:mod:`rosfpga_lab.hw.cdrlayout`): an ``ENCAP``
    first, each field's alignment, strings with their NUL, no exact fit (see
    :mod:`rosfpga_lab.hls.program`).

    Raises:
        GenerateError: as :func:`program_from_layout`.
    """
    return program_from_layout(cdr.layout, max_frame=max_frame, cdr=cdr)


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
    """The generic project of a node configuration (any type but a video stream on TCPROS,
    whose project is :mod:`rosfpga_lab.hls.generator`'s; a video stream on CDR is framed as
    video, :class:`GenericSpec`).

    Raises:
        GenerateError: the configuration's types differ (the generic publisher re-sends the
            subscribed type), or its layout cannot be rendered (see :func:`program_from_layout`).
    """
    from rosfpga_lab.hw.layout import layout_from_config

    if config.publisher.type != config.subscriber.type:
        raise GenerateError(f"publisher.type {config.publisher.type} differs from subscriber.type "
                            f"{config.subscriber.type}: the generated circuit publishes the type "
                            "it subscribes to")
    reg = config.registry()
    app = config.application
    layout = layout_from_config(config, reg)
    program = None
    if config.wire == CDR_WIRE:
        from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config

        cdr = cdr_layout_from_config(config, reg)
        layout, program = cdr.layout, program_from_cdr(cdr)
    elif layout.video is not None:
        raise GenerateError(f"{config.subscriber.type} streams video: on TCPROS its project is "
                            "rosfpga_lab.hls.generator's (rosfpga_lab.rtl.project.generate_project "
                            "picks it)")
    return spec_from_layout(
        layout, reg, node_name=config.node.global_name, program=program, wire=config.wire,
        sub_topic=config.subscriber.topic, pub_topic=config.publisher.topic,
        master_uri=config.node.master_uri, ip_address=config.node.ip_address,
        input_depth=config.fifo.input_depth, output_depth=config.fifo.output_depth,
        axis_depth=config.fifo.axis_depth, part=config.part, clock_mhz=config.clock_mhz,
        op=app.op, ksize=app.ksize, config_name=config.path.name if config.path else "<string>",
        custom_source=app.source, video=layout.video, flavour=config.hls.flavour)


# -- test frames and the models' output ----------------------------------------------------------

_INT64_MAX = int(np.iinfo(np.int64).max)


def _random_value(step: Step, rng: np.random.Generator) -> object:
    """A value of a SCALAR step that its check (if any) accepts."""
    chk = step.check
    if chk is not None and chk.op is CheckOp.EQUAL:
        return chk.value
    if step.type == "bool":
        return bool(rng.integers(0, 2))
    dt = np.dtype(step.dtype)
    if dt.kind == "f":
        if chk is not None and chk.op is CheckOp.RANGE:
            lo = -1e3 if chk.low is None else float(chk.low)
            hi = 1e3 if chk.high is None else float(chk.high)
            if not math.isfinite(hi - lo):  # an infinite bound, or a span beyond a float's
                a, b = max(lo, -1e3), min(hi, 1e3)
                # (-1e3..1e3 inside the range, else its finite end: the draw is never NaN)
                lo, hi = (a, b) if a <= b else ((lo, lo) if math.isfinite(lo) else (hi, hi))
            return float(dt.type(lo + (hi - lo) * rng.random()))
        return float(dt.type(rng.standard_normal() * 100))
    info = np.iinfo(dt)
    lo, hi = int(info.min), int(info.max)
    if chk is not None and chk.op is CheckOp.RANGE:
        lo = lo if chk.low is None else int(chk.low)
        hi = hi if chk.high is None else int(chk.high)
    # drawn in the field's own integer type: numpy's default (int64) cannot hold a uint64's
    # upper half; every other type keeps the default's draws (and the shipped test frames)
    if hi > _INT64_MAX:
        return int(rng.integers(lo, hi, endpoint=True, dtype=np.uint64))
    return int(rng.integers(lo, hi, endpoint=True))


def sample_tokens(layout: Layout, rng: np.random.Generator, *, stream_count: int | None = None,
                  items: int = 2) -> list[Token]:
    """Random values of a message in the layout's walk order, within its checks and maxima:
    at most ``items`` elements per variable array or string of characters other than the stream
    (``stream_count`` elements for it: default, the length the circuit was built for)."""
    steps = layout.steps
    toks: list[Token] = []
    counts: dict[int, int] = {}

    def walk(lo: int, hi: int, at: tuple[int, ...]) -> None:
        i = lo
        while i < hi:
            s = steps[i]
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                n = s.count if s.count is not None else counts[s.length_step or 0]
                for k in range(n):
                    walk(i + 1, s.partner, at + (k,))
                i = s.partner + 1
                continue
            if s.kind is StepKind.LENGTH:
                part = steps[s.partner] if s.partner is not None else s
                if part.action is Action.STREAM:
                    n = layout.stream_length if stream_count is None else stream_count
                elif part.check is not None and part.check.op is CheckOp.EQUAL:
                    n = len(str(part.check.value).encode("utf-8"))
                else:
                    n = int(rng.integers(0, min(items, part.max_count), endpoint=True))
                counts[i] = n
                toks.append(Token(i, n, at))
            elif s.kind is StepKind.SCALAR:
                toks.append(Token(i, _random_value(s, rng), at))
            elif s.kind is StepKind.STRING:
                n = counts[s.length_step or 0]
                value = (str(s.check.value) if s.check is not None and s.check.op is CheckOp.EQUAL
                         else "".join(chr(c) for c in rng.integers(97, 123, n)))
                toks.append(Token(i, value, at))
            elif s.kind is StepKind.ARRAY:
                n = s.count if s.count is not None else counts[s.length_step or 0]
                dt = np.dtype(s.dtype)
                if dt.kind == "f":
                    arr = (rng.standard_normal(n) * 10).astype(dt)
                    arr[rng.random(n) < 0.1] = 0.0
                elif dt.kind == "b":
                    arr = rng.integers(0, 2, n).astype(dt)
                else:
                    info = np.iinfo(dt)
                    arr = rng.integers(info.min, info.max, n, dtype=dt, endpoint=True)
                toks.append(Token(i, arr, at))
            i += 1

    walk(1, len(steps), ())
    return toks


def model_output(layout: Layout, op: str, ksize: int, frames: list[bytes]) -> tuple[bytes, list[str]]:
    """What the lab's Python models (``hw.walker`` fast model, ``hw.morph1d``) publish for
    ``frames``, one whole frame each, and the refusal (``""`` for accepted) per frame."""
    from rosfpga_lab.hw.errors import FrameFieldError
    from rosfpga_lab.hw.morph1d import morph1d_fast
    from rosfpga_lab.hw.walker import extract_fast, publish_fast

    out = bytearray()
    why = []
    for frame in frames:
        try:
            ex = extract_fast(layout, frame)
        except FrameFieldError as exc:
            why.append(str(exc))
            continue
        why.append("")
        out += publish_fast(layout, ex.tokens, morph1d_fast(np.asarray(ex.stream), op, ksize))
    return bytes(out), why


def sample_frames_generic(layout: Layout, op: str, ksize: int, *, seed: int = 20240606
                          ) -> tuple[bytes, bytes]:
    """The testbench's input (a good frame, a refused one, another good one) and what the
    models publish for it (``op: custom``: no expected output).

    The refused frame's stream has one element too few when the stream has a variable length,
    else the frame has one byte too many; both are refused before anything is published.
    """
    rng = np.random.default_rng(seed)
    good = [marshal(layout, sample_tokens(layout, rng)) for _ in range(2)]
    if layout.stream.is_variable and layout.stream_length > 0:
        bad = marshal(layout, sample_tokens(layout, rng, stream_count=layout.stream_length - 1))
    else:
        body = marshal(layout, sample_tokens(layout, rng))[4:] + b"\0"
        bad = struct.pack("<I", len(body)) + body
    frames = [good[0], bad, good[1]]
    if op == "custom":
        return b"".join(frames), b""
    expected, _why = model_output(layout, op, ksize, frames)
    return b"".join(frames), expected


# -- CDR: test samples and the models' output ----------------------------------------------------

def model_output_cdr(cdr: CdrLayout, op: str, ksize: int, records: list[bytes]
                     ) -> tuple[bytes, list[str]]:
    """What the lab's CDR models (``hw.cdrwalker`` fast model, the application of
    ``hw.cdrpipeline``: ``hw.morph1d``, or ``hw.morph`` on a video stream) publish for
    ``records`` (each a 4-byte sample length + CDR payload), and the refusal per record."""
    from rosfpga_lab.hw.cdrpipeline import apply_application
    from rosfpga_lab.hw.cdrwalker import extract_cdr_fast, publish_cdr_fast
    from rosfpga_lab.hw.errors import FrameFieldError

    out = bytearray()
    why = []
    for record in records:
        try:
            ex = extract_cdr_fast(cdr, record)
        except FrameFieldError as exc:
            why.append(str(exc))
            continue
        why.append("")
        out += publish_cdr_fast(cdr, ex.tokens, apply_application(
            cdr.layout.video, op, ksize, np.asarray(ex.stream)))
    return bytes(out), why


def sample_records_cdr(cdr: CdrLayout, op: str, ksize: int, *, seed: int = 20240606
                       ) -> tuple[bytes, bytes]:
    """The CDR testbench's input (a good sample, one with a bad encapsulation header, another
    good one padded at its end as Cyclone DDS pads, options 3 and three zeros) and what the
    models publish for it (``op: custom``: no expected output)."""
    from rosfpga_lab.hw.cdrlayout import cdr_marshal, to_cdr_tokens

    rng = np.random.default_rng(seed)
    good = [cdr_marshal(cdr, to_cdr_tokens(cdr, sample_tokens(cdr.base, rng))) for _ in range(2)]
    bad = good[0][:4] + b"\x01\x00" + good[0][6:]           # CDR big-endian: refused
    body = good[1][4:6] + b"\x00\x03" + good[1][8:] + bytes(3)
    records = [good[0], bad, struct.pack("<I", len(body)) + body]
    if op == "custom":
        return b"".join(records), b""
    expected, _why = model_output_cdr(cdr, op, ksize, records)
    return b"".join(records), expected
