"""The circuit layout: one walk over a TCPROS frame, derived from a ``.msg`` and the node configuration.

How this works: :func:`derive_layout` walks the message type in wire order (the same order the
``msg`` layer serializes it) and writes one :class:`Step` per thing the subscriber circuit reads:
the 4-byte frame length, each fixed-size scalar (``time``/``duration`` as two: ``secs``,
``nsecs``), each ``uint32`` length prefix, each string's bytes, each array of numbers as one
block, and for arrays of messages, strings, times or durations a ``LOOP`` step, the steps of
one element, and an ``END`` step (the circuit walks the elements one by one). Each step says
what the circuit does with it (:class:`Action`): ``stream`` (the one numeric array the
application processes, as AXI4-Stream beats of the element's width), ``check`` (equal to a
value fixed at synthesis time, or within a bound; kept and re-sent), ``carry`` (kept and
written into the output message) or ``skip`` (read and dropped; the publisher writes the
field's default). Every length prefix is checked too (its maximum, from the configuration's
``limits:`` or the documented defaults ``config.limits.DEFAULT_STRING_MAX`` /
``DEFAULT_ARRAY_MAX``; the stream's must equal ``stream.length``). Renderers (the Python models,
the HLS C++, the Verilog) walk ``layout.steps`` and never need to know a message type: every
name, size, maximum and status code is in the steps.

Worked example: ``pkg/Scan`` = ``Header header``, ``string[] names``, ``float32[] ranges``,
``derive_layout(reg, "pkg/Scan", stream="ranges", stream_length=4, checks={"header.seq": 0})``;
:func:`format_layout` prints (a test holds this text equal to its output)::

    pkg/Scan (md5 115c5a6fcd20cb3c1c340cbd2d284ee1): stream ranges 4 x float32, body 40..16936 bytes
    #   kind      ident                   label                   type     bytes     max  action  check
    0   length    frame_length            frame length            uint32   4         -    check   SUB_BAD_FRAME_LENGTH: 40..67108864
    1   scalar    header_seq              header.seq              uint32   4         -    check   SUB_BAD_HEADER_SEQ: == 0
    2   scalar    header_stamp_secs       header.stamp.secs       uint32   4         -    carry   -
    3   scalar    header_stamp_nsecs      header.stamp.nsecs      uint32   4         -    carry   -
    4   length    header_frame_id_length  header.frame_id length  uint32   4         -    carry   SUB_BAD_HEADER_FRAME_ID_LENGTH: <= 256
    5   string    header_frame_id         header.frame_id         string   1 x [4]   256  carry   -
    6   length    names_length            names length            uint32   4         -    carry   SUB_BAD_NAMES_LENGTH: <= 64
    7   loop      names                   names                   string   0 x [6]   64   carry   -
    8     length  names_item_length       names[] length          uint32   4         -    carry   SUB_BAD_NAMES_ITEM_LENGTH: <= 256
    9     string  names_item              names[]                 string   1 x [8]   256  carry   -
    10  end       names                   names                   string   0         -    carry   -
    11  length    ranges_length           ranges length           uint32   4         -    stream  SUB_BAD_RANGES_LENGTH: == 4
    12  array     ranges                  ranges                  float32  4 x [11]  4    stream  -

(``x [11]``: as many elements as step 11 says). A frame's byte offsets follow from its values
(:func:`frame_geometry`); a refused field is named by its label with indices filled in
(``names[2] length``). Status codes: ``SUB_OK`` then one per checked step, in step order
(:attr:`Layout.statuses`); for Image the hand exhibit's ``rtl.exhibit.params.SUBSCRIBER_STATUSES`` but
for the ``HEADER_`` prefix.

Refusal order (what every renderer does, so models, C++ and RTL give the same status): when a
step completes, (1) step 0, the frame length: below ``min_body`` or above
``hw.limits.MAX_FRAME_BYTES`` -> ``SUB_BAD_FRAME_LENGTH``, nothing trusted, wait for the next
frame; (2) the step's own check (``EQUAL``, ``RANGE`` -- a NaN fails it --, ``MAX``) -> its
status; (3) a LENGTH step's :class:`LengthRule` (:func:`length_rules`): when only fixed-size
data follows, the frame must end exactly there (else ``SUB_BAD_FRAME_LENGTH``), otherwise its
elements must fit in the bytes left (else its own status); (4) on to the next step: LOOPs
with no elements and empty strings/arrays are passed at once; reaching the frame's end before
a step that has bytes, or inside one, refuses the frame (``SUB_BAD_FRAME_LENGTH``). After a
refusal with a sane frame length the rest of the frame is skipped.

:func:`tokens` lists a message's values in walk order (what the subscriber emits step by step)
and :func:`marshal` writes tokens back into a frame (what the publisher does): the two are
the layout's definition of the wire, tested against the ``msg`` layer. CDR, the second wire
format, is the same walk of the type's ROS 2 form with the kinds ``ENCAPSULATION`` and ``NUL``
and each step's alignment added (:mod:`rosfpga_lab.hw.cdrlayout`).

The code is in four modules, one idea each: :mod:`~rosfpga_lab.hw.layoutsteps` (the types and
:func:`format_layout`), :mod:`~rosfpga_lab.hw.layoutderive` (:func:`derive_layout`,
:func:`layout_from_config`), :mod:`~rosfpga_lab.hw.layoutlengths` (:func:`length_rules`) and
:mod:`~rosfpga_lab.hw.layouttokens` (:func:`tokens`, :func:`marshal`, :func:`frame_geometry`);
this module gathers their public names, the import the notebooks and the renderers use.
"""

from __future__ import annotations

from rosfpga_lab.config.vocabulary import STREAM_ELEMENT_TYPES
from rosfpga_lab.hw.layoutderive import derive_layout, layout_from_config
from rosfpga_lab.hw.layoutlengths import LengthRule, length_rules
from rosfpga_lab.hw.layoutsteps import (
    Action, CheckOp, FieldCheck, Layout, Step, StepKind, VideoShape, format_layout,
)
from rosfpga_lab.hw.layouttokens import (
    FrameGeometry, Token, encode_token, frame_geometry, marshal, tokens,
)

__all__ = [
    "Action", "CheckOp", "FieldCheck", "FrameGeometry", "Layout", "LengthRule", "Step", "StepKind",
    "Token", "length_rules",
    "VideoShape", "STREAM_ELEMENT_TYPES", "derive_layout", "encode_token", "format_layout",
    "frame_geometry", "layout_from_config", "marshal", "tokens",
]
