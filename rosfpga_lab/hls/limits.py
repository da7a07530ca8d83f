"""Limits of the generator layer, in one place (the circuit's own limits are the node
configuration's, :mod:`rosfpga_lab.config.limits`)."""

from __future__ import annotations

#: Seconds allowed for one C-simulation build and for one run.
BUILD_TIMEOUT = 300.0
RUN_TIMEOUT = 300.0
#: Largest carry memory a generated project holds (bytes kept of one frame for the publisher:
#: carried strings and arrays at their maxima). Beyond it the configuration's ``limits:`` must
#: lower the maxima (a C simulation copies the memory by value; an FPGA has a few MB of RAM).
MAX_CARRY_BYTES = 256 * 1024
#: Deepest nesting of arrays of messages (loops) a generated walk may have (the walkers' stacks).
MAX_LOOP_DEPTH = 8
