"""Argument types shared by the sub-commands: a bad number is refused by argparse (exit code 2)."""

from __future__ import annotations

import argparse
from collections.abc import Callable


def positive_int(text: str) -> int:
    """An integer of at least 1 (frames, counts, rounds, queue lengths)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"want a number of at least 1, got {value}")
    return value


def _float(text: str, ok: Callable[[float], bool], want: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a number, got {text!r}") from None
    if not ok(value) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"want a number {want}, got {text}")
    return value


def positive_float(text: str) -> float:
    """A number greater than 0 (seconds, rates, scales)."""
    return _float(text, lambda v: v > 0, "greater than 0")


def non_negative_float(text: str) -> float:
    """A number of at least 0 (0 meaning 'off' where the option's help says so)."""
    return _float(text, lambda v: v >= 0, "of at least 0")
