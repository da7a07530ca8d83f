"""The application: streaming dilate/erode (reference) == cv2 (fast) == brute-force oracle."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.hw import Mat, PipelineConfigError, morph_fast, morph_reference
from tests.hw.test_oracles import images, morph_oracle


def reference(image: np.ndarray, op: str, ksize: tuple[int, int]) -> np.ndarray:
    src = Mat.from_numpy(image)
    dst = Mat(src.rows, src.cols, src.channels)
    morph_reference(src, dst, op, ksize)
    assert src.empty and dst.level == src.rows * src.cols  # every pixel in, every pixel out
    return dst.to_numpy()


SHAPES = [(1, 1), (1, 9), (9, 1), (2, 2), (5, 7), (7, 4), (13, 11)]
KSIZES = [(3, 3), (1, 1), (5, 5), (3, 1), (1, 3), (2, 2), (4, 3), (7, 5)]


@pytest.mark.parametrize("op", ["dilate", "erode"])
@pytest.mark.parametrize("shape", SHAPES, ids=str)
def test_reference_equals_oracle_and_cv2_on_edges_and_thin_images(op, shape):
    rng = np.random.default_rng(sum(shape))
    for channels in (1, 3, 4):
        image = rng.integers(0, 256, (*shape, channels), dtype=np.uint8)
        for kw, kh in KSIZES:
            expected = morph_oracle(image, op, kw, kh)
            fn = cv2.dilate if op == "dilate" else cv2.erode
            by_cv2 = fn(image, np.ones((kh, kw), np.uint8)).reshape(image.shape)
            assert np.array_equal(by_cv2, expected), ("cv2 default border", kw, kh)
            assert np.array_equal(reference(image, op, (kw, kh)), expected), (kw, kh, channels)
            assert np.array_equal(morph_fast(image, op, (kw, kh)), expected), (kw, kh, channels)


def test_single_bright_pixel_grows_into_the_kernel_rectangle():
    image = np.zeros((7, 9, 1), np.uint8)
    image[3, 4] = 200
    grown = reference(image, "dilate", (5, 3))[:, :, 0]
    assert (grown == 200).sum() == 15
    assert np.array_equal(np.argwhere(grown == 200)[[0, -1]], [[2, 2], [4, 6]])
    assert reference(grown[:, :, None], "erode", (5, 3))[3, 4, 0] == 200


@given(images(max_side=10), st.sampled_from(["dilate", "erode", "passthrough"]),
       st.integers(1, 6), st.integers(1, 6))
@settings(max_examples=100, deadline=None)
def test_reference_equals_fast_random(img_enc, op, kw, kh):
    image, _ = img_enc
    assert np.array_equal(reference(image, op, (kw, kh)), morph_fast(image, op, (kw, kh)))


def test_fast_writes_into_a_given_buffer_and_keeps_the_input():
    image = np.random.default_rng(3).integers(0, 256, (6, 5, 1), dtype=np.uint8)
    keep = image.copy()
    out = np.empty_like(image)
    assert morph_fast(image, "dilate", (3, 3), out=out) is out
    assert np.array_equal(out, morph_oracle(image, "dilate", 3, 3)) and np.array_equal(image, keep)


@pytest.mark.parametrize("op, ksize", [("blur", (3, 3)), ("dilate", (0, 3)), ("dilate", (3, 99)),
                                       ("erode", "3x3")])
def test_bad_op_or_kernel_is_refused(op, ksize):
    with pytest.raises(PipelineConfigError):
        morph_fast(np.zeros((2, 2, 1), np.uint8), op, ksize)
