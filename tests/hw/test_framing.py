"""Framing of a damaged AXI4-Stream video input (``hw.framing``, the rules ``rfl_morph.v`` keeps).

Hand-made streams with the expected frames written out by hand: an early TLAST pads the line
with zeros, a late TLAST drops the extra beats, a TUSER inside a frame pads the rest of the
frame and starts the next, beats before the first TUSER are dropped; each sets its flag and the
good frame after it comes out right. Random damaged streams hold the fast model equal to the
reference.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.hw import PipelineConfigError
from rosfpga_lab.hw.encodings import pixel_format
from rosfpga_lab.hw.framing import (EOL_EARLY, EOL_LATE, FRAMING_FLAGS, SOF_EARLY, SOF_MISSING,
                                    flag_names, reframe_fast, reframe_reference)
from rosfpga_lab.hw.morph import morph_fast, morph_stream_fast, morph_stream_reference
from rosfpga_lab.hw.streams import Beats

U, L = "u", "l"     # marks on a beat: TUSER, TLAST


def stream(*beats: tuple) -> Beats:
    """Beats from (value, marks...) tuples."""
    return Beats(np.array([b[0] for b in beats], np.uint32), 1,
                 np.array([U in b[1:] for b in beats]), np.array([L in b[1:] for b in beats]))


GOOD = [(11, U), (12,), (13, L), (14,), (15,), (16, L)]          # a clean 3x2 frame


CASES = {
    # name: (beats, expected frames, expected flags)
    "clean": (GOOD + GOOD, [[11, 12, 13, 14, 15, 16]] * 2, 0),
    "early-tlast": ([(1, U), (2, L), (3,), (4,), (5, L)] + GOOD,
                    [[1, 2, 0, 3, 4, 5], [11, 12, 13, 14, 15, 16]], EOL_EARLY),
    "late-tlast": ([(1, U), (2,), (3,), (8,), (9, L), (4,), (5,), (6, L)] + GOOD,
                   [[1, 2, 3, 4, 5, 6], [11, 12, 13, 14, 15, 16]], EOL_LATE),
    "late-tlast-on-last-line": ([(1, U), (2,), (3, L), (4,), (5,), (6,), (7,), (8, L)] + GOOD,
                                [[1, 2, 3, 4, 5, 6], [11, 12, 13, 14, 15, 16]], EOL_LATE),
    "tuser-mid-frame": ([(1, U), (2,), (3, L), (4,)] + GOOD,
                        [[1, 2, 3, 4, 0, 0], [11, 12, 13, 14, 15, 16]], SOF_EARLY),
    "tuser-ends-a-late-line": ([(1, U), (2,), (3,), (7,)] + GOOD,
                               [[1, 2, 3, 0, 0, 0], [11, 12, 13, 14, 15, 16]],
                               EOL_LATE | SOF_EARLY),
    "junk-before-tuser": ([(7,), (8, L), (9,)] + GOOD, [[11, 12, 13, 14, 15, 16]], SOF_MISSING),
    "frame-too-long": (GOOD + [(7,), (8, L)] + GOOD, [[11, 12, 13, 14, 15, 16]] * 2,
                       SOF_MISSING),
}


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("model", [reframe_reference, reframe_fast], ids=["reference", "fast"])
def test_damaged_stream_is_repaired_flagged_and_the_next_frame_is_right(name, model):
    beats, frames, flags = CASES[name]
    got = model(stream(*beats), 2, 3)
    assert [f.tolist() for f in got.frames] == frames
    assert got.flags == flags, flag_names(got.flags)
    # the good frame's own flags: none, unless beats dropped while waiting for it
    waited = name in ("junk-before-tuser", "frame-too-long")
    assert got.frame_flags[-1] == (flags if waited else 0)
    assert got.used == len(beats)


def test_flags_are_named_in_bit_order():
    assert FRAMING_FLAGS == ("sof_early", "eol_early", "eol_late", "sof_missing")
    assert flag_names(SOF_EARLY | SOF_MISSING) == ["sof_early", "sof_missing"]


def test_a_frame_cut_short_by_the_end_of_the_stream_is_not_emitted():
    for model in (reframe_reference, reframe_fast):
        got = model(stream(*(GOOD + GOOD[:4])), 2, 3)
        assert len(got.frames) == 1 and got.flags == 0 and got.used == 10


def test_bad_size_is_refused():
    with pytest.raises(PipelineConfigError):
        reframe_fast(stream(*GOOD), 0, 3)


def test_stream_models_filter_each_repaired_frame():
    fmt = pixel_format("mono8")
    beats = stream(*([(1, U), (2, L), (3,), (4,), (5, L)] + GOOD))
    for model in (morph_stream_reference, morph_stream_fast):
        out, framed = model(beats, 2, 3, fmt, "dilate", (3, 3))
        assert framed.flags == EOL_EARLY
        first = morph_fast(np.array([[1, 2, 0], [3, 4, 5]], np.uint8)[:, :, None], "dilate", (3, 3))
        assert out.tdata[:6].tolist() == first.ravel().tolist() == [4, 5, 5, 4, 5, 5]
        assert out.tuser.tolist() == [1, 0, 0, 0, 0, 0] * 2
        assert out.tlast.tolist() == [0, 0, 1] * 4


@st.composite
def damaged(draw):
    rows, cols = draw(st.integers(1, 4)), draw(st.integers(1, 5))
    n = draw(st.integers(0, 40))
    data = draw(st.lists(st.integers(0, 2**32 - 1), min_size=n, max_size=n))
    user = draw(st.lists(st.booleans(), min_size=n, max_size=n))
    last = draw(st.lists(st.booleans(), min_size=n, max_size=n))
    return rows, cols, Beats(np.array(data, np.uint32), 15, np.array(user, bool),
                             np.array(last, bool))


@given(damaged())
@settings(max_examples=300, deadline=None)
def test_fast_equals_reference_on_random_streams(case):
    rows, cols, beats = case
    ref, fast = reframe_reference(beats, rows, cols), reframe_fast(beats, rows, cols)
    assert [f.tolist() for f in ref.frames] == [f.tolist() for f in fast.frames]
    assert (ref.frame_flags, ref.flags, ref.used) == (fast.frame_flags, fast.flags, fast.used)
