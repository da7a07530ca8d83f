"""Live view: frames as they arrive, with fps and latency, throttled so the browser keeps up.

How this works: :meth:`LiveView.update` may be called from any thread (a subscriber callback)
at any rate. It always records the frame's arrival (for the incoming fps) and latency, and
keeps only the newest frame. A :class:`Throttle` lets at most ``max_fps`` frames per second
through to the browser; a frame that arrives too early is not dropped at once but parked, and a
timer shows the newest parked frame when the next slot opens (so the last frame of a burst
always appears). Encoding happens outside the state lock; one lock serialises pushes.

Static form: the view's output carries HTML of the newest frame and the status line beside the
live widget. It is displayed with a display id, and :meth:`LiveView.close` replaces the output
with that HTML, so an exported or reopened notebook shows the last frame and the final figures
(not the widget's Python repr, nor a "model not found" box for a closed widget).
"""

from __future__ import annotations

import base64
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import ipywidgets as w
import numpy as np

from rosfpga_lab.graph.rate import RateMeter
from rosfpga_lab.widgets._common import (
    LIVE_MAX_FPS,
    LIVE_RATE_WINDOW,
    StaticFallback,
    WidgetError,
    as_image,
    display_rgb,
    display_scale,
    downscale,
    esc,
)


class Throttle:
    """Lets events through at most ``max_rate`` times per second (leading edge).

    Args:
        max_rate: events per second (> 0).
        clock: a monotonic clock in seconds (injectable for tests).
    """

    def __init__(self, max_rate: float, clock: Callable[[], float] = time.monotonic) -> None:
        if max_rate <= 0:
            raise WidgetError(f"max_rate must be positive, got {max_rate}")
        self.interval = 1.0 / max_rate
        self.clock = clock
        self._last: float | None = None

    def wait_time(self, now: float | None = None) -> float:
        """Seconds until the next event may pass (0 if now)."""
        now = self.clock() if now is None else now
        return 0.0 if self._last is None else max(0.0, self._last + self.interval - now)

    def ready(self, now: float | None = None) -> bool:
        """True (and the slot is taken) if an event may pass now."""
        now = self.clock() if now is None else now
        if self.wait_time(now) > 0:
            return False
        self._last = now
        return True


class LiveView(StaticFallback, w.VBox):
    """Shows the newest frame, incoming and shown fps, and latency; safe to update from any thread.

    Args:
        max_fps: most frames per second sent to the browser.
        max_width: frames wider than this are shrunk (by an integer step) before sending.
        channel_order: ``"rgb"`` or ``"bgr"`` for colour frames.
        image_format: ``"jpeg"`` (small, fast) or ``"png"`` (exact pixels).
        trailing: show the newest parked frame when the throttle reopens (needs a timer thread).
        title: a line above the pictures.
        stop: called (once) when the view's Stop button is pressed; no button without it.
        clock: monotonic clock (injectable for tests).

    Give :meth:`update` an ``input=`` picture too and the view shows input beside output.
    """

    def __init__(self, *, max_fps: float = LIVE_MAX_FPS, max_width: int = 480, channel_order: str = "rgb",
                 image_format: str = "jpeg", trailing: bool = True, title: str = "",
                 stop: Callable[[], Any] | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if image_format not in ("jpeg", "png"):
            raise WidgetError(f"image_format must be 'jpeg' or 'png', got {image_format!r}")
        self.throttle = Throttle(max_fps, clock)
        self.clock = clock
        self.max_width, self.channel_order, self.image_format, self.trailing = max_width, channel_order, image_format, trailing
        self.incoming = RateMeter(window_s=LIVE_RATE_WINDOW, clock=clock)
        self.shown_rate = RateMeter(window_s=LIVE_RATE_WINDOW, clock=clock)
        self.received = 0
        self.shown = 0
        self.latencies: deque[float] = deque(maxlen=50)
        self._lock = threading.Lock()
        self._push_lock = threading.Lock()
        self._pending: tuple[np.ndarray, np.ndarray | None] | None = None
        self._timer: threading.Timer | None = None
        self._closed = False
        self._handle: Any = None
        self.title = title
        self.image = w.Image(format=image_format, layout=w.Layout(max_width="100%"))
        self.input_image = w.Image(format=image_format, layout=w.Layout(max_width="100%"))
        self._input_box = w.VBox([w.HTML("<b>input</b>"), self.input_image],
                                 layout=w.Layout(display="none", margin="0 12px 0 0", max_width="100%"))
        self._output_caption = w.HTML("", layout=w.Layout(display="none"))
        pictures = w.HBox([self._input_box, w.VBox([self._output_caption, self.image],
                                                   layout=w.Layout(max_width="100%"))],
                          layout=w.Layout(flex_flow="row wrap", max_width="100%"))
        self.status = w.HTML("waiting for frames\u2026")
        self._stop = stop
        self.stop_button = w.Button(description="Stop", icon="stop", button_style="danger",
                                    layout=w.Layout(display="" if stop else "none", width="auto"))
        self.stop_button.on_click(lambda _b: self.press_stop())
        self.stopped = False
        super().__init__([w.HTML(f"<b>{esc(title)}</b>") if title else w.HTML(), pictures,
                          w.HBox([self.stop_button, self.status], layout=w.Layout(flex_flow="row wrap"))])

    def press_stop(self) -> None:
        """What the Stop button does: call ``stop`` once, then say so."""
        if self.stopped or self._stop is None:
            return
        self.stopped = True
        self.stop_button.disabled = True
        self.stop_button.description = "Stopped"
        self._stop()

    def update(self, frame: Any, *, latency: float | None = None, stamp: float | None = None,
               channel_order: str | None = None, input: Any = None) -> bool:
        """Offer a new frame (any thread). Returns True if it was pushed to the browser now.

        Args:
            frame: HxW or HxWxC uint8 image.
            latency: seconds from capture to now, if known.
            stamp: capture time as ``time.time()`` (e.g. the message's header stamp);
                latency is then ``time.time() - stamp``.
            channel_order: ``"rgb"``/``"bgr"`` for this frame (default: the view's).
            input: the picture the frame was made from, shown beside it.
        """
        img = as_image(frame, "frame")
        inp = None if input is None else as_image(input, "input")
        if channel_order is not None and channel_order != self.channel_order:
            def swap(a: np.ndarray) -> np.ndarray:
                return a[:, :, [2, 1, 0] + ([3] if a.shape[2] == 4 else [])] if a.ndim == 3 and a.shape[2] >= 3 else a
            img = swap(img)
            inp = None if inp is None else swap(inp)
        if latency is None and stamp is not None:
            latency = time.time() - stamp
        with self._lock:
            if self._closed:
                return False
            self.received += 1
            self.incoming.tick()
            if latency is not None:
                self.latencies.append(float(latency))
            if self.throttle.ready():
                self._pending = None
                go = True
            else:
                self._pending = (img, inp)
                go = False
                if self.trailing and self._timer is None:
                    self._timer = threading.Timer(self.throttle.wait_time() + 1e-3, self._fire)
                    self._timer.daemon = True
                    self._timer.start()
        if go:
            self._push(img, inp)
        return go

    def feed(self, frame: Any) -> bool:
        """Callback for ``rosfpga_lab.component.Viewer(on_frame=live.feed)``: shows a
        ``ViewedFrame`` (its ``image``, ``encoding`` and ``latency``). Returns as :meth:`update`."""
        image = getattr(frame, "image", None)
        if image is None:
            return False
        order = "bgr" if str(getattr(frame, "encoding", "")).startswith("bgr") else "rgb"
        return self.update(image, latency=getattr(frame, "latency", None), channel_order=order)

    def _fire(self) -> None:
        with self._lock:
            self._timer = None
            if self._closed or self._pending is None:
                return
            if not self.throttle.ready():  # a direct push took the slot; try again later
                self._timer = threading.Timer(self.throttle.wait_time() + 1e-3, self._fire)
                self._timer.daemon = True
                self._timer.start()
                return
            pair, self._pending = self._pending, None
        self._push(*pair)

    def flush(self) -> bool:
        """Show the parked frame now, ignoring the throttle. Returns True if there was one."""
        with self._lock:
            pair, self._pending = self._pending, None
        if pair is None:
            return False
        self._push(*pair)
        return True

    def _encode(self, img: np.ndarray) -> tuple[bytes, str]:
        import cv2

        rgb = downscale(display_rgb(img, self.channel_order), self.max_width)
        scale = display_scale(rgb.shape[1], self.max_width)
        if scale > 1:  # small frames: enlarge by whole pixels so they stay sharp
            rgb = np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1)
        ext = ".jpg" if self.image_format == "jpeg" else ".png"
        ok, buf = cv2.imencode(ext, np.ascontiguousarray(rgb[:, :, ::-1]))
        if not ok:  # pragma: no cover
            raise WidgetError("could not encode the frame")
        return buf.tobytes(), f"{rgb.shape[1]}px"

    def _push(self, img: np.ndarray, inp: np.ndarray | None = None) -> None:
        data, width = self._encode(img)
        inp_data, inp_width = self._encode(inp) if inp is not None else (b"", "")
        with self._push_lock:
            if self.image.layout.width != width:
                self.image.layout.width = width
            if inp is not None:
                if self._input_box.layout.display == "none":
                    self._input_box.layout.display = ""
                    self._output_caption.value = "<b>output</b>"
                    self._output_caption.layout.display = ""
                if self.input_image.layout.width != inp_width:
                    self.input_image.layout.width = inp_width
                self.input_image.value = inp_data
            with self._lock:
                self.shown += 1
                self.shown_rate.tick()
                text = self.status_text()
            self.image.value = data
            self.status.value = text

    def to_html(self) -> str:
        """Static HTML: the title, the newest frame shown (if any) and the status line."""
        head = f"<b>{esc(self.title)}</b>" if self.title else ""
        img = ""
        mime = "jpeg" if self.image_format == "jpeg" else "png"
        pictures = [(name, widget.value) for name, widget in (("input", self.input_image),
                                                              ("output", self.image)) if widget.value]
        if pictures:
            both = len(pictures) > 1
            img = '<div style="display:flex;flex-wrap:wrap;gap:12px">' + "".join(
                f'<figure style="margin:0;max-width:100%"><img style="max-width:100%" '
                f'src="data:image/{mime};base64,{base64.b64encode(raw).decode("ascii")}" alt="newest {name}"/>'
                + (f"<figcaption>{name}</figcaption>" if both else "") + "</figure>"
                for name, raw in pictures) + "</div>"
        status = self.status_text() if self.received else "waiting for frames\u2026"
        return f"<div>{head}{img}<div>{esc(status)}</div></div>"

    def _ipython_display_(self) -> None:
        from IPython.display import display

        data = self._repr_mimebundle_()
        data = data[0] if isinstance(data, tuple) else data
        self._handle = display(data, raw=True, display_id=True)

    @property
    def stats(self) -> dict[str, float]:
        """Counters: received, shown, skipped, fps_in, fps_shown, latency_last/mean (s, NaN if unknown)."""
        lat = list(self.latencies)
        return {
            "received": self.received, "shown": self.shown, "skipped": self.received - self.shown,
            "fps_in": self.incoming.rate(), "fps_shown": self.shown_rate.rate(),
            "latency_last": lat[-1] if lat else float("nan"),
            "latency_mean": sum(lat) / len(lat) if lat else float("nan"),
        }

    def status_text(self) -> str:
        """The status line shown under the frame."""
        s = self.stats
        lat = "" if s["latency_last"] != s["latency_last"] else (
            f"; latency {s['latency_last'] * 1000:.1f} ms (mean {s['latency_mean'] * 1000:.1f} ms)")
        return (f"{s['received']} frames received ({s['fps_in']:.1f} fps), {s['shown']} shown "
                f"({s['fps_shown']:.1f} fps, at most {1 / self.throttle.interval:g}){lat}")

    def close(self) -> None:
        """Stop the timer and close the widget (no more updates are shown)."""
        if not hasattr(self, "_lock"):  # constructor failed early; nothing to stop
            return
        with self._lock:
            self._closed = True
            timer, self._timer = self._timer, None
        if timer is not None:
            timer.cancel()
            timer.join(1.0)
        if self._handle is not None:  # freeze the output: the last frame and the final figures
            self._handle.update({"text/html": self.to_html(), "text/plain": self.status_text()},
                                raw=True)
            self._handle = None
        super().close()
