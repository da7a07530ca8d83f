"""A clickable image widget: shows a picture sharp at any size and reports clicked pixels.

The browser gets PNG bytes (binary, no base64) and the size of the source image; a click is
converted there to source-image pixel coordinates and synced back as :attr:`ClickImage.clicked`.
Python code reacts through :meth:`ClickImage.on_click` (used by the image diff to zoom and by
the beat viewer to select a pixel's beat).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import anywidget
import traitlets

STATIC = Path(__file__).resolve().parent / "static"


class ClickImage(anywidget.AnyWidget):
    """An image whose clicks are reported in the source image's pixel coordinates.

    Attributes:
        png: PNG bytes of what is displayed (may be enlarged or shrunk from the source).
        src_width, src_height: size of the *source* image the coordinates refer to.
        display_width: width on screen in CSS pixels.
        caption: a line of text under the image.
        clicked: ``[x, y]`` of the last click (source pixels), ``[-1, -1]`` before any.
    """

    _esm = STATIC / "clickimage.js"
    png = traitlets.Bytes(b"").tag(sync=True)
    src_width = traitlets.Int(1).tag(sync=True)
    src_height = traitlets.Int(1).tag(sync=True)
    display_width = traitlets.Int(100).tag(sync=True)
    caption = traitlets.Unicode("").tag(sync=True)
    clicked = traitlets.List(traitlets.Int(), [-1, -1]).tag(sync=True)
    clicks = traitlets.Int(0).tag(sync=True)

    def on_click(self, callback: Callable[[int, int], Any]) -> None:
        """Call ``callback(x, y)`` (source pixels) on every click."""
        def handler(_change: Any) -> None:
            x, y = self.clicked
            if x >= 0 and y >= 0:
                callback(x, y)
        self.observe(handler, "clicks")

    def click(self, x: int, y: int) -> None:
        """Act as if ``(x, y)`` had been clicked (for tests and scripted demos)."""
        self.clicked = [int(x), int(y)]
        self.clicks += 1
