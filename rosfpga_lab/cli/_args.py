"""Argument types shared by the sub-commands: a bad number is refused by argparse (exit code 2)."""

from __future__ import annotations

import argparse


def positive_int(text: str) -> int:
    """An integer of at least 1 (frames, counts, rounds, queue lengths)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"want a number of at least 1, got {value}")
    return value


def positive_float(text: str) -> float:
    """A number greater than 0 (seconds, rates, scales)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a number, got {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"want a number greater than 0, got {text}")
    return value


def non_negative_float(text: str) -> float:
    """A number of at least 0 (0 meaning 'off' where the option's help says so)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"want a number, got {text!r}") from None
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"want a number of at least 0, got {text}")
    return value
