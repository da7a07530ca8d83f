"""Exercise checks for the notebooks: they say *what* is right or wrong, not only pass/fail.

Each check compares the reader's answer with the right one, computed from the lab's library
(itself tested against real ROS, OpenCV and the paper), and either returns a
:class:`CheckResult` (shown as a green line saying what was verified) or raises
:class:`ExerciseError` listing the findings, e.g.::

    Exercise 3.2 (marshal an Image): not right yet
      - byte 12 (field header.frame_id length, uint32 at bytes 12..15) is 5, expected 7

In a notebook the error shows only those lines (no traceback). A placeholder answer (``...``)
is refused with "replace it with your answer".

========  ======================================================================
notebook  checks
========  ======================================================================
1         :func:`check_call_order`, :func:`check_talker_contact`, :func:`check_http_body`
2         :func:`check_connection_header`, :func:`check_md5`, :func:`check_frame_split`
3         :func:`check_data_offset`, :func:`check_marshal`, :func:`check_extract`
4         :func:`check_tdata`, :func:`check_markers`, :func:`check_fifo2axi`
5         :func:`check_dilate`, :func:`check_frame_timing`
6         :func:`check_node_config`, :func:`check_sloc`
9         :func:`check_cdr_data_offset`, :func:`check_fragment_count`
10        :func:`check_stream_offset`, :func:`check_frame_clocks`, :func:`check_refused_field`
11        :func:`check_discovery_port`, :func:`check_pixel_offsets`, :func:`check_qos_mismatch`
12        :func:`check_rtps_offset`, :func:`check_handoff_clock`
========  ======================================================================

:mod:`rosfpga_lab.checks.nbbuild` makes the student notebooks from the instructor notebooks
(``rosfpga-lab notebooks build``).
"""

from rosfpga_lab.checks._core import (
    ByteField, CheckResult, ExerciseError, describe_byte_difference, field_at,
)
from rosfpga_lab.checks.application import check_dilate, check_frame_timing
from rosfpga_lab.checks.fabric import check_handoff_clock, check_rtps_offset
from rosfpga_lab.checks.flow import EROSION_NODE, check_node_config, check_sloc
from rosfpga_lab.checks.handshake import (
    SUBSCRIBER_FIRST_CALLS, check_call_order, check_http_body, check_talker_contact,
)
from rosfpga_lab.checks.message import (
    check_data_offset, check_extract, check_marshal, frame_fields, message_fields,
)
from rosfpga_lab.checks.ownmsg import check_frame_clocks, check_refused_field, check_stream_offset
from rosfpga_lab.checks.ros2 import (
    check_cdr_data_offset, check_discovery_port, check_fragment_count, check_pixel_offsets,
    check_qos_mismatch,
)
from rosfpga_lab.checks.stream import check_fifo2axi, check_markers, check_tdata
from rosfpga_lab.checks.tcpros import (
    check_connection_header, check_frame_split, check_md5, header_fields,
)

__all__ = [
    "ByteField", "CheckResult", "EROSION_NODE", "ExerciseError", "SUBSCRIBER_FIRST_CALLS",
    "check_call_order", "check_cdr_data_offset", "check_connection_header", "check_data_offset", "check_dilate",
    "check_extract", "check_fifo2axi", "check_fragment_count", "check_frame_split", "check_frame_timing",
    "check_http_body", "check_markers", "check_marshal", "check_md5", "check_node_config",
    "check_sloc", "check_talker_contact", "check_tdata", "describe_byte_difference", "field_at",
    "frame_fields", "header_fields", "message_fields",
    "check_frame_clocks", "check_refused_field", "check_stream_offset",
    "check_discovery_port", "check_pixel_offsets", "check_qos_mismatch",
    "check_handoff_clock", "check_rtps_offset",
]
