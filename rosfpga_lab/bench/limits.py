"""Limits and defaults of the benchmark layer, in one place."""

from __future__ import annotations

#: Seconds to wait for a middle to register, and for its first frame.
START_TIMEOUT = 20.0
#: Seconds without an output before in-flight frames count as lost (sustained phase).
STALL_TIMEOUT = 1.0
#: Seconds one sustained run may take at most, whatever its frame count.
SUSTAINED_MAX_SECONDS = 15.0
#: Seconds a system tool asked for facts (``dpkg -L``, ``lscpu``) may take.
TOOL_TIMEOUT = 20.0
