"""The DDS entities of one ROS 2 node on a participant, as rmw creates them: sans-IO.

How this works: :class:`RosNodeEntities` adds to a :class:`~rosfpga_lab.rtps.participant.Participant`
what ``rmw_cyclonedds_cpp`` adds for a node: the ``ros_discovery_info`` writer (RELIABLE
TRANSIENT_LOCAL KEEP_LAST 1, :data:`GRAPH_QOS`), then one writer per publisher and one reader per
subscriber on ``rt/<topic>`` with the DDS type name and the ROS 2 type hash (SEDP USER_DATA), and
writes the node's :func:`~rosfpga_lab.rtps.build.participant_entities_info` sample. The software
node (``rosfpga_lab.graph.ros2.Ros2Node``) runs it on sockets; the fabric's discovery ROM
(``rosfpga_lab.rtl.discrom``) renders the same entities at build time.
"""

from __future__ import annotations

from rosfpga_lab.msg.errors import MsgError
from rosfpga_lab.msg.registry import MsgRegistry
from rosfpga_lab.msg.typehash import type_hash as ros2_type_hash
from rosfpga_lab.rtps.build import (
    ROS_DISCOVERY_TOPIC, ROS_DISCOVERY_TYPE, dds_topic, dds_type, participant_entities_info,
)
from rosfpga_lab.rtps.entities import PARTICIPANT_ENTITY, Qos
from rosfpga_lab.rtps.participant import Participant

#: The QoS of ``ros_discovery_info``'s writer, as rmw publishes it.
GRAPH_QOS = Qos(True, 1, transient_local=True)


def node_type_hash(type_name: str, registry: MsgRegistry | None = None) -> str:
    """The ROS 2 type hash a node announces for ``type_name`` (its definition in ``registry``,
    default the shipped types); '' for a type it cannot load (no hash sent)."""
    try:
        return ros2_type_hash(type_name, registry)
    except MsgError:
        return ""


class RosNodeEntities:
    """One ROS 2 node's DDS entities on ``participant`` (its ``ros_discovery_info`` writer is
    added at once: :attr:`graph_writer`; ``graph_locator``: the unicast locator that writer's
    SEDP data announces, None for the participant's default user-data one)."""

    def __init__(self, participant: Participant, name: str, namespace: str = "/", *,
                 graph_locator: tuple[str, int] | None = None) -> None:
        self.participant, self.name, self.namespace = participant, name, namespace
        self.graph_writer = participant.add_writer(ROS_DISCOVERY_TOPIC, ROS_DISCOVERY_TYPE,
                                                   GRAPH_QOS, locator=graph_locator)
        self.readers: list[bytes] = []
        self.writers: list[bytes] = []

    def guid(self, entity_id: int) -> bytes:
        return self.participant.guid_prefix + entity_id.to_bytes(4, "big")

    def add_publisher(self, topic: str, type_name: str, qos: Qos = Qos(),
                      registry: MsgRegistry | None = None) -> int:
        """The writer of ROS 2 topic ``topic`` (``/image``) of ROS type ``type_name``; its id."""
        wid = self.participant.add_writer(dds_topic(topic), dds_type(type_name), qos,
                                          node_type_hash(type_name, registry))
        self.writers.append(self.guid(wid))
        return wid

    def add_subscriber(self, topic: str, type_name: str, qos: Qos = Qos(),
                       registry: MsgRegistry | None = None) -> int:
        """The reader of ROS 2 topic ``topic`` of ROS type ``type_name``; its id."""
        rid = self.participant.add_reader(dds_topic(topic), dds_type(type_name), qos,
                                          node_type_hash(type_name, registry))
        self.readers.append(self.guid(rid))
        return rid

    def entities_info(self) -> bytes:
        """The ``ros_discovery_info`` sample: this participant and its one node's endpoints."""
        return participant_entities_info(self.guid(PARTICIPANT_ENTITY),
                                         [(self.namespace, self.name, self.readers, self.writers)])


#: The node name when a configuration's name has none after its last ``/``.
DEFAULT_NODE_NAME = "fpga"


def split_node_name(global_name: str) -> tuple[str, str]:
    """``/ns/fpga_samples`` -> ``("/ns", "fpga_samples")``; ``/fpga`` -> ``("/", "fpga")``: the
    namespace and name a ROS 2 node announces in ``ros_discovery_info``."""
    namespace, _, base = global_name.rpartition("/")
    return namespace or "/", base or DEFAULT_NODE_NAME
