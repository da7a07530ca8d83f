"""The Cyclone DDS configuration under which its participants and the lab's find each other on
one host.

How this works: ROS 2's ``rmw_cyclonedds_cpp`` reads Cyclone DDS's XML configuration from
``CYCLONEDDS_URI``. Linux's loopback has no multicast, so a ROS 2 user who keeps a graph on one
machine sets the interface to 127.0.0.1, turns multicast off and lists ``localhost`` as a peer:
Cyclone then sends its SPDP announcements to the unicast discovery port of every participant
index up to ``MaxAutoParticipantIndex``, the same indices the lab probes
(:data:`~rosfpga_lab.rtps.limits.MAX_PARTICIPANT_INDEX`).
"""

from __future__ import annotations

from rosfpga_lab.rtps.limits import MAX_PARTICIPANT_INDEX

__all__ = ["cyclone_loopback_uri"]


def cyclone_loopback_uri(lease_seconds: float | None = None,
                         max_message_bytes: int | None = None) -> str:
    """The ``CYCLONEDDS_URI`` value for a DDS graph on 127.0.0.1 without multicast.

    Args:
        lease_seconds: the participant lease Cyclone announces (None: Cyclone's default, 10 s).
        max_message_bytes: the longest datagram Cyclone sends (None: its default, 14720 bytes,
            which a network port passes as IP fragments; a peer that reassembles none, as the
            node in the fabric, needs at most one Ethernet frame's payload, 1472).
    """
    lease = "" if lease_seconds is None else f"<LeaseDuration>{lease_seconds:g}s</LeaseDuration>"
    size = ("" if max_message_bytes is None else
            f"<MaxMessageSize>{max_message_bytes}B</MaxMessageSize>")
    return ('<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/>'
            f'</Interfaces><AllowMulticast>false</AllowMulticast>{size}</General><Discovery><Peers>'
            '<Peer address="localhost"/></Peers><ParticipantIndex>auto</ParticipantIndex>'
            f'<MaxAutoParticipantIndex>{MAX_PARTICIPANT_INDEX}</MaxAutoParticipantIndex>{lease}'
            '</Discovery></Domain></CycloneDDS>')
