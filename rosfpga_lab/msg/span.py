"""Byte spans: the lab's one record of "these bytes are that field".

A :class:`Span` names ``data[offset:offset + size]``. The message layout
(:func:`rosfpga_lab.msg.field_layout`), the TCPROS header and frame parsers
(:func:`rosfpga_lab.tcpros.header_spans`, :func:`rosfpga_lab.tcpros.frame_spans`), the byte
viewers and the exercise checks all produce and read this one type.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

#: What a span's bytes are for (a viewer picks a fixed colour for some).
ROLE_LENGTH = "length"      # a uint32 length prefix
ROLE_VALUE = "value"        # a value
ROLE_ARRAY = "array"        # a block of array elements
ROLE_ERROR = "error"        # bytes that could not be parsed (the value says why)
ROLE_TRAILING = "trailing"  # bytes after a complete message or header
ROLE_PADDING = "padding"    # bytes between the fields of interest (e.g. XML around values)


@dataclass(frozen=True)
class Span:
    """One field's bytes: ``data[offset:offset + size]``.

    Attributes:
        offset: first byte of the field.
        size: number of bytes (0 for an empty array: it is listed but owns no byte).
        path: the field's name, e.g. ``header.stamp.secs``, ``data``, ``points[3].x``,
            ``callerid`` (a header field), ``frame length``.
        type: its type as text, e.g. ``uint32``, ``string``, ``uint8[]``, ``key=value``.
        value: the decoded value (any object).
        role: what the bytes are for (``ROLE_*``), e.g. ``length`` for a length prefix.
    """

    offset: int
    size: int
    path: str
    type: str = ""
    value: Any = None
    role: str = ""

    @property
    def end(self) -> int:
        """One past the last byte."""
        return self.offset + self.size

    @property
    def label(self) -> str:
        """A name for text: the path, with " length" added for a length prefix whose path does
        not say so (``data`` -> ``data length``); ``(trailing)`` and the like for an unnamed span."""
        name = self.path or f"({self.role})"
        if self.role == ROLE_LENGTH and not name.endswith("length"):
            return f"{name} length"
        return name

    def moved(self, by: int = 0, prefix: str = "") -> Span:
        """This span ``by`` bytes later, its path prefixed with ``prefix``."""
        return dataclasses.replace(self, offset=self.offset + by, path=prefix + self.path)
