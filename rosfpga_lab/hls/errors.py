"""Typed errors of the HLS layer (generator, C simulation); configuration errors are ``rosfpga_lab.config.ConfigError``."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class HlsError(LabError):
    """Base class of every error the ``hls`` layer raises on purpose."""


class GenerateError(HlsError):
    """The generator refuses to write (e.g. the output directory holds other files)."""


class CsimError(HlsError):
    """Building or running the C-simulation testbench failed (the message quotes g++ or it)."""
