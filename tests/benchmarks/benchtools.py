"""What the benchmark scripts share (they run as scripts: this folder is on their path)."""

from __future__ import annotations

import time
from typing import Callable


def per_call(fn: Callable[[], object], n: int) -> float:
    """Mean seconds of one call of ``fn`` over ``n`` calls."""
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n
