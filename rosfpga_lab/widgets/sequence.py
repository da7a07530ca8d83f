"""Sequence diagram of a recorded XML-RPC / TCPROS conversation (the paper's Figure 2).

How this works: a conversation is a list of :class:`SeqEvent` (from, to, label, raw bytes,
timestamp, kind). :func:`sequence_svg` draws one lifeline per participant and one numbered arrow
per event, top to bottom in time order; every arrow is an SVG group with ``data-index`` and a
tooltip. :class:`SequenceDiagram` makes the arrows clickable (a small anywidget) and shows the
clicked event's bytes in a :class:`~rosfpga_lab.widgets.byteview.ByteViewer`, fields from
:func:`~rosfpga_lab.widgets.byte_sources.spans_for`. :func:`events_from_trace` turns a
``rosfpga_lab.graph`` trace into events (an XML-RPC call gives a request and a reply arrow);
:func:`events_from_capture` does the same for a capture file of real traffic.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import anywidget
import ipywidgets as w
import traitlets

from rosfpga_lab.widgets._common import StaticFallback, WidgetError, esc, hex_bytes
from rosfpga_lab.widgets.byte_sources import spans_for
from rosfpga_lab.widgets.byteview import ByteMap, ByteViewer, Span, as_span

STATIC = Path(__file__).resolve().parent / "static"

#: Lifelines drawn first when present (the master), as in the paper's Figure 2.
FIRST_PARTICIPANTS = ("/master", "master")

#: Widest a diagram is drawn (pixels): a notebook's output area at 1,000 px is about 940 wide.
#: Columns narrow to fit; beyond that the SVG scales down (it never makes the page scroll).
FIT_WIDTH = 920
#: Narrowest and widest lifeline column.
COL_MIN, COL_MAX = 96, 220
#: A repeated arrow (same ends, kind and label) within this many arrows is folded into the first.
FOLD_WINDOW = 4
#: Average width of a label character at the diagram's font size, to cut labels to their arrow.
CHAR_PX = 6.6
#: Room a label gets on a short arrow (pixels).
LABEL_MIN_PX = 210

#: Arrow colour and dash per event kind.
KIND_STYLE = {
    "xmlrpc": ("#1f5fbf", ""),
    "xmlrpc_reply": ("#6b86b3", "6 4"),
    "tcp_connect": ("#555555", "2 3"),
    "tcp_close": ("#555555", "2 3"),
    "tcpros_header": ("#c46200", ""),
    "tcpros_frame": ("#1b8a3a", ""),
    "error": ("#cc0000", ""),
    "rtps_match": ("#7b3fa0", "2 3"),
}


@dataclass
class SeqEvent:
    """One arrow of the diagram.

    Attributes:
        src, dst: participant names (the same name means a self-message).
        label: text on the arrow, e.g. ``registerPublisher``.
        raw: the bytes on the wire (may be empty).
        t: timestamp in seconds (any origin), or None.
        kind: ``xmlrpc``, ``xmlrpc_reply``, ``tcpros_header``, ``tcpros_frame``, ``tcp_connect`` ...
            (chooses colour and how ``raw`` is split into fields).
        detail: tooltip text.
        type_name: message type of a ``tcpros_frame`` (so its body is shown field by field).
        spans: explicit byte fields for ``raw`` (default: worked out from ``kind``).
        size: the bytes the arrow stands for when they are part of ``raw`` (``None``: all).
    """

    src: str
    dst: str
    label: str
    raw: bytes = b""
    t: float | None = None
    kind: str = ""
    detail: str = ""
    type_name: str | None = None
    spans: list[Any] | None = field(default=None, repr=False)
    size: int | None = None

    @property
    def bytes_drawn(self) -> int:
        """The bytes this arrow stands for: :attr:`size` when it is a share of :attr:`raw` (the
        submessages of one sender in a datagram packing several), else all of ``raw``."""
        return len(self.raw) if self.size is None else self.size

    def byte_spans(self) -> list[Span]:
        """The fields of :attr:`raw` for the byte viewer."""
        if self.spans is not None:
            return [as_span(s) for s in self.spans]
        return spans_for(self.raw, self.kind, self.type_name)


def _as_event(item: Any) -> SeqEvent:
    if isinstance(item, SeqEvent):
        return item
    if isinstance(item, dict):
        return SeqEvent(**item)
    if isinstance(item, (tuple, list)):
        return SeqEvent(*item)
    raise WidgetError(f"cannot use {type(item).__name__} as a sequence event; use SeqEvent, dict or tuple")


def participants_of(events: Sequence[SeqEvent], first: Sequence[str] = ()) -> list[str]:
    """Participants in order: ``first`` (those that appear), then by first appearance."""
    seen: list[str] = []
    present = {e.src for e in events} | {e.dst for e in events}
    for name in first:
        if name in present and name not in seen:
            seen.append(name)
    for e in events:
        for name in (e.src, e.dst):
            if name not in seen:
                seen.append(name)
    return seen


def peer_names(items: Sequence[Any]) -> dict[str, str]:
    """Node names for the other labels a trace gives the same party: slave API URIs and TCP
    peer addresses (``host:port``).

    Sources: ``registerPublisher``/``registerSubscriber`` calls (``caller_api`` -> ``caller_id``),
    and the connection headers of each TCPROS connection (both sides send ``callerid``: a
    label on that connection that is not a node name belongs to the side it is not).
    """
    names: dict[str, str] = {}
    for e in items:
        if e.kind == "xmlrpc" and e.method in ("registerPublisher", "registerSubscriber") \
                and isinstance(e.args, (list, tuple)) and len(e.args) >= 3:
            names.setdefault(str(e.args[-1]), str(e.src))
    by_conn: dict[int, list[Any]] = {}
    for e in items:
        if e.kind in ("tcpros_header", "tcpros_frame", "tcp_connect", "tcp_close", "error") and e.conn:
            by_conn.setdefault(e.conn, []).append(e)
    for evs in by_conn.values():
        callers = {e.args["callerid"] for e in evs if e.kind == "tcpros_header"
                   and isinstance(e.args, dict) and e.args.get("callerid")}
        for e in evs:
            for label, other in ((e.src, e.dst), (e.dst, e.src)):
                if label and not label.startswith("/"):
                    rest = callers - {other}
                    if len(rest) == 1:
                        names.setdefault(label, next(iter(rest)))
    return names


_URI_PREFIX = re.compile(r"((?:http|rosrpc)://[^\s/]+/?):\s*")


def _fold_repeats(events: list[SeqEvent]) -> list[SeqEvent]:
    """Fold an arrow that repeats one of the last :data:`FOLD_WINDOW` (retries) into it."""
    out: list[SeqEvent] = []
    keys: list[tuple[str, str, str, str]] = []
    counts: list[int] = []
    details: list[str] = []
    for e in events:
        key = (e.src, e.dst, e.kind, e.label)
        for j in range(len(out) - 1, max(-1, len(out) - 1 - FOLD_WINDOW), -1):
            if keys[j] == key:
                counts[j] += 1
                out[j].label = f"{key[3]} \u00d7{counts[j]}"
                out[j].detail = (details[j] + f"\n(repeated {counts[j]} times; bytes of the first)").strip()
                break
        else:
            out.append(e)
            keys.append(key)
            counts.append(1)
            details.append(e.detail)
    return out


def events_from_trace(trace: Any, *, frames_per_connection: int = 2, replies: bool = True,
                      fold: bool = True) -> list[SeqEvent]:
    """Events from a ``rosfpga_lab.graph`` ``Trace`` (or a list of its ``TraceEvent``).

    Args:
        trace: a Trace (its ``conversation()`` is used) or TraceEvent-like objects.
        frames_per_connection: message frames drawn per TCPROS connection; the rest are
            summarised in one "... N more" arrow.
        replies: draw the reply arrow of each XML-RPC call.
        fold: fold retries (an arrow repeating a recent one) into one arrow marked ``xN``.

    Parties are named by node name wherever the trace tells it (:func:`peer_names`), so one
    node is one lifeline, whether it was seen by name, slave API URI or TCP address.
    """
    items = trace.conversation() if hasattr(trace, "conversation") else list(trace)
    alias = peer_names(items)
    out: list[SeqEvent] = []
    types: dict[int, str] = {}
    frames: dict[int, int] = {}
    skipped: dict[int, tuple[Any, int]] = {}
    for e in items:
        kind = e.kind
        if kind == "xmlrpc":
            args = ", ".join(repr(a) for a in (e.args or []))
            out.append(SeqEvent(e.src, e.dst, e.method, bytes(e.raw), e.t0, "xmlrpc",
                                detail=f"{e.method}({args})"[:300]))
            if replies and (e.raw_reply or e.result is not None):
                res = e.result
                status = res[1] if isinstance(res, (list, tuple)) and len(res) > 1 else res
                out.append(SeqEvent(e.dst, e.src, f"\u21a9 {status or 'reply'}"[:60], bytes(e.raw_reply), e.t,
                                    "xmlrpc_reply", detail=repr(res)[:300]))
        elif kind == "tcpros_header":
            if isinstance(e.args, dict) and "type" in e.args and e.args.get("type") != "*":
                types[e.conn] = e.args["type"]
            who = "error" if isinstance(e.args, dict) and "error" in e.args else "header"
            out.append(SeqEvent(e.src, e.dst, f"TCPROS {who} {e.method}".strip(), bytes(e.raw), e.t0,
                                "tcpros_header", detail=repr(e.args)[:300]))
        elif kind == "tcpros_frame":
            n = frames.get(e.conn, 0)
            frames[e.conn] = n + 1
            if n < frames_per_connection:
                out.append(SeqEvent(e.src, e.dst, f"message #{e.index} ({e.size} B)", bytes(e.raw), e.t0,
                                    "tcpros_frame", detail=f"{e.method} frame {e.index}, {e.size} bytes",
                                    type_name=types.get(e.conn)))
            else:
                first, count = skipped.get(e.conn, (e, 0))
                skipped[e.conn] = (first, count + 1)
        elif kind in ("tcp_connect", "tcp_close", "error"):
            result, dst = str(e.result or ""), e.dst
            found = _URI_PREFIX.match(result) if kind == "error" else None
            if found:   # "http://host:port/: what failed": the URI is the peer, the rest the label
                dst = dst or found[1]
                result = result[found.end():]
                result = result.split(" failed: ")[-1] if " failed: " in result else result
            label = {"tcp_connect": "TCP connect", "tcp_close": "TCP close"}.get(kind, f"error: {result}")
            out.append(SeqEvent(e.src, dst, label[:60], b"", e.t0, kind, detail=str(e.result or "")[:300]))
    for _conn, (first, count) in skipped.items():
        out.append(SeqEvent(first.src, first.dst, f"\u2026 {count} more messages", b"", first.t0 + 1e-9,
                            "tcpros_frame"))
    for ev in out:
        ev.src = alias.get(ev.src, ev.src) or "(unknown)"
        ev.dst = alias.get(ev.dst, ev.dst) or "(unknown)"
    out.sort(key=lambda ev: (ev.t if ev.t is not None else 0.0))
    return _fold_repeats(out) if fold else out


def _fit(text: str, px: float) -> str:
    """``text`` cut with an ellipsis to about ``px`` pixels."""
    n = max(4, int(px / CHAR_PX))
    return text if len(text) <= n else text[: n - 1] + "\u2026"


def _fit_label(number: str, text: str, size: str, px: float) -> str:
    """An arrow's label cut to about ``px`` pixels in its middle: the arrow's number and its
    byte count (``[123 B]``) always stay whole, the text between gets the ellipsis."""
    n = max(4, int(px / CHAR_PX)) - len(number) - len(size)
    return number + (text if len(text) <= n else text[: max(n - 1, 3)] + "\u2026") + size


def _label_lines(number: str, text: str, size: str, px: float) -> list[str]:
    """An arrow's label in one line of about ``px`` pixels, or two (the second drawn under the
    arrow), broken between words of the text; the byte count stays whole at the end, and only
    text longer than two lines is cut (its middle, as :func:`_fit_label` does)."""
    n = max(4, int(px / CHAR_PX))
    head = number + text
    if len(head) + len(size) <= n:
        return [head + size]
    cut = head.rfind(" ", 0, n + 1)
    if cut <= len(number):
        cut = n
    first, rest = head[:cut].rstrip(), head[cut:].lstrip()
    if len(rest) + len(size) <= n:
        return [first, rest + size]
    return [first, _fit_label("", rest, size, px)]


def events_from_capture(path: str | Path, **options: Any) -> list[SeqEvent]:
    """Events of the ROS 1 conversation in a capture file (pcap/pcapng of real traffic), via
    ``rosfpga_lab.graph.capture_read.trace_from_capture``; options as :func:`events_from_trace`."""
    from rosfpga_lab.graph.capture_read import trace_from_capture

    return events_from_trace(trace_from_capture(path), **options)


def sequence_svg(events: Sequence[SeqEvent], participants: Sequence[str] | None = None, *,
                 selected: int | None = None, col: int | None = None, row: int = 34,
                 fit_width: int = FIT_WIDTH) -> str:
    """The diagram as an SVG string: lifelines, numbered arrows (``<g data-index=k>``), times.

    Columns are as wide as ``fit_width`` allows (``col`` forces a width); labels are cut to
    their arrow (the tooltip has the full text) and drawn on a white halo so lifelines do not
    cross them; the SVG scales down to its container rather than overflow it.
    """
    names = list(participants) if participants else participants_of(events, FIRST_PARTICIPANTS)
    missing = ({e.src for e in events} | {e.dst for e in events}) - set(names)
    if missing:
        raise WidgetError(f"participants {sorted(missing)} appear in events but not in participants=")
    left, top = 80, 50
    if col is None:
        col = max(COL_MIN, min(COL_MAX, (fit_width - left - 20) // max(len(names), 1)))
    xs = {n: left + col // 2 + i * col for i, n in enumerate(names)}
    height = top + 20 + row * max(len(events), 1) + 20
    width = left + col * max(len(names), 1) + 20
    t0 = next((e.t for e in events if e.t is not None), None)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" style="max-width:100%;height:auto" '
           f'font-family="sans-serif" font-size="12">',
           '<defs><marker id="rfl-ah" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="8" '
           'markerHeight="8" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" fill="context-stroke"/>'
           "</marker></defs>"]
    for n, x in xs.items():
        out.append(f'<rect x="{x - col // 2 + 10}" y="8" width="{col - 20}" height="26" rx="4" fill="#f0f0f0" stroke="#333"/>')
        out.append(f'<text x="{x}" y="26" text-anchor="middle" font-weight="bold" font-size="11">'
                   f'{esc(_fit(n, (col - 14) * 1.1))}</text>')
        out.append(f'<line x1="{x}" y1="34" x2="{x}" y2="{height - 10}" stroke="#999" stroke-dasharray="4 4"/>')
    for k, e in enumerate(events):
        y = top + 20 + k * row
        colour, dash = KIND_STYLE.get(e.kind, ("#333333", ""))
        dash_attr = f' stroke-dasharray="{dash}"' if dash else ""
        sel = " sel" if k == selected else ""
        tip = esc(f"{k + 1}. {e.src} \u2192 {e.dst}: {e.label}" + (
            f" ({e.bytes_drawn} bytes)" if e.raw and e.bytes_drawn == len(e.raw) else
            f" ({e.bytes_drawn} of the datagram's {len(e.raw)} bytes)" if e.raw else "")
                  + (f"\n{e.detail}" if e.detail else ""))
        out.append(f'<g class="rfl-arrow{sel}" data-index="{k}"><title>{tip}</title>')
        x1, x2 = xs[e.src], xs[e.dst]
        tx: float
        room: float
        if x1 == x2:
            path = f"M{x1},{y - 8} h40 v14 h-40"
            out.append(f'<path d="{path}" fill="none" stroke="transparent" stroke-width="12"/>')
            out.append(f'<path class="rfl-vis" d="{path}" fill="none" stroke="{colour}" stroke-width="1.5"{dash_attr} marker-end="url(#rfl-ah)"/>')
            tx, anchor, room = x1 + 46, "start", col - 50
        else:
            out.append(f'<line x1="{x1}" y1="{y}" x2="{x2}" y2="{y}" stroke="transparent" stroke-width="14"/>')
            out.append(f'<line class="rfl-vis" x1="{x1}" y1="{y}" x2="{x2}" y2="{y}" stroke="{colour}" '
                       f'stroke-width="1.5"{dash_attr} marker-end="url(#rfl-ah)"/>')
            # a label may run past a short arrow's ends: its white halo keeps it readable
            tx, anchor, room = (x1 + x2) / 2, "middle", max(abs(x2 - x1) - 16, min(2.2 * col, LABEL_MIN_PX))
        size = f" [{e.bytes_drawn} B]" if e.raw and e.kind != "tcpros_frame" else ""
        for j, line in enumerate(_label_lines(f"{k + 1}. ", e.label, size, room)):
            out.append(f'<text x="{tx}" y="{y - 5 + 17 * j}" text-anchor="{anchor}" fill="{colour}" '
                       f'paint-order="stroke" stroke="#fff" stroke-width="4" stroke-linejoin="round">'
                       f'{esc(line)}</text>')
        if e.t is not None and t0 is not None:
            out.append(f'<text x="4" y="{y + 4}" fill="#777" font-size="10">+{(e.t - t0) * 1000:.1f} ms</text>')
        out.append("</g>")
    out.append("</svg>")
    return "".join(out)


def _events_table(events: Sequence[SeqEvent], with_bytes: bool) -> str:
    t0 = next((e.t for e in events if e.t is not None), None)
    rows = ['<table style="border-collapse:collapse;font-size:12px"><tr><th>#</th><th>time</th><th>from</th>'
            "<th>to</th><th>what</th><th>bytes</th></tr>"]
    for k, e in enumerate(events):
        when = f"+{(e.t - t0) * 1000:.1f} ms" if e.t is not None and t0 is not None else ""
        rows.append(f"<tr><td>{k + 1}</td><td>{when}</td><td>{esc(e.src)}</td><td>{esc(e.dst)}</td>"
                    f"<td>{esc(e.label)}</td><td style=\"font-family:monospace\">{len(e.raw)}: {esc(hex_bytes(e.raw, 12))}</td></tr>")
        if with_bytes and e.raw:
            page = ByteMap(e.raw, e.byte_spans(), title=f"{k + 1}. {e.label}", page_size=256).to_html(0, max_table_rows=40)
            rows.append(f'<tr><td></td><td colspan="5"><details><summary>bytes of {k + 1}</summary>{page}</details></td></tr>')
    rows.append("</table>")
    return "".join(rows)


def sequence_html(events: Iterable[Any], participants: Sequence[str] | None = None, *, with_bytes: bool = True) -> str:
    """Static HTML: the SVG diagram and a table of every arrow with its bytes (no JavaScript needed)."""
    evs = [_as_event(e) for e in events]
    return "<div>" + sequence_svg(evs, participants) + _events_table(evs, with_bytes) + "</div>"


class SvgPane(anywidget.AnyWidget):
    """An SVG whose elements with ``data-index`` are clickable; the index lands in ``selected``."""

    _esm = STATIC / "svgpane.js"
    _css = STATIC / "svgpane.css"
    svg = traitlets.Unicode("").tag(sync=True)
    selected = traitlets.Int(-1).tag(sync=True)


class SequenceDiagram(StaticFallback, w.VBox):
    """The clickable diagram, a list of the arrows, and a byte viewer of the selected arrow's bytes.

    Args:
        events: :class:`SeqEvent` (or dicts / tuples of its fields), a ``graph`` Trace, or the
            path of a capture file of real ROS 1 traffic (pcap/pcapng).
        participants: lifeline order (default: order of appearance).
        static_fallback: put the static HTML form in the output too (exported notebooks, GitHub).
    """

    def __init__(self, events: Any, participants: Sequence[str] | None = None, *,
                 static_fallback: bool = True) -> None:
        if isinstance(events, (str, Path)):
            events = events_from_capture(events)
        elif hasattr(events, "conversation"):
            events = events_from_trace(events)
        self.events = [_as_event(e) for e in events]
        self.participants = list(participants) if participants else participants_of(self.events, FIRST_PARTICIPANTS)
        self.static_fallback = static_fallback
        self.pane = SvgPane(svg=sequence_svg(self.events, self.participants))
        self.list = w.Dropdown(options=[(f"{k + 1}. {e.src} \u2192 {e.dst}: {e.label}", k)
                                        for k, e in enumerate(self.events)],
                               value=None, description="arrow",
                               layout=w.Layout(width="640px", max_width="100%"))
        self.bytes = ByteViewer(b"", static_fallback=False)
        self.pane.observe(lambda c: self.select(c["new"]) if c["new"] >= 0 else None, "selected")
        self.list.observe(lambda c: self.select(c["new"]) if c["new"] is not None else None, "value")
        super().__init__([self.pane, self.list, self.bytes])
        if self.events:  # the byte viewer starts on the first arrow, not on "0 bytes"
            self.select(0)

    @property
    def selected(self) -> SeqEvent | None:
        """The selected event, or None."""
        k = self.pane.selected
        return self.events[k] if 0 <= k < len(self.events) else None

    def select(self, index: int) -> SeqEvent:
        """Select arrow ``index`` (0-based): highlight it and show its bytes."""
        if not 0 <= index < len(self.events):
            raise WidgetError(f"arrow {index} does not exist; there are {len(self.events)}")
        e = self.events[index]
        self.pane.selected = index
        self.list.value = index
        self.bytes.set_data(e.raw, e.byte_spans(), title=f"{index + 1}. {e.src} \u2192 {e.dst}: {e.label}")
        return e

    def to_html(self, with_bytes: bool = True) -> str:
        """The static HTML form (see :func:`sequence_html`)."""
        return sequence_html(self.events, self.participants, with_bytes=with_bytes)
