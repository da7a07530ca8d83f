"""Limits of the generator layer, in one place (the circuit's own limits are the node
configuration's, :mod:`rosfpga_lab.config.limits`)."""

from __future__ import annotations

#: Seconds allowed for one C-simulation build and for one run.
BUILD_TIMEOUT = 300.0
RUN_TIMEOUT = 300.0
