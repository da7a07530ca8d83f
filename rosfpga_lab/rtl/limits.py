"""Limits and defaults of the rtl layer, in one place."""

from __future__ import annotations

#: Seconds allowed for one build and for one run.
BUILD_TIMEOUT = 600.0
RUN_TIMEOUT = 900.0

#: Seconds allowed for one synthesis.
SYNTH_TIMEOUT = 1800.0
