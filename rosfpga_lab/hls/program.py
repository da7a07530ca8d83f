"""The generated circuit's walk over a frame as a small program (the microcode of any layout).

How this works: the generated subscriber and publisher of a message other than
``sensor_msgs/Image`` are two small walkers (the same in HLS C++ and in Verilog) that step
through one table, :class:`Program`, rendered into the generated files with a comment per field
naming it. One instruction per field in wire order:

* ``FIXED`` -- ``size`` bytes (a number, a time, a fixed array of numbers);
* ``VAR`` -- a uint32 count, then count x ``size`` bytes (a string, a variable array);
* ``LOOP`` -- an array of messages: ``count`` elements (fixed) or a uint32 count read from the
  frame (``size`` 0 ... see :attr:`Instr.variable`), then the instructions up to its ``END``
  once per element;
* ``END`` -- the end of a loop's body; ``DONE`` -- the end of the message;
* ``ENCAP`` -- CDR's 4-byte encapsulation header (see below).

What the subscriber does with the bytes (:class:`Sub`): skip them, carry them (into the carry
memory, in order, lengths included), check them (equal to ``const`` bytes from the constant
table) or stream them (to the application; a ``VAR`` stream's count must equal ``count``).
What the publisher writes (:class:`Pub`): the carried bytes, the constant bytes, its own
message counter (``COUNT``: a uint32 from ``seq_start``), zeros (``ZERO``; an empty string or
array for ``VAR``) or the application's output (``STREAM``).

The subscriber adds up the publisher's output length as it walks, so the publisher can write
the frame length first; it starts once the subscriber has read (and accepted) the whole frame,
or, with streaming early release (:attr:`Program.stream_early`: nothing after the stream's count
can refuse the frame), once the stream's count is checked, writing the stream as it flows (the
Verilog, and the HLS C++'s metadata word at the count; :func:`run_program` hands whole frames
over: the same bytes).
A frame refused after its stream went to the application is dropped by the publisher (it reads
the application's output and writes nothing). :func:`run_program` is the Python executor of the
same program: the specification the C++ and Verilog walkers are tested against.

CDR (ROS 2's samples, :mod:`rosfpga_lab.hw.cdrlayout`) is the same program with four more
things, all no-ops for TCPROS: each instruction's ``align`` (padding before its first byte:
the subscriber skips ``-(pos - 8) % align`` bytes, counted from byte 8 of its input, after the
sample length and the encapsulation header; the publisher writes zeros counted from its own
output position, because skipped or re-sized fields change where its fields fall), a ``VAR``'s
``elem_align`` (padding before its elements, only when it has some), a ``VAR``'s ``nul``
(a string whose count includes its NUL: at least 1, the last byte 0, else ``status3``), and
``ENCAP``: the subscriber checks ``00 01`` (CDR little-endian) and takes the padding that ends
the payload from the options' two low bits (skipped after ``DONE``); the publisher writes its
constant ``00 01 00 00``. At ``DONE``, when the options announce fewer bytes than are left and
those are the 1 to :data:`END_ALIGN` - 1 that bring the payload (header included) to a multiple of
:data:`END_ALIGN` (Cyclone DDS pads so with options ``00 00``), the subscriber takes them; any
other bytes left refuse the frame with the frame length's status. Padding is never looked at,
whatever its value (CDR leaves it undefined; Cyclone DDS writes zeros and reads past it), so a
walk whose stream is its last field can be released at the stream's count
(:attr:`Program.stream_early`). No count is held to an exact fit in CDR (``fixed_after`` -1),
but with early release the stream's count is held to the payload's end, up to that end padding.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import IntEnum

from rosfpga_lab.hls.limits import MAX_LOOP_DEPTH
from rosfpga_lab.hw.cdrlayout import (
    ALIGN_ORIGIN, END_ALIGN, OPTIONS_PADDING_MASK, unannounced_padding,
)
from rosfpga_lab.msg.cdr import CDR_LE


#: Bytes of one element of a ``VAR`` (a number): the walkers shift a count by their log2.
VAR_SIZES = (1, 2, 4, 8)


class Op(IntEnum):
    """Instruction kinds (their codes are the C++ and Verilog ones)."""

    FIXED = 0
    VAR = 1
    LOOP = 2
    END = 3
    DONE = 4
    ENCAP = 5


class Sub(IntEnum):
    """What the subscriber does with a field's bytes."""

    SKIP = 0
    CARRY = 1
    CHECK = 2
    STREAM = 3
    RANGE = 4


class Pub(IntEnum):
    """What the publisher writes for a field."""

    CARRY = 0
    CONST = 1
    COUNT = 2
    ZERO = 3
    STREAM = 4


@dataclass(frozen=True)
class Instr:
    """One instruction (one field of the message, in wire order).

    Attributes:
        op, sub, pub: see the module docstring.
        size: FIXED: bytes; VAR: bytes per element; LOOP: 0.
        count: VAR: most elements accepted (for a stream: the exact count);
            LOOP: elements of a fixed array, or the most accepted of a variable one.
        variable: LOOP: the count is read from the frame (a uint32) rather than fixed.
        status: the status code the subscriber refuses with at this field (0: it cannot fail);
            for VAR, a bad count.
        status2: VAR with CHECK: the status of contents unlike the constant.
        fixed_after: VAR and variable LOOP: when only fixed-size fields follow the counted part,
            their bytes (then the count must fill the frame exactly), else -1.
        elem_min: VAR and variable LOOP: fewest bytes of one element (VAR: ``size``).
        kind: RANGE: how the value is ordered: 0 unsigned, 1 signed, 2 IEEE float (a NaN is out
            of every range, -0.0 equals +0.0).
        const: CHECK/CONST: the bytes (VAR: the elements' bytes, count = len // size).
        name: the field's path in the message, e.g. ``header.frame_id``.
        type: its ROS type, e.g. ``string`` or ``float32[]``.
        jump: LOOP: the index of its END; END: the index of its LOOP (filled by :class:`Program`).
        align: CDR: alignment of the field's first byte (a count's, for VAR and variable LOOP).
        elem_align: CDR VAR: alignment of its first element (applied when the count is > 0).
        nul: CDR VAR: a string whose count includes its NUL (at least 1, last byte 0).
        status3: a ``nul`` VAR: the status of a last byte that is not 0.
    """

    op: Op
    sub: Sub = Sub.SKIP
    pub: Pub = Pub.CARRY
    size: int = 0
    count: int = 0
    variable: bool = False
    status: int = 0
    status2: int = 0
    kind: int = 0
    fixed_after: int = -1
    elem_min: int = 0
    const: bytes = b""
    name: str = ""
    type: str = ""
    jump: int = 0
    align: int = 1
    elem_align: int = 1
    nul: bool = False
    status3: int = 0


@dataclass(frozen=True)
class Program:
    """A message's walk: the instructions, the constant table and the statuses.

    Attributes:
        instrs: the instructions, the last one ``DONE``.
        statuses: ``(name, label)`` per status code, code 0 first (accepted), code 1 the frame
            length's.
        min_body, max_frame: the frame lengths accepted are min_body..max_frame.
        seq_start: the publisher's first ``COUNT`` value.
        stream_bytes: bytes of one element of the streamed array; stream_length its elements.
        carry_bytes: size of the carry memory (the most carried bytes of one frame).
        type_in, type_out: the message types.
    """

    instrs: tuple[Instr, ...]
    statuses: tuple[tuple[str, str], ...]
    min_body: int
    max_frame: int
    seq_start: int
    stream_bytes: int
    stream_length: int
    carry_bytes: int
    type_in: str = ""
    type_out: str = ""
    const_offsets: tuple[int, ...] = field(default=(), compare=False)

    @staticmethod
    def build(instrs: list[Instr], **kwargs: object) -> "Program":
        """Fill each LOOP's and END's ``jump``, the constant offsets, and check nesting.

        Raises:
            ValueError: unbalanced loops, nesting deeper than :data:`MAX_LOOP_DEPTH`, no DONE last,
                a ``VAR`` whose elements are not :data:`VAR_SIZES` bytes (its ``elem_min``).
        """
        stack: list[int] = []
        fixed = list(instrs)
        for i, ins in enumerate(fixed):
            if ins.op == Op.VAR and ins.elem_min == 0:
                fixed[i] = ins = _replace(ins, elem_min=ins.size)
            if ins.op == Op.VAR and (ins.size not in VAR_SIZES or ins.elem_min != ins.size):
                # the walkers shift a count by log2(size) (no multiplier in the circuit)
                raise ValueError(f"{ins.name}: an array of {ins.size}-byte elements (fewest "
                                 f"{ins.elem_min}); a VAR's elements are 1, 2, 4 or 8 bytes")
            if ins.op == Op.LOOP:
                stack.append(i)
                if len(stack) > MAX_LOOP_DEPTH:
                    raise ValueError(f"arrays of messages nest deeper than {MAX_LOOP_DEPTH} at {ins.name}")
            elif ins.op == Op.END:
                if not stack:
                    raise ValueError(f"END without LOOP at instruction {i}")
                j = stack.pop()
                fixed[j] = _replace(fixed[j], jump=i)
                fixed[i] = _replace(ins, jump=j)
        if stack or not fixed or fixed[-1].op != Op.DONE:
            raise ValueError("the program must close every loop and end with DONE")
        offsets, at = [], 0
        for ins in fixed:
            offsets.append(at)
            at += len(ins.const)
        return Program(tuple(fixed), const_offsets=tuple(offsets), **kwargs)  # type: ignore[arg-type]

    @property
    def cdr(self) -> bool:
        """The walk reads CDR samples (it has an ``ENCAP``), not TCPROS frames."""
        return any(ins.op == Op.ENCAP for ins in self.instrs)

    @property
    def stream_early(self) -> int | None:
        """Where the subscriber may hand a frame over early (streaming early release), or None.

        The streamed array must be a ``VAR`` outside any loop, written as the application's
        output, whose count decides the frame's fate: nothing after the count may refuse it.
        TCPROS: the count must fill the frame exactly with what follows (``fixed_after`` >= 0),
        and only ``FIXED`` fields that cannot refuse (skipped or carried) follow it. CDR: the
        array is the last field and its elements align to at most :data:`END_ALIGN` (so no
        padding falls between its count and its elements, in or out); at the count the
        subscriber then checks that the elements end the payload exactly or leave only the
        unannounced end padding (whose bytes are never looked at). The subscriber then hands
        the fields over (``meta_valid``, with the whole output length) at the count's decision,
        and the publisher writes the frame while the stream flows (the FIFO after the
        application holds a few beats, not the whole array). Returns the bytes the publisher
        writes from the count on (the count, the array, the fixed fields after it), added to
        the output length so far; None: the whole frame is read first (a variable field or a
        check after the stream may refuse the frame after its stream went out).
        """
        depth = 0
        cdr = self.cdr
        for i, ins in enumerate(self.instrs):
            depth += (ins.op == Op.LOOP) - (ins.op == Op.END)
            if ins.sub != Sub.STREAM or ins.op not in (Op.FIXED, Op.VAR):
                continue
            rest = self.instrs[i + 1:-1]
            if ins.op != Op.VAR or ins.pub != Pub.STREAM or depth:
                return None
            if cdr and (rest or ins.elem_align > END_ALIGN):
                return None
            if not cdr and (ins.fixed_after < 0 or any(
                    r.op != Op.FIXED or r.sub not in (Sub.SKIP, Sub.CARRY) for r in rest)):
                return None
            return 4 + ins.count * ins.size + sum(r.size for r in rest)
        return None

    @property
    def const_table(self) -> bytes:
        """Every instruction's constant bytes, one after the other."""
        return b"".join(ins.const for ins in self.instrs)


def _replace(ins: Instr, **changes: object) -> Instr:
    return replace(ins, **changes)  # type: ignore[arg-type]


class Refused(Exception):
    """The subscriber refused a frame (``status``); ``streamed``: its stream had gone out."""

    def __init__(self, status: int, streamed: bool) -> None:
        super().__init__(status)
        self.status = status
        self.streamed = streamed


#: The status of a frame whose length is refused, or which ends inside a field or after the last.
FRAME_LENGTH_STATUS = 1
# CDR: where alignment counts from (after the 4-byte sample length and the encapsulation
# header), the header the circuit reads and the publisher writes (CDR little-endian, options
# 0), and the options' end-padding bits: each owned by the CDR layout and the codec below.
ENCAP_BYTES = CDR_LE
ENCAP_PAD_MASK = OPTIONS_PADDING_MASK


def pad(pos: int, align: int) -> int:
    """Padding bytes before a field of alignment ``align`` at byte ``pos`` (see ALIGN_ORIGIN)."""
    return -(pos - ALIGN_ORIGIN) % align


def order_key(b: bytes, kind: int) -> int:
    """The unsigned key a value's little-endian bytes order by (``kind`` as :attr:`Instr.kind`):
    two's complement flips the sign bit, IEEE floats map by totalOrder with -0.0 taken as +0.0."""
    v = int.from_bytes(b, "little")
    sign = 1 << (8 * len(b) - 1)
    if kind == 1:
        return v ^ sign
    if kind == 2:
        if v == sign:
            v = 0
        return (~v & (2 * sign - 1)) if v & sign else v | sign
    return v


def is_nan(b: bytes) -> bool:
    """The bytes of a float32/float64 hold a NaN."""
    v = int.from_bytes(b, "little")
    mant = 23 if len(b) == 4 else 52
    exp = (v >> mant) & ((1 << (8 * len(b) - 1 - mant)) - 1)
    return exp == (1 << (8 * len(b) - 1 - mant)) - 1 and v & ((1 << mant) - 1) != 0


def in_range(b: bytes, bounds: bytes, kind: int) -> bool:
    """``b`` is within ``bounds`` (low bytes then high bytes), ordered by ``kind``."""
    n = len(b)
    if kind == 2 and is_nan(b):
        return False
    return order_key(bounds[:n], kind) <= order_key(b, kind) <= order_key(bounds[n:], kind)


def _u32(b: bytes) -> int:
    return int.from_bytes(b, "little")


#: Clocks of each of the subscriber's decisions (S_FCHK, S_DECODE, S_COUNTED, S_FINISH): two
#: that settle its arithmetic into registers, then the one that acts.
DECIDE_CLOCKS = 3


def least_clocks(elem_min: int) -> int:
    """Clocks of the subscriber's S_LEAST for an array of messages whose elements take at least
    ``elem_min`` bytes: a bit of ``elem_min`` per clock (count x elem_min with no multiplier),
    then one that finds none left."""
    return 1 + elem_min.bit_length()


# long: one dispatch of the subscriber's state machine, whose closures (take, out_pad, fits)
# share one walk's state (position, frame end, streamed bytes, output length) and its timeline
def subscribe(prog: Program, frame: bytes, timeline: bytearray | None = None,
              marks: dict[str, int] | None = None) -> tuple[bytes, bytes, int]:
    """Walk one whole frame as the subscriber does.

    ``timeline``: appended a 1 per clock the Verilog walker takes a byte and a 0 per clock it
    does not, from the frame length's first byte to the clock it accepts the frame (see
    :func:`frame_clocks`): :data:`DECIDE_CLOCKS` for each decision (the frame length's checks,
    each instruction's decode, a count's checks, each field's end), ``1 + bits(elem_min)`` for
    an array of messages' fewest bytes (:func:`least_clocks`), a byte per clock. ``marks``:
    set ``release`` to the timeline's length at the stream count's decision (where a walk with
    :attr:`Program.stream_early` hands the frame over) and ``carried`` to the clock (1-based)
    of each carried byte after the stream, in order, as ``carried_N``.

    Returns:
        ``(carried bytes, streamed bytes, output body length)``.

    Raises:
        Refused: a field failed (status code), with whether the stream had gone out.
    """
    flen = _u32(frame[:4])
    if not prog.min_body <= flen <= prog.max_frame or len(frame) != 4 + flen:
        raise Refused(1, False)
    end = 4 + flen
    fend = end               # where the fields end (CDR: less the payload's end padding)
    pos = 4
    carry = bytearray()
    stream = bytearray()
    out_len = 0
    loops: list[list[int]] = []  # [elements left, suppressed]
    pc = 0
    tl = timeline if timeline is not None else bytearray()
    tl += b"\1" * 4                                   # the frame length
    decide = b"\0" * DECIDE_CLOCKS
    tl += decide                                      # its checks (S_FCHK)

    def take(n: int, status: int, align: int = 1) -> bytes:
        nonlocal pos
        start = pos
        if n and align > 1:
            if pos + pad(pos, align) >= fend:  # the frame ends before this field
                raise Refused(FRAME_LENGTH_STATUS, bool(stream))
            pos += pad(pos, align)
        if pos + n > fend:  # the frame ends inside (or before) this field
            raise Refused(status or FRAME_LENGTH_STATUS, bool(stream))
        b = frame[pos:pos + n]
        pos += n
        tl.extend(b"\1" * (pos - start))               # a byte per clock, padding included
        return b

    def out_pad(n: int, align: int) -> None:
        """The publisher's padding before a part of ``n`` bytes (its position: 4 + out_len)."""
        nonlocal out_len
        if n and not quiet:
            out_len += pad(4 + out_len, align)

    def fits(ins: Instr, n: int) -> None:
        """A count's checks: its maximum (a stream's: exact), then the bytes left."""
        if n != ins.count if ins.sub == Sub.STREAM else n > ins.count:
            raise Refused(ins.status, bool(stream))
        if ins.nul and n == 0:
            raise Refused(ins.status, bool(stream))
        need = n * ins.elem_min
        if ins.fixed_after >= 0 and need + ins.fixed_after != fend - pos:
            raise Refused(FRAME_LENGTH_STATUS, bool(stream))
        if need > fend - pos:
            raise Refused(ins.status, bool(stream))
        if early_cdr and ins.sub == Sub.STREAM and need != fend - pos and \
                not unannounced_padding(pos + need, fend, end):
            raise Refused(FRAME_LENGTH_STATUS, bool(stream))  # as DONE would, at the count

    cdr = prog.cdr
    early_cdr = cdr and prog.stream_early is not None
    suppressed = 0
    while True:
        ins = prog.instrs[pc]
        quiet = suppressed > 0
        tl += decide  # each instruction's decode (S_DECODE); S_COUNTED, S_FINISH below
        if ins.op == Op.DONE:
            after = end - pos  # CDR: unannounced padding up to a multiple of END_ALIGN
            if cdr and unannounced_padding(pos, fend, end):
                tl.extend(b"\1" * after)  # taken before the frame is accepted
            elif pos != fend:
                raise Refused(ins.status, bool(stream))
            return bytes(carry), bytes(stream), out_len
        if ins.op == Op.ENCAP:
            b = take(4, ins.status)
            tl += decide                                # S_FINISH
            if b[:2] != ins.const[:2]:
                raise Refused(ins.status, bool(stream))
            tail = b[3] & ENCAP_PAD_MASK
            if tail > fend - pos:
                raise Refused(FRAME_LENGTH_STATUS, bool(stream))
            fend -= tail
            out_len += len(ins.const)
        elif ins.op == Op.FIXED:
            b = take(ins.size, ins.status, ins.align)
            tl += decide if ins.size else b""          # S_FINISH
            out_pad(ins.size, ins.align)
            if ins.sub in (Sub.CARRY, Sub.RANGE):
                if marks is not None and "release" in marks:  # the clock each was taken
                    at = len(tl) - DECIDE_CLOCKS - ins.size + 1
                    for k in range(ins.size):
                        marks[f"carried_{len(carry) + k}"] = at + k
                carry += b
            if ins.sub == Sub.CHECK and b != ins.const:
                raise Refused(ins.status, bool(stream))
            if ins.sub == Sub.RANGE and not in_range(b, ins.const, ins.kind):
                raise Refused(ins.status, bool(stream))
            elif ins.sub == Sub.STREAM:
                stream += b
            out_len += 0 if quiet else ins.size
        elif ins.op == Op.VAR:
            lb = take(4, ins.status, ins.align)
            tl += decide                                # S_COUNTED
            n = _u32(lb)
            fits(ins, n)
            if ins.sub == Sub.STREAM and marks is not None:
                marks["release"] = len(tl)
            b = take(n * ins.size, ins.status, ins.elem_align)
            tl += decide                                # S_FINISH
            text = b[:-1] if ins.nul else b
            if ins.sub == Sub.CARRY:
                carry += lb + b
            elif ins.sub == Sub.CHECK and text != ins.const:
                raise Refused(ins.status2, bool(stream))
            elif ins.sub == Sub.STREAM:
                stream += b
            if ins.nul and b[-1] != 0:
                raise Refused(ins.status3, bool(stream))
            out_pad(4, ins.align)
            if not quiet:
                out_len += 4
            body = {Pub.CARRY: n * ins.size, Pub.CONST: len(ins.const) + ins.nul,
                    Pub.ZERO: int(ins.nul), Pub.STREAM: n * ins.size, Pub.COUNT: 0}[ins.pub]
            out_pad(body, ins.elem_align)
            if not quiet:
                out_len += body
        elif ins.op == Op.LOOP:
            n = ins.count
            if ins.variable:
                lb = take(4, ins.status, ins.align)
                n = _u32(lb)
                fits(ins, n)
                if ins.sub == Sub.CARRY:
                    carry += lb
                out_pad(4, ins.align)
                out_len += 0 if quiet else 4
            tl += b"\0" * least_clocks(ins.elem_min)   # S_LEAST
            tl += decide                                # S_COUNTED
            zero = ins.variable and ins.pub == Pub.ZERO
            if n == 0:
                pc = ins.jump + 1
                continue
            loops.append([n, int(zero)])
            suppressed += int(zero)
        elif ins.op == Op.END:
            top = loops[-1]
            top[0] -= 1
            if top[0] > 0:
                pc = ins.jump + 1
                continue
            suppressed -= top[1]
            loops.pop()
        pc += 1


def _fixed_bytes(ins: Instr, carry: bytes, ci: int, stream: bytes, si: int, seq: int
                 ) -> tuple[bytes, int, int]:
    """The bytes the publisher writes for a ``FIXED`` field (after its padding), with the
    carried and streamed bytes' next positions."""
    if ins.pub == Pub.CARRY:
        return carry[ci:ci + ins.size], ci + ins.size, si
    if ins.pub == Pub.CONST:
        return ins.const, ci, si
    if ins.pub == Pub.COUNT:
        return (seq & 0xFFFFFFFF).to_bytes(4, "little") + bytes(ins.size - 4), ci, si
    if ins.pub == Pub.ZERO:
        return bytes(ins.size), ci, si
    return stream[si:si + ins.size], ci, si + ins.size


def _var_body(ins: Instr, carry: bytes, ci: int, stream: bytes, si: int
              ) -> tuple[int, bytes, int, int]:
    """A ``VAR`` field's count and body as the publisher writes them, with the carried and
    streamed bytes' next positions."""
    if ins.pub == Pub.CARRY:
        n = _u32(carry[ci:ci + 4])
        return n, carry[ci + 4:ci + 4 + n * ins.size], ci + 4 + n * ins.size, si
    if ins.pub == Pub.CONST:
        body = ins.const + bytes(int(ins.nul))
        return len(body) // ins.size, body, ci, si
    if ins.pub == Pub.ZERO:
        return int(ins.nul), bytes(int(ins.nul)), ci, si
    return ins.count, stream[si:si + ins.count * ins.size], ci, si + ins.count * ins.size


def publish(prog: Program, carry: bytes, stream: bytes, out_len: int, seq: int,
            timeline: bytearray | None = None, marks: dict[str, int] | None = None) -> bytes:
    """The frame the publisher writes for an accepted frame (see the module docstring).

    ``timeline``: appended a 1 per clock the Verilog walker writes a byte and a 0 per clock it
    does not, from its first byte (output always ready, the stream's bytes there in time): a
    clock to decode each instruction (P_DECODE) and one after each count (P_COUNTED).
    ``marks``: set ``stream`` to the timeline's index of the stream's first byte and
    ``carried_N`` to that of carried byte N (see :func:`subscribe`)."""
    out = bytearray(out_len.to_bytes(4, "little"))
    tl = timeline if timeline is not None else bytearray()
    written = 0

    def moved() -> None:
        """A clock per byte written since the last call."""
        nonlocal written
        tl.extend(b"\1" * (len(out) - written))
        written = len(out)

    ci = 0
    si = 0
    loops: list[int] = []
    pc = 0
    while True:
        ins = prog.instrs[pc]
        moved()
        tl.append(0)  # a clock to decode each instruction (then one after each count)
        if ins.op == Op.DONE:
            assert len(out) == 4 + out_len, (len(out), out_len)
            return bytes(out)
        if ins.op == Op.ENCAP:
            out += ins.const
        elif ins.op == Op.FIXED:
            if ins.size:
                out += bytes(pad(len(out), ins.align))
            if marks is not None and ins.pub == Pub.CARRY:
                for k in range(ins.size):
                    marks[f"carried_{ci + k}"] = len(tl) + k
            b, ci, si = _fixed_bytes(ins, carry, ci, stream, si, seq)
            out += b
        elif ins.op == Op.VAR:
            out += bytes(pad(len(out), ins.align))
            n, body, ci, si = _var_body(ins, carry, ci, stream, si)
            out += n.to_bytes(4, "little")
            moved()
            tl.append(0)
            if body:
                out += bytes(pad(len(out), ins.elem_align))
            if marks is not None and ins.pub == Pub.STREAM:
                marks["stream"] = len(tl) + len(out) - written
            out += body
        elif ins.op == Op.LOOP:
            n = ins.count
            if ins.variable:
                out += bytes(pad(len(out), ins.align))
                if ins.pub == Pub.ZERO:
                    out += bytes(4)
                    moved()
                    tl.append(0)
                    pc = ins.jump + 1
                    continue
                n = _u32(carry[ci:ci + 4])
                ci += 4
                out += n.to_bytes(4, "little")
                moved()
            tl.append(0)
            if n == 0:
                pc = ins.jump + 1
                continue
            loops.append(n)
        elif ins.op == Op.END:
            loops[-1] -= 1
            if loops[-1] > 0:
                pc = ins.jump + 1
                continue
            loops.pop()
        pc += 1


def run_program(prog: Program, frames: list[bytes], apply: Callable[[bytes], bytes]) -> tuple[bytes, list[int]]:
    """Frames through subscriber, application (``apply``: stream bytes -> bytes) and publisher.

    Returns:
        ``(output bytes, status code per frame)``.
    """
    out = bytearray()
    statuses = []
    seq = prog.seq_start
    for frame in frames:
        try:
            carry, stream, out_len = subscribe(prog, frame)
        except Refused as exc:
            statuses.append(exc.status)
            continue
        statuses.append(0)
        out += publish(prog, carry, apply(stream), out_len, seq)
        seq += 1
    return bytes(out), statuses



#: Frames' records the subscriber holds for the publisher (its output length, drop flag and a
#: carry bank each: ``rfl_gsubscriber``'s meta_* and nxt_*; the HLS meta FIFO's depth, the carry
#: FIFO's that many frames): it reads the next frame while the publisher writes one.
RECORDS = 2
#: Clocks from the subscriber accepting a frame to the publisher's first byte (its fields are
#: handed over on a register; the publisher leaves its idle state on the next clock).
ACCEPT_TO_PUBLISH = 2
#: Back to back (:func:`stream_clocks`): from the publisher's release of a frame (P_DONE, the
#: clock after its timeline) to its next frame's first byte, and to the subscriber's first
#: byte of the frame that waited for that record (counted, as the subscriber's timeline is,
#: from the input's handshake: the rx FIFO and its register slice come before the subscriber).
DONE_TO_PUBLISH = 2
RELEASE_TO_TAKE = 0
#: Clocks from the publisher's byte to the node's output: the register slice before the tx
#: FIFO (one), then the FIFO (two).
TX_LATENCY = 3
#: Clocks of the stream's path from the subscriber to the publisher beyond the application's
#: own wait (register slices, the element packer, the FIFOs' output registers, the unpacker):
#: through ``rfl_window1d``, and through the video project's ``rfl_morph``.
WINDOW_PATH = 9
VIDEO_PATH = 14
#: Clocks from the subscriber writing a carried byte to the publisher able to write it (the
#: carry memory's write, its read register, carry_rdata).
CARRY_PATH = 3


def stream_latency(ebytes: int, ksize: int, line: int | None = None,
                   length: int | None = None) -> int:
    """Clocks from a streamed byte into the subscriber to that byte of the application's output
    at the publisher, when nothing waits (streaming early release: see :func:`frame_clocks`).

    Args:
        ebytes: bytes of a beat (an element; a pixel of a video stream).
        ksize: the window (1: pass-through).
        line: a video stream's pixels per line (``rfl_morph`` waits for ``ksize // 2`` lines
            and pixels more); None: ``rfl_window1d`` (``ksize // 2`` elements more; of an
            array shorter than that, the elements it has and a clock per missing one).
        length: ``rfl_window1d``: the array's elements (None: long enough for the window).
    """
    if line is None:
        ahead = ksize // 2 if length is None else min(ksize // 2, length - 1)
        return (ahead + 1) * ebytes + WINDOW_PATH + (ksize // 2 - ahead)
    return ((ksize // 2) * line + ksize // 2 + 1) * ebytes + VIDEO_PATH


@dataclass(frozen=True)
class FrameClocks:
    """Clocks of one accepted frame in the generated Verilog (``rfl_gtop``), from the walkers'
    timelines (:func:`subscribe`, :func:`publish`: each says the clocks of its walker's states).

    Attributes:
        subscriber: from the frame length's first byte in to the clock the frame is accepted.
        publisher: from the publisher's first byte out to its last.
        total: from the first byte into the subscriber to the last byte out of the node,
            ``start + ACCEPT_TO_PUBLISH - 1 + publisher + TX_LATENCY`` with the output always
            ready, where ``start`` is the clock the subscriber hands the frame over: its
            acceptance, or with streaming early release (:attr:`Program.stream_early`) the
            stream count's decision (and the publisher then waits for the stream, by
            :func:`stream_latency`, and the carried bytes after it); with ``ready`` < 1 at least
            the output bytes at that share after the publisher starts.
        in_bytes, out_bytes: the frames' sizes.
    """

    subscriber: int
    publisher: int
    total: int
    in_bytes: int
    out_bytes: int


@dataclass(frozen=True)
class _Walk:
    """One accepted frame's walks: the subscriber's clocks (its timeline, then the announced end
    padding it skips after acceptance), where it hands the frame over, the publisher's timeline
    and the marks of both (:func:`subscribe`, :func:`publish`)."""

    sub_clocks: int
    busy: int
    start: int
    pub_tl: bytes
    sub_marks: dict[str, int]
    pub_marks: dict[str, int]
    out_bytes: int


def _walk(prog: Program, frame: bytes) -> _Walk:
    sub_tl, pub_tl = bytearray(), bytearray()
    sub_marks: dict[str, int] = {}
    pub_marks: dict[str, int] = {}
    carry, stream, out_len = subscribe(prog, frame, sub_tl, sub_marks)
    out = publish(prog, carry, stream, out_len, prog.seq_start, pub_tl, pub_marks)
    start = len(sub_tl) if prog.stream_early is None else sub_marks["release"]
    return _Walk(len(sub_tl), len(sub_tl) + len(frame) - sub_tl.count(1), start, bytes(pub_tl),
                 sub_marks, pub_marks, len(out))


def _publisher_wait(prog: Program, w: _Walk, sub_at: int, pub_at: int, latency: int) -> int:
    """Clocks the publisher of ``w`` waits, its timeline index 0 at clock ``pub_at`` and the
    subscriber's at ``sub_at``: with streaming early release, for the stream's first byte (then
    the stream flows a byte per clock, as it writes) and for each carried byte after the
    stream; else none (the publisher starts with all of them in)."""
    if prog.stream_early is None:
        return 0
    wait = max(0, sub_at + w.start + 1 + latency - (pub_at + w.pub_marks["stream"]))
    for key, at in w.sub_marks.items():
        if key.startswith("carried_"):
            wait = max(wait, sub_at + at + CARRY_PATH - (pub_at + w.pub_marks[key]))
    return wait


def frame_clocks(prog: Program, frame: bytes, ready: float = 1.0, *,
                 latency: int = 0) -> FrameClocks:
    """The clocks of ``frame`` through the generated circuit (see :class:`FrameClocks`), the
    output ready ``ready`` of the clocks. ``latency``: the stream's path,
    :func:`stream_latency` (used by a walk with :attr:`Program.stream_early` only).

    Raises:
        Refused: the circuit refuses the frame (its clocks are not modelled).
        ValueError: ``ready`` is not in (0, 1].
    """
    if not 0 < ready <= 1:
        raise ValueError(f"ready must be in (0, 1], got {ready}")
    w = _walk(prog, frame)
    start = w.start
    # the publisher's timeline index i is at clock start + ACCEPT_TO_PUBLISH + i
    pub = w.pub_tl.rindex(1) + 1 + _publisher_wait(prog, w, 0, start + ACCEPT_TO_PUBLISH,
                                                   latency)
    total = start + ACCEPT_TO_PUBLISH - 1 + pub + TX_LATENCY
    if ready < 1:
        total = max(total, start + ACCEPT_TO_PUBLISH + TX_LATENCY - 1
                    + -(-w.out_bytes * 1000 // round(ready * 1000)))
    return FrameClocks(w.sub_clocks, pub, total, len(frame), w.out_bytes)


def stream_clocks(prog: Program, frames: list[bytes], *, latency: int = 0) -> list[int]:
    """Frames back to back through the generated circuit (their bytes always there, the output
    always ready): for each, the clocks from the first frame's first byte in to its own last
    byte out (the first's is :func:`frame_clocks`'s ``total``). The subscriber takes a frame
    once it is done with the last (its timeline, then the end padding it skips) and fewer than
    :data:`RECORDS` records are held, i.e. once the publisher has released the frame
    ``RECORDS`` before (``RELEASE_TO_TAKE``); the publisher starts a frame once handed over
    and done with the last (``DONE_TO_PUBLISH`` after its release). So in steady state a frame
    costs the larger of the subscriber's clocks and the publisher's, not their sum. Exact while
    the stream's path never makes the subscriber wait: the FIFO after the application holds a
    whole stream (``axis_depth`` beats with streaming early release), and the next frame's
    stream queues behind this one's; a video window flushing a small image's last lines holds
    the next frame back (16x8 mono8 dilated over 3: 265 clocks a frame, the model says 255).

    Raises:
        Refused: the circuit refuses a frame.
    """
    ends: list[int] = []
    released: list[int] = []            # the clock each frame's record is released
    sub_at = 0                          # the clock the subscriber's timeline starts
    for k, frame in enumerate(frames):
        w = _walk(prog, frame)
        if k >= RECORDS:
            sub_at = max(sub_at, released[k - RECORDS] + RELEASE_TO_TAKE)
        pub_at = sub_at + w.start + ACCEPT_TO_PUBLISH
        if k:
            pub_at = max(pub_at, released[-1] + DONE_TO_PUBLISH)
        wait = _publisher_wait(prog, w, sub_at, pub_at, latency)
        ends.append(pub_at + w.pub_tl.rindex(1) + wait + TX_LATENCY)
        released.append(pub_at + wait + len(w.pub_tl))
        sub_at += w.busy
    return ends
