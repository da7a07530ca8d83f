"""Helpers for tests that start the lab's commands as processes."""

from __future__ import annotations

import signal


def interruptible() -> None:
    """``preexec_fn`` that gives the child the default SIGINT (so Python turns it into
    KeyboardInterrupt, as at a terminal's Ctrl-C). A shell running the suite as a background job
    starts it with SIGINT ignored, and children inherit that: a test that sends SIGINT would
    then wait for a process that never hears it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
