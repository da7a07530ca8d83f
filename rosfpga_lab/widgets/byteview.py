"""Byte viewer: a hex + ASCII view of a byte string with its fields coloured.

How this works: a :class:`ByteMap` holds the bytes and a sorted list of :class:`Span` (offset,
size, path, type, value, role); it answers "which field owns byte N", "which fields are on page
P" and renders a self-contained static HTML page (inline colours, a tooltip on every field run,
and a field table, so the meaning survives GitHub's JavaScript-free view). :class:`ByteViewer`
is the live widget: it ships only the current page (``BYTE_PAGE_SIZE`` bytes) and the field list
to the browser, where hovering a byte names its field and clicking selects it; the selection is
synced back to Python (:attr:`ByteViewer.selection`).

Spans can come from anywhere: ``Span`` objects, any object with ``offset``/``size`` and
``path`` (or ``label``/``name``) attributes (such as ``rosfpga_lab.msg`` field spans), dicts
with the same keys, or tuples ``(offset, size, path[, type[, value[, role]]])``. Ready-made
adapters live in :mod:`rosfpga_lab.widgets.byte_sources`.
"""

from __future__ import annotations

import bisect
import difflib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import anywidget
import numpy as np
import traitlets

from rosfpga_lab.msg.span import Span
from rosfpga_lab.widgets._common import (
    BYTE_PAGE_SIZE,
    BYTE_PAGE_SIZE_MAX,
    BYTE_ROW_SIZE,
    FIELD_LIST_LIMIT,
    StaticFallback,
    WidgetError,
    colour_for,
    esc,
    format_value,
    hex_bytes,
)

STATIC = Path(__file__).resolve().parent / "static"


def as_span(item: Any) -> Span:
    """Coerce ``item`` (Span, object with attributes, dict or tuple) into a :class:`Span`.

    Raises:
        WidgetError: when ``item`` has no offset, size and name.
    """
    if isinstance(item, Span):
        return item
    if isinstance(item, dict):
        get = item.get
    elif isinstance(item, (tuple, list)):
        keys = ("offset", "size", "path", "type", "value", "role")
        mapping = dict(zip(keys, item))
        get = mapping.get
    else:
        def get(key: str, default: Any = None) -> Any:
            return getattr(item, key, default)
    offset, size = get("offset"), get("size")
    path = get("path")
    if path is None:
        path = get("label", get("name"))
    if offset is None or size is None or path is None:
        raise WidgetError(f"cannot use {item!r} as a field span: it needs offset, size and path/label")
    if isinstance(path, (tuple, list)):
        path = ".".join(str(p) for p in path)
    return Span(int(offset), int(size), str(path), str(get("type", "") or ""),
                get("value"), str(get("role", "") or ""))


def _as_bytes(data: Any) -> bytes:
    if isinstance(data, np.ndarray):
        if data.dtype != np.uint8:
            raise WidgetError(f"byte data must be uint8, got a {data.dtype} array (use arr.tobytes())")
        return data.tobytes()
    if isinstance(data, (bytes, bytearray, memoryview)):
        return bytes(data)
    raise WidgetError(f"byte data must be bytes, bytearray, memoryview or a uint8 array, got {type(data).__name__}")


class ByteMap:
    """Bytes plus the fields that cover them: lookup, paging, colours, static HTML.

    Args:
        data: the bytes (bytes, bytearray, memoryview or uint8 numpy array).
        spans: the fields (see the module doc for accepted forms). They must lie inside
            ``data`` and must not overlap; bytes in no span are shown uncoloured.
        title: a caption.
        page_size: bytes per page (a multiple of ``row_size``).
        row_size: bytes per hex row.

    Raises:
        WidgetError: a span outside the data, overlapping spans, a bad page size.
    """

    def __init__(self, data: Any, spans: Iterable[Any] = (), *, title: str = "",
                 page_size: int = BYTE_PAGE_SIZE, row_size: int = BYTE_ROW_SIZE) -> None:
        self.data = _as_bytes(data)
        self.title = title
        if row_size < 1 or page_size < row_size or page_size % row_size or page_size > BYTE_PAGE_SIZE_MAX:
            raise WidgetError(
                f"page_size={page_size} must be a multiple of row_size={row_size} and at most {BYTE_PAGE_SIZE_MAX}")
        self.page_size, self.row_size = page_size, row_size
        ordered = sorted((as_span(s) for s in spans), key=lambda s: (s.offset, s.size))
        for span in ordered:
            if span.offset < 0 or span.size < 0 or span.offset + span.size > len(self.data):
                raise WidgetError(
                    f"field {span.path!r} (offset {span.offset}, size {span.size}) lies outside the "
                    f"{len(self.data)} data bytes")
        owning = [s for s in ordered if s.size > 0]
        for a, b in zip(owning, owning[1:]):
            if b.offset < a.offset + a.size:
                raise WidgetError(
                    f"fields {a.path!r} (bytes {a.offset}..{a.offset + a.size - 1}) and {b.path!r} "
                    f"(from byte {b.offset}) overlap; give each byte to one field")
        self.spans: list[Span] = ordered
        self._starts = [s.offset for s in ordered]

    # --- lookup -----------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.data)

    def span_at(self, offset: int) -> int | None:
        """Index of the span that owns byte ``offset``, or None (uncovered or out of range)."""
        if not 0 <= offset < len(self.data):
            return None
        i = bisect.bisect_right(self._starts, offset) - 1
        while i >= 0:
            s = self.spans[i]
            if s.size > 0:
                return i if offset < s.offset + s.size else None
            i -= 1  # skip zero-size spans sharing the start
        return None

    def find(self, path: str) -> int:
        """Index of the first span named ``path`` (its value span if a length prefix shares the name).

        Raises:
            WidgetError: no such field (the message suggests close names).
        """
        matches = [i for i, s in enumerate(self.spans) if s.path == path]
        for i in matches:  # a value rather than its length prefix when both share the path
            if self.spans[i].role != "length":
                return i
        if matches:
            return matches[0]
        close = difflib.get_close_matches(path, [s.path for s in self.spans], n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise WidgetError(f"no field {path!r} in this byte map{hint}")

    def colour(self, index: int) -> str:
        """Background colour of span ``index``."""
        return colour_for(index, self.spans[index].role)

    def label(self, index: int) -> str:
        """Span ``index``'s path, with its role in brackets unless it is a plain value
        (``header.frame_id [length]``)."""
        s = self.spans[index]
        return s.path + (f" [{s.role}]" if s.role not in ("", "value") else "")

    def describe(self, index: int) -> str:
        """One line naming span ``index``: path, type, offset, size and decoded value."""
        s = self.spans[index]
        parts = [self.label(index)]
        if s.type:
            parts.append(s.type)
        parts += [f"offset {s.offset}", f"size {s.size}"]
        value = format_value(s.value) if s.value is not None else ""
        if value:
            parts.append(f"value {value}")
        else:
            parts.append(f"bytes {hex_bytes(self.data[s.offset:s.offset + s.size], 8) or '(none)'}")
        return " \u00b7 ".join(parts)

    # --- paging -------------------------------------------------------------------------------
    @property
    def n_pages(self) -> int:
        """Number of pages (at least 1, even for no data)."""
        return max(1, -(-len(self.data) // self.page_size))

    def check_page(self, page: int) -> int:
        """``page`` if it exists.

        Raises:
            WidgetError: otherwise.
        """
        if not 0 <= page < self.n_pages:
            raise WidgetError(f"page {page} does not exist; pages are 0..{self.n_pages - 1}")
        return page

    def page_range(self, page: int) -> tuple[int, int]:
        """``(start, stop)`` byte offsets shown on ``page``."""
        self.check_page(page)
        start = page * self.page_size
        return start, min(start + self.page_size, len(self.data))

    def page_of(self, offset: int) -> int:
        """The page that shows byte ``offset`` (offsets at the end map to the last page)."""
        return min(max(offset, 0) // self.page_size, self.n_pages - 1)

    def spans_on_page(self, page: int) -> list[int]:
        """Indices of spans with at least one byte on ``page`` (zero-size ones by their offset)."""
        start, stop = self.page_range(page)
        last = page == self.n_pages - 1
        out = []
        i = max(0, bisect.bisect_right(self._starts, start) - 1)
        for j in range(i, len(self.spans)):
            s = self.spans[j]
            if s.offset >= stop and not (last and s.offset == stop):
                break
            if s.size == 0:
                if start <= s.offset < stop or (last and s.offset == stop):
                    out.append(j)
            elif s.offset + s.size > start:
                out.append(j)
        return out

    # --- static HTML --------------------------------------------------------------------------
    def _runs(self, start: int, stop: int) -> list[tuple[int, int, int | None]]:
        """``(from, to, span index or None)`` runs of bytes on one row."""
        runs: list[tuple[int, int, int | None]] = []
        off = start
        while off < stop:
            idx = self.span_at(off)
            end = min(stop, self.spans[idx].offset + self.spans[idx].size) if idx is not None else off + 1
            if idx is None:
                while end < stop and self.span_at(end) is None:
                    end += 1
            runs.append((off, end, idx))
            off = end
        return runs

    def to_html(self, page: int = 0, *, max_table_rows: int = 200) -> str:
        """Self-contained HTML of ``page``: hex + ASCII with coloured fields and a field table.

        It needs no JavaScript and no stylesheet: colours are inline, every field run has a
        tooltip naming the field, and the table lists each field on the page with its colour.
        """
        start, stop = self.page_range(page)
        mono = "font-family:ui-monospace,SFMono-Regular,Menlo,Consolas,monospace;font-size:12px"
        out = [f'<div class="rfl-bytemap" style="{mono};line-height:1.5">']
        cap = f"{esc(self.title)} \u2014 " if self.title else ""
        out.append(
            f"<div><b>{cap}{len(self.data)} bytes, {len(self.spans)} fields</b>; page {page + 1} of "
            f"{self.n_pages} (bytes {start}..{max(start, stop - 1)})</div>")
        out.append('<pre style="margin:4px 0;line-height:1.5">')
        for row in range(start, stop, self.row_size):
            row_stop = min(row + self.row_size, stop)
            hex_parts, asc_parts = [], []
            for a, b, idx in self._runs(row, row_stop):
                chunk = self.data[a:b]
                hx = " ".join(f"{v:02x}" for v in chunk)
                asc = esc("".join(chr(v) if 32 <= v < 127 else "." for v in chunk))
                if idx is None:
                    hex_parts.append(hx)
                    asc_parts.append(asc)
                else:
                    s = self.spans[idx]
                    first = ";border-left:2px solid #444" if a == s.offset else ""
                    style = f'style="background:{self.colour(idx)}{first}" title="{esc(self.describe(idx))}"'
                    hex_parts.append(f"<span {style}>{hx}</span>")
                    asc_parts.append(f"<span {style}>{asc}</span>")
            pad = "   " * (self.row_size - (row_stop - row))
            out.append(f"{row:08x}  {' '.join(hex_parts)}{pad}  |{''.join(asc_parts)}|\n")
        out.append("</pre>")
        rows = self.spans_on_page(page)
        out.append('<table style="border-collapse:collapse;font-size:12px">'
                   "<tr><th></th><th>field</th><th>type</th><th>offset</th><th>size</th><th>value</th></tr>")
        for idx in rows[:max_table_rows]:
            s = self.spans[idx]
            value = format_value(s.value) if s.value is not None else hex_bytes(self.data[s.offset:s.offset + s.size], 8)
            out.append(
                f'<tr><td style="background:{self.colour(idx)};width:14px;border:1px solid #888"></td>'
                f"<td>{esc(self.label(idx))}</td><td>{esc(s.type)}</td><td>{s.offset}</td><td>{s.size}</td>"
                f"<td>{esc(value)}</td></tr>")
        if len(rows) > max_table_rows:
            out.append(f'<tr><td></td><td colspan="5">\u2026 {len(rows) - max_table_rows} more fields on this page</td></tr>')
        out.append("</table>")
        others = len(self.spans) - len(rows)
        if others > 0:
            out.append(f"<div>{others} more fields on other pages.</div>")
        out.append("</div>")
        return "".join(out)

    def _repr_html_(self) -> str:
        return self.to_html(0)


class ByteViewer(StaticFallback, anywidget.AnyWidget):
    """Live byte viewer: hover a byte to name its field, click to select it, page through.

    Args:
        data: the bytes (see :class:`ByteMap`).
        spans: the fields (see :class:`ByteMap`); or pass a ready ``ByteMap`` as ``data``.
        title: a caption.
        page_size: bytes per page shipped to the browser.
        static_fallback: also put the static HTML form in the output, so exported notebooks
            and GitHub show the bytes and fields without a kernel.

    Attributes:
        selection: the selected :class:`Span` or None (synced from clicks in the browser).
    """

    _esm = STATIC / "byteviewer.js"
    _css = STATIC / "byteviewer.css"

    title = traitlets.Unicode("").tag(sync=True)
    total = traitlets.Int(0).tag(sync=True)
    page = traitlets.Int(0).tag(sync=True)
    n_pages = traitlets.Int(1).tag(sync=True)
    page_start = traitlets.Int(0).tag(sync=True)
    row_size = traitlets.Int(BYTE_ROW_SIZE).tag(sync=True)
    page_hex = traitlets.Unicode("").tag(sync=True)
    fields: traitlets.List[Any] = traitlets.List([]).tag(sync=True)
    page_fields: traitlets.List[Any] = traitlets.List([]).tag(sync=True)
    fields_truncated = traitlets.Int(0).tag(sync=True)
    #: Index of the selected field in the byte map's spans, -1 for none.
    selected = traitlets.Int(-1).tag(sync=True)
    #: The byte last clicked, -1 for none.
    selected_offset = traitlets.Int(-1).tag(sync=True)

    def __init__(self, data: Any = b"", spans: Iterable[Any] = (), *, title: str = "",
                 page_size: int = BYTE_PAGE_SIZE, static_fallback: bool = True, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.static_fallback = static_fallback
        self._callbacks: list[Callable[[Span | None], None]] = []
        self.bytemap = ByteMap(b"")
        self.set_data(data, spans, title=title, page_size=page_size)

    # --- Python API -------------------------------------------------------------------------
    def set_data(self, data: Any, spans: Iterable[Any] = (), *, title: str = "",
                 page_size: int = BYTE_PAGE_SIZE) -> None:
        """Show other bytes (keeps the widget on screen); resets page and selection."""
        bm = data if isinstance(data, ByteMap) else ByteMap(data, spans, title=title, page_size=page_size)
        self.bytemap = bm
        listed = bm.spans[:FIELD_LIST_LIMIT]
        with self.hold_sync():
            self.title = bm.title
            self.total = len(bm)
            self.n_pages = bm.n_pages
            self.row_size = bm.row_size
            self.fields = [self._field_dict(i) for i in range(len(listed))]
            self.fields_truncated = len(bm.spans) - len(listed)
            self.selected = -1
            self.selected_offset = -1
            self.page = 0
            self._send_page()

    @property
    def selection(self) -> Span | None:
        """The selected span, or None."""
        return self.bytemap.spans[self.selected] if 0 <= self.selected < len(self.bytemap.spans) else None

    def select(self, field: str | int) -> Span:
        """Select a field by path or span index, turning to its page; returns it."""
        index = self.bytemap.find(field) if isinstance(field, str) else int(field)
        if not 0 <= index < len(self.bytemap.spans):
            raise WidgetError(f"field index {index} does not exist; there are {len(self.bytemap.spans)} fields")
        self.selected = index
        return self.bytemap.spans[index]

    def select_byte(self, offset: int) -> Span | None:
        """Select the field owning byte ``offset`` (as a click would); returns it or None."""
        if not 0 <= offset < len(self.bytemap):
            raise WidgetError(f"byte {offset} is outside the {len(self.bytemap)} bytes")
        self.selected_offset = offset
        idx = self.bytemap.span_at(offset)
        self.selected = -1 if idx is None else idx
        if self.bytemap.page_of(offset) != self.page:
            self.page = self.bytemap.page_of(offset)
        return self.selection

    def on_select(self, callback: Callable[[Span | None], None]) -> None:
        """Call ``callback(span_or_None)`` whenever the selection changes."""
        self._callbacks.append(callback)

    def highlighted(self) -> range:
        """Offsets on the current page that are highlighted (the selected field's bytes there)."""
        span = self.selection
        start, stop = self.bytemap.page_range(self.page)
        if span is None:
            return range(0)
        return range(max(start, span.offset), min(stop, span.offset + span.size))

    def to_html(self, page: int | None = None) -> str:
        """The static HTML form (current page unless ``page`` is given)."""
        return self.bytemap.to_html(self.page if page is None else page)

    # --- sync ---------------------------------------------------------------------------------
    def _field_dict(self, i: int) -> dict[str, Any]:
        s = self.bytemap.spans[i]
        return {"i": i, "path": s.path, "label": self.bytemap.label(i), "type": s.type, "offset": s.offset, "size": s.size,
                "colour": self.bytemap.colour(i), "info": self.bytemap.describe(i)}

    def _send_page(self) -> None:
        start, stop = self.bytemap.page_range(self.page)
        self.page_start = start
        self.page_hex = self.bytemap.data[start:stop].hex()
        self.page_fields = [self._field_dict(i) for i in self.bytemap.spans_on_page(self.page)]

    @traitlets.validate("page")
    def _valid_page(self, proposal: Any) -> int:
        return max(0, min(int(proposal["value"]), self.bytemap.n_pages - 1))

    @traitlets.observe("page")
    def _page_changed(self, change: Any) -> None:
        self._send_page()

    @traitlets.observe("selected")
    def _selected_changed(self, change: Any) -> None:
        span = self.selection
        if span is not None and span.size > 0:
            lo, hi = self.bytemap.page_of(span.offset), self.bytemap.page_of(span.offset + span.size - 1)
            if not lo <= self.page <= hi:
                self.page = lo
        for cb in list(self._callbacks):
            cb(span)
