"""Progress for long work (the reference model on a large image, a C simulation).

In a Jupyter kernel it shows an ipywidgets progress bar (its output also carries the progress
line as text, updated once at the end, so an exported notebook shows the final state rather
than the bar's Python repr); anywhere else it writes text to a
stream (stderr by default): one updating line on a terminal, or a line per 10 % otherwise (so
CI logs stay short). Updates are throttled to ``min_interval`` seconds, so calling it once per
pixel is cheap. Use it as a context manager, a callback ``progress(done, total)``, a step
callback ``progress("compiling the testbench")`` (what ``rosfpga_lab.hls`` and
``rosfpga_lab.component`` accept as ``progress=``), or wrap an iterable with :func:`track`.
"""

from __future__ import annotations

import html
import sys
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TextIO, TypeVar

from rosfpga_lab.widgets._common import WidgetError

T = TypeVar("T")


def in_notebook() -> bool:
    """True when running inside a Jupyter kernel (where widgets can be displayed)."""
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover
        return False
    ip = get_ipython()
    return ip is not None and "IPKernelApp" in getattr(ip, "config", {})


class Progress:
    """A progress display that works in a notebook and in a terminal.

    Args:
        total: units of work (None: unknown; shows a count only).
        desc: what is being done.
        unit: unit name shown after counts (e.g. ``"rows"``).
        mode: ``"auto"`` (widget in a kernel, else text), ``"widget"``, ``"text"`` or ``"off"``.
        file: text stream for text mode (default ``sys.stderr``).
        min_interval: least seconds between display updates.
        clock: monotonic clock (injectable for tests).
    """

    def __init__(self, total: int | None = None, desc: str = "", *, unit: str = "", mode: str = "auto",
                 file: TextIO | None = None, min_interval: float = 0.1,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if mode not in ("auto", "widget", "text", "off"):
            raise WidgetError(f"mode must be auto, widget, text or off, got {mode!r}")
        if total is not None and total < 0:
            raise WidgetError(f"total must be >= 0, got {total}")
        self.total, self.desc, self.unit = total, desc, unit
        self.mode = ("widget" if in_notebook() else "text") if mode == "auto" else mode
        self.file = file if file is not None else sys.stderr
        self.min_interval, self.clock = min_interval, clock
        self.done = 0
        self.start = clock()
        self._last_shown = -1e18
        self._last_decile = -1
        self._last_written = -1
        self.note = ""
        self.closed = False
        self.widget: Any = None
        self._handle: Any = None
        if self.mode == "widget":
            import ipywidgets as w
            from IPython.display import display

            # the bar draws the fraction, the label says the rest in words (no second, ASCII
            # bar; the description is in the label, where it is never cut short); with no
            # total there is no fraction to draw, so no bar
            self._bar = w.IntProgress(value=0, min=0, max=max(1, total or 1),
                                      layout=w.Layout(display="" if total else "none"))
            self._label = w.Label("", layout=w.Layout(width="auto"))
            self.widget = w.HBox([self._bar, self._label], layout=w.Layout(flex_flow="row wrap"))
            self._handle = display(self.mimebundle(), raw=True, display_id=True)

    def mimebundle(self) -> dict[str, str]:
        """The widget's output: its live view plus the progress line as text and HTML."""
        data = self.widget._repr_mimebundle_()
        data = dict(data[0] if isinstance(data, tuple) else data)
        line = self.text()
        data["text/plain"] = line
        data["text/html"] = f"<pre>{html.escape(line)}</pre>"
        return data

    # --- feeding ------------------------------------------------------------------------------
    def update(self, n: int = 1) -> None:
        """Add ``n`` units of finished work."""
        self.set(self.done + n)

    def set(self, done: int, total: int | None = None) -> None:
        """Say ``done`` units are finished (and, optionally, a new total)."""
        if total is not None:
            self.total = total
        self.done = done
        now = self.clock()
        if now - self._last_shown >= self.min_interval:
            self._show(now)

    def __call__(self, done: int | str, total: int | None = None) -> None:
        """Callback form: ``progress(done, total)``, or ``progress("message")`` for a step."""
        if isinstance(done, str):
            self.step(done)
        else:
            self.set(done, total)

    def step(self, message: str) -> None:
        """One step of work done, described by ``message`` (always shown, not throttled)."""
        self.note = message
        self.done += 1
        self._show(self.clock(), note=True)

    def close(self) -> None:
        """Show the final state (once)."""
        if self.closed:
            return
        self.closed = True
        self._show(self.clock(), final=True)

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # --- display ------------------------------------------------------------------------------
    def text(self, now: float | None = None, *, bar: bool = True) -> str:
        """The progress line, e.g. ``dilate [#########           ]  45% 450/1000 rows  1.2 s, 0.8 s left``
        (``bar=False``: without the ASCII bar, for beside a drawn one)."""
        now = self.clock() if now is None else now
        elapsed = now - self.start
        unit = f" {self.unit}" if self.unit else ""
        note = f" \u2013 {self.note}" if self.note else ""
        if self.total:
            frac = min(1.0, self.done / self.total)
            hashes = "#" * int(frac * 20)
            drawn = f" [{hashes:<20}]" if bar else ""
            left = f", {elapsed * (1 - frac) / frac:.1f} s left" if 0 < frac < 1 else ""
            return f"{self.desc}{drawn} {frac * 100:3.0f}% {self.done}/{self.total}{unit}  {elapsed:.1f} s{left}{note}".strip()
        count = f" {self.done}{unit}" if self.done else ""   # no total, nothing counted: no "0"
        state = "" if self.done or self.note else (" done in" if self.closed else " running,")
        return f"{self.desc}{count}{state}  {elapsed:.1f} s{note}".strip()

    def _show(self, now: float, final: bool = False, note: bool = False) -> None:
        self._last_shown = now
        if self.mode == "off":
            return
        line = self.text(now)
        if self.mode == "widget":
            self._bar.max = max(1, self.total or max(self.done, 1))
            self._bar.value = min(self.done, self._bar.max)
            self._bar.layout.display = "" if self.total else "none"
            self._label.value = self.text(now, bar=False)
            if final:
                self._bar.bar_style = "success"
                if self._handle is not None:
                    self._handle.update(self.mimebundle(), raw=True)
            return
        if self.file.isatty() if hasattr(self.file, "isatty") else False:
            self.file.write("\r" + line + ("\n" if final or note else ""))
            self.file.flush()
            return
        decile = int(10 * self.done / self.total) if self.total else -1
        if note or (final and self.done != self._last_written) or decile > self._last_decile:
            self._last_written = self.done
            self._last_decile = decile
            self.file.write(line + "\n")
            self.file.flush()


def track(iterable: Iterable[T], total: int | None = None, desc: str = "", **kwargs: Any) -> Iterator[T]:
    """Iterate ``iterable`` while showing progress (``total`` defaults to ``len(iterable)``)."""
    if total is None and hasattr(iterable, "__len__"):
        total = len(iterable)  # type: ignore[arg-type]
    with Progress(total, desc, **kwargs) as bar:
        for item in iterable:
            yield item
            bar.update()
