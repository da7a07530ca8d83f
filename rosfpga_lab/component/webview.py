"""A live page for an audience: ``rosfpga-lab demo --view``.

How this works: :class:`DemoPage` runs a small HTTP server on ``127.0.0.1`` (a free port by
default) in a background thread. The component hands it every frame (:meth:`DemoPage.offer`,
cheap: it only keeps references to the newest input and output pictures); the pictures are
encoded as JPEG only when the page asks for them. The page itself is one self-contained HTML
document (no script or style from anywhere else) that refreshes the two pictures and the
counters a few times a second. Only ``GET`` of four fixed paths is served; anything else gets
404, and the server stops with :meth:`DemoPage.stop` (the demo calls it when it ends).
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import cv2
import numpy as np

from rosfpga_lab.component.limits import PAGE_IMAGE_MAX_WIDTH
from rosfpga_lab.component.sources import to_rgb

#: How often the page asks for new pictures and counters (milliseconds).
REFRESH_MS = 250
#: JPEG quality of the pictures.
JPEG_QUALITY = 85

PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
 body {{ font-family: sans-serif; margin: 16px; background: #fafafa; color: #222; }}
 h1 {{ font-size: 20px; margin: 0 0 8px; }}
 .pics {{ display: flex; flex-wrap: wrap; gap: 16px; }}
 figure {{ margin: 0; max-width: 100%; }}
 figure img {{ max-width: 100%; width: min(46vw, {width}px); image-rendering: pixelated; background: #ddd; }}
 figcaption {{ font-weight: bold; margin: 4px 0; }}
 table {{ border-collapse: collapse; margin-top: 12px; font-size: 18px; }}
 td {{ padding: 3px 14px 3px 0; }} td.n {{ font-weight: bold; text-align: right; }}
</style></head>
<body><h1>{title}</h1>
<div class="pics">
 <figure><figcaption>input (camera)</figcaption><img id="input" alt="input"></figure>
 <figure><figcaption>output (FPGA component)</figcaption><img id="output" alt="output"></figure>
</div>
<table id="counters"></table>
<script>
const rows = {labels};
async function tick() {{
  try {{
    const s = await (await fetch("stats.json", {{cache: "no-store"}})).json();
    document.getElementById("counters").innerHTML = rows.map(
      ([k, label]) => `<tr><td>${{label}}</td><td class="n" id="${{k}}">${{s[k]}}</td></tr>`).join("");
    if (s.frame !== window.lastFrame) {{
      window.lastFrame = s.frame;
      for (const id of ["input", "output"]) document.getElementById(id).src = `frame/${{id}}.jpg?n=${{s.frame}}`;
    }}
  }} catch (e) {{ document.title = "stopped"; }}
}}
tick(); setInterval(tick, {refresh});
</script></body></html>
"""

#: The counters on the page, in order: key in the stats dict -> label.
COUNTER_LABELS = (("sent", "frames sent by the camera"), ("processed", "frames through the circuit"),
                  ("received", "frames back at the checker"), ("bit_exact", "bit-exact vs OpenCV"),
                  ("refused", "refused"), ("fps", "frames per second"), ("latency_ms", "latency (median)"))


class DemoPage:
    """The page's server. Use as a context manager, or :meth:`start` / :meth:`stop`.

    Args:
        counters: returns the counters shown (keys of :data:`COUNTER_LABELS`), called per request.
        encoding: the pictures' ROS encoding (``rgba8``, ``bgr8``, ``mono8`` ...).
        title: the page's heading.
        host, port: where to listen (default: loopback, a free port).
    """

    def __init__(self, counters: Callable[[], dict[str, Any]], *, encoding: str = "rgb8",
                 title: str = "ROS-compliant FPGA component, live", host: str = "127.0.0.1",
                 port: int = 0) -> None:
        self.counters, self.encoding, self.title = counters, encoding, title
        self._lock = threading.Lock()
        self._newest: tuple[np.ndarray, np.ndarray] | None = None
        self.frame = 0
        page = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - the http.server name
                page._serve(self)

            def log_message(self, *_args: Any) -> None:  # quiet: the demo prints its own lines
                pass

        self._server = ThreadingHTTPServer((host, port), Handler)
        self._server.daemon_threads = True
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address, e.g. ``http://127.0.0.1:43123/``."""
        host, port = self._server.server_address[:2]
        return f"http://{host.decode() if isinstance(host, bytes) else host}:{port}/"

    def start(self) -> DemoPage:
        """Serve in a background thread."""
        self._thread = threading.Thread(target=self._server.serve_forever, name="demo-page", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close the socket (idempotent)."""
        if self._thread is not None:
            self._server.shutdown()
            self._thread.join(5)
            self._thread = None
        self._server.server_close()

    def __enter__(self) -> DemoPage:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def offer(self, input_image: np.ndarray, output_image: np.ndarray) -> None:
        """The newest input and output pictures (any thread; only references are kept)."""
        with self._lock:
            self._newest = (input_image, output_image)
            self.frame += 1

    def observe(self, record: Any) -> None:
        """A ``FpgaComponent.add_observer`` callback: offer each processed frame's pictures."""
        result = getattr(record, "result", None)
        if result is not None:
            self.offer(result.input_image, result.output_image)

    def jpeg(self, which: str) -> bytes | None:
        """The newest ``input`` or ``output`` picture as JPEG, or None before the first frame."""
        with self._lock:
            newest = self._newest
        if newest is None:
            return None
        rgb = to_rgb(newest[0 if which == "input" else 1], self.encoding)
        if rgb.shape[1] > PAGE_IMAGE_MAX_WIDTH:
            step = -(-rgb.shape[1] // PAGE_IMAGE_MAX_WIDTH)
            rgb = rgb[::step, ::step]
        ok, buf = cv2.imencode(".jpg", np.ascontiguousarray(rgb[:, :, ::-1]),
                               [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        return buf.tobytes() if ok else None

    def html(self) -> str:
        """The page."""
        return PAGE.format(title=self.title, labels=json.dumps([list(x) for x in COUNTER_LABELS]),
                           refresh=REFRESH_MS, width=PAGE_IMAGE_MAX_WIDTH)

    def _serve(self, req: BaseHTTPRequestHandler) -> None:
        path = req.path.split("?", 1)[0]
        body: bytes | None
        if path in ("/", "/index.html"):
            body, kind = self.html().encode(), "text/html; charset=utf-8"
        elif path == "/stats.json":
            stats = dict(self.counters())
            stats["frame"] = self.frame
            body, kind = json.dumps(stats).encode(), "application/json"
        elif path in ("/frame/input.jpg", "/frame/output.jpg"):
            body, kind = self.jpeg(path[7:-4]), "image/jpeg"
        else:
            body, kind = None, ""
        if body is None:
            req.send_error(404, "no such page (or no frame yet)")
            return
        req.send_response(200)
        req.send_header("Content-Type", kind)
        req.send_header("Content-Length", str(len(body)))
        req.send_header("Cache-Control", "no-store")
        req.end_headers()
        req.wfile.write(body)
