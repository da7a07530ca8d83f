"""Errors of the TCPROS layer.

Every problem the codecs or the handshake machines detect is a :class:`ProtocolError`
(a :class:`~rosfpga_lab.errors.LabError`). ``local`` tells who broke the protocol: ``True``
when the *peer* sent bytes we refuse (we detected it here), ``False`` when the peer told us
it refused *our* request with an ``error=`` header (:class:`RemoteError`).
"""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class ProtocolError(LabError):
    """A TCPROS protocol violation.

    Attributes:
        offset: byte offset in the stream (or header) where the problem was found, if known.
        local: True when we detected the problem in the peer's bytes; False when the peer
            reported an error to us.
    """

    local = True

    def __init__(self, message: str, *, offset: int | None = None) -> None:
        super().__init__(message)
        self.offset = offset
        #: results decoded from the same input *before* the problem (frame bodies for a
        #: FrameDecoder, events for a handshake machine): deliver them, nothing good is lost
        self.partial: list = []


class HeaderFormatError(ProtocolError):
    """A connection header that cannot be decoded (bad length, field without '=', not UTF-8)."""


class FrameError(ProtocolError):
    """A message frame that cannot be decoded (length over the limit)."""


class IncompleteError(ProtocolError):
    """The stream ended (EOF) in the middle of a header or a frame."""


class HandshakeRejected(ProtocolError):
    """The peer's connection header is well-formed but unacceptable (missing field, md5 mismatch)."""


class RemoteError(ProtocolError):
    """The peer answered our connection header with an ``error=`` header."""

    local = False


class HandshakeTimeout(ProtocolError):
    """The peer did not complete its connection header within the time-out."""


class StateError(ProtocolError):
    """The handshake machine was asked to do something its transition table does not allow."""
