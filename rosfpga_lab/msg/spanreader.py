"""The plain reader both wire formats' layouts build on: a body read field by field, one
:class:`~rosfpga_lab.msg.span.Span` recorded per value.

:mod:`rosfpga_lab.msg.layout` (TCPROS, ROS 1) and :mod:`rosfpga_lab.msg.cdr` (CDR, ROS 2) each
subclass :class:`SpanReader` with their format's rules (length prefixes, strings, alignment);
taking bytes, numeric arrays and the end of a read (an ``error`` span in partial mode, a
``trailing`` span or a refusal for bytes left over) are the same for both and live here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.decode import too_long
from rosfpga_lab.msg.errors import DeserializeError
from rosfpga_lab.msg.limits import MsgLimits
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.span import ROLE_ARRAY, ROLE_ERROR, ROLE_TRAILING, Span


class SpanReader:
    """Takes bytes from a body in order and records spans; subclasses read the fields.

    Args:
        reg: the registry holding the types.
        data: the body (a subclass's :meth:`hold` decides whether it is copied or viewed).
        limits: limits on declared lengths.
        element_spans: numeric arrays longer than this get one ``array`` span.
    """

    #: what ran out, in "... ends early" errors ("message", "payload")
    body = "message"

    def __init__(self, reg: MsgRegistry, data: Any, limits: MsgLimits, element_spans: int) -> None:
        self.reg = reg
        self.data = self.hold(data)
        self.pos = 0
        self.limits = limits
        self.element_spans = element_spans
        self.spans: list[Span] = []

    @staticmethod
    def hold(data: Any) -> bytes | memoryview:
        """The body as this reader keeps it (default: a copy, so spans outlive the caller's buffer)."""
        return bytes(data)

    @property
    def left(self) -> int:
        """Bytes not read yet."""
        return len(self.data) - self.pos

    def _take(self, size: int, path: str, what: str) -> bytes | memoryview:
        if size > self.left:
            raise DeserializeError(
                f"{self.body} ends early: {what} at byte offset {self.pos} needs {size} byte(s), "
                f"only {self.left} left (field {path})", path, self.pos)
        chunk = self.data[self.pos:self.pos + size]
        self.pos += size
        return chunk

    def check_length(self, path: str, start: int, n: int, elem_min: int, limit: int,
                     limit_name: str) -> int:
        """``n``, the length prefix read at ``start``; refused over ``limit`` or when ``n``
        elements of at least ``elem_min`` bytes cannot fit in the bytes left."""
        if n > limit:
            raise DeserializeError(f"field {path}: length prefix at byte offset {start} declares "
                                   f"{n}, more than {limit_name}={limit}", path, start)
        if n * elem_min > self.left:
            raise too_long(path, start, n, elem_min, self.left, limit_name)
        return n

    def align(self, size: int, path: str) -> None:
        """Skip the padding before a ``size``-byte value (none in TCPROS)."""

    def scalar_array(self, base: str, type_: str, n: int, path: str) -> Any:
        """``n`` numeric elements of ``base``: one ``array`` span when there are more than
        ``element_spans`` of them, else a span each (via the subclass's ``element``)."""
        if n > self.element_spans:
            dtype = SCALARS[base].dtype
            self.align(dtype.itemsize, path)
            start = self.pos
            arr = np.frombuffer(self._take(n * dtype.itemsize, path, f"{n} x {base}"), dtype)
            arr = arr.astype(bool) if base == "bool" else arr
            self.spans.append(Span(start, self.pos - start, path, type_, arr, ROLE_ARRAY))
            return arr
        items = [self.element(base, f"{path}[{i}]") for i in range(n)]
        return np.array(items, dtype=bool if base == "bool" else SCALARS[base].dtype)

    def element(self, base: str, path: str) -> Any:
        """One element of type ``base`` (the subclass's rules)."""
        raise NotImplementedError

    def read(self, type_name: str, allow_trailing: bool, partial: bool,
             start: Any = None) -> tuple[dict | None, list[Span]]:
        """Read one ``type_name`` (after ``start()``, e.g. an encapsulation header), then the end.

        ``partial``: never raise on bad bytes; the undecodable rest gets one ``error`` span
        whose value is the error message. Bytes after the message are refused unless
        ``allow_trailing`` or ``partial`` (then they get a ``trailing`` span).
        """
        try:
            if start is not None:
                start()
            value: dict | None = self.message(type_name)
        except DeserializeError as exc:
            if not partial:
                raise
            at = self.spans[-1].end if self.spans else 0
            self.spans.append(Span(at, len(self.data) - at, exc.path, "error", str(exc),
                                   ROLE_ERROR))
            return None, self.spans
        rest = self.left
        if rest:
            if not (allow_trailing or partial):
                raise DeserializeError(
                    f"{rest} byte(s) left over after a complete {self.reg.resolve(type_name)} at "
                    f"byte offset {self.pos} (pass allow_trailing=True to ignore)", "", self.pos)
            self.spans.append(Span(self.pos, rest, "", "uint8[]", bytes(self.data[self.pos:]),
                                   ROLE_TRAILING))
        return value, self.spans

    def message(self, type_name: str, prefix: str = "") -> dict:
        """The fields of one ``type_name`` (the subclass's rules)."""
        raise NotImplementedError
