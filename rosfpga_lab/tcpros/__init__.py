"""TCPROS, sans-IO: connection-header and frame codecs and the handshake state machines.

Nothing here touches a socket or a thread: feed bytes, get events (see ``handshake``); the
``graph`` layer does the I/O. Byte layouts match rospy and roscpp exactly (fields sorted by key).
The handshake is two state machines, publisher and subscriber, driven by one table,
:data:`TRANSITIONS`, which the notebooks draw (``widgets.StateDiagram(tcpros.TRANSITIONS)``).
Sizes and the handshake's time-out are the constants of module ``limits``; services (request
and response over TCPROS) are module ``service``.
"""

from rosfpga_lab.tcpros.errors import (
    FrameError,
    HandshakeRejected,
    HandshakeTimeout,
    HeaderFormatError,
    IncompleteError,
    ProtocolError,
    RemoteError,
    StateError,
)
from rosfpga_lab.tcpros.limits import (
    HANDSHAKE_TIMEOUT,
    MAX_FIELD_BYTES,
    MAX_FRAME_BYTES,
    MAX_HEADER_BYTES,
)
from rosfpga_lab.tcpros.frame import FrameDecoder, encode_frame, frame_prefix, frame_spans
from rosfpga_lab.tcpros.handshake import (
    ANY,
    STATES,
    TRANSITIONS,
    Closed,
    Connected,
    Frame,
    HeaderReceived,
    PublisherHandshake,
    Rejected,
    Role,
    State,
    SubscriberHandshake,
    TopicSpec,
    Transition,
    Trigger,
    check_publisher_header,
    check_subscriber_header,
    publisher_reply_fields,
    subscriber_request_fields,
)
from rosfpga_lab.tcpros.service import (
    ServiceClientConnection,
    ServiceServerConnection,
    ServiceSpec,
)
from rosfpga_lab.tcpros.header import (
    HeaderDecoder,
    decode_header,
    encode_error_header,
    encode_header,
    header_spans,
    parse_fields,
)

__all__ = [
    "ANY", "HANDSHAKE_TIMEOUT", "MAX_FIELD_BYTES", "MAX_FRAME_BYTES", "MAX_HEADER_BYTES",
    "STATES", "TRANSITIONS", "Closed", "Connected", "Frame", "FrameDecoder", "FrameError",
    "HandshakeRejected", "HandshakeTimeout", "HeaderDecoder", "HeaderFormatError",
    "HeaderReceived", "IncompleteError", "ProtocolError", "PublisherHandshake", "Rejected",
    "RemoteError", "Role", "ServiceClientConnection", "ServiceServerConnection", "ServiceSpec", "State", "StateError", "SubscriberHandshake", "TopicSpec", "Transition",
    "Trigger",
    "check_publisher_header", "check_subscriber_header", "decode_header", "encode_error_header",
    "encode_frame", "encode_header", "frame_prefix", "frame_spans", "header_spans", "parse_fields", "publisher_reply_fields",
    "subscriber_request_fields",
]
