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


def test_a_message_layout_is_drawn_as_its_subscriber_state_machine(tmp_path) -> None:
    """Every step of a derived layout is a state; loops, empty arrays and refusals are moves."""
    from rosfpga_lab.hw.layout import derive_layout
    from rosfpga_lab.msg import registry_with
    from rosfpga_lab.widgets import layout_transitions

    (tmp_path / "t_msgs/msg").mkdir(parents=True)
    (tmp_path / "t_msgs/msg/Scan.msg").write_text("string[] names\nuint8 gain\nfloat32[] ranges\n")
    layout = derive_layout(registry_with([tmp_path]), "t_msgs/Scan", stream="ranges",
                           stream_length=4, checks={"gain": 2})
    rows = layout_transitions(layout)
    svg = state_diagram_svg(rows, in_order=True)
    assert _states(svg) == ["FRAME_LENGTH", "NAMES_LENGTH", "NAMES_LOOP", "NAMES_ITEM_LENGTH",
                            "NAMES_ITEM", "NAMES_END", "GAIN", "RANGES_LENGTH", "RANGES", "SKIP"]
    arrows = _arrows(svg)
    role = "t_msgs/Scan subscriber"
    assert "not == 2: refuse: SUB_BAD_GAIN" in arrows[(role, "GAIN", "SKIP")]
    assert "no elements: names is empty" in arrows[(role, "NAMES_LOOP", "GAIN")]
    # the stream's length must be 4: no "0" arrow past it (notebook 10 drew one; a frame with
    # no values is refused)
    assert (role, "RANGES_LENGTH", "FRAME_LENGTH") not in arrows
    assert "not == 4: refuse: SUB_BAD_RANGES_LENGTH" in arrows[(role, "RANGES_LENGTH", "SKIP")]
    empty = derive_layout(registry_with([tmp_path]), "t_msgs/Scan", stream="ranges",
                          stream_length=0, checks={"gain": 2})
    assert "0: ranges is empty" in _arrows(state_diagram_svg(layout_transitions(empty), in_order=True)
                                           )[(role, "RANGES_LENGTH", "FRAME_LENGTH")]
    assert (role, "NAMES_LENGTH", "GAIN") not in arrows   # the loop's own state says it
    assert "more elements: next element of names" in arrows[(role, "NAMES_END", "NAMES_ITEM_LENGTH")]
    assert "last element: names done" in arrows[(role, "NAMES_END", "GAIN")]
    assert "n x 4 bytes: stream ranges (float32), n = ranges length as AXI4-Stream beats" \
        in arrows[(role, "RANGES", "FRAME_LENGTH")]
    assert "rest of the frame" in arrows[(role, "SKIP", "FRAME_LENGTH")]
    # the walk folds into bands that fit a notebook; the handshake's picture is not folded
    assert int(re.search(r'width="(\d+)"', svg)[1]) <= 940
    assert state_diagram_svg(tcpros.TRANSITIONS) == state_diagram_svg(tcpros.TRANSITIONS, in_order=False)


def test_a_walks_arrows_pass_no_box_and_its_title_is_clear(tmp_path) -> None:
    """Notebook 10's diagram (12 states in bands) drew long arrows straight through other
    states' boxes, and FRAME_LENGTH's loop label over the title."""
    from rosfpga_lab.hw.layout import derive_layout
    from rosfpga_lab.msg import registry_with
    from rosfpga_lab.widgets import layout_transitions

    (tmp_path / "t_msgs/msg").mkdir(parents=True)
    (tmp_path / "t_msgs/msg/Line.msg").write_text(
        "Header header\nstring sensor\nuint8 gain\nfloat32[2] window\nuint16[] values\n")
    layout = derive_layout(registry_with([tmp_path]), "t_msgs/Line", stream="values",
                           stream_length=32, checks={"gain": 4}, limits_={"sensor": 16})
    svg = state_diagram_svg(layout_transitions(layout), in_order=True)
    boxes = {s: tuple(map(float, xywh)) for s, *xywh in re.findall(
        r'data-state="([^"]+)"><rect x="([-\d.]+)" y="([-\d.]+)" width="([\d.]+)" '
        r'height="([\d.]+)"', svg)}
    assert len(boxes) == 13
    groups = re.findall(r'data-source="([^"]+)" data-target="([^"]+)"><title>[^<]*</title>'
                        r'<path d="([^"]+)"', svg)
    assert groups

    def crosses(p: tuple[float, float], q: tuple[float, float], box: tuple[float, ...]) -> bool:
        x, y, w, h = box          # an axis-parallel segment through the box's inside
        (x1, y1), (x2, y2) = p, q
        lo_x, hi_x, lo_y, hi_y = min(x1, x2), max(x1, x2), min(y1, y2), max(y1, y2)
        return lo_x < x + w - 1 and hi_x > x + 1 and lo_y < y + h - 1 and hi_y > y + 1

    for source, target, d in groups:
        if "C" in d:               # a loop over its own box
            continue
        points = [tuple(map(float, xy.split(","))) for xy in re.findall(r"[-\d.]+,[-\d.]+", d)]
        segments = list(zip(points, points[1:]))
        assert all(p[0] == q[0] or p[1] == q[1] for p, q in segments) or len(segments) == 1
        for state, box in boxes.items():
            if state in (source, target):
                continue
            for p, q in segments:
                assert not crosses(p, q, box), (source, target, state, d)
    title_y = float(re.search(r'<text x="8" y="([\d.]+)" font-weight="bold"', svg)[1])
    loop_label_y = min(float(y) for y in re.findall(
        r'<text x="[\d.]+" y="([\d.]+)" text-anchor="middle" font-size="11" fill="#1f5fbf"', svg))
    assert loop_label_y - title_y >= 14, (title_y, loop_label_y)
