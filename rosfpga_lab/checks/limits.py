"""Limits of the exercise checks, in one place."""

from __future__ import annotations

#: How many problems one failed check lists at most.
MAX_PROBLEMS = 5
#: Bytes compared when looking for a shifted stream, and the largest shift looked for.
SHIFT_WINDOW = 16
MAX_SHIFT = 8
#: Exercise 3.3: how far (bytes) from its field a wrongly read value is looked for.
MAX_READ_SHIFT = 16
