"""The waveform viewer's Python side: windowing, values at a clock, markers, jumps, VCD export."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.widgets import WidgetError
from rosfpga_lab.widgets.waveform import MAX_EDGES, Waves, WaveformViewer


def _stream(n_beats: int, gap: int, width: int) -> dict[str, np.ndarray]:
    """A hand-made stream: one beat every ``gap`` clocks, tready low on every 5th clock."""
    clocks = 2 * n_beats * gap + 8
    valid = np.zeros(clocks, bool)
    ready = np.ones(clocks, bool)
    ready[::5] = False
    data = np.zeros(clocks, np.uint64)
    tuser = np.zeros(clocks, bool)
    tlast = np.zeros(clocks, bool)
    beat, c = 0, 1
    while beat < n_beats and c < clocks:
        valid[c] = True
        data[c] = 0x11223300 + beat
        tuser[c] = beat == 0
        tlast[c] = beat % width == width - 1
        if ready[c]:           # the beat moves; the next one comes gap clocks later
            beat += 1
            c += gap
        else:                  # held until tready
            c += 1
    return {"aclk": np.ones(clocks, bool), "s_axis_tvalid": valid, "s_axis_tready": ready,
            "s_axis_tdata": data, "s_axis_tuser": tuser, "s_axis_tlast": tlast}


def test_beats_are_the_handshakes_and_markers_sit_on_them() -> None:
    arrays = _stream(12, 4, width=4)
    waves = Waves.from_arrays(arrays)
    clocks = waves.beat_clocks("s_axis")
    assert clocks.size == 12
    valid, ready = arrays["s_axis_tvalid"], arrays["s_axis_tready"]
    assert all(valid[c] and ready[c] for c in clocks)
    # held beats (valid, not ready) are not beats
    held = np.flatnonzero(valid & ~ready)
    assert held.size > 0 and not set(held) & set(clocks.tolist())
    markers = waves.markers()
    assert [m.kind for m in markers if m.kind == "tuser"] == ["tuser"]
    assert markers[0].clock == clocks[0]
    assert [m.clock for m in markers if m.kind == "tlast"] == [int(clocks[k]) for k in (3, 7, 11)]
    assert waves.beat_clock("s_axis", 5) == int(clocks[5])
    assert waves.stream_values("s_axis").tolist() == [0x11223300 + k for k in range(12)]
    with pytest.raises(WidgetError, match="no tkeep"):
        waves.stream_values("s_axis", "tkeep")
    assert waves.pixel_clock("s_axis", 1, 2, width=4) == int(clocks[9])
    with pytest.raises(WidgetError, match="carries beats 0..11"):
        waves.beat_clock("s_axis", 12)


def test_value_at_a_clock_and_formatting() -> None:
    arrays = _stream(3, 4, width=3)
    waves = Waves.from_arrays(arrays, widths={"s_axis_tdata": 32})
    c = int(waves.beat_clocks("s_axis")[1])
    vals = waves.values_at(c)
    assert vals["s_axis_tdata"] == "11223301"
    assert vals["s_axis_tvalid"] == "1" and vals["s_axis_tready"] == "1"
    assert waves.value_at("s_axis_tdata", c) == 0x11223301
    with pytest.raises(WidgetError, match="clocks are 0.."):
        waves.values_at(waves.clocks)
    with pytest.raises(WidgetError, match="did you mean s_axis_tdata"):
        waves.signal("tdata")


def test_runs_of_a_window_match_a_naive_scan() -> None:
    rng = np.random.default_rng(3)
    values = rng.integers(0, 3, 500).astype(np.uint64)
    waves = Waves.from_arrays({"sig": values}, widths={"sig": 2})
    for start, span in ((0, 500), (17, 40), (499, 1), (480, 100)):
        firsts, lengths, vals = waves.runs("sig", start, span)
        s, n = waves.clamp_window(start, span)
        naive, k = [], s
        while k < s + n:
            j = k
            while j + 1 < s + n and values[j + 1] == values[k]:
                j += 1
            naive.append((k, j - k + 1, int(values[k])))
            k = j + 1
        assert list(zip(firsts.tolist(), lengths.tolist(), vals.tolist())) == naive
        assert int(lengths.sum()) == n


def test_a_million_clocks_draw_as_a_bounded_picture() -> None:
    n = 1_200_000
    toggling = (np.arange(n) % 4 == 0)
    waves = Waves.from_arrays({"m_axis_tvalid": toggling, "count": np.arange(n) % 4096})
    svg = waves.svg(0, n)
    # zoomed out: hatched busy bands instead of a million edges; the picture stays small
    assert "rfl-busy" in svg
    assert len(svg) < 200_000
    assert svg.count("<rect data-index") == 0
    # zoomed in, each clock is a clickable column
    near = waves.svg(1000, 32, cursor=1005)
    assert near.count("<rect data-index") == 32
    assert 'data-index="1005"' in near
    assert re.search(r'fill="#d00">0</text>', near)  # cursor values: tvalid at 1005 is 0
    assert MAX_EDGES < n


def test_viewer_scrolls_zooms_and_reports_the_cursor() -> None:
    arrays = _stream(40, 3, width=8)
    viewer = WaveformViewer(arrays, width=8, span=16)
    assert (viewer.start, viewer.span) == (0, 16)
    viewer.scroll(10)
    assert viewer.start == 10
    viewer.show(10_000)
    assert viewer.start + viewer.span == viewer.waves.clocks
    viewer.zoom(2.0)
    assert viewer.span == 32
    clock = viewer.jump_to_beat("s_axis", 9)
    assert viewer.start <= clock < viewer.start + viewer.span
    assert viewer.cursor == clock
    assert "m_axis_tdata" not in viewer.values.value and "s_axis_tdata = <b>11223309</b>" in viewer.values.value
    # the browser's click lands in SvgPane.selected and moves the cursor
    viewer.pane.selected = clock + 1
    assert viewer.cursor == clock + 1
    pixel = viewer.jump_to_pixel("s_axis", 2, 1)
    assert pixel == viewer.waves.beat_clock("s_axis", 10)
    viewer.jump_kind.value = "beat of s_axis"
    viewer.jump_to.value = "999"
    viewer._jump_from_controls()
    assert "carries beats 0..39" in viewer.info.value
    assert "<svg" in viewer.to_html()


def test_vcd_export_opens_as_the_same_values(tmp_path: Path) -> None:
    arrays = _stream(6, 3, width=3)
    waves = Waves.from_arrays(arrays, widths={"s_axis_tdata": 32})
    path = waves.to_vcd(tmp_path / "w.vcd")
    text = path.read_text()
    assert "$var wire 32" in text and "s_axis_tdata [31:0]" in text
    # Read it back with a tiny independent parser: value of every signal at each rising edge.
    ids, widths = {}, {}
    for m in re.finditer(r"\$var wire (\d+) (\S+) (\S+)", text):
        ids[m.group(2)] = m.group(3)
        widths[m.group(3)] = int(m.group(1))
    body = text.split("$enddefinitions $end\n", 1)[1].split("\n")
    current: dict[str, int] = {}
    sampled: dict[str, list[int]] = {name: [] for name in ids.values()}
    t = 0
    for line in body + ["#end"]:
        if line.startswith("#"):
            if t % 2 == 0 and current:
                for name in sampled:
                    sampled[name].append(current.get(name, 0))
            t = int(line[1:]) if line[1:].isdigit() else -1
        elif line.startswith("b"):
            value, ident = line[1:].split()
            current[ids[ident]] = int(value, 2)
        elif line:
            current[ids[line[1:]]] = int(line[0])
    for name, values in arrays.items():
        if name == "aclk":
            continue
        assert sampled[name][: waves.clocks] == [int(v) for v in values], name


def test_bad_input_is_refused_with_a_reason() -> None:
    with pytest.raises(WidgetError, match="lengths differ"):
        Waves.from_arrays({"a": [0, 1], "b": [0, 1, 0]})
    with pytest.raises(WidgetError, match="at least one signal"):
        Waves([])
    with pytest.raises(WidgetError, match="negative"):
        Waves.from_arrays({"a": np.array([-1, 2])})
    waves = Waves.from_arrays({"a": [0, 1]})
    with pytest.raises(WidgetError, match="no stream"):
        waves.beat_clocks("m_axis")
    viewer = WaveformViewer(waves)
    with pytest.raises(WidgetError, match="width="):
        viewer.jump_to_pixel("m_axis", 0, 0)


def test_a_chosen_set_of_signals_draws_only_its_streams_markers_and_the_static_form_follows() -> None:
    arrays = _stream(6, 3, width=3)
    arrays.update({k.replace("s_axis", "m_axis"): v for k, v in _stream(6, 3, width=2).items() if k != "aclk"})
    waves = Waves.from_arrays(arrays)
    only_s = waves.svg(0, 40, names=["aclk", "s_axis_tvalid", "s_axis_tlast"])
    assert "s_axis tlast" in only_s and "m_axis tlast" not in only_s
    viewer = WaveformViewer(waves, names=["aclk", "m_axis_tvalid"], span=20)
    viewer.set_cursor(5)
    static = viewer.to_html()
    assert "m_axis_tvalid" in static and "s_axis_tdata" not in static and 'stroke="#d00"' in static


def test_cursor_panel_lists_the_drawn_signals_first_and_folds_the_rest() -> None:
    """Notebook 8's cursor panel dumped all 63 signals; the drawn ones come first now."""
    arrays = _stream(6, 3, width=3)
    arrays.update({k.replace("s_axis", "m_axis"): v for k, v in _stream(6, 3, width=2).items() if k != "aclk"})
    viewer = WaveformViewer(Waves.from_arrays(arrays), names=["m_axis_tvalid", "aclk"], span=20)
    viewer.set_cursor(5)
    panel = viewer.values.value
    visible, folded = panel.split('<details class="rfl-wave-others">')
    assert visible.index('data-signal="m_axis_tvalid"') < visible.index('data-signal="aclk"')
    assert "s_axis_tdata" not in visible and 'data-signal="s_axis_tdata"' in folded
    assert f"the other {len(arrays) - 2} signals" in folded
    everything = WaveformViewer(Waves.from_arrays(_stream(6, 3, width=3)), span=20)
    everything.set_cursor(5)
    assert "<details" not in everything.values.value      # all drawn: nothing folded
