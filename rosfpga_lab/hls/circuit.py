"""The circuit record: one object per node configuration holding everything its circuit is
rendered from.

How this works: :func:`circuit_of` builds, once per configuration object, a :class:`Circuit`
holding the configuration's layouts (:class:`~rosfpga_lab.hw.circuit.CircuitLayouts`: the
TCPROS layout with Image's video shape, the published type's, the CDR walks, the field the
publisher numbers), and, derived on first use and kept, the generated project's
:class:`~rosfpga_lab.hls.generic.GenericSpec` (:func:`~rosfpga_lab.hls.generic.spec_from_layouts`)
and its walkers' :class:`~rosfpga_lab.hls.program.Program`. The Python models take it
(:meth:`Circuit.model`: :class:`~rosfpga_lab.hw.msgpipeline.MessagePipeline` on TCPROS,
:class:`~rosfpga_lab.hw.cdrpipeline.CdrPipeline` on CDR), the HLS renderer its ``spec``, the
component its model and its program's clocks (:meth:`Circuit.frame_clocks`, the generated
circuit's, first byte in to last byte out; :meth:`Circuit.stream_clocks`, frames back to
back). The RTL tools can take it in place of ``spec_from_config`` (the same spec, derived
once).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hls.generic import GenericSpec, spec_from_layouts, stream_path
from rosfpga_lab.hls.program import FrameClocks, Program, frame_clocks, stream_clocks
from rosfpga_lab.hw.cdrlayout import CdrLayout
from rosfpga_lab.hw.cdrpipeline import CdrPipeline
from rosfpga_lab.hw.circuit import CircuitLayouts, ConfigCache, circuit_layouts
from rosfpga_lab.hw.layoutsteps import Layout, VideoShape
from rosfpga_lab.hw.msgpipeline import MessagePipeline
from rosfpga_lab.msg import MsgRegistry


@dataclass(frozen=True, eq=False)
class Circuit:
    """One configuration's circuit (see the module docstring).

    Attributes:
        layouts: the configuration's derived layouts.
    """

    layouts: CircuitLayouts

    @property
    def config(self) -> NodeConfig:
        """The configuration."""
        return self.layouts.config

    @property
    def reg(self) -> MsgRegistry:
        """Its registry (loaded once)."""
        return self.layouts.reg

    @property
    def layout(self) -> Layout:
        """The subscribed type's TCPROS layout."""
        return self.layouts.layout

    @property
    def cdr(self) -> CdrLayout:
        """The subscribed type's CDR walk (derived on first use)."""
        return self.layouts.cdr

    @property
    def video(self) -> VideoShape | None:
        """The stream's video shape (Image), else None."""
        return self.layouts.video

    @cached_property
    def spec(self) -> GenericSpec:
        """The generated project's spec (derived on first use, then kept).

        Raises:
            GenerateError: as :func:`~rosfpga_lab.hls.generic.spec_from_config`.
        """
        return spec_from_layouts(self.layouts)

    @property
    def program(self) -> Program:
        """The generated walkers' program (``spec.program``).

        Raises:
            GenerateError: as :attr:`spec`.
        """
        return self.spec.program

    def frame_clocks(self, frame: bytes) -> FrameClocks:
        """The generated circuit's clocks for one input ``frame`` (a TCPROS frame, or on CDR a
        record), first byte in to last byte out (:func:`~rosfpga_lab.hls.program.frame_clocks`,
        equal to the RTL's clock for clock).

        Raises:
            GenerateError: as :attr:`spec`.
            Refused: the circuit refuses the frame.
        """
        return frame_clocks(self.program, frame, latency=stream_path(self.spec))

    def stream_clocks(self, frames: list[bytes]) -> list[int]:
        """The generated circuit's clocks for ``frames`` back to back, no backpressure: for
        each, from the first frame's first byte in to its own last byte out
        (:func:`~rosfpga_lab.hls.program.stream_clocks`; the differences of consecutive ones
        are the clocks a frame costs in steady state).

        Raises:
            GenerateError: as :attr:`spec`.
            Refused: the circuit refuses a frame.
        """
        return stream_clocks(self.program, frames, latency=stream_path(self.spec))

    def model(self, model: str = "fast") -> MessagePipeline:
        """A fresh Python model of the TCPROS circuit (its own publisher count).

        Raises:
            PipelineConfigError: ``op: custom`` (no Python model of the user's C++).
        """
        return MessagePipeline.from_layouts(self.layouts, model)

    def cdr_model(self, model: str = "fast") -> CdrPipeline:
        """A fresh Python model of the CDR circuit.

        Raises:
            PipelineConfigError: as :class:`~rosfpga_lab.hw.cdrpipeline.CdrPipeline`.
        """
        return CdrPipeline(self.config, model, layouts=self.layouts)


_circuits: ConfigCache[Circuit] = ConfigCache()


def circuit_of(config: NodeConfig) -> Circuit:
    """The circuit record of ``config``, built once per configuration object (its layouts
    derived then, its spec and program on first use).

    Raises:
        LayoutError: a key of the configuration the type cannot take.
    """
    return _circuits.get(config, lambda: Circuit(circuit_layouts(config)))


__all__ = ["Circuit", "circuit_of"]
