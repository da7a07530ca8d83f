"""The ROS 1 message model: ``.msg`` definitions, md5 sums, full texts and the wire format.

Everything above this layer (TCPROS, the node, the hardware models, the generator, the byte
viewers) describes messages through it::

    from rosfpga_lab.msg import default_registry, serialize, deserialize, field_layout
    reg = default_registry()                      # shipped std_msgs, sensor_msgs, geometry_msgs
    reg.md5("sensor_msgs/Image")                  # '060021388200f6f0f447d0fcd9c64743'
    body = serialize(reg, "std_msgs/String", {"data": "hi"})   # b'\\x02\\x00\\x00\\x00hi'
    deserialize(reg, "std_msgs/String", body)     # {'data': 'hi'}
    field_layout(reg, "std_msgs/String", body)    # [Span(offset=0, size=4, path='data',
                                                  #   type='uint32', value=2, role='length'), ...]

Python values of ROS fields (what ``deserialize`` returns and ``serialize``/``new_message`` take):

=====================================  =========================================================
ROS field                              Python value
=====================================  =========================================================
nested message                         dict (serialize also takes objects with the attributes)
``time`` / ``duration``                ``Time(secs, nsecs)`` / ``Duration(secs, nsecs)`` (also
                                       (secs, nsecs) tuples or {"secs", "nsecs"} dicts on input)
``string``                             str (UTF-8; bytes accepted on input)
``bool``                               bool
integers, floats (incl. byte, char)    int, float
``uint8[]``, ``char[]`` (any length)   read-only numpy uint8 view into the input buffer; on
                                       input any bytes-like value, numpy array or list
other numeric and ``bool`` arrays      read-only numpy array of the little-endian dtype; on
                                       input numpy arrays or lists (range-checked)
arrays of strings, times, messages     lists
=====================================  =========================================================

Your own types: ``reg = MsgRegistry.with_defaults(); reg.load_path("my_ws/src")`` (finds
``PKG/msg/NAME.msg``); ``new_message(reg, TYPE, **fields)`` fills the rest with defaults. Errors
are typed (``MsgDefinitionError`` with file:line, ``UnknownTypeError``, ``SerializeError`` /
``DeserializeError`` with field path and byte offset); limits live in module ``limits``. The
shipped definitions, their versions and why ``message_definition`` is genpy's ``_full_text``
byte for byte: ``definitions/README.md``. On the command line (``rosfpga_lab.cli.msg``)::

    rosfpga-lab msg show sensor_msgs/Image             # fields (like rosmsg show), md5, full text
    rosfpga-lab msg md5 [--msg-path DIR]... TYPE...    # one "TYPE MD5" line per type
    rosfpga-lab msg list [PKG]
    rosfpga-lab msg layout std_msgs/String --hex "02000000 6869"   # byte layout table

Modules: ``parser`` (text -> MsgSpec), ``registry`` (types, md5, full text), ``decode`` and
``encode`` (the fast wire codecs), ``layout`` (byte spans, and the plain reference decoder),
``values`` (defaults, new_message), ``builtins`` (types, Time, Duration), ``limits``, ``errors``,
``describe`` (text views), ``ros2`` (the ROS 2 forms of the types), ``typehash`` (their ROS 2
type hash, RIHS01) and ``cdr`` (the ROS 2
wire format: ``serialize_cdr``, ``deserialize_cdr``, ``cdr_layout``), ``strategies`` (hypothesis strategies, for tests), ``bench``.
"""

from rosfpga_lab.msg.builtins import BUILTIN_TYPES, PRIMITIVE_TYPES, Duration, Time
from rosfpga_lab.msg.cdr import cdr_layout, deserialize_cdr, serialize_cdr
from rosfpga_lab.msg.decode import deserialize, deserialize_partial, min_size
from rosfpga_lab.msg.encode import serialize
from rosfpga_lab.msg.errors import (
    DeserializeError, MsgDefinitionError, MsgError, SerializeError, UnknownTypeError,
)
from rosfpga_lab.msg.layout import FieldSpan, deserialize_reference, field_layout
from rosfpga_lab.msg.limits import DEFAULT_LIMITS, MsgLimits
from rosfpga_lab.msg.parser import (
    Constant, Field, MsgSpec, parse_msg, split_full_text, strip_comments,
)
from rosfpga_lab.msg.registry import (
    DEFINITIONS_DIR, SHIPPED_PACKAGES, MsgRegistry, default_registry, registry_with,
)
from rosfpga_lab.msg.ros2 import ros2_registry, to_ros2_value
from rosfpga_lab.msg.span import Span
from rosfpga_lab.msg.values import default_value, new_message

__all__ = [
    "BUILTIN_TYPES", "Constant", "DEFAULT_LIMITS", "DEFINITIONS_DIR", "DeserializeError",
    "Duration", "Field", "FieldSpan", "MsgDefinitionError", "MsgError", "MsgLimits",
    "MsgRegistry", "MsgSpec", "PRIMITIVE_TYPES", "SHIPPED_PACKAGES", "SerializeError", "Span", "Time",
    "UnknownTypeError", "default_registry", "default_value", "deserialize",
    "deserialize_partial", "deserialize_reference", "field_layout", "min_size", "new_message",
    "parse_msg", "registry_with", "serialize", "split_full_text", "strip_comments",
    "cdr_layout", "deserialize_cdr", "ros2_registry", "serialize_cdr", "to_ros2_value",
]
