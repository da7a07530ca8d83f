"""Limits and defaults of the rtps layer, in one place."""

from __future__ import annotations

#: Largest sample :class:`FragmentAssembler` puts together, and most samples it holds at once.
MAX_SAMPLE_BYTES = 64 * 1024 * 1024
MAX_PENDING_SAMPLES = 16
