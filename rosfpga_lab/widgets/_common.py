"""Shared pieces of the notebook widgets: the error type, colours, HTML helpers (limits: ``limits``).

Everything here is plain Python (no front-end needed), so the widgets' logic can be tested in
pytest and their static HTML forms can be produced without a kernel.
"""

from __future__ import annotations

import base64
import html
from typing import Any

import numpy as np

from rosfpga_lab.errors import LabError
from rosfpga_lab.widgets.limits import (  # noqa: F401  (re-exported: widgets import them from here)
    BYTE_PAGE_SIZE,
    BYTE_PAGE_SIZE_MAX,
    BYTE_ROW_SIZE,
    FIELD_LIST_LIMIT,
    VALUE_TEXT_LIMIT,
    DIFF_POSITIONS_LIMIT,
    ZOOM_MAX,
    BEAT_PAGE_SIZE,
    WAVE_BEATS,
    LIVE_MAX_FPS,
    LIVE_RATE_WINDOW,
    DISPLAY_MAX_WIDTH,
)


class WidgetError(LabError):
    """Bad input to a notebook widget (wrong shape, overlapping fields, unknown field name)."""


#: Output priority for exporting executed notebooks to self-contained HTML that needs no widget
#: JavaScript (offline): static forms first. Pass as ``NbConvertBase.display_data_priority``.
STATIC_EXPORT_PRIORITY = ["text/html", "image/svg+xml", "image/png", "image/jpeg", "text/markdown",
                          "text/latex", "text/plain"]


def show_static(widget: Any) -> None:
    """Display ``widget.to_html()`` as plain HTML (a frozen copy that needs no kernel to render)."""
    from IPython.display import HTML, display

    display(HTML(widget.to_html()))


class StaticFallback:
    """Mixin for widgets: put ``self.to_html()`` in the output beside the live widget view.

    JupyterLab shows the live view; exported HTML, nbviewer and GitHub (which run no widget
    JavaScript) show the static HTML instead. Set ``static_fallback = False`` on an instance
    to leave it out.
    """

    static_fallback = True

    def to_html(self) -> str:  # pragma: no cover - every user defines it
        raise NotImplementedError

    def _repr_mimebundle_(self, **kwargs: Any) -> Any:
        bundle = super()._repr_mimebundle_(**kwargs)  # type: ignore[misc]
        if not self.static_fallback or bundle is None:
            return bundle
        data, meta = bundle if isinstance(bundle, tuple) else (bundle, {})
        return dict(data, **{"text/html": self.to_html()}), meta


# Pastel colours that keep black text readable; adjacent fields get different ones. None is
# reddish (every hue at least 60 degrees from the alignment red below), so a field beside CDR
# padding never looks like padding.
PALETTE = (
    "#fdffb6", "#caffbf", "#9bf6ff", "#bdb2ff", "#e4c1f9", "#eeffa8",
    "#b8e0d2", "#a0c4ff", "#d0f4de", "#cfbaf0", "#bde0fe", "#b9fbc0",
)
#: Fixed colours for bytes whose role matters more than which field they belong to.
ROLE_COLOURS = {
    "length": "#d9d9d9",   # length prefixes of strings, arrays, header fields, frames
    "padding": "#ffffff",
    "alignment": "#ff595e",  # CDR alignment padding (ROS 2): bytes a circuit must skip
    "error": "#ff8080",     # bytes that could not be decoded
    "trailing": "#eeeeee",  # bytes after the end of the message or header
}


def colour_for(index: int, role: str = "") -> str:
    """The background colour of field number ``index`` (role colours win)."""
    role = (role or "").lower()
    for key, colour in ROLE_COLOURS.items():
        if key in role:
            return colour
    return PALETTE[index % len(PALETTE)]


def esc(value: Any) -> str:
    """HTML-escape ``str(value)`` including quotes (safe inside attributes)."""
    return html.escape(str(value), quote=True)


def shorten(text: str, limit: int = VALUE_TEXT_LIMIT) -> str:
    """``text`` cut to ``limit`` characters with an ellipsis when longer."""
    return text if len(text) <= limit else text[: max(0, limit - 1)] + "\u2026"


def format_value(value: Any, limit: int = VALUE_TEXT_LIMIT) -> str:
    """A short, readable text for a decoded field value (arrays and bytes are summarised)."""
    if value is None:
        return ""
    if isinstance(value, (bytes, bytearray, memoryview)):
        raw = bytes(value)
        preview = " ".join(f"{b:02x}" for b in raw[:16])
        more = " \u2026" if len(raw) > 16 else ""
        return shorten(f"{len(raw)} bytes: {preview}{more}", limit)
    if isinstance(value, np.ndarray):
        flat = value.ravel()
        preview = " ".join(str(v) for v in flat[:12])
        more = " \u2026" if flat.size > 12 else ""
        return shorten(f"{value.dtype}{list(value.shape)}: {preview}{more}", limit)
    if isinstance(value, (list, tuple)) and len(value) > 12:
        head = ", ".join(repr(v) for v in value[:12])
        return shorten(f"[{head}, \u2026] ({len(value)} items)", limit)
    if isinstance(value, str):
        return shorten(repr(value), limit)
    return shorten(str(value), limit)


def hex_bytes(data: bytes, limit: int = 16) -> str:
    """``data`` as spaced hex, cut after ``limit`` bytes."""
    text = " ".join(f"{b:02x}" for b in data[:limit])
    return text + (" \u2026" if len(data) > limit else "")


def as_image(array: Any, name: str = "image") -> np.ndarray:
    """``array`` checked to be an image: HxW or HxWxC (C in 1, 3, 4), dtype uint8.

    Raises:
        WidgetError: when the shape or dtype is not an image's.
    """
    img = np.asarray(array)
    if img.dtype != np.uint8:
        raise WidgetError(f"{name}: expected dtype uint8, got {img.dtype} (convert with .astype(np.uint8))")
    if img.ndim == 3 and img.shape[2] in (1, 3, 4):
        return img
    if img.ndim == 2:
        return img
    raise WidgetError(f"{name}: expected shape HxW or HxWxC with C in 1, 3, 4, got {img.shape}")


def display_rgb(img: np.ndarray, channel_order: str = "rgb") -> np.ndarray:
    """An HxWx3 RGB view of ``img`` for display (alpha dropped, grey expanded, BGR swapped)."""
    if img.ndim == 2:
        img = img[:, :, None]
    if img.shape[2] == 1:
        return np.repeat(img, 3, axis=2)
    rgb = img[:, :, :3]
    if channel_order.lower().startswith("bgr"):
        rgb = rgb[:, :, ::-1]
    return np.ascontiguousarray(rgb)


def png_bytes(rgb: np.ndarray, scale: int = 1) -> bytes:
    """PNG bytes of an HxWx3 RGB uint8 image, enlarged ``scale`` times by nearest neighbour."""
    import cv2

    if scale > 1:
        rgb = np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1)
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(rgb[:, :, ::-1]))
    if not ok:  # pragma: no cover - cv2 only fails on impossible input
        raise WidgetError("could not encode image as PNG")
    return buf.tobytes()


def png_data_uri(rgb: np.ndarray, scale: int = 1) -> str:
    """A ``data:image/png;base64,...`` URI of ``rgb`` (for self-contained static HTML)."""
    return "data:image/png;base64," + base64.b64encode(png_bytes(rgb, scale)).decode("ascii")


def display_scale(width: int, max_width: int = DISPLAY_MAX_WIDTH) -> int:
    """Integer enlargement so small images are visible (never shrinks)."""
    if width <= 0:
        return 1
    return max(1, min(16, max_width // width))


def downscale(rgb: np.ndarray, max_width: int = DISPLAY_MAX_WIDTH) -> np.ndarray:
    """``rgb`` reduced by an integer step so it is at most ``max_width`` wide."""
    step = -(-rgb.shape[1] // max_width) if rgb.shape[1] > max_width else 1
    return rgb[::step, ::step] if step > 1 else rgb


def enlarged_png(rgb: np.ndarray, *, step: int = 1, max_width: int = DISPLAY_MAX_WIDTH,
                 box: tuple[int, int, int, int] | None = None) -> tuple[bytes, int]:
    """PNG of ``rgb`` (already shrunk by ``step``) enlarged for display, with an optional box.

    Args:
        rgb: HxWx3 display image.
        step: how much ``rgb`` was shrunk from the source (box coordinates are source pixels).
        max_width: enlargement stops below this width.
        box: inclusive ``(x0, y0, x1, y1)`` in source pixels, outlined in blue one pixel outside.

    Returns:
        ``(png bytes, displayed width)``.
    """
    scale = display_scale(rgb.shape[1], max_width)
    big = np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1) if scale > 1 else rgb.copy()
    if box is not None:
        h, w_ = big.shape[:2]
        x0, y0 = box[0] // step * scale - 1, box[1] // step * scale - 1
        x1, y1 = (box[2] // step + 1) * scale, (box[3] // step + 1) * scale
        xs, ys = slice(max(x0, 0), min(x1, w_ - 1) + 1), slice(max(y0, 0), min(y1, h - 1) + 1)
        for y in (y0, y1):
            if 0 <= y < h:
                big[y, xs] = (0, 0, 255)
        for x in (x0, x1):
            if 0 <= x < w_:
                big[ys, x] = (0, 0, 255)
    return png_bytes(big), int(big.shape[1])
