"""Live view throttling and statistics, thread safety, and the progress helper."""

from __future__ import annotations

import io
import threading
import time

import numpy as np
import pytest

from rosfpga_lab.widgets import LiveView, Progress, RateMeter, Throttle, WidgetError, track


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_throttle_lets_through_at_most_the_rate() -> None:
    clock = FakeClock()
    t = Throttle(4.0, clock)  # one per 0.25 s
    passed = []
    for k in range(100):  # 10 s of offers every 0.1 s ... compressed: 100 offers over 9.9 s
        clock.now = k * 0.1
        if t.ready():
            passed.append(round(clock.now, 2))
    assert passed[:5] == [0.0, 0.3, 0.6, 0.9, 1.2]  # the first offer after each 0.25 s gap
    assert len(passed) == 34  # 0.0, 0.3, ..., 9.9
    clock.now = 9.95
    assert t.wait_time() == pytest.approx(0.2) and not t.ready()
    clock.now = 20.0
    assert t.wait_time() == 0.0 and t.ready() and t.wait_time() == pytest.approx(0.25)
    with pytest.raises(WidgetError, match="positive"):
        Throttle(0)


def test_rate_meter_over_a_window() -> None:
    clock = FakeClock()
    m = RateMeter(window_s=1.0, clock=clock)
    assert m.rate() == 0.0
    for k in range(31):  # 30 intervals of 1/30 s
        clock.now = k / 30
        m.tick()
    assert m.rate() == pytest.approx(30.0)
    clock.now = 5.0
    assert m.rate() == 0.0  # everything fell out of the window


def test_live_view_counts_and_throttles_with_a_fake_clock() -> None:
    clock = FakeClock()
    v = LiveView(max_fps=8, trailing=False, clock=clock)
    frame = np.zeros((4, 6, 3), np.uint8)
    shown = []
    for k in range(128):  # 128 frames at 128 fps for 1 s (binary fractions: exact times)
        clock.now = k / 128
        shown.append(v.update(frame, latency=0.002 * (k % 5)))
    assert [k for k, s in enumerate(shown) if s] == [0, 16, 32, 48, 64, 80, 96, 112]
    s = v.stats
    assert (s["received"], s["shown"], s["skipped"]) == (128, 8, 120)
    assert s["fps_in"] == pytest.approx(128.0) and s["fps_shown"] == pytest.approx(8.0)
    # the last 50 latencies: k = 78..127, (k % 5) * 2 ms; k=127 -> 4 ms
    assert s["latency_last"] == pytest.approx(0.004)
    assert s["latency_mean"] == pytest.approx(sum(0.002 * (k % 5) for k in range(78, 128)) / 50)
    assert "128 frames received (128.0 fps), 8 shown (8.0 fps, at most 8)" in v.status_text()
    assert bytes(v.image.value)[:2] == b"\xff\xd8"  # a JPEG reached the image widget
    assert v.flush()  # the newest parked frame can be shown at once
    assert v.stats["shown"] == 9 and not v.flush()
    v.close()


def test_live_view_stamp_gives_latency_and_bad_frames_are_refused() -> None:
    v = LiveView(trailing=False, image_format="png")
    v.update(np.zeros((2, 2), np.uint8), stamp=time.time() - 0.5)
    assert 0.5 <= v.stats["latency_last"] < 5.0
    assert bytes(v.image.value).startswith(b"\x89PNG")
    with pytest.raises(WidgetError, match="uint8"):
        v.update(np.zeros((2, 2), np.float64))
    with pytest.raises(WidgetError, match="jpeg' or 'png"):
        LiveView(image_format="gif")
    v.close()


def test_live_view_trailing_frame_appears_and_threads_are_cleaned_up() -> None:
    before = set(threading.enumerate())
    v = LiveView(max_fps=20)
    frames = [np.full((8, 8, 3), k, np.uint8) for k in range(40)]

    def producer(offset: int) -> None:
        for f in frames[offset::4]:
            v.update(f)

    workers = [threading.Thread(target=producer, args=(i,)) for i in range(4)]
    for t in workers:
        t.start()
    for t in workers:
        t.join()
    deadline = time.monotonic() + 2.0
    while v._pending is not None and time.monotonic() < deadline:  # the timer shows the parked frame
        time.sleep(0.01)
    assert v._pending is None
    s = v.stats
    assert s["received"] == 40 and 1 <= s["shown"] < 40
    v.update(frames[0])
    v.update(frames[1])  # parks a frame and arms the timer
    v.close()
    assert v.update(frames[2]) is False  # closed: ignored
    time.sleep(0.1)
    assert set(threading.enumerate()) <= before


def test_progress_text_mode_lines_per_ten_percent() -> None:
    out = io.StringIO()
    clock = FakeClock()
    with Progress(200, "dilate", unit="rows", mode="text", file=out, min_interval=0, clock=clock) as p:
        for _ in range(200):
            clock.now += 0.01
            p.update()
    lines = out.getvalue().splitlines()
    assert len(lines) == 11  # 0 %, 10 %, ..., 100 %, no duplicate final line
    assert lines[-1] == "dilate [####################] 100% 200/200 rows  2.0 s"
    assert lines[5].startswith("dilate [##########          ]  50% 100/200 rows  1.0 s, 1.0 s left")


def test_progress_callback_unknown_total_and_throttling() -> None:
    out = io.StringIO()
    clock = FakeClock()
    p = Progress(desc="csim", mode="text", file=out, min_interval=1.0, clock=clock)
    shown = []
    p._show_orig = p._show  # count how often the display is refreshed

    def counting(now: float, final: bool = False) -> None:
        shown.append(now)
        p._show_orig(now, final)

    p._show = counting  # type: ignore[method-assign]
    for k in range(1000):
        clock.now = k * 0.005  # 5 s of calls
        p(k + 1)
    p.close()
    p.close()
    assert len(shown) == 6  # once per second, plus the final state (once)
    assert out.getvalue() == "csim 1000  5.0 s\n"
    assert p.text() == "csim 1000  5.0 s"


def test_progress_widget_mode_and_track() -> None:
    p = Progress(10, "work", mode="widget", min_interval=0)
    p.set(4)
    assert (p._bar.value, p._bar.max) == (4, 10) and "40%" in p._label.value
    # the label is not cut to the description and does not draw a second, ASCII bar
    assert p._label.value.startswith("work  40% 4/10") and "#" not in p._label.value
    assert p._bar.description == ""
    p.close()
    assert p._bar.bar_style == "success"
    bundle = p.mimebundle()   # what an exported notebook shows instead of the live bar
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert "40% 4/10" in bundle["text/plain"] and "<pre>work [########" in bundle["text/html"]
    assert "IntProgress" not in bundle["text/plain"]
    out = io.StringIO()
    assert list(track(range(5), desc="t", mode="text", file=out, min_interval=0)) == [0, 1, 2, 3, 4]
    assert out.getvalue().splitlines()[-1].startswith("t [####################] 100% 5/5")
    assert Progress(3, mode="auto").mode == "text"  # plain pytest is not a kernel
    with pytest.raises(WidgetError, match="mode must be"):
        Progress(mode="fancy")


def test_progress_step_messages_as_the_hls_and_component_layers_send_them() -> None:
    out = io.StringIO()
    clock = FakeClock()
    p = Progress(desc="generate", mode="text", file=out, min_interval=10.0, clock=clock)
    for k, msg in enumerate(("rendering templates", "compiling the testbench", "running C simulation")):
        clock.now = float(k)
        p(msg)  # steps are shown at once, whatever min_interval says
    p.close()
    assert out.getvalue().splitlines() == [
        "generate 1  0.0 s \u2013 rendering templates",
        "generate 2  1.0 s \u2013 compiling the testbench",
        "generate 3  2.0 s \u2013 running C simulation",
    ]


def test_live_view_feed_takes_viewed_frames_and_swaps_bgr() -> None:
    from types import SimpleNamespace

    from rosfpga_lab.component.camera import ViewedFrame

    v = LiveView(trailing=False, image_format="png")
    bgr = np.zeros((2, 2, 3), np.uint8)
    bgr[:, :, 0] = 200  # blue in BGR order
    assert v.feed(ViewedFrame(0, {}, 2, 2, "bgr8", bgr, None, 0.25))
    shown = cv2_decode(bytes(v.image.value))
    assert (shown[0, 0] == (0, 0, 200)).all()  # shown as blue (RGB)
    assert v.stats["latency_last"] == 0.25
    assert not v.feed(SimpleNamespace(image=None, encoding="yuv422", latency=0.1))
    v.close()


def cv2_decode(png: bytes) -> np.ndarray:
    import cv2

    return cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)[:, :, ::-1]


def test_live_view_static_form_and_close_freezes_the_output(monkeypatch: pytest.MonkeyPatch) -> None:
    """Exported notebooks show the newest frame and the figures, not the widget's repr."""
    import base64

    import IPython.display

    shown: list[tuple[dict, dict]] = []

    class Handle:
        def update(self, data: dict, **kw: object) -> None:
            shown.append((data, kw))

    def fake_display(data: dict, **kw: object) -> Handle:
        shown.append((data, kw))
        return Handle()

    monkeypatch.setattr(IPython.display, "display", fake_display)
    v = LiveView(trailing=False, image_format="png", title="/out <&>")
    v._ipython_display_()
    first, kw = shown[0]
    assert kw == {"raw": True, "display_id": True}
    assert "application/vnd.jupyter.widget-view+json" in first
    assert "waiting for frames" in first["text/html"] and "/out &lt;&amp;&gt;" in first["text/html"]
    assert "<img" not in first["text/html"]
    frame = np.zeros((3, 5, 3), np.uint8)
    frame[1, 2] = (255, 0, 0)
    v.update(frame)
    v.close()
    frozen, kw = shown[-1]
    assert kw == {"raw": True} and "application/vnd.jupyter.widget-view+json" not in frozen
    assert frozen["text/plain"].startswith("1 frames received")
    uri = frozen["text/html"].split('src="data:image/png;base64,')[1].split('"')[0]
    import cv2

    img = cv2.imdecode(np.frombuffer(base64.b64decode(uri), np.uint8), cv2.IMREAD_COLOR)
    assert img is not None and img.shape[1] >= 5                # the frame itself, enlarged
    scale = img.shape[1] // 5
    assert tuple(img[1 * scale, 2 * scale]) == (0, 0, 255)      # BGR of the red pixel
    assert len(shown) == 2                                      # closing twice adds nothing
    v.close()
    assert len(shown) == 2


def test_progress_without_a_total_says_running_not_an_empty_bar_and_zero() -> None:
    """The C simulation's progress (no total): no bar, no "0", but what it is doing."""
    clock = iter([0.0, 0.0, 2.8, 2.8]).__next__
    p = Progress(None, "C simulation", mode="widget", min_interval=0, clock=clock)
    assert p._bar.layout.display == "none"
    p.close()
    assert p._label.value == "C simulation done in  2.8 s"
    stepped = Progress(2, "C simulation", mode="text", file=io.StringIO(), min_interval=0)
    stepped.step("compiled with g++")
    assert stepped.text().endswith("\u2013 compiled with g++") and "1/2" in stepped.text()


def test_live_view_shows_input_beside_output_and_stops_once() -> None:
    stopped = []
    live = LiveView(max_fps=100, trailing=False, stop=lambda: stopped.append(True))
    assert live._input_box.layout.display == "none" and live.stop_button.layout.display == ""
    out = np.full((4, 6, 3), 200, np.uint8)
    inp = np.zeros((4, 6, 3), np.uint8)
    assert live.update(out, input=inp)
    assert live.input_image.value and live.image.value and live._input_box.layout.display == ""
    html = live.to_html()
    assert "alt=\"newest input\"" in html and "alt=\"newest output\"" in html
    live.stop_button.click()
    live.stop_button.click()                 # a second press does nothing more
    assert stopped == [True] and live.stop_button.disabled
    assert LiveView(trailing=False).stop_button.layout.display == "none"   # no stop: no button
    live.close()
