"""Stop a command that registers with a ROS master on SIGINT *and* SIGTERM, as rospy does.

How this works: ``timeout``, ``kill``, systemd and container stops send SIGTERM, whose default
kills the process before it unregisters (phantom publishers stay on the master); a shell starts a
background job (``cmd &``) with SIGINT *ignored*, and a child inherits that. rospy installs its
own handlers for both whatever it inherited; :class:`StopSignals` does the same for the time a
command runs. The first signal raises :class:`KeyboardInterrupt` in the main thread (what Ctrl-C
does at a terminal, so the command's ``finally`` unregisters), or with ``raise_interrupt=False``
only sets :attr:`StopSignals.fired`, for a loop that polls it. Later signals are ignored while
the command cleans up (its clean-up is bounded by time-outs; SIGKILL still works). While a
command registers or unregisters (:func:`holding`), a signal waits until that step is over, so
an interrupt can never leave a registration behind half done. The previous dispositions come
back on exit. Off the main thread (a notebook) it does nothing.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType, TracebackType
from typing import Any

#: The signals a registering command stops on.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopSignals:
    """Context manager: SIGINT and SIGTERM stop the command (see the module docstring).

    Args:
        raise_interrupt: raise KeyboardInterrupt on the first signal (else only set ``fired``).
    """

    def __init__(self, raise_interrupt: bool = True) -> None:
        self.raise_interrupt = raise_interrupt
        self.fired: int | None = None   # the first signal received, if any
        self._previous: dict[int, Any] = {}
        self._held = False
        self._delivered = False

    def _handler(self, signum: int, _frame: FrameType | None) -> None:
        if self.fired is not None:
            return   # already stopping: let the clean-up finish
        self.fired = signum
        if self.raise_interrupt and not self._held:
            self._delivered = True
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def holding(self, deliver: bool = True) -> Iterator[None]:
        """A signal during the block waits for its end; with ``deliver`` it then raises
        KeyboardInterrupt (registering), else it only stays in :attr:`fired` (unregistering)."""
        outer = self._held
        self._held = True
        try:
            yield
        finally:
            self._held = outer
        if (deliver and not outer and self.raise_interrupt and self.fired is not None
                and not self._delivered):
            self._delivered = True
            raise KeyboardInterrupt

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                self._previous[sig] = signal.getsignal(sig)
                signal.signal(sig, self._handler)
            _active.append(self)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous if previous is not None else signal.SIG_DFL)
        if self._previous and _active and _active[-1] is self:
            _active.pop()
        self._previous.clear()


_active: list[StopSignals] = []


def holding(deliver: bool = True) -> contextlib.AbstractContextManager[None]:
    """:meth:`StopSignals.holding` of the command's active handlers (nothing without them)."""
    return _active[-1].holding(deliver) if _active else contextlib.nullcontext()



def deliver_held() -> None:
    """Raise the KeyboardInterrupt of a signal that came while held (call it first thing in the
    ``try`` whose ``finally`` unregisters)."""
    stop = _active[-1] if _active else None
    if stop is not None and stop.raise_interrupt and stop.fired is not None and not stop._delivered:
        stop._delivered = True
        raise KeyboardInterrupt
