"""The application on a 1-D numeric stream: sliding maximum (dilate) or minimum (erode), or a copy.

The 1-D sibling of :mod:`rosfpga_lab.hw.morph`: element ``i`` of the output is the extreme of
input elements ``i - r .. i + r`` (``r = ksize // 2``) that lie inside the array, OpenCV's
border rule for a rectangular kernel. Every integer type (8 to 64 bits, signed or unsigned)
and ``float32``/``float64`` work; the element dtype is kept.

The order is numpy's: ``max2(a, b)`` is ``a`` if ``a`` is NaN, else ``b`` if ``b`` is NaN,
else ``a if a > b else b`` (so of ``-0.0`` and ``+0.0`` the later one wins; ``min2`` likewise
with ``<``). The window is folded left to right, ``acc = max2(acc, x)``, which is what
``np.maximum`` does element-wise. **NaN**: a window that holds a NaN gives its first NaN,
bits unchanged (payload and sign), so a NaN spreads over ``ksize`` outputs. The reference model
is the fold written out, one element per clock, as the generated C++ runs it; the fast model
folds shifted numpy slices padded with the identity (the type's lowest value or ``-inf`` for a
maximum), which gives the same bits.
"""

from __future__ import annotations

import math

import numpy as np

from rosfpga_lab.config.vocabulary import MODEL_OPS, PASSTHROUGH, canonical_op
from rosfpga_lab.hw import limits
from rosfpga_lab.hw.errors import PipelineConfigError

#: The element types the 1-D application takes (numpy kinds: signed, unsigned, float).
_KINDS = "iuf"


def check_op1d(op: str, ksize: int, dtype: np.dtype) -> str:
    """Validate ``op``, ``ksize`` and the element type; return the canonical op name.

    Raises:
        PipelineConfigError: unknown op, even or out-of-range ``ksize``, or a dtype that is not
            an integer or float.
    """
    name = canonical_op(op)
    if name not in MODEL_OPS:
        raise PipelineConfigError(f"unknown op {op!r}; the models run {', '.join(MODEL_OPS)}")
    if not (isinstance(ksize, int) and ksize % 2 == 1 and 1 <= ksize <= limits.MAX_KSIZE):
        raise PipelineConfigError(f"ksize must be odd, 1..{limits.MAX_KSIZE}, got {ksize!r}")
    if dtype.kind not in _KINDS or dtype.itemsize > 8:
        raise PipelineConfigError(f"the application takes integer and float elements, not {dtype}")
    return name


def _is_nan(x: float | int) -> bool:
    return isinstance(x, float) and math.isnan(x)


def max2(a: float | int, b: float | int) -> float | int:
    """numpy's ``maximum`` of two scalars (see the module docstring)."""
    if _is_nan(a):
        return a
    if _is_nan(b):
        return b
    return a if a > b else b


def min2(a: float | int, b: float | int) -> float | int:
    """numpy's ``minimum`` of two scalars."""
    if _is_nan(a):
        return a
    if _is_nan(b):
        return b
    return a if a < b else b


def morph1d_reference(values: np.ndarray, op: str, ksize: int) -> np.ndarray:
    """One output element per step: the fold of the in-array window (bit-exact).

    Floats are carried through the fold as their exact bit patterns (a NaN's payload survives).
    """
    name = check_op1d(op, ksize, values.dtype)
    if name == PASSTHROUGH:
        return values.copy()
    pick = max2 if name == "dilate" else min2
    r = ksize // 2
    n = len(values)
    out = np.empty(n, values.dtype)
    items = list(values) if values.dtype.kind == "f" else [int(v) for v in values]
    for i in range(n):
        idx = range(max(0, i - r), min(n, i + r + 1))
        acc_i = idx[0]
        for j in idx[1:]:
            # compare as Python numbers, keep the element itself (its bits)
            a, b = float(items[acc_i]) if values.dtype.kind == "f" else items[acc_i], \
                float(items[j]) if values.dtype.kind == "f" else items[j]
            acc_i = acc_i if pick(a, b) is a else j
        out[i] = values[acc_i]
    return out


def morph1d_fast(values: np.ndarray, op: str, ksize: int) -> np.ndarray:
    """numpy: fold ``ksize`` shifted slices of the identity-padded array."""
    name = check_op1d(op, ksize, values.dtype)
    if name == PASSTHROUGH or len(values) == 0:
        return values.copy()
    r = ksize // 2
    dtype = values.dtype
    if dtype.kind == "f":
        pad = -np.inf if name == "dilate" else np.inf
    else:
        info = np.iinfo(dtype)
        pad = info.min if name == "dilate" else info.max
    padded = np.concatenate([np.full(r, pad, dtype), values, np.full(r, pad, dtype)])
    fold = np.maximum if name == "dilate" else np.minimum
    n = len(values)
    out = padded[0:n].copy()
    for k in range(1, ksize):
        out = fold(out, padded[k:k + n])
    return out
