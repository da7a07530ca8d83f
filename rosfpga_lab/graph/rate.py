"""Arrival rates: the lab's one meter of events per second (``rostopic hz``, live views, status lines).

A :class:`RateMeter` keeps the times of the last ``samples`` arrivals (memory stays bounded
however long it runs) and derives from them: the rate over a sliding time window (a live view's
fps), the rate over everything since the first arrival (a checker's summary), and rostopic's
interval statistics. The rate over ``n`` arrival times is ``(n - 1) / (last - first)``: the
number of intervals over the time they span.
"""

from __future__ import annotations

import statistics
import time
from collections import deque
from collections.abc import Callable

from rosfpga_lab.graph.limits import RATE_SAMPLES



class RateMeter:
    """Events per second from arrival times.

    Not thread-safe: a caller that ticks in one thread and reads in another holds its own lock.

    Args:
        samples: arrival times kept (the newest ones).
        window_s: :meth:`rate` counts only arrivals this many seconds before now; None: all kept.
        stale_s: :meth:`rate` reads 0 once the newest arrival is older than this; None: never.
        clock: monotonic clock, seconds (injectable for tests).

    Attributes:
        count: arrivals ever recorded.
    """

    def __init__(self, *, samples: int = RATE_SAMPLES, window_s: float | None = None,
                 stale_s: float | None = None, clock: Callable[[], float] = time.monotonic) -> None:
        if samples < 2:
            raise ValueError(f"a rate needs at least 2 samples, got {samples}")
        self.window_s, self.stale_s, self.clock = window_s, stale_s, clock
        self._times: deque[float] = deque(maxlen=samples)
        self._first: float | None = None
        self.count = 0
        self.reported = 0  # count at the last report()

    def tick(self, t: float | None = None) -> None:
        """Record one arrival at ``t`` (now by default)."""
        t = self.clock() if t is None else t
        if self._first is None:
            self._first = t
        self._times.append(t)
        self.count += 1

    @property
    def times(self) -> list[float]:
        """The arrival times kept, oldest first."""
        return list(self._times)

    def rate(self, now: float | None = None) -> float:
        """Events per second over the window (0 with fewer than two arrivals in it, or stale)."""
        now = self.clock() if now is None else now
        times = list(self._times)
        if self.window_s is not None:
            times = [t for t in times if t >= now - self.window_s]
        if self.stale_s is not None and times and now - times[-1] > self.stale_s:
            return 0.0
        return _rate(times)

    def overall_rate(self) -> float:
        """Events per second from the first arrival ever to the last (0 before two)."""
        if self._first is None or self.count < 2:
            return 0.0
        span = self._times[-1] - self._first
        return (self.count - 1) / span if span > 0 else 0.0

    def report(self) -> str | None:
        """rostopic hz's report over the kept arrivals; None (print "no new messages") before two
        arrived or when none arrived since the last report (the old rate would hide that they
        stopped)."""
        times = list(self._times)
        if len(times) < 2 or self.count == self.reported:
            return None
        self.reported = self.count
        gaps = [b - a for a, b in zip(times, times[1:])]
        mean = sum(gaps) / len(gaps)
        std = statistics.pstdev(gaps)
        rate = 1.0 / mean if mean > 0 else float("inf")
        return (f"average rate: {rate:.3f}\n\tmin: {min(gaps):.3f}s max: {max(gaps):.3f}s "
                f"std dev: {std:.5f}s window: {len(times)}")


def _rate(times: list[float]) -> float:
    if len(times) < 2 or times[-1] <= times[0]:
        return 0.0
    return (len(times) - 1) / (times[-1] - times[0])
