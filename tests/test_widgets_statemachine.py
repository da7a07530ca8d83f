"""The handshake's state machine is drawn from ``tcpros.TRANSITIONS`` itself (notebook 2)."""

from __future__ import annotations

import html
import re
from dataclasses import replace

import pytest

from rosfpga_lab import tcpros
from rosfpga_lab.widgets import StateDiagram, WidgetError, state_diagram_svg


def _states(svg: str) -> list[str]:
    return re.findall(r'<g class="rfl-state" data-state="([^"]+)"', svg)


def _arrows(svg: str) -> dict[tuple[str, str, str], str]:
    found = re.findall(r'<g class="rfl-transition" data-role="([^"]+)" data-source="([^"]+)" '
                       r'data-target="([^"]+)"><title>([^<]*)</title>', svg)
    return {(r, a, b): html.unescape(t) for r, a, b, t in found}


def test_every_state_and_transition_of_the_table_is_drawn() -> None:
    svg = state_diagram_svg(tcpros.TRANSITIONS)
    for role in ("subscriber", "publisher"):
        assert f">{role}</text>" in svg
    states = _states(svg)
    want = {(t.role, s) for t in tcpros.TRANSITIONS for s in (t.source, t.target)}
    assert len(states) == len(want)          # each state once per role
    arrows = _arrows(svg)
    for t in tcpros.TRANSITIONS:
        assert f"{t.trigger}: {t.action}" in arrows[(t.role, t.source, t.target)], t
    assert 'style="max-width:100%;height:auto"' in svg
    assert int(re.search(r'width="(\d+)"', svg)[1]) <= 940   # fits a 1,000 px notebook


def test_the_picture_follows_the_table() -> None:
    extra = replace(tcpros.TRANSITIONS[0], source="STREAMING", trigger="pause", target="PAUSED",
                    action="a made-up move")
    svg = StateDiagram([*tcpros.TRANSITIONS, extra])._repr_html_()
    assert "PAUSED" in _states(svg) and "pause: a made-up move" in _arrows(svg)[("subscriber", "STREAMING", "PAUSED")]
    with pytest.raises(WidgetError):
        state_diagram_svg([])
