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
from typing import Any

from rosfpga_lab.widgets._common import WidgetError, esc
from rosfpga_lab.widgets.limits import DIAGRAM_MAX_WIDTH

#: Drawing sizes (pixels): column step, row step, state box.
COL, ROW, BOX_W, BOX_H = 215, 84, 128, 30


def _states_by_depth(rows: Sequence[Any]) -> list[list[str]]:
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


def _panel(role: str, rows: Sequence[Any], top: int, uid: str) -> tuple[list[str], int, int]:
    columns = _states_by_depth(rows)
    col = min(COL, (DIAGRAM_MAX_WIDTH - BOX_W - 20) // max(len(columns) - 1, 1))
    pos: dict[str, tuple[float, float]] = {}
    first = top + 70   # room for the panel's title and a loop above the first row
    for c, states in enumerate(columns):
        # the end states' column starts a row lower, so arrows into it pass beside the others
        shift = 1 if c == len(columns) - 1 and len(columns) > 1 else 0
        for k, s in enumerate(states):
            pos[s] = (20 + BOX_W / 2 + c * col, first + (k + shift) * ROW)
    height = 70 + ROW * max(len(c) + (1 if i == len(columns) - 1 else 0)
                            for i, c in enumerate(columns)) - ROW + 30
    width = int(20 + BOX_W + col * (len(columns) - 1) + 20)
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
        if a == b:  # a loop above the box
            d = f"M{x1 - 18},{y1 - BOX_H / 2} C{x1 - 30},{y1 - 48} {x1 + 30},{y1 - 48} {x1 + 18},{y1 - BOX_H / 2}"
            lx, ly, anchor = x1, y1 - 44, "middle"
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
        if a == b or y1 == y2:   # loops and level arrows carry their triggers
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
                   f'stroke="#333"/><text x="{x}" y="{y + 4}" text-anchor="middle" font-size="12">{esc(s)}</text></g>')
    for k, line in enumerate(legend):
        out.append(f'<text x="20" y="{top + height + 4 + 15 * k}" font-size="11" fill="#333">'
                   f'<tspan fill="#1f5fbf" font-weight="bold">{k + 1}</tspan>  {esc(line)}</text>')
    return out, width, height + 15 * len(legend) + 12


def state_diagram_svg(transitions: Iterable[Any], roles: Sequence[str] | None = None) -> str:
    """An SVG of the state machine(s) in ``transitions``, one panel per role.

    Args:
        transitions: rows with ``role``, ``source``, ``trigger``, ``target``, ``action``.
        roles: which roles, in which order (default: order of appearance).

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
        body, w, h = _panel(role, mine, top, "rfl-sm-ah")
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

    def __init__(self, transitions: Iterable[Any], roles: Sequence[str] | None = None) -> None:
        self.transitions = list(transitions)
        self.svg = state_diagram_svg(self.transitions, roles)

    def _repr_html_(self) -> str:
        return f"<div>{self.svg}</div>"
