"""Typed errors of the hardware-model layer, all under :class:`rosfpga_lab.errors.LabError`.

Every error names the stage that found it; frame errors also name the field (of
``sensor_msgs/Image`` or of any type's layout, e.g. ``history[1].sensor_name length``) and the
byte offset in the TCPROS frame (offset 0 is the first byte of the 4-byte frame
length). After any of these errors the stage (and the :class:`~rosfpga_lab.hw.MessagePipeline`) has
reset itself: the next good frame comes out right.
"""

from __future__ import annotations

from typing import Any

from rosfpga_lab.errors import LabError


class PipelineError(LabError):
    """Base class of every error the hardware models raise on purpose.

    Attributes:
        stage: name of the stage that found the problem (``"interpreter"``, ``"fifo2axi"`` ...).
        partial: whatever the stage had produced so far (an image, beats, bytes) or ``None``;
            notebooks show it to make a fault visible.
    """

    def __init__(self, message: str, stage: str = "", partial: Any = None) -> None:
        self.stage = stage
        self.partial = partial
        super().__init__(f"{stage}: {message}" if stage else message)


class PipelineConfigError(PipelineError):
    """A :class:`Pipeline` or stage was configured with impossible values (the message names it)."""


class FrameFieldError(PipelineError):
    """A field of the incoming frame has a value the circuit refuses.

    Attributes:
        field: the field name (``"height"``, ``"encoding"``, ``"data length"`` ...).
        offset: byte offset of the field's first byte in the TCPROS frame.
        value: the decoded value.
        rule: the rule the value broke, in a few words without the value (``"over the limit"``,
            ``"not what the circuit was built for"`` ...): refusals count by :attr:`kind`.
    """

    #: The rule when the raiser names none.
    default_rule = "value refused"

    def __init__(self, message: str, field: str, offset: int, value: Any = None,
                 stage: str = "interpreter", *, rule: str = "") -> None:
        self.field = field
        self.offset = offset
        self.value = value
        self.rule = rule or self.default_rule
        super().__init__(f"field {field!r} at byte {offset}: {message}", stage)

    @property
    def kind(self) -> str:
        """``"field: rule"``: the same for every frame that broke the same rule, whatever its value."""
        return f"{self.field}: {self.rule}"


class UnsupportedEncodingError(FrameFieldError):
    """The frame's ``encoding`` is not one the circuit packs (see ``hw.PIXEL_FORMATS``)."""

    default_rule = "unsupported encoding"


class FrameTruncatedError(FrameFieldError):
    """The frame ended (or its ``frame length`` ran out) before the named field was complete."""

    default_rule = "cut short"


class FrameLengthError(FrameFieldError):
    """The 4-byte frame length disagrees with the message it announces."""

    default_rule = "frame length disagrees"


class StreamStarvedError(PipelineError):
    """A stage needed another byte or beat and its input stream was empty.

    In the circuit the stage would wait for ever (a hang); the model reports it instead.

    Attributes:
        needed: how many items the stage needed in total.
        got: how many it had read when the stream ran dry.
    """

    def __init__(self, message: str, stage: str, needed: int, got: int, partial: Any = None) -> None:
        self.needed = needed
        self.got = got
        super().__init__(message, stage, partial)


class LayoutError(PipelineConfigError):
    """A circuit layout cannot be derived: a key names a missing field or one it cannot take.

    Attributes:
        key: the configuration key at fault, dotted (``stream.field``, ``checks.height``,
            ``limits.points``), so a configuration loader can point at its line.
    """

    def __init__(self, message: str, key: str = "") -> None:
        self.key = key
        super().__init__(f"{key}: {message}" if key else message, "layout")
