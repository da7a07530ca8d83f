"""RTPS, the wire protocol of DDS (ROS 2): a sans-IO decoder of whole RTPS messages.

Bytes in, events out: :func:`parse_message` takes one UDP datagram and returns an
:class:`RtpsMessage` (its header and one dataclass per submessage: INFO_TS, INFO_DST, DATA,
DATA_FRAG, HEARTBEAT, HEARTBEAT_FRAG, ACKNACK, NACK_FRAG, GAP; others as ``Unknown``).
:func:`parse_parameters` reads SPDP/SEDP parameter lists, :func:`discovery` names participants,
topics and types from them, and :class:`FragmentAssembler` puts DATA_FRAG fragments back
together into the serialized sample (a CDR payload for ``rosfpga_lab.msg.deserialize_cdr``).

The other way, :mod:`rosfpga_lab.rtps.build` writes RTPS messages, SPDP/SEDP parameter lists
and the ROS 2 names (``rt/...``, ``pkg::msg::dds_::Type_``), and
:class:`rosfpga_lab.rtps.participant.Participant` is a whole DDS participant as a sans-IO state
machine (discovery, matching, reliable and best-effort writers and readers; its entities in
:mod:`rosfpga_lab.rtps.entities`, its parts in ``participant_base``, ``spdp``, ``sedp``,
``writer_side`` and ``reader_side``); ``rosfpga_lab.graph.ros2`` runs it on sockets, with a
ROS 2 node's entities from :mod:`rosfpga_lab.rtps.rosnode` (which the fabric's discovery ROM,
``rosfpga_lab.rtl.discrom``, renders too).
Checked against Cyclone DDS (``tests/flow/test_ros2_interop.py``) and rclpy on Fast DDS
(``tests/flow/test_ros2_realros2.py``); the same by hand, and captures in Wireshark: ``docs/ros2.md``.
"""

from rosfpga_lab.rtps.errors import RtpsError, RtpsTruncatedError
from rosfpga_lab.rtps.message import (
    ANY_PARTICIPANT, ENTITY_NAMES, SUBMESSAGE_NAMES, AckNack, Data, DataFrag, Gap, Heartbeat,
    HeartbeatFrag, InfoDst, InfoSrc, InfoTs, NackFrag, RtpsHeader, RtpsMessage, Submessage,
    Unknown, entity_name, parse_message,
)
from rosfpga_lab.rtps.discovery import (
    Endpoint, FragmentAssembler, Participant, discovery, parse_parameters,
)

__all__ = [
    "ANY_PARTICIPANT", "AckNack", "Data", "DataFrag", "ENTITY_NAMES", "Endpoint",
    "FragmentAssembler", "Gap", "Heartbeat", "HeartbeatFrag", "InfoDst", "InfoSrc", "InfoTs",
    "NackFrag", "Participant", "RtpsError",
    "RtpsHeader", "RtpsMessage", "RtpsTruncatedError", "SUBMESSAGE_NAMES", "Submessage",
    "Unknown", "discovery", "entity_name", "parse_message", "parse_parameters",
]
