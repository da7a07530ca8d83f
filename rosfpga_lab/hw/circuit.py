"""A node configuration's circuit layouts, derived once: what every model of its circuit reads.

How this works: :func:`circuit_layouts` derives, from one loaded configuration, the layout of
its subscribed type (:func:`~rosfpga_lab.hw.layout.layout_from_config`, with Image's video
shape), the published type's when it differs, the CDR walks when asked for
(:func:`~rosfpga_lab.hw.cdrlayout.cdr_layout_from_config`, derived on first use: a ROS 1 node
never needs them) and the field the publisher numbers (:func:`numbered_field`), and keeps them
in one :class:`CircuitLayouts` per configuration object (the same object asked again gets the
same record; a configuration loaded again, a ``.msg`` edited in between, gets a new one). The
models (:class:`~rosfpga_lab.hw.msgpipeline.MessagePipeline`,
:class:`~rosfpga_lab.hw.cdrpipeline.CdrPipeline`) take it; the circuit record of the layers
above (:func:`rosfpga_lab.hls.circuit.circuit_of`: the program and the HLS project's spec
besides) holds it.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Generic, TypeVar

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.config.limits import IMAGE_TYPE
from rosfpga_lab.hw.cdrlayout import CdrLayout, cdr_layout_from_config
from rosfpga_lab.hw.layoutderive import layout_from_config
from rosfpga_lab.hw.layoutsteps import Layout, VideoShape
from rosfpga_lab.msg import MsgRegistry

#: The field a ``sensor_msgs/Image`` publisher on TCPROS numbers itself (1, 2, 3 ... over the
#: frames it publishes) instead of re-sending it, as rospy does and as the lab's Image circuit
#: always has (the generated one: ``hls.compiler.program_from_layout(count=...)``).
NUMBERED_FIELD = "header.seq"
#: The layout idents of ``header.stamp`` (seconds, nanoseconds) whose values a result reports as
#: its frame's stamp (``MessageResult.stamp``), for any type with a ``std_msgs/Header``.
STAMP_FIELDS = ("header_stamp_secs", "header_stamp_nsecs")

#: Configurations whose records are kept (the newest; a notebook loads a few).
_KEPT = 16


def numbered_field(config: NodeConfig) -> str | None:
    """The label of the field ``config``'s TCPROS publisher numbers itself: :data:`NUMBERED_FIELD`
    for ``sensor_msgs/Image``, else None (every other field is re-sent as received; a CDR walk
    has no ``header.seq``)."""
    if config.is_image and config.publisher.type == IMAGE_TYPE:
        return NUMBERED_FIELD
    return None


@dataclass(frozen=True, eq=False)
class CircuitLayouts:
    """One configuration's circuit, as layouts (see the module docstring).

    Attributes:
        config: the configuration.
        reg: its registry (``config.registry()``, loaded once).
        layout: the subscribed type's TCPROS layout (``layout.video``: Image's video shape).
        out_layout: the published type's layout when it is another type, else None.
        numbered: the label of the field the publisher numbers (:func:`numbered_field`).
    """

    config: NodeConfig
    reg: MsgRegistry
    layout: Layout
    out_layout: Layout | None
    numbered: str | None

    @property
    def video(self) -> VideoShape | None:
        """The stream's video shape (Image's ``width x height`` pixels), else None."""
        return self.layout.video

    @cached_property
    def cdr(self) -> CdrLayout:
        """The subscribed type's CDR walk (ROS 2), derived on first use.

        Raises:
            LayoutError: as :func:`~rosfpga_lab.hw.cdrlayout.cdr_layout_from_config`.
        """
        return cdr_layout_from_config(self.config, self.reg)

    @cached_property
    def out_cdr(self) -> CdrLayout | None:
        """The published type's CDR walk when it is another type, else None."""
        if self.config.publisher.type == self.config.subscriber.type:
            return None
        return cdr_layout_from_config(self.config, self.reg, output=True)


T = TypeVar("T")


class ConfigCache(Generic[T]):
    """One value per configuration object, built on first use: the same object asked again gets
    the same value; a configuration loaded again (a ``.msg`` edited in between) a new one. The
    newest ``kept`` are kept (a notebook loads a few).
    """

    def __init__(self, kept: int = _KEPT) -> None:
        self._kept = kept
        self._values: dict[int, tuple[weakref.ref[NodeConfig], T]] = {}
        self._lock = threading.Lock()

    def get(self, config: NodeConfig, build: Callable[[], T]) -> T:
        """The value of ``config``, ``build()`` when it has none yet (errors propagate; nothing
        is kept then)."""
        with self._lock:
            kept = self._values.get(id(config))
            if kept is not None and kept[0]() is config:
                return kept[1]
        value = build()
        with self._lock:
            self._values.pop(id(config), None)
            while len(self._values) >= self._kept:
                self._values.pop(next(iter(self._values)))
            self._values[id(config)] = (weakref.ref(config), value)
        return value


_records: ConfigCache[CircuitLayouts] = ConfigCache()


def circuit_layouts(config: NodeConfig, reg: MsgRegistry | None = None) -> CircuitLayouts:
    """The layouts of ``config``'s circuit, derived once per configuration object.

    Args:
        config: a loaded configuration.
        reg: its registry when the caller has loaded it (a record is then derived from it and
            not kept: the caller's registry may not be the configuration's own).

    Raises:
        LayoutError: a key of the configuration the type cannot take.
    """
    if reg is not None:
        return _derive(config, reg)
    return _records.get(config, lambda: _derive(config, config.registry()))


def _derive(config: NodeConfig, reg: MsgRegistry) -> CircuitLayouts:
    layout = layout_from_config(config, reg)
    out_layout = (layout_from_config(config, reg, output=True)
                  if config.publisher.type != config.subscriber.type else None)
    return CircuitLayouts(config, reg, layout, out_layout, numbered_field(config))


__all__ = ["NUMBERED_FIELD", "STAMP_FIELDS", "CircuitLayouts", "ConfigCache", "circuit_layouts", "numbered_field"]
