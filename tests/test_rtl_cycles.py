"""Cycles of the RTL against the cycle model (``hw.cycles``), every encoding, with and without
random backpressure on the output.

Tolerances, and why:

* No backpressure: the model's ``total`` (first byte in to last byte out) is within 1 % + 8
  clocks of the RTL's. The model leaves out the FIFO registers on the way (a clock or two each)
  and takes the filter's latency from the HLS loop (which also runs over the padding columns),
  while the RTL's filter is a few pixels quicker.
* 50 % backpressure: the output takes a byte on a random half of the clocks, so sending ``n``
  bytes takes a negative-binomial number of clocks: mean ``n / p``, standard deviation
  ``sqrt(n (1 - p)) / p``. The RTL must be within four standard deviations (+ 16 clocks) of the
  model; seeds are fixed, so the test is repeatable.
* Exact: fifo2axi makes a beat every ``bytes_per_pixel`` clocks (4 for ``rgba8``), the model's
  ``clocks_per_beat``; its span is the data bytes plus one clock (its output register); the
  subscriber's span is the frame's bytes and axi2fifo's the data bytes plus one, as the model's
  per-stage ``cycles`` say.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from realros import require_rtl
from rosfpga_lab.hw import PIXEL_FORMATS, Pipeline, image_frame
from rosfpga_lab.rtl import build, rtl_params, run
from rosfpga_lab.rtl.cycles import compare, format_rows, model_report
from test_rtl_sim import random_image, small_config

pytestmark = pytest.mark.rtl


@pytest.mark.parametrize("encoding", list(PIXEL_FORMATS))
def test_model_and_rtl_agree_on_cycles(encoding: str, tmp_path: Path) -> None:
    sim_name = require_rtl()
    config = small_config(encoding, width=48, height=24)
    sim = build(rtl_params(config), tmp_path, simulator=sim_name)
    frame = image_frame(random_image(config, 1), encoding, frame_id="cam")
    pipe = Pipeline.from_config(config)
    bpp = PIXEL_FORMATS[encoding].bytes_per_pixel
    pixels = config.image.width * config.image.height

    free = compare(encoding, sim, pipe, frame)
    assert abs(free.rtl - free.model) <= 0.01 * free.model + 8, format_rows([free])
    report = model_report(pipe, frame)
    assert report.clocks_per_beat == bpp
    assert free.spans["fifo2axi"] == report.cycles["fifo2axi"] + 1 == pixels * bpp + 1
    # The byte-wide stages take exactly their byte counts (+1: an output register).
    assert free.spans["subscriber"] == report.cycles["interpreter"] == len(frame)
    if pipe.op == "passthrough":  # pixels reach the publisher while it still writes its header
        assert free.spans["axi2fifo"] > report.cycles["axi2fifo"] + 1
    else:
        assert free.spans["axi2fifo"] == report.cycles["axi2fifo"] + 1

    p = 0.5
    loaded = compare(encoding, sim, pipe, frame, bp=500, seed=3)
    n = len(pipe.process(frame).output_frame)
    sigma = math.sqrt(n * (1 - p)) / p
    assert abs(loaded.rtl - loaded.model) <= 4 * sigma + 16, format_rows([free, loaded])
    assert loaded.rtl > 1.8 * free.rtl  # the output, not the input, now sets the pace


@pytest.mark.parametrize("encoding", ["rgba8", "rgb8", "mono8"])
def test_the_clocked_fifo2axi_model_matches_the_rtl_clock_by_clock(encoding: str,
                                                                   tmp_path: Path) -> None:
    """``hw.clocked.fifo2axi_clocks``, fed the valid and ready the RTL's fifo2axi saw (input
    gaps, and backpressure through FIFOs only 2 deep), gives the RTL's ports at every clock."""
    from rosfpga_lab.hw.clocked import fifo2axi_clocks

    sim_name = require_rtl()
    config = small_config(encoding, width=7, height=3, fifo_depth=2)
    image = random_image(config, 4)
    frame = image_frame(image, encoding, frame_id="c")
    # +clocks_f2a is the Verilog testbench's: not the fast harness, on Verilator too
    sim = build(rtl_params(config), tmp_path, simulator=sim_name, harness=False)
    trace = tmp_path / "f2a.txt"
    run(sim, frame, seed=13, gap=300, bp=600, plusargs=[f"+clocks_f2a={trace}"])
    rows = [line.split() for line in trace.read_text().splitlines()]
    rtl = {name: np.array([int(r[i], 16) for r in rows], np.uint64) for i, name in enumerate(
        ("s_tvalid", "s_tready", "s_tdata", "m_axis_tvalid", "m_axis_tready", "m_axis_tdata",
         "m_axis_tuser", "m_axis_tlast"))}
    pixels = config.image.width * config.image.height
    # the RTL's fifo2axi sees only this frame's pixel bytes on its input
    assert int((rtl["s_tvalid"] & rtl["s_tready"]).sum()) == image.size
    model = fifo2axi_clocks(image.tobytes(), config.image.width,
                            PIXEL_FORMATS[encoding].bytes_per_pixel,
                            in_valid=rtl["s_tvalid"].astype(bool),
                            out_ready=rtl["m_axis_tready"].astype(bool), clocks=len(rows))
    assert int((model["m_axis_tvalid"] & model["m_axis_tready"]).sum()) == pixels
    for name in ("s_tready", "m_axis_tvalid", "m_axis_tuser", "m_axis_tlast", "m_axis_tdata"):
        got, want = rtl[name], model[name]
        if name == "m_axis_tdata":  # compare where a beat is on the bus
            got, want = got * rtl["m_axis_tvalid"], want * model["m_axis_tvalid"]
        bad = np.nonzero(got != want)[0]
        assert bad.size == 0, f"{name} differs first at clock {bad[0]}: RTL {got[bad[0]]}, model {want[bad[0]]}"
    assert (rtl["m_axis_tready"] == 0).any() and (rtl["s_tvalid"] == 0).any()  # both were exercised
