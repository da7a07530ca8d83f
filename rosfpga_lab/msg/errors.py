"""Typed errors of the message layer, all under :class:`rosfpga_lab.errors.LabError`."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class MsgError(LabError):
    """Base class of every error the message layer raises on purpose."""


class MsgDefinitionError(MsgError):
    """A ``.msg`` text is malformed (the message names file, line and reason).

    Attributes:
        source: file path or label of the definition (``None`` if unknown).
        line: 1-based line number (``None`` when the problem is not on one line).
        reason: what is wrong, without the location.
    """

    def __init__(self, reason: str, source: str | None = None, line: int | None = None,
                 text: str | None = None) -> None:
        self.reason = reason
        self.source = source
        self.line = line
        where = source or "<string>"
        if line is not None:
            where = f"{where}:{line}"
        message = f"{where}: {reason}"
        if text is not None:
            message += f"\n    {text.rstrip()!s}"
        super().__init__(message)


class UnknownTypeError(MsgError):
    """A message type could not be found (the message says what and where it looked).

    Attributes:
        type_name: the name that was looked up.
        searched: human-readable list of the places searched.
    """

    def __init__(self, message: str, type_name: str = "", searched: tuple[str, ...] = ()) -> None:
        self.type_name = type_name
        self.searched = searched
        super().__init__(message)


class SerializeError(MsgError):
    """A Python value cannot be serialized as the declared field type.

    Attributes:
        path: field path such as ``header.stamp.secs`` or ``points[3].x``.
        expected: the ROS type expected there.
    """

    def __init__(self, message: str, path: str = "", expected: str = "") -> None:
        self.path = path
        self.expected = expected
        super().__init__(message)


class DeserializeError(MsgError):
    """Bytes do not decode as the message type (truncated, over-long, or over a limit).

    Attributes:
        path: field path being decoded when the problem was found.
        offset: byte offset in the message body where the problem was found.
    """

    def __init__(self, message: str, path: str = "", offset: int = 0) -> None:
        self.path = path
        self.offset = offset
        super().__init__(message)
