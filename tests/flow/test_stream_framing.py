"""Short, long and oversize frames between good ones, as one continuous byte stream: the HLS C
simulation and the Verilog read it the same way, byte for byte, and publish what the Python
model (``hw.MessagePipeline``, which takes whole frames) publishes for the good frames.

The circuit gets the TCP payload as one byte stream, not cut into frames. A frame length below
the smallest Image (but framed) is refused and its bytes skipped; a frame longer than its
Image says is refused at the data length and skipped to its end; a frame length above
``hw.limits.MAX_FRAME_BYTES`` cannot be trusted for skipping, so only its 4 bytes are taken and
the next 4 are read as a new frame length. The short frame's body below is itself a plausible
frame length: a subscriber that did not skip it would read it as one (issue 24, item 4: the
HLS subscriber returned without reading the body, and the C testbench hid it by cutting the
input into frames itself).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from tests.support.realros import cxx_missing_reason, require_rtl
from rosfpga_lab.hls import generate, run_csim
from rosfpga_lab.hw import MessagePipeline, image_frame
from rosfpga_lab.hw.limits import MAX_FRAME_BYTES
from rosfpga_lab.rtl import build, design_from_config, run
from tests.rtl.test_sim import random_image, small_config


def _stream(config) -> tuple[bytes, list[tuple[int, str]]]:
    """good, short, good, long, oversize, good: the bytes and the expected status per frame (the
    long frame is refused at its frame length: the generated walk's exact-fit rule)."""
    enc = config.image.encoding
    goods = [image_frame(random_image(config, s), enc, frame_id=f"g{s}") for s in range(3)]
    # a short frame: length 12 and 12 body bytes that start like a 40-byte frame length
    short = struct.pack("<I", 12) + struct.pack("<I", 40) + bytes(range(1, 9))
    good = goods[1]
    long_ = struct.pack("<I", len(good) - 4 + 8) + good[4:] + b"\x07" * 8
    oversize = struct.pack("<I", MAX_FRAME_BYTES + 1)
    parts = [(goods[0], "SUB_OK"), (short, "SUB_BAD_FRAME_LENGTH"), (good, "SUB_OK"),
             (long_, "SUB_BAD_FRAME_LENGTH"), (oversize, "SUB_BAD_FRAME_LENGTH"),
             (goods[2], "SUB_OK")]
    status, offset = [], 0
    for data, name in parts:
        status.append((offset, name))
        offset += len(data)
    return b"".join(p for p, _ in parts), status


@pytest.mark.rtl
def test_csim_rtl_and_models_agree_byte_for_byte(tmp_path: Path) -> None:
    config = small_config("rgb8", width=5, height=3)
    data, status = _stream(config)
    # the three good frames, in order, numbered 1, 2, 3 by the publisher
    pipe = MessagePipeline.from_config(config)
    goods = [data[o:o + 4 + struct.unpack_from("<I", data, o)[0]]
             for o, n in status if n == "SUB_OK"]
    expected = b"".join(pipe.process(f).output_frame for f in goods)
    sim = build(design_from_config(config), tmp_path / "rtl", simulator=require_rtl())
    rtl = run(sim, data, seed=5, gap=200, bp=300)
    assert rtl.status == tuple(status)
    assert rtl.output == expected
    if cxx_missing_reason() is None:
        generate(config, tmp_path / "hls")
        csim = run_csim(tmp_path / "hls", data)
        assert csim.status == tuple(status)
        assert csim.output == expected
        assert "cannot trust" in csim.log and "WARNING" not in csim.log
        # the beats were tapped for the three good frames only
        assert len(csim.input_beats) == 3 * 5 * 3
    assert np.frombuffer(expected, np.uint8).size > 0
