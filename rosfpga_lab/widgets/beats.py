"""Beat viewer: AXI4-Stream beats as a table and a waveform, linked to the pixels they carry.

How this works: the bytes a stream carries are the *kept* byte lanes of each beat (``tkeep``
bit i set -> byte lane i, ``tdata`` bits 8i+7..8i, is data), in beat order. Numbered from 0, byte
``b`` belongs to pixel ``b // bytes_per_pixel``, which sits at ``x = p % width, y = p // width``.
So a :class:`BeatMap` needs only the four signals and the image geometry; it works for one
pixel per beat (the lab's packing, see ``rosfpga_lab.hw.encodings``), several pixels per beat, or
beats with null lanes. It also says where ``tuser`` (start of frame: the beat with the first
byte) and ``tlast`` (end of line: the beat with a row's last byte) *should* be, and lists every
beat where the signal differs, which is how a lost or repeated beat shows up.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import ipywidgets as w
import numpy as np

from rosfpga_lab.widgets._common import (
    BEAT_PAGE_SIZE,
    WAVE_BEATS,
    StaticFallback,
    WidgetError,
    as_image,
    display_rgb,
    enlarged_png,
    esc,
)
from rosfpga_lab.widgets.clickimage import ClickImage

TUSER_COLOUR = "#b9fbc0"
TLAST_COLOUR = "#a0c4ff"
WRONG_COLOUR = "#ff8080"


@dataclass(frozen=True)
class MarkerMismatch:
    """A beat whose ``tuser``/``tlast`` differs from what the pixel positions call for."""

    beat: int
    signal: str       # "tuser" or "tlast"
    expected: bool
    actual: bool


class BeatMap:
    """Beats plus image geometry: beat <-> pixel mapping and marker checks.

    Args:
        beats: an object with ``tdata``, ``tkeep``, ``tuser``, ``tlast`` arrays (such as
            ``rosfpga_lab.hw.streams.Beats``), or None when the arrays are given separately.
        width, height: image size in pixels.
        bytes_per_pixel: bytes of one pixel (3 for rgb8, 4 for rgba8, 1 for mono8).
        tdata: (N,) unsigned words (byte lane 0 = bits 7..0) or (N, bus_bytes) uint8 lanes.
        tkeep: (N,) bit masks or (N, bus_bytes) booleans; default: all lanes kept.
        tuser, tlast: (N,) booleans; default all False.
        bus_bytes: bytes per beat (4 for the lab's 32-bit bus).

    Raises:
        WidgetError: mismatched lengths, bad geometry.
    """

    def __init__(self, beats: Any = None, *, width: int, height: int, bytes_per_pixel: int,
                 tdata: Any = None, tkeep: Any = None, tuser: Any = None, tlast: Any = None,
                 bus_bytes: int = 4) -> None:
        if beats is not None:
            tdata, tkeep, tuser, tlast = beats.tdata, beats.tkeep, beats.tuser, beats.tlast
        if tdata is None:
            raise WidgetError("BeatMap needs beats (an object with tdata/tkeep/tuser/tlast) or tdata=")
        if width < 1 or height < 1 or bytes_per_pixel < 1:
            raise WidgetError(f"bad geometry: width={width}, height={height}, bytes_per_pixel={bytes_per_pixel}")
        self.width, self.height, self.bpp, self.bus_bytes = width, height, bytes_per_pixel, bus_bytes
        td = np.asarray(tdata)
        if td.ndim == 2:
            if td.shape[1] != bus_bytes:
                raise WidgetError(f"tdata lanes: expected {bus_bytes} per beat, got {td.shape[1]}")
            lanes = td.astype(np.uint8)
        elif td.ndim == 1:
            words = td.astype(np.uint64)
            lanes = ((words[:, None] >> (8 * np.arange(bus_bytes, dtype=np.uint64))) & 0xFF).astype(np.uint8)
        else:
            raise WidgetError(f"tdata must be (N,) words or (N, {bus_bytes}) lanes, got shape {td.shape}")
        n = lanes.shape[0]
        self.lanes = lanes
        if tkeep is None:
            keep = np.ones((n, bus_bytes), bool)
        else:
            tk = np.asarray(tkeep)
            if tk.ndim == 2:
                keep = tk.astype(bool)
            else:
                tk = np.broadcast_to(tk, (n,)).astype(np.uint64)
                keep = ((tk[:, None] >> np.arange(bus_bytes, dtype=np.uint64)) & 1).astype(bool)
        self.keep = keep
        self.tuser = np.zeros(n, bool) if tuser is None else np.broadcast_to(np.asarray(tuser, bool), (n,)).copy()
        self.tlast = np.zeros(n, bool) if tlast is None else np.broadcast_to(np.asarray(tlast, bool), (n,)).copy()
        if keep.shape != (n, bus_bytes):
            raise WidgetError(f"tkeep has shape {keep.shape}, tdata has {n} beats of {bus_bytes} bytes")
        counts = keep.sum(axis=1)
        self.ends = np.cumsum(counts)            # stream bytes up to and including beat i
        self.starts = self.ends - counts         # first stream byte of beat i
        self.frame_bytes = width * height * bytes_per_pixel

    @classmethod
    def from_stages(cls, stages: Any, which: str = "input") -> BeatMap:
        """The beats of one frame's video stages (``rosfpga_lab.hw.videostages.VideoStages``):
        ``which`` is ``input`` (into ``AXIvideo2Mat``) or ``output`` (out of ``Mat2AXIvideo``);
        geometry from the stages' picture."""
        if which not in ("input", "output"):
            raise WidgetError(f"which must be 'input' or 'output', got {which!r}")
        beats = stages.axis_in if which == "input" else stages.axis_out
        height, width, bytes_per_pixel = stages.input_image.shape
        return cls(beats, width=width, height=height, bytes_per_pixel=bytes_per_pixel)

    def __len__(self) -> int:
        return int(self.lanes.shape[0])

    @property
    def stream_bytes(self) -> int:
        """Kept bytes carried by all beats."""
        return int(self.ends[-1]) if len(self) else 0

    def check_beat(self, beat: int) -> int:
        if not 0 <= beat < len(self):
            raise WidgetError(f"beat {beat} does not exist; beats are 0..{len(self) - 1}")
        return beat

    def beat_bytes(self, beat: int) -> bytes:
        """The kept bytes of ``beat``, lane 0 first."""
        self.check_beat(beat)
        return self.lanes[beat][self.keep[beat]].tobytes()

    def beat_pixels(self, beat: int) -> list[tuple[int, int]]:
        """``(x, y)`` of every pixel with a byte in ``beat`` (none for null beats or past the frame)."""
        self.check_beat(beat)
        a, b = int(self.starts[beat]), int(self.ends[beat])
        if a == b:
            return []
        first, last = a // self.bpp, (b - 1) // self.bpp
        n = self.width * self.height
        return [(p % self.width, p // self.width) for p in range(first, min(last, n - 1) + 1)]

    def pixel_beat(self, x: int, y: int) -> int | None:
        """The beat carrying the first byte of pixel ``(x, y)``, or None if the stream ends first."""
        if not (0 <= x < self.width and 0 <= y < self.height):
            raise WidgetError(f"pixel ({x}, {y}) is outside the {self.width}x{self.height} image")
        byte = (y * self.width + x) * self.bpp
        beat = int(np.searchsorted(self.ends, byte, side="right"))
        return beat if beat < len(self) else None

    def pixel_bytes(self, x: int, y: int) -> bytes:
        """The bytes of pixel ``(x, y)`` as the stream carries them (short if the stream ends)."""
        start = (y * self.width + x) * self.bpp
        stream = self.lanes[self.keep]
        return stream[start:start + self.bpp].tobytes()

    def expected_markers(self) -> tuple[np.ndarray, np.ndarray]:
        """``(tuser, tlast)`` as the pixel positions call for them."""
        n = len(self)
        eu, el = np.zeros(n, bool), np.zeros(n, bool)
        if n == 0:
            return eu, el
        first = int(np.searchsorted(self.ends, 0, side="right"))
        if first < n:
            eu[first] = True
        row_last = (np.arange(1, self.height + 1) * self.width * self.bpp) - 1
        beats = np.searchsorted(self.ends, row_last, side="right")
        el[beats[beats < n]] = True
        return eu, el

    def marker_mismatches(self) -> list[MarkerMismatch]:
        """Every beat whose ``tuser`` or ``tlast`` differs from the expected one, in beat order."""
        eu, el = self.expected_markers()
        out = [MarkerMismatch(int(i), "tuser", bool(eu[i]), bool(self.tuser[i])) for i in np.flatnonzero(eu != self.tuser)]
        out += [MarkerMismatch(int(i), "tlast", bool(el[i]), bool(self.tlast[i])) for i in np.flatnonzero(el != self.tlast)]
        return sorted(out, key=lambda m: (m.beat, m.signal))

    def summary(self) -> str:
        """One line: beats, bytes carried vs the frame's, marker counts and mismatches."""
        wrong = self.marker_mismatches()
        return (f"{len(self)} beats carrying {self.stream_bytes} bytes (frame: {self.frame_bytes} = "
                f"{self.width}x{self.height}x{self.bpp}); tuser on {int(self.tuser.sum())}, tlast on "
                f"{int(self.tlast.sum())} beats; {len(wrong)} marker mismatch{'es' if len(wrong) != 1 else ''}")

    def describe_beat(self, beat: int) -> str:
        """One line about ``beat``: signals, bytes and the pixels it carries."""
        self.check_beat(beat)
        px = self.beat_pixels(beat)
        where = ", ".join(f"({x}, {y})" for x, y in px[:4]) + (" \u2026" if len(px) > 4 else "")
        return (f"beat {beat}: tdata 0x{self._word(beat):0{2 * self.bus_bytes}x} tkeep 0b{self._keep(beat):0{self.bus_bytes}b}"
                f" tuser {int(self.tuser[beat])} tlast {int(self.tlast[beat])}; bytes "
                f"{self.beat_bytes(beat).hex(' ') or '(none)'} -> pixel {where or '(none)'}")

    def _word(self, beat: int) -> int:
        return int.from_bytes(self.lanes[beat].tobytes(), "little")

    def _keep(self, beat: int) -> int:
        return int(sum(1 << i for i in range(self.bus_bytes) if self.keep[beat, i]))

    # --- HTML ---------------------------------------------------------------------------------
    def table_html(self, start: int = 0, count: int = BEAT_PAGE_SIZE, selected: int | None = None) -> str:
        """An HTML table of beats ``start .. start+count-1``; TUSER/TLAST rows coloured, wrong ones red."""
        eu, el = self.expected_markers()
        stop = min(len(self), start + count)
        rows = ['<table style="border-collapse:collapse;font-family:monospace;font-size:12px" cellpadding="2">'
                "<tr><th>beat</th><th>tdata</th><th>tkeep</th><th>tuser</th><th>tlast</th><th>pixels (x, y)</th></tr>"]
        for i in range(max(0, start), stop):
            def flag(actual: bool, expected: bool, colour: str) -> str:
                bg = WRONG_COLOUR if actual != expected else (colour if actual else "")
                note = "" if actual == expected else f" (expected {int(expected)})"
                return f'<td style="background:{bg};text-align:center;padding:1px 4px">{int(actual)}{note}</td>'
            px = self.beat_pixels(i)
            where = " ".join(f"({x}, {y})" for x, y in px[:3]) + (" \u2026" if len(px) > 3 else "")
            sel = ' style="background:#ffe08a"' if i == selected else ""  # red means wrong here
            td = '<td style="padding:1px 4px">'
            rows.append(f"<tr{sel}>{td}{i}</td>{td}0x{self._word(i):0{2 * self.bus_bytes}x}</td>"
                        f"{td}0b{self._keep(i):0{self.bus_bytes}b}</td>"
                        + flag(bool(self.tuser[i]), bool(eu[i]), TUSER_COLOUR)
                        + flag(bool(self.tlast[i]), bool(el[i]), TLAST_COLOUR)
                        + f"{td}{esc(where)}</td></tr>")
        rows.append("</table>")
        return "".join(rows)

    def clock_arrays(self, start: int = 0, count: int = WAVE_BEATS) -> dict[str, np.ndarray]:
        """Per-clock signals of beats ``start ..`` as ``fifo2axi`` makes them from the 8-bit FIFO.

        One byte enters per clock, so a beat is on the bus the clock after its last byte: a
        pixel of ``B`` bytes every ``B`` clocks (4 for ``rgba8``), no gaps, no backpressure (the
        generated ``fifo2axi``'s timing: ``tests/rtl/test_cycles.py`` holds the RTL to it).
        The beats' own ``tdata``/``tuser``/``tlast`` are drawn, wrong ones included, held in
        the output register until the next beat loads.
        """
        stop = min(len(self), start + count)
        if stop <= start:
            raise WidgetError(f"no beats from {start}; beats are 0..{len(self) - 1}")
        first_byte = int(self.starts[start])
        last_clock = int(self.ends[stop - 1]) - first_byte  # the last beat's clock
        n = last_clock + 1
        stream = self.lanes[self.keep]
        s_tdata = np.zeros(n, np.uint64)
        nbytes = int(self.ends[stop - 1]) - first_byte
        s_tdata[:nbytes] = stream[first_byte:first_byte + nbytes]
        s_tvalid = np.zeros(n, bool)
        s_tvalid[:nbytes] = True
        on = (self.ends[start:stop] - first_byte).astype(np.int64)  # clock of each beat
        valid = np.zeros(n, bool)
        valid[on] = True
        # register contents: each beat's values from its clock until the next beat's
        idx = np.full(n, -1, np.int64)
        idx[on] = np.arange(start, stop)
        idx = np.maximum.accumulate(idx)
        have = idx >= 0
        words = (self.lanes.astype(np.uint64) << (8 * np.arange(self.bus_bytes, dtype=np.uint64))).sum(axis=1)
        keeps = (self.keep.astype(np.uint64) << np.arange(self.bus_bytes, dtype=np.uint64)).sum(axis=1)
        def held(values: np.ndarray) -> np.ndarray:
            out = np.zeros(n, np.uint64)
            out[have] = values[idx[have]]
            return out
        return {"aclk": np.ones(n, bool), "s_tdata": s_tdata, "s_tvalid": s_tvalid,
                "s_tready": np.ones(n, bool), "m_axis_tvalid": valid, "m_axis_tready": np.ones(n, bool),
                "m_axis_tdata": held(words), "m_axis_tkeep": held(keeps),
                "m_axis_tuser": held(self.tuser.astype(np.uint64)).astype(bool),
                "m_axis_tlast": held(self.tlast.astype(np.uint64)).astype(bool)}

    def waveform_svg(self, start: int = 0, count: int = WAVE_BEATS, selected: int | None = None) -> str:
        """A logic-analyser picture of beats ``start ..``, clock by clock: the 8-bit stream into
        ``fifo2axi`` and the beats out of it with ``tvalid``/``tready``; the cursor on ``selected``."""
        from rosfpga_lab.widgets.waveform import Waves

        if not len(self):
            return "<div>no beats</div>"
        arrays = self.clock_arrays(start, count)
        waves = Waves.from_arrays(arrays, widths={"s_tdata": 8, "m_axis_tdata": 8 * self.bus_bytes,
                                                  "m_axis_tkeep": self.bus_bytes})
        first = int(self.starts[start])
        cursor = None
        if selected is not None and start <= selected < min(len(self), start + count):
            cursor = int(self.ends[selected]) - first
        return waves.svg(0, waves.clocks, cursor=cursor)

    def to_html(self, start: int = 0, count: int = BEAT_PAGE_SIZE) -> str:
        """Static HTML: summary, waveform of the first beats, the beat table, marker mismatches."""
        wrong = self.marker_mismatches()
        parts = [f"<div><b>{esc(self.summary())}</b></div>", self.waveform_svg(start, min(count, WAVE_BEATS)),
                 self.table_html(start, count)]
        if wrong:
            items = "".join(f"<li>beat {m.beat}: {m.signal} is {int(m.actual)}, expected {int(m.expected)}</li>"
                            for m in wrong[:20])
            more = f"<li>\u2026 {len(wrong) - 20} more</li>" if len(wrong) > 20 else ""
            parts.append(f"<div>Marker mismatches:</div><ul>{items}{more}</ul>")
        return "<div>" + "".join(parts) + "</div>"

    def _repr_html_(self) -> str:
        return self.to_html()


class BeatViewer(StaticFallback, w.VBox):
    """Beats linked to pixels: pick a beat to see its pixel, or a pixel to see its beat.

    Args:
        beats: as :class:`BeatMap` (or a ready ``BeatMap``); other keywords go to ``BeatMap``.
        image: the frame (HxW or HxWxC uint8) the beats carry; shown with the selected pixel
            outlined, and clicking a pixel selects its beat.
        channel_order: ``"rgb"`` or ``"bgr"``, for showing ``image``.

    Its output carries the static form (:meth:`BeatMap.to_html`: summary, waveform and table of
    the first beats, marker mismatches) for views without a kernel.
    """

    def __init__(self, beats: Any = None, *, image: Any = None, channel_order: str = "rgb", **kwargs: Any) -> None:
        self.map = beats if isinstance(beats, BeatMap) else BeatMap(beats, **kwargs)
        m = self.map
        self.frame_rgb = None
        self.picture: ClickImage | None = None
        if image is not None:
            img = as_image(image, "image")
            if img.shape[:2] != (m.height, m.width):
                raise WidgetError(f"image is {img.shape[1]}x{img.shape[0]} but the beats carry "
                                  f"{m.width}x{m.height} pixels")
            self.frame_rgb = display_rgb(img, channel_order)
            self.picture = ClickImage(src_width=m.width, src_height=m.height,
                                      caption="click a pixel to find its beat")
            self.picture.on_click(lambda x, y: self.select_pixel(x, y))
        last = max(0, len(m) - 1)
        self.beat = w.BoundedIntText(0, min=0, max=last, description="beat")
        self.x = w.BoundedIntText(0, min=0, max=m.width - 1, description="pixel x")
        self.y = w.BoundedIntText(0, min=0, max=m.height - 1, description="pixel y")
        self.info = w.HTML()
        self.wave = w.HTML()
        self.table = w.HTML()
        self._busy = False
        self.beat.observe(self._on_beat, "value")
        self.x.observe(self._on_pixel, "value")
        self.y.observe(self._on_pixel, "value")
        tables = w.VBox([self.wave, self.table])
        body = w.HBox([self.picture, tables]) if self.picture is not None else tables
        super().__init__([w.HTML(f"<b>{esc(m.summary())}</b>"), w.HBox([self.beat, self.x, self.y]),
                          self.info, body])
        self._render()

    @classmethod
    def from_stages(cls, stages: Any, which: str = "input") -> BeatViewer:
        """A viewer of one frame's video stages' input or output beats and picture (see
        :meth:`BeatMap.from_stages`)."""
        image = stages.input_image if which == "input" else stages.output_image
        return cls(BeatMap.from_stages(stages, which), image=image)

    def select_beat(self, beat: int) -> list[tuple[int, int]]:
        """Select ``beat``; the pixel fields follow. Returns the beat's pixels."""
        self.map.check_beat(beat)
        self.beat.value = beat
        return self.map.beat_pixels(beat)

    def select_pixel(self, x: int, y: int) -> int | None:
        """Select pixel ``(x, y)``; the beat field follows. Returns its beat (None: not carried)."""
        beat = self.map.pixel_beat(x, y)
        self._busy = True
        try:
            self.x.value, self.y.value = x, y
        finally:
            self._busy = False
        if beat is not None:
            self._busy = True
            try:
                self.beat.value = beat
            finally:
                self._busy = False
        self._render(pixel=(x, y))
        return beat

    def _on_beat(self, change: Any) -> None:
        if self._busy:
            return
        px = self.map.beat_pixels(self.beat.value) if len(self.map) else []
        if px:
            self._busy = True
            try:
                self.x.value, self.y.value = px[0]
            finally:
                self._busy = False
        self._render(pixel=px[0] if px else None)

    def _on_pixel(self, change: Any) -> None:
        if not self._busy:
            self.select_pixel(self.x.value, self.y.value)

    def _render(self, pixel: tuple[int, int] | None = None) -> None:
        m = self.map
        if not len(m):
            self.info.value = "no beats"
            return
        b = self.beat.value
        pix = pixel or (m.beat_pixels(b)[0] if m.beat_pixels(b) else None)
        text = esc(m.describe_beat(b))
        if pix is not None:
            carried = m.pixel_beat(*pix)
            text += (f"<br>pixel ({pix[0]}, {pix[1]}): bytes {m.pixel_bytes(*pix).hex(' ') or '(not carried)'}"
                     f"; first byte in beat {carried if carried is not None else '(stream ended)'}")
        self.info.value = f'<div style="font-family:monospace">{text}</div>'
        if self.picture is not None and pix is not None and self.frame_rgb is not None:
            step = -(-m.width // 320) if m.width > 320 else 1
            png, width = enlarged_png(self.frame_rgb[::step, ::step], step=step, max_width=320,
                                      box=(pix[0], pix[1], pix[0], pix[1]))
            self.picture.png, self.picture.display_width = png, width
        start = max(0, b - WAVE_BEATS // 2)
        self.wave.value = m.waveform_svg(start, WAVE_BEATS, selected=b)
        tstart = max(0, b - BEAT_PAGE_SIZE // 2)
        self.table.value = m.table_html(tstart, BEAT_PAGE_SIZE, selected=b)

    def to_html(self) -> str:
        """Static HTML form (see :meth:`BeatMap.to_html`)."""
        return self.map.to_html()
