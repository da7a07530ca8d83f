"""The RTL dump shipped for notebook 08: what it shows is right, and it is what the RTL makes now."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.support.realros import require_rtl

from rosfpga_lab.hw import Pipeline
from rosfpga_lab.hw.interpreter import SUBSCRIBER_STATUSES
from rosfpga_lab.rtl.demo import DUMP_SIMULATOR, demo_config, demo_frames, run_demo, shipped_dump
from rosfpga_lab.rtl.vcd import read_vcd

STATUS_CODES = {name: code for code, (name, _label) in enumerate(SUBSCRIBER_STATUSES)}


def _stream_bytes(dump, prefix: str) -> bytes:
    fire = dump.values(f"{prefix}_tvalid").astype(bool) & dump.values(f"{prefix}_tready").astype(bool)
    return dump.values(f"{prefix}_tdata")[fire].astype(np.uint8).tobytes()


def test_the_shipped_dump_shows_a_refusal_then_the_models_output() -> None:
    path = shipped_dump()
    assert path is not None and path.name == "rtl_demo.vcd"
    dump = read_vcd(path, clock="clk")
    refused, good = demo_frames()
    assert _stream_bytes(dump, "s") == refused + good          # everything offered was taken
    model = Pipeline.from_config(demo_config()).process(good).output_frame
    assert _stream_bytes(dump, "m") == model                   # one frame out, bit-exact
    decided = dump.values("status_valid").astype(bool)
    codes = dump.values("status")[decided].tolist()
    assert codes == [STATUS_CODES["SUB_BAD_WIDTH"], STATUS_CODES["SUB_OK"]]
    # the backpressure the notebook talks about is in the dump: the output stalls with data waiting
    stalled = dump.values("m_tvalid").astype(bool) & ~dump.values("m_tready").astype(bool)
    assert stalled.sum() > 100


def test_the_shipped_dump_is_what_the_rtl_makes_today(tmp_path: Path) -> None:
    require_rtl(DUMP_SIMULATOR)
    fresh = tmp_path / "rtl_demo.vcd"
    run_demo(fresh, simulator=DUMP_SIMULATOR)
    old, new = read_vcd(shipped_dump(), clock="clk"), read_vcd(fresh, clock="clk")
    assert old.signals == new.signals, "signals changed: run python data/make_rtl_demo_dump.py"
    assert old.cycles == new.cycles, "clock count changed: run python data/make_rtl_demo_dump.py"
    for name in old.signals:
        assert np.array_equal(old.values(name), new.values(name)), (
            f"{name} differs from the RTL's: run python data/make_rtl_demo_dump.py and review")
