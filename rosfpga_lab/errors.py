"""The root of every error the lab raises on purpose.

Each layer defines its own subclasses (``MsgDefinitionError`` in ``msg``, ``ProtocolError`` in
``tcpros``, ``PipelineError`` in ``hw`` ...). Catching ``LabError`` therefore catches every
problem the lab diagnosed itself, and nothing else: a bare ``ValueError`` or ``KeyError``
escaping the library is a bug.
"""

from __future__ import annotations


class LabError(Exception):
    """Base class of all errors raised deliberately by rosfpga_lab.

    The message says what went wrong, where (file:line, field, byte offset) and, when it
    helps, what to do about it.
    """
