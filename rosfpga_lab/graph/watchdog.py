"""A lab node's master watchdog: register again after the master restarts, and say so once.

How it works: from its first registration on, every :class:`~rosfpga_lab.graph.node.Node`
runs one thread that asks the master every :data:`MASTER_CHECK_PERIOD` seconds whether it
still knows the node (:func:`~rosfpga_lab.graph.master.knows_node`: a master in this process
directly, another one by ``lookupNode``, untraced). A master that forgot the node (it
restarted) gets every publisher, subscriber and service again
(:meth:`~rosfpga_lab.graph.node.Node.register_again`, established links stay up): one warning
line per restart. An unreachable master is one warning line until it answers again; a name
taken by another node (ROS: the newer wins) is one error line, and the node never registers
over it. roscpp and rospy nodes do none of this: a graph of theirs stays broken after a master
restart.
"""

from __future__ import annotations

import logging
import threading
from typing import Protocol

from rosfpga_lab.graph.errors import GraphError
from rosfpga_lab.graph.limits import JOIN_TIMEOUT, MASTER_CHECK_PERIOD, MASTER_CHECK_TIMEOUT
from rosfpga_lab.graph.master import knows_node

log = logging.getLogger("rosfpga_lab.graph")


class WatchedNode(Protocol):
    """What :class:`MasterWatch` needs of a node (a :class:`~rosfpga_lab.graph.node.Node` is
    one; this module does not import it, so the node can import this one)."""

    name: str
    master_uri: str
    watch_master: bool
    is_shutdown: bool

    @property
    def uri(self) -> str: ...

    def register_again(self) -> None: ...


class MasterWatch:
    """The watchdog thread of one node (see the module docstring)."""

    def __init__(self, node: WatchedNode, period: float = MASTER_CHECK_PERIOD) -> None:
        self.node = node
        self.period = period
        self.reachable = True
        self.name_taken = False
        #: times the node registered again
        self.reregistered = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True,
                                        name=f"rosfpga-master-watch-{node.name}")
        self._thread.start()

    def _loop(self) -> None:
        while not self._stop.wait(self.period):
            if self.node.watch_master and not self.node.is_shutdown:
                self.check()

    def check(self) -> bool:
        """One check; True when the node registered again."""
        node = self.node
        try:
            known = knows_node(node.master_uri, node.name, node.uri, MASTER_CHECK_TIMEOUT)
            if known is False and not self.name_taken and not self._stop.is_set():
                node.register_again()
        except GraphError as exc:
            if self.reachable:
                log.warning("%s: master %s unreachable: %s (will keep trying)", node.name,
                            node.master_uri, exc)
            self.reachable = False
            return False
        if not self.reachable:
            log.warning("%s: master %s answers again", node.name, node.master_uri)
            self.reachable = True
        if known is None and not self.name_taken:
            self.name_taken = True
            log.error("%s: another node registered under this name at %s; not registering "
                      "again", node.name, node.master_uri)
        if known is False and not self.name_taken:
            self.reregistered += 1
            log.warning("%s: the master %s did not know this node (restarted?); registered "
                        "again", node.name, node.master_uri)
            return True
        return False

    def stop(self) -> None:
        """End the thread (joins it unless called from it)."""
        self._stop.set()
        if self._thread is not threading.current_thread():
            self._thread.join(JOIN_TIMEOUT)
