"""A state machine drawn from its transition table (``tcpros.TRANSITIONS``, ``hw`` tables).

How this works: :func:`state_diagram_svg` takes rows with ``role``, ``source``, ``trigger``,
``target`` and ``action`` (any objects with those attributes) and draws one panel per role. A
role's states are placed in columns by their distance from the role's first state (breadth
first over the table), so the handshake reads left to right; the transitions between the same
two states share one arrow labelled with all their triggers, a transition back to its own state
is a loop, and each arrow's tooltip lists the actions. Nothing is written by hand: change the
table and the picture follows.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, NamedTuple

from rosfpga_lab.widgets._common import WidgetError, esc
from rosfpga_lab.widgets.limits import DIAGRAM_MAX_WIDTH

#: Drawing sizes (pixels): column step, row step, state box.
COL, ROW, BOX_W, BOX_H = 215, 84, 128, 30
#: Narrowest column step; a table with more columns than fit at it folds into bands.
MIN_COL = BOX_W + 40


def _states_by_depth(rows: Sequence[Any], in_order: bool = False) -> list[list[str]]:
    if in_order:   # a walk: one column per state, in the order the table's rows leave them
        return [[s] for s in dict.fromkeys([r.source for r in rows] + [r.target for r in rows])]
    start = rows[0].source
    depth = {start: 0}
    queue = [start]
    while queue:
        s = queue.pop(0)
        for r in rows:
            if r.source == s and r.target not in depth:
                depth[r.target] = depth[s] + 1
                queue.append(r.target)
    for r in rows:  # states the first one does not reach: after the rest
        for s in (r.source, r.target):
            depth.setdefault(s, max(depth.values()) + 1)
    # end states (nothing leaves them) get a column of their own, on the right
    ends = [s for s in depth if not any(r.source == s and r.target != s for r in rows)]
    last = max(d for s, d in depth.items() if s not in ends) + 1 if len(ends) < len(depth) else 0
    for s in ends:
        depth[s] = last
    columns: list[list[str]] = [[] for _ in range(max(depth.values()) + 1)]
    for s, d in depth.items():
        columns[d].append(s)
    return columns


def _font(name: str) -> str:
    """Font size of a state's name: 12, smaller for a long name so it stays in its box."""
    return "12" if len(name) <= 15 else f"{max(7.0, 12 * 15 / len(name)):.1f}"


def _panel(role: str, rows: Sequence[Any], top: int, uid: str,
           in_order: bool = False) -> tuple[list[str], int, int]:
    columns = _states_by_depth(rows, in_order)
    # a long walk (a message's fields) folds into bands of as many columns as fit side by side
    per_band = max(1, (DIAGRAM_MAX_WIDTH - BOX_W - 20) // MIN_COL + 1)
    bands = -(-len(columns) // per_band) if len(columns) > per_band else 1
    across = per_band if bands > 1 else len(columns)
    col = min(COL, (DIAGRAM_MAX_WIDTH - BOX_W - 20) // max(across - 1, 1))
    band_rows = max(len(c) for c in columns) + 1
    pos: dict[str, tuple[float, float]] = {}
    # room for the panel's title and a loop above the first row (its trigger above the loop)
    first = top + (86 if any(r.source == r.target for r in rows) else 70)
    for c, states in enumerate(columns):
        # the end states' column starts a row lower, so arrows into it pass beside the others
        shift = 1 if c == len(columns) - 1 and len(columns) > 1 else 0
        band, slot = (c // per_band, c % per_band) if bands > 1 else (0, c)
        for k, s in enumerate(states):
            pos[s] = (20 + BOX_W / 2 + slot * col, first + (band * band_rows + k + shift) * ROW)
    height = first - top + ROW * max(len(c) + (1 if i == len(columns) - 1 else 0)
                            + (i // per_band * band_rows if bands > 1 else 0)
                            for i, c in enumerate(columns)) - ROW + 30
    width = int(20 + BOX_W + col * (across - 1) + 20)
    out = [f'<text x="8" y="{top + 18}" font-weight="bold" font-size="13">{esc(role)}</text>']
    legend: list[str] = []
    edges: dict[tuple[str, str], list[Any]] = {}
    for r in rows:
        edges.setdefault((r.source, r.target), []).append(r)
    # arrows leaving one state, top to bottom: each puts its label further along, so they part
    order = {key: sum(1 for (a, b) in edges if a == key[0] and b != a and pos[b][1] < pos[key[1]][1])
             for key in edges}
    for (a, b), group in edges.items():
        (x1, y1), (x2, y2) = pos[a], pos[b]
        tip = esc("\n".join(f"{r.trigger}: {r.action}" for r in group))
        out.append(f'<g class="rfl-transition" data-role="{esc(role)}" data-source="{esc(a)}" data-target="{esc(b)}"><title>{tip}</title>')
        routed = in_order and a != b and not (y1 == y2 and abs(x2 - x1) <= col + 1)
        if a == b:  # a loop above the box
            d = f"M{x1 - 18},{y1 - BOX_H / 2} C{x1 - 30},{y1 - 48} {x1 + 30},{y1 - 48} {x1 + 18},{y1 - BOX_H / 2}"
            lx, ly, anchor = x1, y1 - 44, "middle"
        elif routed:  # a walk's longer arrow: along the free lanes between rows and columns
            d, lx, ly = _route(x1, y1, x2, y2, col, len(legend))
            anchor = "middle"
        else:
            sx = x1 + (BOX_W / 2 if x2 > x1 else -BOX_W / 2 if x2 < x1 else 0)
            ex = x2 - (BOX_W / 2 if x2 > x1 else -BOX_W / 2 if x2 < x1 else 0)
            sy = y1 + (0 if x2 != x1 else BOX_H / 2)
            ey = y2 - (0 if x2 != x1 else BOX_H / 2)
            d = f"M{sx},{sy} L{ex},{ey}"
            # the label sits a third of the way along, so arrows leaving one state keep theirs apart
            f = 0.5 if ey == sy else min(0.3 + 0.24 * order[(a, b)], 0.8)
            lx, ly, anchor = sx + (ex - sx) * f, sy + (ey - sy) * f - 5, "middle"
        out.append(f'<path d="{d}" fill="none" stroke="#555" stroke-width="1.4" marker-end="url(#{uid})"/>')
        triggers = ", ".join(dict.fromkeys(r.trigger for r in group))
        if a == b or (y1 == y2 and not routed):   # loops and level arrows carry their triggers
            out.append(f'<text x="{lx:.0f}" y="{ly:.0f}" text-anchor="{anchor}" font-size="11" fill="#1f5fbf" '
                       f'paint-order="stroke" stroke="#fff" stroke-width="4" stroke-linejoin="round">'
                       f'{esc(triggers)}</text>')
        else:                    # slanted ones a numbered tag, explained under the panel
            legend.append(f"{a} \u2192 {b}: {triggers}")
            n = len(legend)
            out.append(f'<circle cx="{lx:.0f}" cy="{ly + 5:.0f}" r="8" fill="#fff" stroke="#1f5fbf"/>'
                       f'<text x="{lx:.0f}" y="{ly + 9:.0f}" text-anchor="middle" font-size="11" '
                       f'fill="#1f5fbf">{n}</text>')
        out.append("</g>")
    for s, (x, y) in pos.items():
        end = not any(r.source == s and r.target != s for r in rows)
        fill = "#f4f4f4" if end else "#e8f0fb"
        out.append(f'<g class="rfl-state" data-state="{esc(s)}"><rect x="{x - BOX_W / 2}" y="{y - BOX_H / 2}" '
                   f'width="{BOX_W}" height="{BOX_H}" rx="{BOX_H / 2 if end else 6}" fill="{fill}" '
                   f'stroke="#333"/><text x="{x}" y="{y + 4}" text-anchor="middle" '
                   f'font-size="{_font(s)}">{esc(s)}</text></g>')
    for k, line in enumerate(legend):
        out.append(f'<text x="20" y="{top + height + 4 + 15 * k}" font-size="11" fill="#333">'
                   f'<tspan fill="#1f5fbf" font-weight="bold">{k + 1}</tspan>  {esc(line)}</text>')
    return out, width, height + 15 * len(legend) + 12


def _route(x1: float, y1: float, x2: float, y2: float, col: float, k: int
           ) -> tuple[str, float, float]:
    """An arrow between two states of a folded walk that never crosses a box: out of the source
    box's bottom (top, when the target is higher) into the lane between rows, along it to the
    lane between columns beside the target, along that to the lane beside the target's row,
    and into the target box. ``k`` shifts the lanes a little so arrows sharing them stay
    apart. Returns the path and where its numbered tag goes (on its first lane)."""
    lane = (k % 7 - 3) * 5.0
    up = y2 < y1
    out_y = y1 - BOX_H / 2 if up else y1 + BOX_H / 2
    row_lane = y1 + (-ROW / 2 if up else ROW / 2) + lane
    if y2 == y1:    # the same row: along the lane under it
        end_y = y2 + BOX_H / 2
        d = (f"M{x1 + lane},{out_y} L{x1 + lane},{row_lane} L{x2 + lane},{row_lane} "
             f"L{x2 + lane},{end_y}")
        return d, (x1 + x2) / 2, row_lane - 5
    gutter = x2 + (-col / 2 if x1 <= x2 else col / 2) + lane
    gutter = max(gutter, 6.0)
    near = y2 + (ROW / 2 if up else -ROW / 2) + lane
    end_y = y2 + BOX_H / 2 if up else y2 - BOX_H / 2
    d = (f"M{x1 + lane},{out_y} L{x1 + lane},{row_lane} L{gutter},{row_lane} L{gutter},{near} "
         f"L{x2 + lane},{near} L{x2 + lane},{end_y}")
    return d, (x1 + gutter) / 2 if abs(gutter - x1) > 30 else gutter, (
        row_lane - 5 if abs(gutter - x1) > 30 else (row_lane + near) / 2)


def state_diagram_svg(transitions: Iterable[Any], roles: Sequence[str] | None = None,
                      in_order: bool = False) -> str:
    """An SVG of the state machine(s) in ``transitions``, one panel per role.

    Args:
        transitions: rows with ``role``, ``source``, ``trigger``, ``target``, ``action``.
        roles: which roles, in which order (default: order of appearance).
        in_order: place the states one per column in the order the table's rows leave them, folded
            into bands (a walk over a message's fields, :func:`layout_transitions`), instead
            of by their distance from the first state.

    Raises:
        WidgetError: no transitions, or a role with none.
    """
    rows = list(transitions)
    if not rows:
        raise WidgetError("no transitions to draw")
    names = list(roles) if roles else list(dict.fromkeys(r.role for r in rows))
    parts, width, top = [], 0, 0
    for role in names:
        mine = [r for r in rows if r.role == role]
        if not mine:
            raise WidgetError(f"no transitions for role {role!r}")
        body, w, h = _panel(role, mine, top, "rfl-sm-ah", in_order)
        parts += body
        width, top = max(width, w), top + h
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{top}" '
            f'viewBox="0 0 {width} {top}" style="max-width:100%;height:auto" font-family="sans-serif">'
            '<defs><marker id="rfl-sm-ah" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
            'markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>'
            + "".join(parts) + "</svg>")


class StateDiagram:
    """Displays :func:`state_diagram_svg` in a notebook (and in exported HTML: it is plain SVG).

    Hover an arrow for the actions of its transitions.
    """

    def __init__(self, transitions: Iterable[Any], roles: Sequence[str] | None = None,
                 in_order: bool = False) -> None:
        self.transitions = list(transitions)
        self.svg = state_diagram_svg(self.transitions, roles, in_order)

    def _repr_html_(self) -> str:
        return f"<div>{self.svg}</div>"


class WalkTransition(NamedTuple):
    """One move of a message walk's state machine (a row :func:`state_diagram_svg` draws)."""

    role: str
    source: str
    trigger: str
    target: str
    action: str


#: The state a refused frame's remaining bytes are read in (as the Image interpreter's SKIP).
SKIP_STATE = "SKIP"


def layout_transitions(layout: Any) -> list[WalkTransition]:
    """The subscriber circuit of a circuit layout (``rosfpga_lab.hw.layout.Layout``) as the
    rows of a state machine: one state per step (``HEADER_SEQ``, a loop's ``<IDENT>_LOOP`` and
    ``<IDENT>_END``), each moving on when its bytes are in; a zero count passes the counted
    part; a failed check goes to ``SKIP`` (the frame length's back to ``FRAME_LENGTH``); the last
    step goes back to ``FRAME_LENGTH`` for the next frame. Triggers and actions come from the
    steps (sizes, maxima, checks and status codes), so the picture follows the ``.msg``.
    """
    steps = layout.steps
    role = f"{layout.type_name} subscriber"

    def state(i: int) -> str:
        if i >= len(steps):
            return steps[0].ident.upper()
        s = steps[i]
        suffix = {"loop": "_LOOP", "end": "_END"}.get(str(s.kind), "")
        return s.ident.upper() + suffix

    def after(i: int) -> int:
        s = steps[i]
        return (s.partner if str(s.kind) == "loop" else i) + 1

    def size(s: Any) -> str:   # the trigger: short, the tooltip says more
        if str(s.kind) in ("scalar", "length"):
            return f"{s.size} byte{'s' if s.size != 1 else ''}"
        if s.count is None:
            return "n bytes" if str(s.kind) == "string" else f"n x {s.size} bytes"
        return f"{s.count} x {s.size} bytes"

    def count_of(s: Any) -> str:
        return "" if s.length_step is None else f", n = {steps[s.length_step].label}"

    rows: list[WalkTransition] = []
    for i, s in enumerate(steps):
        kind = str(s.kind)
        what = f"{s.action} {s.label} ({s.type})"
        if kind == "loop":
            rows.append(WalkTransition(role, state(i), "an element left", state(i + 1),
                                       f"walk one element of {s.label}"))
            if s.count is None:
                rows.append(WalkTransition(role, state(i), "no elements", state(after(i)),
                                           f"{s.label} is empty"))
            continue
        if kind == "end":
            rows.append(WalkTransition(role, state(i), "more elements", state(s.partner + 1),
                                       f"next element of {s.label}"))
            rows.append(WalkTransition(role, state(i), "last element", state(i + 1),
                                       f"{s.label} done"))
            continue
        rows.append(WalkTransition(role, state(i), size(s), state(i + 1),
                                   what + count_of(s) + (" as AXI4-Stream beats"
                                                         if str(s.action) == "stream" else "")))
        if s.check is not None:
            back = state(0) if i == 0 else SKIP_STATE
            rows.append(WalkTransition(role, state(i), f"not {s.check.describe()}", back,
                                       f"refuse: {s.check.status}"))
        # a zero count passes a string or array at once (a loop's own state says "no elements"),
        # unless the count is checked for another value (the stream's fixed length)
        fixed = s.check is not None and str(s.check.op) == "equal" and s.check.value != 0
        if (kind == "length" and i > 0 and s.partner is not None and not fixed
                and str(steps[s.partner].kind) != "loop" and steps[s.partner].count is None):
            rows.append(WalkTransition(role, state(i), "0", state(after(s.partner)),
                                       f"{steps[s.partner].label} is empty"))
    rows.append(WalkTransition(role, SKIP_STATE, "rest of the frame", state(0),
                               "drop the refused frame's bytes"))
    return rows
