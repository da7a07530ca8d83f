"""Compile a circuit layout to the walkers' program: one instruction per field.

How this works: :func:`program_from_layout` walks the layout's steps (:mod:`rosfpga_lab.hw.layout`)
once and emits a :class:`~rosfpga_lab.hls.program.Instr` per field: a length prefix and the string
or array it counts become one ``VAR``, an array of messages, strings or times a ``LOOP``/``END``
pair, every other field a ``FIXED``; each instruction says what the subscriber does with the
field's bytes (skip, carry, check, stream) and what the publisher writes (as received, a
constant, a message number, zeros, the application's output). The checks, maxima and status codes
are the layout's; the frame-length rules are the models' (``length_rules``). A CDR walk
(:func:`program_from_cdr`) adds the encapsulation header, alignment and strings' NULs. The
program is what every renderer takes: the HLS C++ (:mod:`rosfpga_lab.hls.generic`), the Verilog
walk (:mod:`rosfpga_lab.rtl.generic`) and the cycle model (:func:`~rosfpga_lab.hls.program.frame_clocks`).
"""

from __future__ import annotations

import struct

import numpy as np

from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.limits import MAX_CARRY_BYTES
from rosfpga_lab.hls.program import _replace
from rosfpga_lab.hls.program import (
    ENCAP_BYTES, FRAME_LENGTH_STATUS, Instr, Op, Program, Pub, Sub,
)
from rosfpga_lab.hw.cdrlayout import CdrLayout, cdr_length_rules
from rosfpga_lab.hw.layout import Action, CheckOp, Layout, Step, StepKind, length_rules
from rosfpga_lab.msg.builtins import SCALARS


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


# long: one pass over the layout's steps building the instruction list, its budget checks
# (carried bytes, status codes, instructions, constant bytes) reading the same state
def program_from_layout(layout: Layout, *, max_frame: int | None = None,
                        count: str | None = None, cdr: CdrLayout | None = None) -> Program:
    """The walkers' program of a circuit layout (one instruction per field, names from it).

    A length prefix and the string or array it counts become one ``VAR`` instruction; an array
    of messages, strings or times a ``LOOP``/``END`` pair; the checks, maxima and statuses are
    the layout's. Skipped fields are written as zeros (empty strings and arrays).

    Args:
        layout: the circuit layout.
        max_frame: the longest frame length accepted (default: the layout's).
        count: the label of a uint32 field the publisher numbers itself (1, 2, 3 ...) instead of
            re-sending it (:data:`rosfpga_lab.hw.circuit.NUMBERED_FIELD` on TCPROS Image).
            A video stream's bytes are a plain array here either way: how they travel to the
            application (as pixels and lines) is the project's (``GenericSpec.video``).
        cdr: the CDR walk whose ``layout`` this is (:func:`program_from_cdr`): the program
            reads and writes CDR samples (alignment, strings with their NUL, the header).

    Raises:
        GenerateError: the layout has no stream, or one of no element, or a walk too large for
            the walkers (carried bytes, status codes, instructions, constant bytes).
    """
    if layout.stream_index is None:
        raise GenerateError(f"the layout of {layout.type_name} has no stream: nothing to generate")
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
    instrs.append(Instr(Op.DONE, status=FRAME_LENGTH_STATUS, name="", type=""))
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
