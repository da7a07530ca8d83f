"""How a layout's length prefixes are held against the frame length (the refusal order's
third rule, :mod:`rosfpga_lab.hw.layout`), and the fewest bytes a run of steps can take.

:func:`length_rules` gives each LENGTH step its :class:`LengthRule`: the bytes one counted
element takes at the least, and, when only fixed-size data follows, the exact number of bytes
after the counted part. :func:`min_bytes` also gives the layout its ``min_body``
(:mod:`rosfpga_lab.hw.layoutderive`).
"""

from __future__ import annotations

from typing import NamedTuple

from rosfpga_lab.hw.layoutsteps import CheckOp, Layout, StepKind


def min_bytes(layout: Layout, lo: int, hi: int, *, accepted: bool = False) -> int:
    """Fewest bytes steps ``lo..hi-1`` can take (variable parts empty); with ``accepted``, the
    fewest the checks accept (the stream holds ``stream_length`` elements, a string checked
    for one value holds it)."""
    total, i = 0, lo
    while i < hi:
        s = layout.steps[i]
        if s.kind is StepKind.LOOP:
            assert s.partner is not None
            if s.count is not None:
                total += s.count * min_bytes(layout, i + 1, s.partner, accepted=accepted)
            i = s.partner + 1
            continue
        if s.kind in (StepKind.SCALAR, StepKind.LENGTH):
            total += s.size
        elif s.count is not None:
            total += s.size * s.count
        elif accepted and s.index == layout.stream_index:
            total += s.size * layout.stream_length
        elif accepted and s.kind is StepKind.STRING and s.check is not None \
                and s.check.op is CheckOp.EQUAL:
            total += len(str(s.check.value).encode("utf-8"))
        i += 1
    return total


def fixed_bytes(layout: Layout, lo: int, hi: int) -> int | None:
    """Bytes of steps ``lo..hi-1`` if they are all fixed-size, else None."""
    total, i = 0, lo
    while i < hi:
        s = layout.steps[i]
        if s.is_variable or s.kind is StepKind.STRING:
            return None
        if s.kind is StepKind.LOOP:
            assert s.partner is not None and s.count is not None
            inner = fixed_bytes(layout, i + 1, s.partner)
            if inner is None:
                return None
            total += s.count * inner
            i = s.partner + 1
            continue
        total += s.size * (s.count if s.count is not None else 1)
        i += 1
    return total


class LengthRule(NamedTuple):
    """How a LENGTH step's value is held against the frame length (after its own check).

    Attributes:
        element_min: fewest bytes one counted element takes (1 for a string's byte).
        fixed_after: when the counted elements and everything after them are fixed-size (and
            the step is in no loop): the bytes after the counted part, so the frame length must
            equal ``offset + value * element_min + fixed_after`` exactly (else a
            ``frame length`` refusal, as Image's ``data length``); otherwise ``None`` and only
            ``value * element_min <= bytes left`` is required (else ``past the frame end``).
    """

    element_min: int
    fixed_after: int | None


def length_rules(layout: Layout) -> dict[int, LengthRule]:
    """The :class:`LengthRule` of every LENGTH step but the frame length, by step index."""
    rules: dict[int, LengthRule] = {}
    steps = layout.steps
    for s in steps:
        if s.kind is not StepKind.LENGTH or s.partner is None:
            continue
        part = steps[s.partner]
        exact = True
        if part.kind is StepKind.LOOP:
            assert part.partner is not None
            element_min = min_bytes(layout, part.index + 1, part.partner)
            exact = fixed_bytes(layout, part.index + 1, part.partner) is not None
            end = part.partner + 1
        else:
            element_min = part.size
            end = part.index + 1
        rules[s.index] = LengthRule(element_min, fixed_bytes(layout, end, len(steps))
                                    if s.depth == 0 and exact else None)
    return rules


__all__ = ["LengthRule", "fixed_bytes", "length_rules", "min_bytes"]
