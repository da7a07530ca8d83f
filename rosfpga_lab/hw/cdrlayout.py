"""CDR, the second wire format of the circuit layout (ROS 2's samples through the same walk).

How this works: the CDR walk is not a second list of fields. :func:`derive_cdr_layout` derives
the ordinary layout (:func:`~rosfpga_lab.hw.layout.derive_layout`) of the type's *ROS 2 form*
(:func:`cdr_registry`: :func:`rosfpga_lab.msg.ros2.ros2_registry`, so ``time`` is
``builtin_interfaces/Time`` -- ``int32 sec``, ``uint32 nanosec`` -- and ``Header`` has no ``seq``;
plus rosidl's ``uint8 structure_needs_at_least_one_member`` in a message without fields, the
zero byte CDR sends for it) and then rewrites that walk for the CDR wire:

* step 0 is still a 4-byte length, the *sample length*: the RTPS reader in software knows the
  size of the serialized payload it reassembled and writes it into the byte FIFO before the
  payload, as TCPROS frames carry theirs (``make csim`` input files are these records too);
* step 1 (``ENCAPSULATION``) reads the 4-byte encapsulation header: representation
  ``00 01`` (CDR little-endian, :data:`rosfpga_lab.msg.cdr.CDR_LE`) or the frame is refused;
  the options' two low bits say how many padding bytes end the payload (DDS-XTypes 1.3
  7.6.3.1.2); after the last field the circuit takes exactly those bytes (not looked at) or,
  when the options announce fewer (or none), the 1 to 3 bytes that bring the payload (header
  included) to a multiple of 4: Cyclone DDS pads its XCDR1 payloads to 4 with options
  ``00 00`` (a 398-byte ``lab_msgs/Samples`` arrives as 400 bytes). Padding bytes are never
  looked at (CDR leaves their value undefined; Cyclone DDS writes zeros and reads past them).
  Any other bytes after the last field are refused: ``frame length`` (bytes the sample length
  announces beyond that);
* every step has an *alignment* (:attr:`CdrLayout.align`): a scalar its size, a length prefix 4,
  a numeric array its element size (only when it has elements), everything else 1; before a step
  the circuit skips ``-(offset - 8) % align`` padding bytes (offset 8: after the sample length
  and the encapsulation header, where CDR's alignment counts from);
* a string's length counts its NUL (``1..max + 1``, 0 refused) and a ``NUL`` step after the
  string's bytes checks it.

Everything else (actions, checks, maxima, loops, ``stream``) is the layout's, step for step:
:attr:`CdrLayout.base_index` maps each CDR step to its step in :attr:`CdrLayout.base` (the
ROS 2 form's TCPROS-shaped walk), so the walker's publisher logic (defaults of skipped
fields, another output type) runs on the base walk and :func:`to_cdr_tokens` /
:func:`to_base_tokens` move values between the two.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.layoutderive import derive_layout, layout_from_config
from rosfpga_lab.hw.layoutlengths import LengthRule, length_rules
from rosfpga_lab.hw.layoutsteps import (
    Action, CheckOp, FieldCheck, Layout, Step, StepKind, format_layout,
)
from rosfpga_lab.hw.layouttokens import Token, encode_token, tokens
from rosfpga_lab.msg import MsgRegistry
from rosfpga_lab.msg.cdr import CDR_LE, ENCAPSULATION_SIZE
from rosfpga_lab.msg.ros2 import PLACEHOLDER_MEMBER as PLACEHOLDER
from rosfpga_lab.msg.ros2 import PLACEHOLDER_TYPE, ros2_registry

#: The representation id the circuit takes (CDR little-endian), big-endian as sent.
REPRESENTATION = int.from_bytes(CDR_LE[:2], "big")
#: Mask of the options' bits that count the padding bytes at the end of the payload.
OPTIONS_PADDING_MASK = 0x3
#: Byte offset in the circuit's input of CDR's alignment origin (sample length + header).
ALIGN_ORIGIN = 4 + ENCAPSULATION_SIZE
#: Label of the padding bytes that end a payload (the encapsulation options count them, or they
#: align the payload to :data:`END_ALIGN` unannounced): where a sample cut short ends.
TAIL_LABEL = "payload end padding"
#: The serialized payload (header included) may end with zeros up to a multiple of this.
END_ALIGN = 4


def unannounced_padding(pos: int, fend: int, end: int) -> bool:
    """The bytes of a sample from ``pos`` (where its fields end, in the circuit's input) to its
    ``end`` are the unannounced end padding: the fields do not end where the options' padding
    starts (``fend``), and they are the 1 to :data:`END_ALIGN` - 1 bytes that bring the
    payload, header included, to a multiple of :data:`END_ALIGN`."""
    after = end - pos
    return pos != fend and 0 < after < END_ALIGN and after == -(pos - ALIGN_ORIGIN) % END_ALIGN


def cdr_registry(reg: MsgRegistry | None = None) -> MsgRegistry:
    """The ROS 2 forms of ``reg``'s types (default: the shipped ones), each message without
    fields given rosidl's ``uint8 structure_needs_at_least_one_member``."""
    r2 = ros2_registry(reg)
    out = MsgRegistry()
    for name in r2.types():
        spec = r2.get(name)
        text = spec.text if spec.fields else spec.text.rstrip("\n") + f"\n{PLACEHOLDER_TYPE} {PLACEHOLDER}\n"
        out.add(name, text.lstrip("\n"), source=spec.source)
    return out


def with_placeholders(reg: MsgRegistry, type_name: str, value: Any) -> Any:
    """``value`` (a ROS 2 value, as ``deserialize_cdr`` gives it) with the placeholder member
    (0) in every message of ``reg`` (a :func:`cdr_registry`) that only has that member."""
    spec = reg.check(type_name)
    if [f.name for f in spec.fields] == [PLACEHOLDER]:
        return {PLACEHOLDER: 0}
    get = value.__getitem__ if isinstance(value, Mapping) else (lambda k: getattr(value, k))
    out = {}
    for f in spec.fields:
        v = get(f.name)
        if not f.is_builtin:
            v = ([with_placeholders(reg, f.base_type, x) for x in v] if f.is_array
                 else with_placeholders(reg, f.base_type, v))
        out[f.name] = v
    return out


@dataclass(frozen=True)
class CdrLayout:
    """The circuit's walk over CDR samples of one type.

    Attributes:
        layout: the CDR walk (a :class:`~rosfpga_lab.hw.layout.Layout`: step 0 the sample
            length, step 1 the encapsulation header, a ``NUL`` step after every string;
            ``min_body`` the smallest payload with its header, ``max_body`` a bound on the
            largest, both in bytes).
        base: the layout of the type's ROS 2 form (the walk without CDR's parts).
        align: alignment of each CDR step's first byte (1: none).
        base_index: each CDR step's step in ``base`` (``None``: the header and the NULs).
        registry: the :func:`cdr_registry` the walk was derived from.
    """

    layout: Layout
    base: Layout
    align: tuple[int, ...]
    base_index: tuple[int | None, ...]
    registry: MsgRegistry

    def pad(self, step: int, offset: int) -> int:
        """Padding bytes before ``step`` when it would start at byte ``offset`` of the input
        (0 = the first byte of the sample length)."""
        a = self.align[step]
        return -(offset - ALIGN_ORIGIN) % a if a > 1 else 0

    @property
    def cdr_index(self) -> dict[int, int]:
        """Each base step's CDR step."""
        return {b: i for i, b in enumerate(self.base_index) if b is not None}


def _unique(base: str, taken: set[str]) -> str:
    out, n = base, 2
    while out in taken:
        out, n = f"{base}_{n}", n + 1
    taken.add(out)
    return out


def to_cdr(base: Layout, reg: MsgRegistry) -> CdrLayout:
    """The CDR walk of ``base`` (a layout derived from ``reg``, a :func:`cdr_registry`)."""
    steps = base.steps
    idx: dict[int, int] = {0: 0}
    n = 2
    for s in steps[1:]:
        idx[s.index] = n
        n += 2 if s.kind is StepKind.STRING else 1
    taken = {s.ident for s in steps}
    out: list[Step] = []
    align: list[int] = []
    base_index: list[int | None] = []

    def remap(i: int | None) -> int | None:
        return None if i is None else idx[i]

    head_ident = _unique("encapsulation", taken)
    for s in steps:
        new = replace(s, index=idx[s.index], partner=remap(s.partner),
                      length_step=remap(s.length_step))
        if s.index == 0:
            new = replace(new, label="sample length")
        elif s.kind is StepKind.LENGTH and s.partner is not None and \
                steps[s.partner].kind is StepKind.STRING:
            assert s.check is not None
            new = replace(new, check=FieldCheck(CheckOp.RANGE, s.check.status, low=1,
                                                high=int(s.check.high) + 1))
        out.append(new)
        base_index.append(s.index)
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH) and s.index > 0:
            align.append(s.size)
        elif s.kind is StepKind.ARRAY:
            align.append(s.size)
        else:
            align.append(1)
        if s.index == 0:
            head = FieldCheck(CheckOp.EQUAL, f"SUB_BAD_{head_ident.upper()}", value=REPRESENTATION)
            out.append(Step(index=1, kind=StepKind.ENCAPSULATION, ident=head_ident,
                            label="encapsulation header", path="", type="uint8", size=4,
                            count=1, length_step=None, max_count=1, action=Action.CHECK,
                            check=head, depth=0, partner=None, dtype="|u1", rel=()))
            align.append(1)
            base_index.append(None)
        elif s.kind is StepKind.STRING:
            ident = _unique(s.ident + "_nul", taken)
            out.append(Step(index=idx[s.index] + 1, kind=StepKind.NUL, ident=ident,
                            label=f"{s.label} NUL", path=s.path, type="uint8", size=1, count=1,
                            length_step=None, max_count=1, action=s.action,
                            check=FieldCheck(CheckOp.EQUAL, f"SUB_BAD_{ident.upper()}", value=0),
                            depth=s.depth, partner=None, dtype="|u1", rel=s.rel))
            align.append(1)
            base_index.append(None)
    stream_index = remap(base.stream_index)
    statuses = (base.statuses[0],) + tuple((s.check.status, s.label) for s in out
                                           if s.check is not None)
    layout = Layout(type_name=base.type_name, md5=base.md5, steps=tuple(out),
                    stream_index=stream_index, stream_length=base.stream_length,
                    min_body=0, max_body=0, statuses=statuses, video=base.video)
    cdr = CdrLayout(layout, base, tuple(align), tuple(base_index), reg)
    low = ENCAPSULATION_SIZE + _min_payload_body(cdr)
    first = replace(out[0], check=FieldCheck(CheckOp.RANGE, out[0].check.status  # type: ignore[union-attr]
                                             , low=low, high=limits.MAX_FRAME_BYTES))
    steps_ = (first,) + tuple(out[1:])
    layout = replace(layout, steps=steps_, min_body=low,
                     max_body=ENCAPSULATION_SIZE + _max_payload_body(cdr))
    return replace(cdr, layout=layout)


def _min_payload_body(cdr: CdrLayout) -> int:
    """Bytes of the smallest body (after the header): every variable part empty, every
    string ``""`` (length 1, its NUL), alignment included."""
    steps = cdr.layout.steps
    offset = ALIGN_ORIGIN

    def walk(lo: int, hi: int) -> None:
        nonlocal offset
        i = lo
        while i < hi:
            s = steps[i]
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                for _ in range(s.count or 0):
                    walk(i + 1, s.partner)
                i = s.partner + 1
                continue
            n = (s.count if s.count is not None else 0) * s.size \
                if s.kind in (StepKind.ARRAY, StepKind.STRING) else s.size
            if n:
                offset += cdr.pad(i, offset) + n
            i += 1

    walk(2, len(steps))
    return offset - ALIGN_ORIGIN


def _max_payload_body(cdr: CdrLayout) -> int:
    """A bound on the largest body the circuit accepts: every maximum reached, and the most
    padding each step could need."""
    steps = cdr.layout.steps

    def size(lo: int, hi: int) -> int:
        total, i = 0, lo
        while i < hi:
            s = steps[i]
            n = s.max_count if s.count is None else s.count
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                total += n * size(i + 1, s.partner)
                i = s.partner + 1
                continue
            many = s.kind in (StepKind.ARRAY, StepKind.STRING)
            total += s.size * (n if many else 1) + cdr.align[i] - 1
            i += 1
        return total

    return size(2, len(steps))


def cdr_length_rules(cdr: CdrLayout) -> dict[int, LengthRule]:
    """How each length prefix is held against the sample length: its elements' fewest bytes
    must fit in the bytes left (a string's length counts its NUL, one byte each). Alignment
    makes the bytes after a part depend on where it ends, so no CDR length is held to an exact
    sample length; the end of the walk is (``frame length disagrees``)."""
    return {i: r._replace(fixed_after=None) for i, r in length_rules(cdr.layout).items()}


def derive_cdr_layout(reg: MsgRegistry, type_name: str, **kw: Any) -> CdrLayout:
    """:func:`~rosfpga_lab.hw.layout.derive_layout` of the ROS 2 form of ``type_name`` (``reg``
    holds the ROS 1 types, as for TCPROS; the keywords are the same), rewritten for CDR.

    Raises:
        LayoutError: as ``derive_layout`` (a check of ``header.seq``: ROS 2 has none).
    """
    creg = cdr_registry(reg)
    return to_cdr(derive_layout(creg, type_name, **kw), creg)


def cdr_layout_from_config(config: NodeConfig, reg: MsgRegistry | None = None, *,
                           output: bool = False) -> CdrLayout:
    """The CDR walk of a node configuration's subscribed (``output``: published) type, as
    :func:`~rosfpga_lab.hw.layout.layout_from_config` derives the TCPROS one."""
    creg = cdr_registry(reg or config.registry())
    return to_cdr(layout_from_config(config, creg, output=output), creg)


# -- values -----------------------------------------------------------------------------------

def _string_length(cdr: CdrLayout, step: Step) -> bool:
    return step.kind is StepKind.LENGTH and step.partner is not None and \
        cdr.layout.steps[step.partner].kind is StepKind.STRING


def to_cdr_tokens(cdr: CdrLayout, toks: Iterable[Token]) -> list[Token]:
    """Tokens of the base walk as tokens of the CDR walk (a string's length + 1)."""
    where = cdr.cdr_index
    out = []
    for t in toks:
        i = where[t.step]
        s = cdr.layout.steps[i]
        out.append(Token(i, t.value + 1 if _string_length(cdr, s) else t.value, t.at))
    return out


def to_base_tokens(cdr: CdrLayout, toks: Iterable[Token]) -> list[Token]:
    """Tokens of the CDR walk as tokens of the base walk (the inverse of :func:`to_cdr_tokens`)."""
    out = []
    for t in toks:
        b = cdr.base_index[t.step]
        assert b is not None, f"step {t.step} has no value"
        s = cdr.layout.steps[t.step]
        out.append(Token(b, t.value - 1 if _string_length(cdr, s) else t.value, t.at))
    return out


def cdr_tokens(cdr: CdrLayout, message: Any) -> list[Token]:
    """The values of ``message`` (a ROS 2 value, e.g. from ``msg.cdr.deserialize_cdr``) in the
    CDR walk's order: what the CDR subscriber emits, step by step."""
    value = with_placeholders(cdr.registry, cdr.layout.type_name, message)
    return to_cdr_tokens(cdr, tokens(cdr.base, value))


def cdr_bytes(cdr: CdrLayout, step: Step, value: Any) -> bytes:
    """The wire bytes of one CDR token (its padding not included)."""
    return encode_token(step, value)


def cdr_marshal(cdr: CdrLayout, toks: Iterable[Token]) -> bytes:
    """The circuit's output record (4-byte sample length + CDR payload, options 0 and no
    trailing padding, as Cyclone DDS's ``serialize()`` writes) from CDR tokens in walk order."""
    parts = [b"", CDR_LE]
    at = 4 + len(CDR_LE)            # offset in the record
    steps = cdr.layout.steps
    for t in toks:
        s = steps[t.step]
        data = encode_token(s, t.value)
        if data:
            pad = cdr.pad(t.step, at)
            if pad:
                parts.append(bytes(pad))
            parts.append(data)
            at += pad + len(data)
        if s.kind is StepKind.STRING:
            parts.append(b"\x00")
            at += 1
    parts[0] = struct.pack("<I", at - 4)
    return b"".join(parts)


def format_cdr_layout(cdr: CdrLayout) -> str:
    """The CDR walk as text: :func:`~rosfpga_lab.hw.layout.format_layout`'s rows with each
    step's alignment."""
    lines = format_layout(cdr.layout).split("\n")
    head, rows = lines[:2], lines[2:]
    width = max(len(r) for r in lines[1:])
    out = [head[0].replace("body", "payload"), head[1].ljust(width) + "  align"]
    out += [r.ljust(width) + f"  {a}" for r, a in zip(rows, cdr.align)]
    return "\n".join(out)


__all__ = [
    "ALIGN_ORIGIN", "CdrLayout", "END_ALIGN", "OPTIONS_PADDING_MASK", "PLACEHOLDER",
    "REPRESENTATION", "TAIL_LABEL",
    "cdr_bytes", "cdr_layout_from_config", "cdr_length_rules", "cdr_marshal", "cdr_registry",
    "cdr_tokens", "derive_cdr_layout", "format_cdr_layout", "to_base_tokens", "to_cdr",
    "to_cdr_tokens", "unannounced_padding", "with_placeholders",
]
