"""The narrow contract between a node and its topics.

A :class:`~rosfpga_lab.graph.Publisher` or :class:`~rosfpga_lab.graph.Subscriber` never sees
its :class:`~rosfpga_lab.graph.Node`: it gets a :class:`TopicContext` (the node's name, its
trace, its message registry and one callback to leave the topic). The node in turn calls only
public methods of its topics: ``attach``/``update_publishers`` (a connection or publisher list
for the topic) and ``close`` (shut the topic's connections down).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rosfpga_lab.graph.trace import Trace
    from rosfpga_lab.msg import MsgRegistry


@dataclass(frozen=True)
class TopicContext:
    """What a publisher or subscriber may use of its node.

    Attributes:
        name: the node's name (the ``callerid`` of its headers and calls).
        trace: the node's conversation trace.
        registry: the message types known to the node.
        leave: ``leave(topic_object)``: the node forgets the publisher or subscriber and tells
            the master (``unregisterPublisher``/``unregisterSubscriber``); the caller closes
            itself afterwards.
    """

    name: str
    trace: Trace
    registry: MsgRegistry
    leave: Callable[[Any], None]
