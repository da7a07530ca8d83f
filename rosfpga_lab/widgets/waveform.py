"""Waveform viewer: signals clock by clock, as a logic analyser or GTKWave shows them.

How this works: a :class:`Waves` holds one numpy array per signal with one value per clock (the
value each signal has at a rising edge of ``aclk``), from an RTL dump
(:meth:`Waves.from_vcd`) or from any model that produces per-clock arrays
(:meth:`Waves.from_arrays`). Nothing draws more than a *window* of clocks: the window's changes
are found with numpy (``np.flatnonzero(np.diff(...))``), so a dump of a whole frame (millions of
clocks) is as quick to scroll as a short one. When a window has more changes than the picture
has room for, the busy stretches are drawn as a hatched band (as GTKWave does when zoomed out)
instead of thousands of edges.

Stream handshakes are found from the names: a group ``PREFIX_tvalid``/``PREFIX_tready``
(``s_axis_tvalid``, ``m_axis_tready``...) transfers a beat at every clock where both are 1
(:meth:`Waves.beat_clocks`); its ``tuser``/``tlast`` at those clocks are the markers drawn above
the waves. A group without ``tready`` is taken as always ready.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import ipywidgets as w
import numpy as np

from rosfpga_lab.widgets._common import StaticFallback, WidgetError, esc
from rosfpga_lab.widgets.limits import MAX_EDGES, MAX_SIGNALS, MAX_SPAN

#: Clocks shown when a viewer opens, and the widest window one picture draws edge by edge.
DEFAULT_SPAN = 64
#: Names drawn as a clock (one pulse per clock) rather than as their sampled value.
CLOCK_NAMES = ("aclk", "clk", "ap_clk")

_ROW, _LEFT, _PLOT = 22, 150, 760
_BUSY_FILL = "url(#rfl-busy)"


@dataclass(frozen=True)
class Signal:
    """One signal: a name, a bit width and its value at every clock.

    Attributes:
        name: e.g. ``"s_axis_tdata"``; dots separate scopes (``top.rx.level``).
        width: bits (1 for a wire).
        values: ``(clocks,)`` uint64, the value at each rising clock edge.
        known: ``(clocks,)`` bool, False where the value was ``x`` or ``z``; None: all known.
    """

    name: str
    width: int
    values: np.ndarray
    known: np.ndarray | None = None

    @property
    def is_bit(self) -> bool:
        return self.width == 1

    def format(self, value: int) -> str:
        """``value`` as a waveform viewer prints it: a bit as 0/1, a bus in hex."""
        if self.is_bit:
            return str(value)
        return f"{value:0{max(1, (self.width + 3) // 4)}x}"


@dataclass(frozen=True)
class Marker:
    """A handshake that carried ``tuser`` or ``tlast``: where it is and on which stream."""

    clock: int
    stream: str
    kind: str  # "tuser" or "tlast"


class Waves:
    """Per-clock signal values with windowing, look-ups, markers and VCD export.

    Args:
        signals: :class:`Signal` objects, in display order.
        period_ns: the clock period (for the time axis and the VCD time scale).
        title: shown above the picture.

    Raises:
        WidgetError: no signals, arrays of different lengths, or a width over 64 bits.
    """

    def __init__(self, signals: Sequence[Signal], *, period_ns: float = 10.0, title: str = "") -> None:
        if not signals:
            raise WidgetError("a waveform needs at least one signal")
        lengths = {int(s.values.shape[0]) for s in signals}
        if len(lengths) != 1:
            raise WidgetError(f"every signal needs one value per clock; lengths differ: {sorted(lengths)}")
        for s in signals:
            if not 1 <= s.width <= 64:
                raise WidgetError(f"{s.name}: width {s.width} is not 1..64 bits")
        names = [s.name for s in signals]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise WidgetError(f"signal names must be unique: {sorted(dup)}")
        if period_ns <= 0:
            raise WidgetError(f"period_ns must be positive, got {period_ns}")
        self.signals = list(signals)
        self.by_name = {s.name: s for s in self.signals}
        self.clocks = lengths.pop()
        self.period_ns = float(period_ns)
        self.title = title

    # --- construction ---------------------------------------------------------------------------
    @classmethod
    def from_arrays(cls, arrays: Mapping[str, Any], *, widths: Mapping[str, int] | None = None,
                    period_ns: float = 10.0, title: str = "") -> Waves:
        """Signals from a mapping name -> per-clock values (bools, ints or arrays of them).

        Widths default to 1 for bool arrays and to the bits the largest value needs otherwise
        (at least 8 for names ending in ``data``).
        """
        widths = dict(widths or {})
        out = []
        for name, values in arrays.items():
            arr = np.asarray(values)
            if arr.ndim != 1:
                raise WidgetError(f"{name}: expected one value per clock, got shape {arr.shape}")
            if arr.dtype == bool:
                width = widths.get(name, 1)
            else:
                if arr.size and int(arr.min()) < 0:
                    raise WidgetError(f"{name}: values must not be negative")
                top = int(arr.max()) if arr.size else 0
                width = widths.get(name, max(1, top.bit_length(), 8 if name.endswith("data") else 1))
            out.append(Signal(name, int(width), arr.astype(np.uint64)))
        return cls(out, period_ns=period_ns, title=title)

    @classmethod
    def from_vcd(cls, source: Any, *, clock: str | None = None, signals: Iterable[str] | None = None,
                 short_names: bool = True, title: str = "") -> Waves:
        """Signals of a VCD dump sampled at the rising edges of its clock.

        Args:
            source: a ``.vcd`` path or its bytes, or a dump already read by
                :func:`rosfpga_lab.rtl.vcd.read_vcd`.
            clock: the clock's name or unique name suffix (default: the first of
                :data:`CLOCK_NAMES` the dump has).
            signals: names or unique suffixes to keep, in this order (default: all).
            short_names: label signals by their last scope part (``m_axis_tdata``) when that
                is unique.
        """
        from rosfpga_lab.rtl.errors import VcdError
        from rosfpga_lab.rtl.vcd import read_vcd

        if hasattr(source, "values") and hasattr(source, "signals"):
            dump = source
        else:
            keep = list(signals) if signals is not None else None
            dump = None
            for name in ([clock] if clock else CLOCK_NAMES):
                try:
                    dump = read_vcd(source, clock=name, signals=keep)
                    break
                except VcdError as exc:
                    if clock or "no signal" not in str(exc):
                        raise WidgetError(str(exc)) from None
            if dump is None:
                raise WidgetError(f"the dump has none of the clocks {', '.join(CLOCK_NAMES)}; "
                                  "name it with clock=")
        names = [dump.resolve(n) for n in signals] if signals is not None else list(dump.signals)
        tails = [n.rsplit(".", 1)[-1] for n in names]
        unique = short_names and len(set(tails)) == len(tails)
        out = []
        for name, tail in zip(names, tails):
            width = int(dump.width(name))
            if width > 64:
                continue  # wider buses are not drawn (the lab's are at most 32 bits)
            values = np.asarray(dump.values(name))
            known = ~np.asarray(dump.unknown(name), bool)
            out.append(Signal(tail if unique else name, width, values.astype(np.uint64),
                              None if known.all() else known))
        period = dump.period
        label = title or (Path(source).name if isinstance(source, (str, Path)) else "")
        return cls(out, period_ns=period * 1e9 if period else 10.0, title=label)

    # --- look-ups --------------------------------------------------------------------------------
    def signal(self, name: str) -> Signal:
        try:
            return self.by_name[name]
        except KeyError:
            close = [n for n in self.by_name if name.lower() in n.lower()][:5]
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise WidgetError(f"no signal {name!r}{hint}") from None

    def check_clock(self, clock: int) -> int:
        if not 0 <= clock < self.clocks:
            raise WidgetError(f"clock {clock} does not exist; clocks are 0..{self.clocks - 1}")
        return int(clock)

    def value_at(self, name: str, clock: int) -> int | None:
        """The value of ``name`` at ``clock`` (None where it was x/z)."""
        s = self.signal(name)
        self.check_clock(clock)
        if s.known is not None and not s.known[clock]:
            return None
        return int(s.values[clock])

    def values_at(self, clock: int) -> dict[str, str]:
        """Every signal's value at ``clock``, formatted as the picture prints it."""
        self.check_clock(clock)
        out = {}
        for s in self.signals:
            v = self.value_at(s.name, clock)
            out[s.name] = "x" if v is None else s.format(v)
        return out

    def streams(self) -> list[str]:
        """Prefixes of the AXI4-Stream-like groups (names ``PREFIX_tvalid``), in signal order."""
        return [s.name[: -len("tvalid")].rstrip("_.") for s in self.signals
                if s.name.endswith("tvalid")]

    def _stream_signal(self, stream: str, part: str) -> Signal | None:
        for sep in ("_", "."):
            name = f"{stream}{sep}{part}" if stream else part
            if name in self.by_name:
                return self.by_name[name]
        return None

    def beat_clocks(self, stream: str) -> np.ndarray:
        """Clocks at which ``stream`` transfers a beat (``tvalid`` and ``tready`` both 1)."""
        valid = self._stream_signal(stream, "tvalid")
        if valid is None:
            raise WidgetError(f"no stream {stream!r} (streams: {', '.join(self.streams()) or 'none'})")
        ready = self._stream_signal(stream, "tready")
        fire = valid.values.astype(bool)
        if ready is not None:
            fire &= ready.values.astype(bool)
        return np.flatnonzero(fire)

    def stream_values(self, stream: str, part: str = "tdata") -> np.ndarray:
        """What ``stream`` carried: ``part`` (``tdata``, ``tuser``...) at each of its handshakes."""
        sig = self._stream_signal(stream, part)
        if sig is None:
            raise WidgetError(f"stream {stream!r} has no {part} signal")
        return sig.values[self.beat_clocks(stream)]

    def beat_clock(self, stream: str, beat: int) -> int:
        """The clock of beat number ``beat`` (from 0) of ``stream``."""
        clocks = self.beat_clocks(stream)
        if not 0 <= beat < clocks.size:
            raise WidgetError(f"{stream} carries beats 0..{clocks.size - 1}; no beat {beat}")
        return int(clocks[beat])

    def pixel_clock(self, stream: str, x: int, y: int, width: int) -> int:
        """The clock at which pixel ``(x, y)`` of a ``width``-pixel-wide frame crosses ``stream``
        (one pixel per beat, the lab's packing; the frame starts at the first ``tuser`` beat)."""
        if not 0 <= x < width or y < 0:
            raise WidgetError(f"pixel ({x}, {y}) is outside a {width}-pixel-wide frame")
        clocks = self.beat_clocks(stream)
        tuser = self._stream_signal(stream, "tuser")
        first = 0
        if tuser is not None and clocks.size:
            starts = np.flatnonzero(tuser.values[clocks].astype(bool))
            first = int(starts[0]) if starts.size else 0
        beat = first + y * width + x
        if beat >= clocks.size:
            raise WidgetError(f"pixel ({x}, {y}) is beat {beat} of {stream}, which carries {clocks.size} beats")
        return int(clocks[beat])

    def markers(self, start: int = 0, stop: int | None = None) -> list[Marker]:
        """TUSER and TLAST handshakes of every stream between ``start`` and ``stop`` (clocks)."""
        stop = self.clocks if stop is None else min(stop, self.clocks)
        out: list[Marker] = []
        for stream in self.streams():
            clocks = self.beat_clocks(stream)
            clocks = clocks[(clocks >= start) & (clocks < stop)]
            for kind in ("tuser", "tlast"):
                sig = self._stream_signal(stream, kind)
                if sig is None:
                    continue
                for c in clocks[sig.values[clocks].astype(bool)]:
                    out.append(Marker(int(c), stream, kind))
        return sorted(out, key=lambda m: (m.clock, m.stream, m.kind))

    def next_change(self, name: str, clock: int) -> int | None:
        """The first clock after ``clock`` where ``name`` changes (None: it never does)."""
        s = self.signal(name)
        self.check_clock(clock)
        rest = s.values[clock:]
        idx = np.flatnonzero(rest[1:] != rest[:-1])
        return int(clock + idx[0] + 1) if idx.size else None

    def count(self, name: str, start: int = 0, stop: int | None = None) -> int:
        """Clocks in ``[start, stop)`` where the 1-bit signal ``name`` is 1."""
        s = self.signal(name)
        stop = self.clocks if stop is None else stop
        return int(np.count_nonzero(s.values[start:stop]))

    # --- windowing -------------------------------------------------------------------------------
    def clamp_window(self, start: int, span: int) -> tuple[int, int]:
        """``(start, span)`` moved inside the dump: 1 <= span <= min(clocks, MAX_SPAN)."""
        span = int(max(1, min(span, self.clocks, MAX_SPAN)))
        start = int(max(0, min(start, self.clocks - span)))
        return start, span

    def runs(self, name: str, start: int, span: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Runs of constant value of ``name`` in the window: ``(first clocks, lengths, values)``."""
        s = self.signal(name)
        start, span = self.clamp_window(start, span)
        seg = s.values[start:start + span]
        known = None if s.known is None else s.known[start:start + span]
        change = seg[1:] != seg[:-1]
        if known is not None:
            change |= known[1:] != known[:-1]
        edges = np.flatnonzero(change) + 1
        firsts = np.concatenate(([0], edges))
        lengths = np.diff(np.concatenate((firsts, [span])))
        values = seg[firsts]
        return firsts + start, lengths, values

    # --- drawing ---------------------------------------------------------------------------------
    def drawn_names(self, names: Sequence[str] | None = None) -> list[str]:
        """The full names of the signals a picture of ``names`` draws (default: the first
        ``MAX_SIGNALS``), in drawing order."""
        return ([self.signal(n).name for n in names] if names
                else [s.name for s in self.signals[:MAX_SIGNALS]])

    def svg(self, start: int = 0, span: int = DEFAULT_SPAN, cursor: int | None = None,
            names: Sequence[str] | None = None) -> str:
        """An SVG of clocks ``start .. start+span-1``: one row per signal, markers on top.

        Every clock column is an element with ``data-index`` = its clock (clickable in the
        viewer); the cursor is a red line with every value written beside its row.
        """
        start, span = self.clamp_window(start, span)
        chosen = [self.signal(n) for n in self.drawn_names(names)]
        px = _PLOT / span
        height = _ROW * (len(chosen) + 2) + 8
        width = _LEFT + _PLOT + 70
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
               f'viewBox="0 0 {width} {height}" style="max-width:100%;height:auto" '
               f'font-family="monospace" font-size="10">',
               '<defs><pattern id="rfl-busy" width="6" height="6" patternUnits="userSpaceOnUse" '
               'patternTransform="rotate(45)"><rect width="3" height="6" fill="#9db4d6"/></pattern></defs>']
        # time axis
        step = _nice_step(span)
        first_tick = -(-start // step) * step
        for c in range(first_tick, start + span, step):
            x = _LEFT + (c - start) * px
            out.append(f'<line x1="{x:.1f}" y1="12" x2="{x:.1f}" y2="{height - 4}" stroke="#eee"/>'
                       f'<text x="{x + 2:.1f}" y="10" fill="#777">{c}</text>')
        # markers row
        y0 = _ROW
        out.append(f'<text x="2" y="{y0 + 14}" fill="#555">TUSER/TLAST</text>')
        shown = {s.name for s in chosen}
        streams = {st for st in self.streams()
                   if any(f"{st}{sep}tvalid" in shown or (not st and "tvalid" in shown) for sep in "_.")}
        for m in [m for m in self.markers(start, start + span) if m.stream in streams][:MAX_EDGES]:
            x = _LEFT + (m.clock - start + 0.5) * px
            colour, label = ("#2a9d3a", "U") if m.kind == "tuser" else ("#1f5fbf", "L")
            out.append(f'<g class="rfl-marker"><title>{esc(m.stream)} {m.kind} at clock {m.clock}</title>'
                       f'<line x1="{x:.1f}" y1="{y0 + 2}" x2="{x:.1f}" y2="{height - 4}" stroke="{colour}" '
                       f'stroke-dasharray="2,2" opacity="0.6"/><text x="{x - 3:.1f}" y="{y0 + 14}" '
                       f'fill="{colour}" font-weight="bold">{label}</text></g>')
        for row, s in enumerate(chosen, start=2):
            out.append(self._row_svg(s, row, start, span, px))
        # clickable clock columns (only when each is at least 2 px wide)
        if px >= 2:
            for k in range(span):
                x = _LEFT + k * px
                out.append(f'<rect data-index="{start + k}" x="{x:.1f}" y="{_ROW}" width="{px:.1f}" '
                           f'height="{height - _ROW}" fill="transparent"/>')
        if cursor is not None and start <= cursor < start + span:
            x = _LEFT + (cursor - start + 0.5) * px
            out.append(f'<line x1="{x:.1f}" y1="12" x2="{x:.1f}" y2="{height - 4}" stroke="#d00" '
                       f'stroke-width="1.5"/>')
            for row, s in enumerate(chosen, start=2):
                v = self.value_at(s.name, cursor)
                text = "x" if v is None else s.format(v)
                out.append(f'<text x="{_LEFT + _PLOT + 4}" y="{row * _ROW + 14}" fill="#d00">{esc(text)}</text>')
        out.append("</svg>")
        return "".join(out)

    def _row_svg(self, s: Signal, row: int, start: int, span: int, px: float) -> str:
        top, bottom = row * _ROW + 3, row * _ROW + _ROW - 3
        mid = (top + bottom) / 2
        label = s.name if len(s.name) <= 22 else "\u2026" + s.name[-21:]
        parts = [f'<text x="2" y="{row * _ROW + 14}"><title>{esc(s.name)} [{s.width}]</title>{esc(label)}</text>']
        if s.name in CLOCK_NAMES:
            if px >= 4:  # one rising edge per clock, as the dump's clock is drawn
                pts = []
                for k in range(span):
                    x0 = _LEFT + k * px
                    pts += [f"{x0:.1f},{bottom}", f"{x0:.1f},{top}", f"{x0 + px / 2:.1f},{top}",
                            f"{x0 + px / 2:.1f},{bottom}"]
                parts.append(f'<polyline fill="none" stroke="#555" points="{" ".join(pts)}"/>')
            else:
                parts.append(f'<rect x="{_LEFT}" y="{top}" width="{span * px:.1f}" height="{bottom - top}" '
                             f'fill="{_BUSY_FILL}" stroke="#6d88b0" stroke-width="0.5"/>')
            return "".join(parts)
        firsts, lengths, values = self.runs(s.name, start, span)
        known = s.known
        if firsts.size > MAX_EDGES:
            # Too many changes to draw: bucket the window into picture columns; a column whose
            # clocks all hold one value is drawn as that value, the others as a busy band.
            cols = int(min(_PLOT, span))
            bounds = np.linspace(start, start + span, cols + 1).astype(np.int64)
            seg = s.values[start:start + span]
            change = np.concatenate(([False], seg[1:] != seg[:-1]))
            csum = np.concatenate(([0], np.cumsum(change)))
            busy_cols = (csum[bounds[1:] - start] - csum[np.minimum(bounds[:-1] - start + 1, span)]) > 0
            k = 0
            while k < cols:
                j = k
                while j + 1 < cols and busy_cols[j + 1] == busy_cols[k]:
                    j += 1
                x0 = _LEFT + (bounds[k] - start) * px
                x1 = _LEFT + (bounds[j + 1] - start) * px
                if busy_cols[k]:
                    parts.append(f'<rect x="{x0:.1f}" y="{top}" width="{max(x1 - x0, 0.5):.1f}" '
                                 f'height="{bottom - top}" fill="{_BUSY_FILL}" stroke="#6d88b0" stroke-width="0.5"/>')
                else:
                    v = int(s.values[bounds[k]])
                    y = (top if v else bottom) if s.is_bit else mid
                    parts.append(f'<line x1="{x0:.1f}" y1="{y}" x2="{x1:.1f}" y2="{y}" stroke="#070"/>')
                k = j + 1
            return "".join(parts)
        if s.is_bit:
            pts = []
            for f, n, v in zip(firsts, lengths, values):
                x0, x1 = _LEFT + (f - start) * px, _LEFT + (f - start + n) * px
                unknown = known is not None and not known[f]
                if unknown:
                    parts.append(f'<rect x="{x0:.1f}" y="{top}" width="{x1 - x0:.1f}" height="{bottom - top}" fill="#f4a0a0"/>')
                y = top if v else bottom
                pts += [f"{x0:.1f},{y}", f"{x1:.1f},{y}"]
            parts.append(f'<polyline fill="none" stroke="#070" stroke-width="1.5" points="{" ".join(pts)}"/>')
            return "".join(parts)
        for f, n, v in zip(firsts, lengths, values):
            x0, x1 = _LEFT + (f - start) * px, _LEFT + (f - start + n) * px
            e = min(3.0, (x1 - x0) / 2)
            unknown = known is not None and not known[f]
            fill = "#f4a0a0" if unknown else "#eef"
            parts.append(f'<polygon fill="{fill}" stroke="#333" stroke-width="0.8" points="{x0:.1f},{mid} '
                         f'{x0 + e:.1f},{top} {x1 - e:.1f},{top} {x1:.1f},{mid} {x1 - e:.1f},{bottom} {x0 + e:.1f},{bottom}"/>')
            text = "x" if unknown else s.format(int(v))
            if (x1 - x0) > 6.5 * len(text) + 4:
                parts.append(f'<text x="{x0 + e + 1:.1f}" y="{mid + 4}">{text}</text>')
        return "".join(parts)

    def summary(self) -> str:
        """One line: clocks, signals, beats per stream."""
        streams = self.streams()
        beats = ", ".join(f"{st or 'stream'} {self.beat_clocks(st).size} beats" for st in streams[:4])
        beats += f" (+{len(streams) - 4} more streams)" if len(streams) > 4 else ""
        time = self.clocks * self.period_ns
        unit, scale = ("ms", 1e-6) if time >= 1e6 else ("\u00b5s", 1e-3) if time >= 1e3 else ("ns", 1.0)
        return (f"{self.clocks} clocks ({time * scale:.4g} {unit} at {1e3 / self.period_ns:g} MHz), "
                f"{len(self.signals)} signals" + (f"; {beats}" if beats else ""))

    def to_html(self, start: int = 0, span: int = DEFAULT_SPAN, cursor: int | None = None,
                names: Sequence[str] | None = None) -> str:
        """Static HTML: title, summary, and the picture of one window (no kernel needed)."""
        start, span = self.clamp_window(start, span)
        head = f"<b>{esc(self.title)}</b> " if self.title else ""
        return (f'<div><div>{head}{esc(self.summary())}</div>'
                f'<div style="font-size:11px;color:#555">clocks {start}..{start + span - 1}; '
                f'U = TUSER, L = TLAST handshake; hatched = too many changes to draw at this zoom</div>'
                f"{self.svg(start, span, cursor, names)}</div>")

    def _repr_html_(self) -> str:
        return self.to_html()

    # --- export ----------------------------------------------------------------------------------
    def to_vcd(self, path: str | Path, *, module: str = "rosfpga_lab") -> Path:
        """Write the waves as a VCD file that GTKWave opens (``aclk`` included, one period per
        clock, values changing at the rising edge)."""
        path = Path(path)
        ids = [_vcd_id(k + 1) for k in range(len(self.signals))]
        half = self.period_ns / 2
        scale_ps = max(1, int(round(half * 1000)))
        with path.open("w", encoding="ascii") as f:
            f.write("$date rosfpga_lab waveform $end\n$version rosfpga_lab $end\n")
            f.write(f"$timescale {scale_ps}ps $end\n$scope module {module} $end\n")
            f.write(f"$var wire 1 {_vcd_id(0)} aclk $end\n")
            for s, i in zip(self.signals, ids):
                if s.name == "aclk":
                    continue
                rng = f" [{s.width - 1}:0]" if s.width > 1 else ""
                safe = re.sub(r"[^A-Za-z0-9_.\[\]]", "_", s.name)
                f.write(f"$var wire {s.width} {i} {safe}{rng} $end\n")
            f.write("$upscope $end\n$enddefinitions $end\n")
            prev: list[Any] = [None] * len(self.signals)
            for clock in range(self.clocks):
                f.write(f"#{2 * clock}\n1{_vcd_id(0)}\n")
                for k, (s, i) in enumerate(zip(self.signals, ids)):
                    if s.name == "aclk":
                        continue
                    unknown = s.known is not None and not s.known[clock]
                    v = None if unknown else int(s.values[clock])
                    if clock and v == prev[k]:
                        continue
                    prev[k] = v
                    if s.is_bit:
                        f.write(f"{'x' if v is None else v}{i}\n")
                    else:
                        f.write(f"b{'x' if v is None else format(v, 'b')} {i}\n")
                f.write(f"#{2 * clock + 1}\n0{_vcd_id(0)}\n")
            f.write(f"#{2 * self.clocks}\n")
        return path


def _vcd_id(k: int) -> str:
    """A short VCD identifier (printable ASCII 33..126)."""
    chars = []
    while True:
        chars.append(chr(33 + k % 94))
        k //= 94
        if not k:
            return "".join(chars)


def _nice_step(span: int) -> int:
    """A round tick spacing giving about 8 ticks over ``span`` clocks."""
    raw = max(1.0, span / 8)
    mag = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 5, 10):
        if raw <= m * mag:
            return int(m * mag)
    return int(10 * mag)  # pragma: no cover


class WaveformViewer(StaticFallback, w.VBox):
    """The waves of a :class:`Waves`, scrolled and zoomed in the notebook.

    Click a clock to put the cursor there: every signal's value at that clock is listed. The
    controls move the window (``<`` ``>``), zoom (``+`` ``-``, ``all``) and jump to a clock, to
    beat N of a stream, or to pixel (x, y) of a frame (``width`` given). Only the window's picture
    is sent to the browser.

    Args:
        waves: the signals (or anything :meth:`Waves.from_arrays` takes).
        width: pixels per line of the frame on the streams (enables the pixel jump).
        span: clocks shown at first.
        names: signals to draw (default: all, up to ``MAX_SIGNALS``).
    """

    def __init__(self, waves: Waves | Mapping[str, Any], *, width: int | None = None,
                 span: int = DEFAULT_SPAN, names: Sequence[str] | None = None) -> None:
        from rosfpga_lab.widgets.sequence import SvgPane

        self.waves = waves if isinstance(waves, Waves) else Waves.from_arrays(waves)
        self.frame_width = width
        self.names = list(names) if names else None
        self.start, self.span = self.waves.clamp_window(0, span)
        self.cursor: int | None = None
        self.pane = SvgPane()
        self.pane.observe(lambda c: self.set_cursor(c["new"]) if c["new"] >= 0 else None, "selected")
        buttons = {}
        for label, tip, action in (("\u25c0\u25c0", "back one window", lambda: self.scroll(-self.span)),
                                   ("\u25c0", "back an eighth", lambda: self.scroll(-max(1, self.span // 8))),
                                   ("\u25b6", "on an eighth", lambda: self.scroll(max(1, self.span // 8))),
                                   ("\u25b6\u25b6", "on one window", lambda: self.scroll(self.span)),
                                   ("+", "zoom in", lambda: self.zoom(0.5)),
                                   ("\u2212", "zoom out", lambda: self.zoom(2.0)),
                                   ("all", "the whole dump", lambda: self.show(0, self.waves.clocks))):
            b = w.Button(description=label, tooltip=tip, layout=w.Layout(width="44px"))
            b.on_click(lambda _b, a=action: a())
            buttons[label] = b
        self.buttons = buttons
        streams = self.waves.streams()
        self.jump_kind = w.Dropdown(options=["clock"] + [f"beat of {s}" for s in streams]
                                    + ([f"pixel of {s}" for s in streams] if width else []),
                                    value="clock", layout=w.Layout(width="190px"))
        self.jump_to = w.Text(placeholder="e.g. 100, or x,y", layout=w.Layout(width="120px"))
        self.jump_go = w.Button(description="go", layout=w.Layout(width="44px"))
        self.jump_go.on_click(lambda _b: self._jump_from_controls())
        self.info = w.HTML()
        self.values = w.HTML()
        super().__init__([w.HTML(f"<b>{esc(self.waves.title)}</b> {esc(self.waves.summary())}"),
                          w.HBox(list(buttons.values()) + [self.jump_kind, self.jump_to, self.jump_go],
                                 layout=w.Layout(flex_flow="row wrap")),
                          self.info, self.pane, self.values])
        self._render()

    # --- actions (also for tests and notebooks) --------------------------------------------------
    def show(self, start: int, span: int | None = None) -> tuple[int, int]:
        """Show clocks ``start .. start+span-1`` (clamped); returns the window shown."""
        self.start, self.span = self.waves.clamp_window(start, self.span if span is None else span)
        self._render()
        return self.start, self.span

    def scroll(self, clocks: int) -> tuple[int, int]:
        return self.show(self.start + clocks)

    def zoom(self, factor: float) -> tuple[int, int]:
        """Multiply the span by ``factor`` about the cursor (or the window's middle)."""
        centre = self.cursor if self.cursor is not None else self.start + self.span // 2
        span = max(4, int(round(self.span * factor)))
        return self.show(centre - span // 2, span)

    def set_cursor(self, clock: int) -> dict[str, str]:
        """Put the cursor at ``clock`` (scrolling to it); returns every signal's value there."""
        self.cursor = self.waves.check_clock(clock)
        if not self.start <= clock < self.start + self.span:
            self.start, self.span = self.waves.clamp_window(clock - self.span // 2, self.span)
        self._render()
        return self.waves.values_at(clock)

    def jump_to_beat(self, stream: str, beat: int) -> int:
        return self._centre(self.waves.beat_clock(stream, beat))

    def jump_to_pixel(self, stream: str, x: int, y: int) -> int:
        if not self.frame_width:
            raise WidgetError("give the viewer width= (pixels per line) to jump to a pixel")
        return self._centre(self.waves.pixel_clock(stream, x, y, self.frame_width))

    def _centre(self, clock: int) -> int:
        self.set_cursor(clock)
        return clock

    def _jump_from_controls(self) -> None:
        text, kind = self.jump_to.value.strip(), self.jump_kind.value
        try:
            nums = [int(v) for v in re.split(r"[,\s]+", text) if v]
            if kind == "clock" and len(nums) == 1:
                self._centre(nums[0])
            elif kind.startswith("beat of ") and len(nums) == 1:
                self.jump_to_beat(kind[len("beat of "):], nums[0])
            elif kind.startswith("pixel of ") and len(nums) == 2:
                self.jump_to_pixel(kind[len("pixel of "):], nums[0], nums[1])
            else:
                raise WidgetError("type one number (a clock or beat) or x,y (a pixel)")
        except (ValueError, WidgetError) as exc:
            self.info.value = f'<span style="color:#b00">{esc(exc)}</span>'

    def _render(self) -> None:
        self.pane.svg = self.waves.svg(self.start, self.span, self.cursor, self.names)
        self.info.value = (f'<span style="font-family:monospace">clocks {self.start}..'
                           f'{self.start + self.span - 1} of {self.waves.clocks}; click a clock for '
                           f'its values</span>')
        if self.cursor is None:
            self.values.value = ""
            return
        vals = self.waves.values_at(self.cursor)
        drawn = [k for k in self.waves.drawn_names(self.names) if k in vals]
        rest = [k for k in vals if k not in drawn]

        def items(keys: list[str]) -> str:
            return (f'<div style="display:flex;flex-wrap:wrap;gap:2px 18px">'
                    + "".join(f'<span data-signal="{esc(k)}">{esc(k)} = <b>{esc(vals[k])}</b></span>'
                              for k in keys) + "</div>")

        others = (f'<details class="rfl-wave-others"><summary>the other {len(rest)} signals</summary>'
                  f'{items(rest)}</details>' if rest else "")
        self.values.value = (f'<div class="rfl-wave-values" style="font-family:monospace;font-size:12px">'
                             f'<b>clock {self.cursor}</b>, the signals drawn above:{items(drawn)}'
                             f'{others}</div>')

    def to_html(self) -> str:
        return self.waves.to_html(self.start, self.span, self.cursor, self.names)
