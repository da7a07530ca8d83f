"""Widget timings on full-size data: ``python -m rosfpga_lab.widgets.bench``.

Prints how long the Python side of each widget takes on a 640x480 rgba8 frame (1,228,800
pixel bytes): building a byte viewer and turning a page, diffing model against reference,
mapping 307,200 AXI4-Stream beats, and the live view's encode + push. These bound how
responsive the notebooks feel; they are figures to read, not pass/fail tests.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def _best(fn: Callable[[], object], repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    import cv2

    from rosfpga_lab import msg
    from rosfpga_lab.widgets import BeatMap, ByteViewer, FrameDiff, LiveView, message_spans

    h, w = 480, 640
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
    reg = msg.default_registry()
    body = msg.serialize(reg, "sensor_msgs/Image", {
        "header": {"seq": 1, "stamp": {"secs": 1, "nsecs": 2}, "frame_id": "camera"},
        "height": h, "width": w, "encoding": "rgba8", "is_bigendian": 0, "step": 4 * w, "data": img.tobytes()})
    spans = message_spans("sensor_msgs/Image", body, registry=reg)
    viewer = ByteViewer(body, spans)
    ref = cv2.dilate(img, np.ones((3, 3), np.uint8))
    out = ref.copy()
    out[100:110, 200] = 0
    tdata = img.reshape(-1, 4).view("<u4").ravel()
    tlast = (np.arange(h * w) % w) == w - 1
    live = LiveView(trailing=False, max_fps=1e6)

    rows = [
        ("message_spans (field_layout) of a 1.2 MB Image", _best(lambda: message_spans("sensor_msgs/Image", body, registry=reg))),
        ("ByteViewer(...) build", _best(lambda: ByteViewer(body, spans))),
        ("ByteViewer page turn", _best(lambda: setattr(viewer, "page", (viewer.page + 1) % viewer.n_pages))),
        ("ByteMap.to_html (one page, static)", _best(lambda: viewer.bytemap.to_html(100))),
        ("FrameDiff 640x480x4", _best(lambda: FrameDiff(out, ref, img))),
        ("FrameDiff.to_html (4 PNGs)", _best(lambda: FrameDiff(out, ref, img).to_html())),
        ("BeatMap of 307,200 beats + marker check", _best(lambda: BeatMap(tdata=tdata, tkeep=0b1111, tuser=np.arange(h * w) == 0, tlast=tlast, width=w, height=h, bytes_per_pixel=4).marker_mismatches())),
        ("LiveView.update (JPEG encode + push)", _best(lambda: live.update(img))),
    ]
    live.close()
    print(f"{'step':<48}{'ms':>10}")
    for name, secs in rows:
        print(f"{name:<48}{secs * 1e3:>10.2f}")


if __name__ == "__main__":
    main()
