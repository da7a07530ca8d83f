"""Cyclone DDS (PyPI ``cyclonedds``) peers for the ROS 2 tests, configured as rmw configures it.

``require_cyclonedds()`` (wiretools) skips on a bare machine and fails under
``ROSFPGA_REQUIRE_WIRE=1``. Discovery runs on 127.0.0.1 without multicast: the peer list is
``localhost``, whose discovery ports of participant indices 0..9 Cyclone probes, as the lab does.
Each test process uses its own DDS domain (from its pid) so parallel runs do not meet.
"""

# no "from __future__ import annotations": cyclonedds reads the field types at class creation

import functools
import os
import time
from dataclasses import dataclass
from typing import Any

from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri
from tests.support.wiretools import require_cyclonedds

#: What a ROS 2 user sets in CYCLONEDDS_URI for a graph on 127.0.0.1 (rosfpga_lab.rtps.cyclone).
CYCLONE_CONFIG = cyclone_loopback_uri()
#: A DDS domain of this test process's own (0..232 keep every port under 65536).
DOMAIN = 100 + os.getpid() % 120


def cyclone() -> Any:
    """The cyclonedds modules and ROS 2 Image types, with CYCLONEDDS_URI set (skip without it)."""
    require_cyclonedds()
    os.environ["CYCLONEDDS_URI"] = CYCLONE_CONFIG
    return _types()


@functools.cache
def _types() -> Any:
    """Built once per process: one Python class per DDS type name."""
    import cyclonedds.idl.types as t
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from tests.support.cdrtypes import Header_, Image_, Time_  # the ROS 2 IDL's one owner in the tests

    @dataclass
    class Gid_(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
        data: t.array[t.uint8, 16]       # char[16] data (rmw_dds_common 2.0+)

    @dataclass
    class NodeEntitiesInfo_(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
        node_namespace: t.bounded_str[256]
        node_name: t.bounded_str[256]
        reader_gid_seq: t.sequence[Gid_]
        writer_gid_seq: t.sequence[Gid_]

    @dataclass
    class ParticipantEntitiesInfo_(IdlStruct,
                                   typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
        gid: Gid_
        node_entities_info_seq: t.sequence[NodeEntitiesInfo_]

    class Ns:
        pass

    ns = Ns()
    ns.__dict__.update(Time_=Time_, Header_=Header_, Image_=Image_, Policy=Policy, Qos=Qos,
                       ParticipantEntitiesInfo_=ParticipantEntitiesInfo_,
                       DomainParticipant=DomainParticipant, DataWriter=DataWriter,
                       DataReader=DataReader, Topic=Topic)
    return ns


def qos(dds: Any, reliable: bool = True, depth: int = 10) -> Any:
    """rmw's QoS: ROS 2's default is RELIABLE KEEP_LAST 10 VOLATILE, XCDR1 data."""
    P = dds.Policy
    rel = P.Reliability.Reliable(1_000_000_000) if reliable else P.Reliability.BestEffort
    return dds.Qos(rel, P.History.KeepLast(depth), P.Durability.Volatile,
                   P.DataRepresentation(use_cdrv0_representation=True))


def image(dds: Any, pixels: Any, encoding: str, sec: int = 0, frame_id: str = "camera") -> Any:
    h, w = pixels.shape[:2]
    return dds.Image_(dds.Header_(dds.Time_(sec, 500), frame_id), h, w, encoding, 0,
                      pixels.shape[1] * (pixels.shape[2] if pixels.ndim == 3 else 1),
                      pixels.tobytes())


def wait(cond: Any, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True
