"""Typed errors of the RTPS decoder, all under :class:`rosfpga_lab.errors.LabError`."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class RtpsError(LabError):
    """Bytes that are not a well-formed RTPS message.

    Attributes:
        offset: byte offset in the datagram where the problem is.
    """

    def __init__(self, message: str, offset: int = 0) -> None:
        self.offset = offset
        super().__init__(message)


class RtpsTruncatedError(RtpsError):
    """The datagram ends inside the header, a submessage or a field."""
