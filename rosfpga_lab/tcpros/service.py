"""TCPROS services, sans-IO: the two ends of a service connection (bytes in, events out).

How it works (as rospy and roscpp speak it): the client connects to the server's
``rosrpc://host:port``, sends a connection header (``callerid``, ``md5sum``, ``service``, and
``persistent=1`` or ``probe=1`` when it wants them); the server answers with its header
(``callerid``, ``md5sum``, ``request_type``, ``response_type``, ``type``) or an ``error=``
header and closes. A probe (``rosservice type``/``info``) gets the header only. Then each call
is one request frame (4-byte length, body) and one response: an ``ok`` byte, then a frame
holding the response body (ok=1) or the error text (ok=0). A non-persistent client makes one
call per connection. Limits are the topic side's: the header (``max_header``/``max_field``)
and every body (``max_frame``), checked when a length arrives, before its bytes do.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rosfpga_lab.tcpros.errors import FrameError, ProtocolError
from rosfpga_lab.tcpros.frame import FrameDecoder, encode_frame
from rosfpga_lab.tcpros.header import HeaderDecoder, encode_error_header, encode_header
from rosfpga_lab.tcpros.limits import MAX_FIELD_BYTES, MAX_FRAME_BYTES, MAX_HEADER_BYTES


#: what a client's ``persistent`` field may say to keep the connection (lower-cased): rospy's
#: ``ServiceImpl.handle`` takes ``'1'`` and ``'true'`` in any case, roscpp ``"1"`` and ``"true"``
PERSISTENT_VALUES = ("1", "true")
#: the fields a client's header must have, in the order rospy's ``service_connection_handler``
#: checks them (its refusal names the first one missing)
REQUIRED_CLIENT_FIELDS = ("service", "md5sum", "callerid")


@dataclass(frozen=True)
class ServiceSpec:
    """What a service server answers a client's header with."""

    service: str
    type_name: str
    md5sum: str
    request_type: str
    response_type: str


@dataclass(frozen=True)
class ServiceHeader:
    """The peer's connection header arrived (``raw``: its bytes)."""

    fields: dict[str, str]
    raw: bytes


@dataclass(frozen=True)
class ServiceAccepted:
    """Server side: send ``reply`` (our header); ``probe``: then close."""

    reply: bytes
    probe: bool
    persistent: bool


@dataclass(frozen=True)
class ServiceRejected:
    """The header was refused: ``reply`` (server side) is the ``error=`` header to send, then
    close; on the client side ``reply`` is empty and ``error`` is the server's text."""

    error: str
    reply: bytes = b""


@dataclass(frozen=True)
class ServiceRequest:
    """Server side: one request body (no length prefix)."""

    body: bytes


@dataclass(frozen=True)
class ServiceResponse:
    """Client side: the answer: ``ok`` and the response body, or the error text when not ok."""

    ok: bool
    body: bytes


@dataclass(frozen=True)
class ServiceClosed:
    """The peer closed (``error``: what was cut short, "" for a clean close)."""

    error: str = ""


ServiceEvent = ServiceHeader | ServiceAccepted | ServiceRejected | ServiceRequest | ServiceResponse | ServiceClosed


def service_reply_fields(callerid: str, spec: ServiceSpec) -> dict[str, str]:
    """The server's header fields (rospy's and roscpp's keys)."""
    return {"callerid": callerid, "md5sum": spec.md5sum, "request_type": spec.request_type,
            "response_type": spec.response_type, "type": spec.type_name}


def service_request_fields(callerid: str, service: str, md5sum: str, *, type_name: str = "",
                           persistent: bool = False, probe: bool = False) -> dict[str, str]:
    """The client's header fields."""
    fields = {"callerid": callerid, "md5sum": md5sum, "service": service}
    if type_name:
        fields["type"] = type_name
    if persistent:
        fields["persistent"] = "1"
    if probe:
        fields["probe"] = "1"
    return fields


def encode_response(ok: bool, body: bytes | str) -> bytes:
    """One response on the wire: the ok byte, then the body (or the error text) as a frame."""
    data = body.encode() if isinstance(body, str) else body
    return (b"\x01" if ok else b"\x00") + encode_frame(data)


class ServiceServerConnection:
    """The server end of one service connection.

    Args:
        callerid: our node name.
        lookup: service name -> its :class:`ServiceSpec`, or None when not served here.
    """

    def __init__(self, callerid: str, lookup: Callable[[str], ServiceSpec | None], *,
                 max_header: int = MAX_HEADER_BYTES, max_field: int = MAX_FIELD_BYTES,
                 max_frame: int = MAX_FRAME_BYTES) -> None:
        self.callerid = callerid
        self.lookup = lookup
        self._header = HeaderDecoder(max_header=max_header, max_field=max_field)
        self._frames = FrameDecoder(max_frame=max_frame)
        self.spec: ServiceSpec | None = None
        self.done = False

    def receive_data(self, data: bytes) -> list[ServiceEvent]:
        """Feed bytes from the client.

        Raises:
            ProtocolError: (HeaderFormatError, FrameError) a header or body over its limit or
                malformed; close the connection.
        """
        if self.done:
            return []
        events: list[ServiceEvent] = []
        if self.spec is None:
            fields = self._header.feed(data)
            if fields is None:
                return events
            events.append(ServiceHeader(fields, self._header.raw))
            error = self._check(fields)
            if error:
                self.done = True
                events.append(ServiceRejected(error, encode_error_header(error)))
                return events
            assert self.spec is not None
            probe = fields.get("probe") == "1"
            events.append(ServiceAccepted(encode_header(service_reply_fields(self.callerid, self.spec)),
                                          probe, fields.get("persistent", "").lower() in PERSISTENT_VALUES))
            if probe:
                self.done = True
                return events
            data = self._header.remainder
        events.extend(ServiceRequest(bytes(body)) for body in self._frames.feed(data))
        return events

    def _check(self, fields: dict[str, str]) -> str:
        for required in REQUIRED_CLIENT_FIELDS:
            if required not in fields:
                return f"Missing required '{required}' field"
        service = fields["service"]
        spec = self.lookup(service)
        if spec is None:
            return f"no provider for service [{service}] in {self.callerid}"
        md5 = fields.get("md5sum", "")
        if md5 not in ("*", spec.md5sum):
            return (f"request from [{fields.get('callerid', '?')}]: md5sums do not match: "
                    f"[{md5}] vs. [{spec.md5sum}]")
        self.spec = spec
        return ""

    def receive_eof(self) -> list[ServiceEvent]:
        """The client closed its end."""
        self.done = True
        try:
            self._frames.eof()
        except (ProtocolError, FrameError) as exc:
            return [ServiceClosed(str(exc))]
        return [ServiceClosed("" if self._header.done else "closed before its header")]


class ServiceClientConnection:
    """The client end of one service connection.

    Args:
        callerid: our node name.
        service: the service's global name.
        md5sum: the service type's md5 (``"*"``: any, as a probe sends).
        persistent: keep the connection for several calls.
        probe: ask for the server's header only.
    """

    def __init__(self, callerid: str, service: str, md5sum: str, *, type_name: str = "",
                 persistent: bool = False, probe: bool = False,
                 max_header: int = MAX_HEADER_BYTES, max_field: int = MAX_FIELD_BYTES,
                 max_frame: int = MAX_FRAME_BYTES) -> None:
        self.md5sum = md5sum
        self.request_header = encode_header(service_request_fields(
            callerid, service, md5sum, type_name=type_name, persistent=persistent, probe=probe))
        self._header = HeaderDecoder(max_header=max_header, max_field=max_field)
        self.max_frame = max_frame
        self._buf = bytearray()  # grows with the bytes received, never with a declared length
        self.fields: dict[str, str] | None = None
        self.failed = ""

    @staticmethod
    def request(body: bytes) -> bytes:
        """One request on the wire (send after :attr:`request_header`)."""
        return encode_frame(body)

    def receive_data(self, data: bytes) -> list[ServiceEvent]:
        """Feed bytes from the server.

        Raises:
            ProtocolError: a header or response over its limit or malformed.
        """
        events: list[ServiceEvent] = []
        if self.failed:
            return events
        if self.fields is None:
            fields = self._header.feed(data)
            if fields is None:
                return events
            self.fields = fields
            events.append(ServiceHeader(fields, self._header.raw))
            if "error" in fields:
                self.failed = fields["error"]
                return [*events, ServiceRejected(self.failed)]
            theirs = fields.get("md5sum", "")
            if self.md5sum != "*" and theirs not in ("*", self.md5sum):
                self.failed = f"md5sums do not match: [{self.md5sum}] vs. [{theirs}]"
                return [*events, ServiceRejected(self.failed)]
            data = self._header.remainder
        self._buf += data
        while len(self._buf) >= 5:  # ok byte, 4-byte length, body: one response at a time
            length = int.from_bytes(self._buf[1:5], "little")
            if length > self.max_frame:
                raise FrameError(f"service response of {length} bytes is over the limit of "
                                 f"{self.max_frame} (tcpros.limits.MAX_FRAME_BYTES)")
            if len(self._buf) < 5 + length:
                break
            events.append(ServiceResponse(self._buf[0] == 1, bytes(self._buf[5:5 + length])))
            del self._buf[:5 + length]
        return events

    def receive_eof(self) -> list[ServiceEvent]:
        """The server closed."""
        if self.fields is None:
            return [ServiceClosed("the service closed the connection before its header")]
        if self._buf:
            return [ServiceClosed("the service closed the connection inside a response")]
        return [ServiceClosed()]
