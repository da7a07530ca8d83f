"""The publisher model of any message type, rendered from its circuit layout.

How this works: the publisher (:func:`publish_reference`, :func:`publish_fast`) writes the
output frame from the subscriber's tokens (:mod:`rosfpga_lab.hw.subscriberwalker`): the carried
and checked values as received, the application's stream, and the default of every skipped
field (0, ``""``, an empty variable array, zeros for a fixed one). A publisher of another type
than the subscriber's (``out_layout``) takes each field from the input's field of the same path
and type, else writes its default (:func:`published_tokens`). The reference writes a byte per
clock (numbers shifted out little-endian, :func:`shift_out`), as the generated publisher does;
the fast model packs each field whole (:func:`~rosfpga_lab.hw.layouttokens.marshal`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rosfpga_lab.hw.layoutsteps import Action, Layout, Step, StepKind, walk_order
from rosfpga_lab.hw.layouttokens import Token, encode_token, marshal, tokens
from rosfpga_lab.msg import MsgRegistry, default_value, new_message


def _default(step: Step, count: int) -> Any:
    if step.kind is StepKind.LENGTH:
        return 0
    if step.kind is StepKind.STRING:
        return ""
    if step.kind is StepKind.ARRAY:
        return np.zeros(count, np.dtype(step.dtype))
    return False if step.type == "bool" else 0.0 if step.type.startswith("float") else 0


def output_tokens(layout: Layout, toks: list[Token], stream: np.ndarray) -> list[Token]:
    """The publisher's values: ``toks`` (a subscriber's, walk order) with the stream replaced
    by ``stream`` and every skipped field at its default."""
    steps = layout.steps
    queue = [t for t in toks if steps[t.step].action is not Action.SKIP]
    out: list[Token] = []
    pos = 0
    counts: dict[int, int] = {}

    def take(i: int, at: tuple[int, ...]) -> Any:
        nonlocal pos
        t = queue[pos]
        assert t.step == i, f"token of step {t.step} where step {i} was expected"
        pos += 1
        return t.value

    for i, at in walk_order(steps, counts.__getitem__):
        s = steps[i]
        n = s.count if s.count is not None else counts.get(s.length_step or 0, 0)
        if i == layout.stream_index:
            take(i, at)
            value: Any = np.asarray(stream)
        elif s.kind is StepKind.LENGTH and s.partner == layout.stream_index:
            take(i, at)
            value = len(stream)
        elif s.action is Action.SKIP:
            value = _default(s, n if s.kind is StepKind.ARRAY else 0)
        else:
            value = take(i, at)
        if s.kind is StepKind.LENGTH:
            counts[i] = value
        out.append(Token(i, value, at))
    return out


def _merge(skeleton: dict[str, Any], got: dict[str, Any]) -> dict[str, Any]:
    for key, value in got.items():
        if isinstance(value, dict) and isinstance(skeleton.get(key), dict):
            _merge(skeleton[key], value)
        else:
            skeleton[key] = value
    return skeleton


def message_of(layout: Layout, toks: list[Token], reg: MsgRegistry) -> dict[str, Any]:
    """The message (nested dicts and lists, ``msg.serialize`` takes it) whose walk gives
    ``toks``: the inverse of :func:`~rosfpga_lab.hw.layout.tokens` (``reg`` fills nested
    messages without fields, which have no steps)."""
    steps = layout.steps
    pos = 0

    def put(obj: dict[str, Any], rel: tuple[str, ...], value: Any) -> None:
        for name in rel[:-1]:
            obj = obj.setdefault(name, {})
        obj[rel[-1]] = value

    def walk(lo: int, hi: int, obj: dict[str, Any]) -> None:
        nonlocal pos
        i = lo
        while i < hi:
            s = steps[i]
            if s.kind is StepKind.LOOP:
                assert s.partner is not None
                n = s.count if s.count is not None else counts[s.length_step or 0]
                items: list[Any] = []
                for _ in range(n):
                    element: dict[str, Any] = {}
                    walk(i + 1, s.partner, element)
                    if "" in element:
                        items.append(element[""])
                    elif s.type in reg:
                        items.append(_merge(new_message(reg, s.type), element))
                    else:
                        items.append(element)
                put(obj, s.rel, items)
                i = s.partner + 1
                continue
            t = toks[pos]
            assert t.step == i, f"token of step {t.step} where step {i} was expected"
            pos += 1
            if s.kind is StepKind.LENGTH:
                counts[i] = t.value
            else:
                put(obj, s.rel or ("",), t.value)
            i += 1

    counts: dict[int, int] = {}
    root: dict[str, Any] = {}
    walk(1, len(steps), root)
    return _merge(new_message(reg, layout.type_name), root)


def _carry_into(reg: MsgRegistry, in_type: str, out_type: str, src: dict[str, Any]) -> dict:
    """A value of ``out_type``: each field the input's field of the same name when the types
    are equal (nested messages field by field), else its default."""
    in_fields = {f.name: f for f in reg.check(in_type).fields}
    out: dict[str, Any] = {}
    for f in reg.check(out_type).fields:
        g = in_fields.get(f.name)
        if g is not None and g.type == f.type:
            out[f.name] = src[f.name]
        elif (g is not None and not f.is_array and not g.is_array and not f.is_builtin
              and not g.is_builtin):
            out[f.name] = _carry_into(reg, g.base_type, f.base_type, src[f.name])
        else:
            out[f.name] = default_value(reg, f)
    return out


def published_tokens(layout: Layout, toks: list[Token], stream: np.ndarray,
                     out_layout: Layout | None = None, reg: MsgRegistry | None = None
                     ) -> list[Token]:
    """What the publisher writes, in its layout's walk order: :func:`output_tokens`, and for a
    publisher of another type (``out_layout``, its registry ``reg``) every field of that type
    taken from the input's field of the same path and type, else its default."""
    same = output_tokens(layout, toks, stream)
    if out_layout is None or out_layout.type_name == layout.type_name:
        return same
    if reg is None:
        raise ValueError("a publisher of another type needs the registry holding both types")
    message = _carry_into(reg, layout.type_name, out_layout.type_name,
                          message_of(layout, same, reg))
    return tokens(out_layout, message)


def publish_fast(layout: Layout, toks: list[Token], stream: np.ndarray,
                 out_layout: Layout | None = None, reg: MsgRegistry | None = None) -> bytes:
    """The output TCPROS frame (4-byte length + body), each field packed whole."""
    return marshal(out_layout or layout, published_tokens(layout, toks, stream, out_layout, reg))


def publish_reference(layout: Layout, toks: list[Token], stream: np.ndarray,
                      out_layout: Layout | None = None, reg: MsgRegistry | None = None) -> bytes:
    """The output frame written a byte per clock: numbers shifted out little-endian, strings
    and arrays byte by byte, as the generated publisher does."""
    out_toks = published_tokens(layout, toks, stream, out_layout, reg)
    layout = out_layout or layout
    length = sum(value_size(layout.steps[t.step], t.value) for t in out_toks)
    out = bytearray()
    shift_out(out, length, 4)
    for t in out_toks:
        write_value(out, layout.steps[t.step], t.value)
    return bytes(out)


def shift_out(out: bytearray, bits: int, size: int) -> None:
    """Append ``size`` bytes of ``bits``, least significant first (a register shifted out)."""
    for k in range(size):
        out.append((bits >> (8 * k)) & 0xFF)


def write_value(out: bytearray, step: Step, value: Any) -> None:
    """Append the bytes of ``step``'s ``value`` as the publisher writes them a byte per clock:
    numbers shifted out little-endian, strings and arrays byte by byte."""
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        shift_out(out, int.from_bytes(encode_token(step, value), "little"), step.size)
    else:
        for byte in encode_token(step, value):
            out.append(byte)


def value_size(step: Step, value: Any) -> int:
    """Bytes of ``step``'s ``value`` on the wire (a string: its UTF-8 bytes, no length)."""
    if step.kind in (StepKind.SCALAR, StepKind.LENGTH):
        return step.size
    if step.kind is StepKind.STRING:
        return len(value.encode("utf-8", "surrogateescape")) if isinstance(value, str) else len(value)
    return step.size * len(value)


__all__ = [
    "message_of", "output_tokens", "publish_fast", "publish_reference", "published_tokens",
    "shift_out", "value_size", "write_value",
]
