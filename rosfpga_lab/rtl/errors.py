"""The RTL layer's errors."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class RtlError(LabError):
    """A configuration the RTL cannot be built for, or a failed build or simulation."""


class SimulatorMissingError(RtlError):
    """No Verilog simulator (Icarus Verilog or Verilator) on this machine."""


class VcdError(RtlError):
    """A waveform dump cannot be read: not a VCD, malformed, or past the reader's limits."""


class SynthError(RtlError):
    """Synthesis could not run (no Yosys) or Yosys refused the RTL (the message quotes it)."""


class TimingError(RtlError):
    """Place and route could not run (no Yosys or nextpnr) or failed (the message quotes it)."""
