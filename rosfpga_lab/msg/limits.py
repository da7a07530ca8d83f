"""The message layer's limits, in one place.

A length prefix larger than the bytes left in the message is always refused before anything is
allocated, whatever these limits say; the limits below bound what a *well-formed* body may ask
for. roscpp itself refuses frames over 1e9 bytes; the lab's defaults are lower and can be raised
per call (``deserialize(..., limits=MsgLimits(...))``).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Longest string (bytes) a body may declare.
MAX_STRING_BYTES = 64 * 1024 * 1024
#: Most elements a variable-length array may declare.
MAX_ARRAY_LENGTH = 256 * 1024 * 1024
#: Most elements an array of zero-byte messages (e.g. ``std_msgs/Empty[]``) may declare; for
#: every other array the bytes left already bound the count.
MAX_EMPTY_ELEMENTS = 65_536
#: Deepest nesting of message types a definition may use (guards against runaway recursion).
MAX_NESTING_DEPTH = 64
#: Most ``.msg`` files ``MsgRegistry.load_path`` reads from one folder tree.
MAX_MSG_FILES = 10_000
#: How many folder levels ``MsgRegistry.load_path`` descends looking for packages.
MAX_SEARCH_DEPTH = 4
#: Largest ``.msg`` file read (bytes).
MAX_MSG_FILE_BYTES = 1024 * 1024
#: Numeric arrays up to this many elements get one FieldSpan per element in ``field_layout``.
LAYOUT_ELEMENT_SPANS = 64


@dataclass(frozen=True)
class MsgLimits:
    """Limits applied while decoding a body.

    Attributes:
        max_string_bytes: longest string a body may declare.
        max_array_length: most elements a variable-length array may declare.
        max_empty_elements: most elements an array of zero-byte messages may declare.
    """

    max_string_bytes: int = MAX_STRING_BYTES
    max_array_length: int = MAX_ARRAY_LENGTH
    max_empty_elements: int = MAX_EMPTY_ELEMENTS


DEFAULT_LIMITS = MsgLimits()
