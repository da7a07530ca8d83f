"""Helpers for tests that start the lab's commands as processes."""

from __future__ import annotations

import signal
import subprocess


def interruptible() -> None:
    """``preexec_fn`` that gives the child the default SIGINT (so Python turns it into
    KeyboardInterrupt, as at a terminal's Ctrl-C). A shell running the suite as a background job
    starts it with SIGINT ignored, and children inherit that: a test that sends SIGINT would
    then wait for a process that never hears it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def stop_with(proc: subprocess.Popen, sig: int, timeout: float = 20.0) -> tuple[str, str]:
    """Send ``sig`` to ``proc`` and return its output once it ended; a process still running
    after ``timeout`` seconds is killed and reaped (and the time-out raised)."""
    try:
        proc.send_signal(sig)
        return proc.communicate(timeout=timeout)
    finally:
        kill_if_running(proc)


def kill_if_running(proc: subprocess.Popen) -> None:
    """Kill and reap ``proc`` when a test ends before it did."""
    if proc.poll() is None:
        proc.kill()
        proc.communicate()
