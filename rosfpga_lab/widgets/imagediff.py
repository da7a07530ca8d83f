"""Image diff: input, model output, reference output and where they differ, down to pixel values.

How this works: :class:`FrameDiff` compares a model's output with the reference (OpenCV) output
pixel by pixel; a pixel mismatches when any channel differs by more than ``tolerance``. It keeps
the exact count, the first ``DIFF_POSITIONS_LIMIT`` positions in row-major order, the bounding
box and the largest difference, and renders a difference view (reference dimmed to grey,
mismatches in red; when an image is shrunk for display a block is red if any pixel in it is).
:meth:`FrameDiff.zoom_html` tabulates the values of a small region of all three images.
:class:`ImageDiffViewer` shows one frame or a sequence with a slider, plus zoom controls.
Images are numpy arrays HxW or HxWxC (C = 1, 3, 4), uint8, channels in ``channel_order``.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from typing import Any

import ipywidgets as w
import numpy as np

from rosfpga_lab.widgets.clickimage import ClickImage
from rosfpga_lab.widgets._common import (
    DIFF_POSITIONS_LIMIT,
    DISPLAY_MAX_WIDTH,
    StaticFallback,
    ZOOM_MAX,
    WidgetError,
    as_image,
    display_rgb,
    display_scale,
    enlarged_png,
    esc,
    png_bytes,
    png_data_uri,
)

MISMATCH_RGB = (255, 0, 0)


#: A change (largest channel difference) this big or bigger is drawn full red in "input vs output".
CHANGE_FULL = 48


def _pool_max(values: np.ndarray, step: int) -> np.ndarray:
    """Shrink a 2-D array by ``step``, a block taking its largest value."""
    if step <= 1:
        return values
    h, w_ = values.shape
    ph, pw = -(-h // step) * step, -(-w_ // step) * step
    padded = np.zeros((ph, pw), values.dtype)
    padded[:h, :w_] = values
    return padded.reshape(ph // step, step, pw // step, step).max(axis=(1, 3))


def _pool_any(mask: np.ndarray, step: int) -> np.ndarray:
    """Shrink a boolean mask by ``step``, a block being True if any pixel in it is."""
    if step <= 1:
        return mask
    h, w_ = mask.shape
    ph, pw = -(-h // step) * step, -(-w_ // step) * step
    padded = np.zeros((ph, pw), bool)
    padded[:h, :w_] = mask
    return np.asarray(padded.reshape(ph // step, step, pw // step, step).any(axis=(1, 3)))


#: The two difference views: the model's output against the reference (is the circuit right?)
#: and the input against the output (what did the circuit change?).
DIFF_VS_REFERENCE = "output vs reference"
DIFF_VS_INPUT = "input vs output"
#: What each picture's caption says (the difference views need their key).
CAPTIONS = {DIFF_VS_REFERENCE: "output vs reference (grey: equal, red: differs)",
            DIFF_VS_INPUT: "input vs output (grey: unchanged, red: changed, the redder the more)"}


def caption(name: str, reference_name: str = "reference") -> str:
    """The caption under the picture called ``name`` (``reference_name`` replaces "reference")."""
    text = CAPTIONS.get(name, name)
    return text.replace("reference", reference_name) if reference_name != "reference" else text


def _mismatch_mask(a: np.ndarray, b: np.ndarray, tolerance: int) -> np.ndarray:
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return np.asarray((diff > tolerance) if diff.ndim == 2 else (diff > tolerance).any(axis=2))


class FrameDiff:
    """One frame's comparison of model output against reference.

    Args:
        output: the model's image.
        reference: the reference (e.g. ``cv2.dilate``) image, same shape.
        input: the input image (optional, shown beside them).
        tolerance: largest per-channel difference still counted as equal (0 = bit exact).
        channel_order: ``"rgb"`` or ``"bgr"`` (how to show colour images; 4th channel ignored).
        name: what this frame is (shown by the viewer, e.g. the fault that made it).
        reference_name: what the reference is, e.g. ``"what AXIvideo2Mat should have made"``.

    Attributes:
        mask: HxW bool, True where a pixel mismatches (output vs reference).
        changed: HxW bool, True where the output differs from the input (None without a
            same-sized input).
        count: number of mismatching pixels (exact).
        positions: up to ``DIFF_POSITIONS_LIMIT`` mismatching ``(x, y)``, row-major.
        bbox: ``(x0, y0, x1, y1)`` inclusive box around all mismatches, or None.
        max_abs: the largest channel difference.

    Raises:
        WidgetError: not images, or output and reference differ in shape.
    """

    def __init__(self, output: Any, reference: Any, input: Any = None, *, tolerance: int = 0,
                 channel_order: str = "rgb", name: str = "", reference_name: str = "reference") -> None:
        self.output = as_image(output, "output")
        self.reference = as_image(reference, "reference")
        self.input = None if input is None else as_image(input, "input")
        if self.output.shape != self.reference.shape:
            raise WidgetError(f"output shape {self.output.shape} differs from reference shape "
                              f"{self.reference.shape}; compare images of the same size and encoding")
        self.tolerance, self.channel_order = int(tolerance), channel_order
        self.name, self.reference_name = name, reference_name
        diff = np.abs(self.output.astype(np.int16) - self.reference.astype(np.int16))
        self.mask: np.ndarray = np.asarray(
            (diff > self.tolerance) if diff.ndim == 2 else (diff > self.tolerance).any(axis=2))
        self.change: np.ndarray | None = None   # per pixel, the largest channel change input -> output
        if self.input is not None and self.input.shape == self.output.shape:
            delta = np.abs(self.output.astype(np.int16) - self.input.astype(np.int16)).astype(np.uint8)
            self.change = delta if delta.ndim == 2 else delta.max(axis=2)
        self.changed = None if self.change is None else self.change > 0
        self.count = int(self.mask.sum())
        self.max_abs = int(diff.max()) if diff.size else 0
        ys, xs = np.nonzero(self.mask)
        self.positions: list[tuple[int, int]] = list(zip(xs[:DIFF_POSITIONS_LIMIT].tolist(),
                                                         ys[:DIFF_POSITIONS_LIMIT].tolist()))
        self.bbox = (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())) if self.count else None

    @classmethod
    def from_result(cls, result: Any, reference: Any, **kwargs: Any) -> FrameDiff:
        """Compare a ``rosfpga_lab.hw`` ``MessageResult``'s output image with ``reference``
        (its input image is shown too)."""
        return cls(result.output_image, reference, result.input_image, **kwargs)

    @property
    def height(self) -> int:
        return int(self.output.shape[0])

    @property
    def width(self) -> int:
        return int(self.output.shape[1])

    @property
    def equal(self) -> bool:
        """True when no pixel mismatches."""
        return self.count == 0

    def summary(self) -> str:
        """One line: equal, or how many pixels differ, where and by how much."""
        total = self.width * self.height
        if self.equal:
            return f"bit-exact: all {total} pixels equal" + (f" (tolerance {self.tolerance})" if self.tolerance else "")
        x0, y0, x1, y1 = self.bbox  # type: ignore[misc]
        first = ", ".join(f"({x}, {y})" for x, y in self.positions[:5])
        return (f"{self.count} of {total} pixels differ ({100 * self.count / total:.3g} %), in x {x0}..{x1}, "
                f"y {y0}..{y1}; largest channel difference {self.max_abs}; first at {first}")

    def next_mismatch(self, x: int, y: int) -> tuple[int, int] | None:
        """The first mismatching pixel after ``(x, y)`` in row-major order (wrapping), or None."""
        if not self.count:
            return None
        flat = np.flatnonzero(self.mask.ravel())
        i = int(np.searchsorted(flat, y * self.width + x, side="right")) % flat.size
        p = int(flat[i])
        return p % self.width, p // self.width

    def diff_rgb(self, max_width: int = DISPLAY_MAX_WIDTH, which: str = DIFF_VS_REFERENCE) -> np.ndarray:
        """A difference view at display size: the image in dim grey, differing pixels red.

        ``which`` is :data:`DIFF_VS_REFERENCE` (output against reference, red: wrong) or
        :data:`DIFF_VS_INPUT` (input against output, red: changed by the circuit).
        """
        step = -(-self.width // max_width) if self.width > max_width else 1
        base, mask = ((self.reference, self.mask) if which == DIFF_VS_REFERENCE else
                      (self.input, self.changed))
        if base is None or mask is None:
            raise WidgetError(f"no {which!r} view: it needs an input of the output's shape")
        ref = display_rgb(base, self.channel_order)[::step, ::step]
        grey = (ref.mean(axis=2) * 0.35 + 150).astype(np.uint8)
        out = np.repeat(grey[:, :, None], 3, axis=2)
        if which == DIFF_VS_INPUT and self.change is not None:
            # how much changed, not only whether: a change of CHANGE_FULL or more is full red
            h, w_ = out.shape[:2]
            amount = _pool_max(self.change, step)[:h, :w_].astype(np.float32)
            alpha = np.clip(amount / CHANGE_FULL, 0.0, 1.0)[:, :, None]
            alpha[amount > 0] = np.maximum(alpha[amount > 0], 0.15)   # any change stays visible
            out = (out * (1 - alpha) + np.array(MISMATCH_RGB, np.float32) * alpha).astype(np.uint8)
            return out
        out[_pool_any(mask, step)[: out.shape[0], : out.shape[1]]] = MISMATCH_RGB
        return out

    def diff_png(self, max_width: int = DISPLAY_MAX_WIDTH, box: tuple[int, int, int, int] | None = None,
                 which: str = DIFF_VS_REFERENCE) -> bytes:
        """PNG of a difference view as displayed (enlarged if small), ``box`` outlined in blue."""
        step = -(-self.width // max_width) if self.width > max_width else 1
        return enlarged_png(self.diff_rgb(max_width, which), step=step, max_width=max_width, box=box)[0]

    def views(self, max_width: int = DISPLAY_MAX_WIDTH) -> dict[str, np.ndarray]:
        """Display RGB images by name: ``input`` (if given), ``output``, ``reference``, then the
        difference views :data:`DIFF_VS_REFERENCE` and (with a same-sized input) :data:`DIFF_VS_INPUT`."""
        step = -(-self.width // max_width) if self.width > max_width else 1
        out = {}
        if self.input is not None:
            istep = -(-self.input.shape[1] // max_width) if self.input.shape[1] > max_width else 1
            out["input"] = display_rgb(self.input, self.channel_order)[::istep, ::istep]
        out["output"] = display_rgb(self.output, self.channel_order)[::step, ::step]
        out["reference"] = display_rgb(self.reference, self.channel_order)[::step, ::step]
        out[DIFF_VS_REFERENCE] = self.diff_rgb(max_width)
        if self.changed is not None:
            out[DIFF_VS_INPUT] = self.diff_rgb(max_width, DIFF_VS_INPUT)
        return out

    def start_point(self) -> tuple[int, int]:
        """Where a zoom starts: the first wrong pixel, else where the circuit changed the input
        most (the first such pixel), else (0, 0)."""
        if self.count:
            return self.positions[0]
        if self.change is not None and self.change.any():
            y, x = np.unravel_index(int(np.argmax(self.change)), self.change.shape)
            return int(x), int(y)
        return 0, 0

    def region(self, x: int, y: int, size: int = 8) -> tuple[int, int, int, int]:
        """The inclusive box ``(x0, y0, x1, y1)`` of a ``size`` square around ``(x, y)``, inside the image."""
        size = max(1, min(int(size), ZOOM_MAX, self.width, self.height))
        x0 = min(max(0, x - size // 2), self.width - size)
        y0 = min(max(0, y - size // 2), self.height - size)
        return x0, y0, x0 + size - 1, y0 + size - 1

    def zoom_html(self, x: int, y: int, size: int = 8) -> str:
        """Tables of pixel values around ``(x, y)`` for output, reference (and input); mismatches red."""
        if not (0 <= x < self.width and 0 <= y < self.height):
            raise WidgetError(f"pixel ({x}, {y}) is outside the {self.width}x{self.height} image")
        x0, y0, x1, y1 = self.region(x, y, size)
        tables = []
        named = [("output", self.output), (self.reference_name, self.reference)]
        if self.input is not None and self.input.shape[:2] == self.output.shape[:2]:
            named.insert(0, ("input", self.input))
        for name, img in named:
            rows = [f'<table style="border-collapse:collapse;font-family:monospace;font-size:10px">'
                    f'<caption>{name} x {x0}..{x1}, y {y0}..{y1}</caption><tr><th>y\\x</th>'
                    + "".join(f"<th>{xx}</th>" for xx in range(x0, x1 + 1)) + "</tr>"]
            for yy in range(y0, y1 + 1):
                cells = []
                for xx in range(x0, x1 + 1):
                    v = img[yy, xx]
                    text = ",".join(str(int(c)) for c in np.atleast_1d(v))
                    bg = "#ff9e9e" if self.mask[yy, xx] and img is not self.input else ""
                    mark = ";outline:2px solid #00f" if (xx, yy) == (x, y) else ""
                    cells.append(f'<td style="border:1px solid #ccc;padding:1px 3px;background:{bg}{mark}">{text}</td>')
                rows.append(f"<tr><th>{yy}</th>{''.join(cells)}</tr>")
            rows.append("</table>")
            tables.append("".join(rows))
        return '<div style="display:flex;gap:12px;flex-wrap:wrap">' + "".join(tables) + "</div>"

    def to_html(self, max_width: int = 320) -> str:
        """Self-contained HTML: the images (wrapping to the page's width), the summary,
        positions and a folded zoom."""
        imgs = []
        for name, rgb in self.views(max_width).items():
            scale = display_scale(rgb.shape[1], max_width)
            imgs.append(f'<figure style="margin:4px;max-width:100%"><img src="{png_data_uri(rgb, scale)}" '
                        f'style="image-rendering:pixelated;max-width:100%" alt="{esc(name)}"/>'
                        f'<figcaption>{esc(caption(name, self.reference_name))}</figcaption></figure>')
        title = f"<div><b>{esc(self.name)}</b></div>" if self.name else ""
        parts = [title + '<div style="display:flex;flex-wrap:wrap">' + "".join(imgs) + "</div>",
                 f"<div><b>{esc(self.summary())}</b></div>"]
        if not self.equal:
            shown = ", ".join(f"({x}, {y})" for x, y in self.positions[:50])
            more = f" \u2026 ({self.count - 50} more)" if self.count > 50 else ""
            parts.append(f"<div>mismatching pixels (x, y): {shown}{more}</div>")
            parts.append(f"<details><summary>pixel values around ({self.positions[0][0]}, "
                         f"{self.positions[0][1]})</summary>{self.zoom_html(*self.positions[0])}</details>")
        return "<div>" + "".join(parts) + "</div>"

    def _repr_html_(self) -> str:
        return self.to_html()


def _as_frames(frames: Iterable[Any], tolerance: int, channel_order: str) -> list[FrameDiff]:
    out = []
    for i, f in enumerate(frames):
        if isinstance(f, FrameDiff):
            out.append(f)
        elif isinstance(f, dict):
            out.append(FrameDiff(f["output"], f["reference"], f.get("input"), tolerance=tolerance,
                                 channel_order=channel_order, name=f.get("name", ""),
                                 reference_name=f.get("reference_name", "reference")))
        elif isinstance(f, (tuple, list)) and len(f) in (2, 3):
            inp, outp, ref = (None, *f) if len(f) == 2 else f
            out.append(FrameDiff(outp, ref, inp, tolerance=tolerance, channel_order=channel_order))
        else:
            raise WidgetError(f"frame {i}: expected FrameDiff, dict or (input, output, reference), got {type(f).__name__}")
    if not out:
        raise WidgetError("no frames to show")
    return out


class ImageDiffViewer(StaticFallback, w.VBox):
    """Input, model output, reference and difference for one frame or a sequence (slider).

    Args:
        output, reference, input: one frame's images; or leave them out and pass ``frames``.
        frames: a sequence of :class:`FrameDiff`, dicts with ``input``/``output``/``reference``
            keys (and optionally ``name``, ``reference_name``), or ``(input, output, reference)``
            (or ``(output, reference)``) tuples. A frame's ``name`` is shown beside the slider.
        tolerance, channel_order: as :class:`FrameDiff`.
        max_width: largest display width of each image.

    Its output carries a static form (:meth:`to_html`) for views without a kernel.
    """

    def __init__(self, output: Any = None, reference: Any = None, input: Any = None, *,
                 frames: Sequence[Any] | None = None, tolerance: int = 0, channel_order: str = "rgb",
                 max_width: int = 320) -> None:
        if frames is None:
            if output is None or reference is None:
                raise WidgetError("give output= and reference= (and optionally input=), or frames=")
            frames = [FrameDiff(output, reference, input, tolerance=tolerance, channel_order=channel_order)]
        self.frames = _as_frames(frames, tolerance, channel_order)
        self.max_width = max_width
        many = len(self.frames) > 1
        self.frame = w.IntSlider(0, min=0, max=len(self.frames) - 1, description="frame", readout=False,
                                 layout=w.Layout(display="" if many else "none"))
        self.frame_name = w.HTML(layout=w.Layout(display="" if many or self.frames[0].name else "none"))
        self.images: dict[str, ClickImage] = {}
        # pictures wrap onto further rows rather than widen the notebook
        self.image_box = w.HBox(layout=w.Layout(flex_flow="row wrap", width="100%"))
        self.summary = w.HTML()
        self.x = w.BoundedIntText(0, min=0, max=10**6, description="zoom x", layout=w.Layout(width="160px"))
        self.y = w.BoundedIntText(0, min=0, max=10**6, description="zoom y", layout=w.Layout(width="160px"))
        self.size = w.BoundedIntText(8, min=1, max=ZOOM_MAX, description="size", layout=w.Layout(width="140px"))
        self.next_button = w.Button(description="next mismatch")
        self.zoom = w.HTML()
        # the value tables are tall: folded until asked for
        self.zoom_fold = w.Accordion(children=[w.VBox([w.HBox([self.x, self.y, self.size, self.next_button],
                                                               layout=w.Layout(flex_flow="row wrap")),
                                                        self.zoom])],
                                     titles=("pixel values (zoom)",), selected_index=None)
        self.frame.observe(lambda _c: self._show_frame(), "value")
        for c in (self.x, self.y, self.size):
            c.observe(lambda _c: self._show_zoom(), "value")
        self.next_button.on_click(lambda _b: self.next_mismatch())
        super().__init__([w.HBox([self.frame, self.frame_name], layout=w.Layout(flex_flow="row wrap")),
                          self.image_box, self.summary, self.zoom_fold])
        self._show_frame()

    @property
    def current(self) -> FrameDiff:
        """The frame on screen."""
        return self.frames[self.frame.value]

    def show(self, index: int) -> FrameDiff:
        """Show frame ``index``."""
        if not 0 <= index < len(self.frames):
            raise WidgetError(f"frame {index} does not exist; frames are 0..{len(self.frames) - 1}")
        self.frame.value = index
        return self.current

    def zoom_to(self, x: int, y: int, size: int | None = None) -> None:
        """Zoom onto ``(x, y)``."""
        f = self.current
        if not (0 <= x < f.width and 0 <= y < f.height):
            raise WidgetError(f"pixel ({x}, {y}) is outside the {f.width}x{f.height} image")
        with self.hold_trait_notifications():
            self.x.value, self.y.value = x, y
            if size is not None:
                self.size.value = size
        self._show_zoom()

    def next_mismatch(self) -> tuple[int, int] | None:
        """Zoom onto the next mismatching pixel after the current zoom point; returns it."""
        p = self.current.next_mismatch(self.x.value, self.y.value)
        if p is not None:
            self.zoom_to(*p)
        return p

    def _show_frame(self) -> None:
        f = self.current
        self.x.max, self.y.max = f.width - 1, f.height - 1
        boxes = []
        for name, rgb in f.views(self.max_width).items():
            scale = display_scale(rgb.shape[1], self.max_width)
            img = self.images.get(name)
            if img is None:
                img = self.images[name] = ClickImage()
                img.on_click(functools.partial(self._clicked, name))
            img.caption = caption(name, f.reference_name)
            src = f.input if name == "input" and f.input is not None else f.output
            img.src_height, img.src_width = int(src.shape[0]), int(src.shape[1])
            img.display_width = rgb.shape[1] * scale
            img.png = png_bytes(rgb, scale)
            boxes.append(img)
        self.image_box.children = boxes
        k = self.frame.value
        self.frame_name.value = (f"{k + 1} of {len(self.frames)}" if len(self.frames) > 1 else "") + (
            f": <b>{esc(f.name)}</b>" if f.name and len(self.frames) > 1 else f"<b>{esc(f.name)}</b>")
        self.summary.value = f"<b>{esc(f.summary())}</b> (click an image to zoom there)"
        self.zoom_to(*f.start_point())

    def _clicked(self, name: str, x: int, y: int) -> None:
        f = self.current
        self.zoom_to(min(x, f.width - 1), min(y, f.height - 1))

    def _show_zoom(self) -> None:
        f = self.current
        x, y = min(self.x.value, f.width - 1), min(self.y.value, f.height - 1)
        self.zoom.value = f.zoom_html(x, y, self.size.value)
        box = f.region(x, y, self.size.value)
        self.zoom_fold.set_title(0, f"pixel values around ({x}, {y})")
        for which in (DIFF_VS_REFERENCE, DIFF_VS_INPUT):
            if which in self.images and (which == DIFF_VS_REFERENCE or f.changed is not None):
                self.images[which].png = f.diff_png(self.max_width, box=box, which=which)

    def to_html(self, all_frames: bool = False) -> str:
        """Static HTML: the frame on screen in full (:meth:`FrameDiff.to_html`) and, for a
        sequence, one summary line per frame (``all_frames=True`` renders every frame in full,
        which for long sequences makes a large page)."""
        k = self.frame.value
        if len(self.frames) == 1:
            return self.current.to_html(self.max_width)
        rows = "".join(f"<tr><td>{i + 1}</td><td>{esc(f.name)}</td><td>{esc(f.summary())}</td></tr>"
                       for i, f in enumerate(self.frames))
        table = (f'<table style="font-size:12px"><tr><th>frame</th><th>name</th><th>result</th></tr>'
                 f"{rows}</table>")
        shown = range(len(self.frames)) if all_frames else [k]
        body = "".join(f"<h4>frame {i + 1} of {len(self.frames)}</h4>" + self.frames[i].to_html(self.max_width)
                       for i in shown)
        return f"<div>{table}{body}</div>"
