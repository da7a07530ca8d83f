"""What every ROS node offers besides its topics: ``/rosout`` logging and the logger services.

How it works: when a :class:`~rosfpga_lab.graph.node.Node` first registers with a master it
calls :func:`start_node_logging`: the node publishes ``rosgraph_msgs/Log`` on ``/rosout`` (what
Debian's ``rosout`` node gathers into ``/rosout_agg`` for rqt_console and roslaunch's logs), a
:class:`RosoutHandler` on the lab's ``rosfpga_lab`` logger turns each record that logger
passes into one such message, and the node serves ``~get_loggers`` and ``~set_logger_level``
(roscpp's service types) over the lab's loggers, as rospy and roscpp nodes do. ROS's five
levels map to Python's: debug, info, warn (WARNING), error, fatal (CRITICAL). In a process
with several nodes each publishes every record of the lab's loggers.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol

from rosfpga_lab.graph.errors import GraphError

if TYPE_CHECKING:  # pragma: no cover
    from rosfpga_lab.graph.publisher import Publisher

log = logging.getLogger("rosfpga_lab.graph")

#: The logger tree the lab's records come from (and the logger services act on).
LAB_LOGGER = "rosfpga_lab"
ROSOUT_TOPIC = "/rosout"
ROSOUT_TYPE = "rosgraph_msgs/Log"
#: ROS level names -> Python logging levels (rosconsole's names, lower case as rospy answers).
ROS_LEVELS = {"debug": logging.DEBUG, "info": logging.INFO, "warn": logging.WARNING,
              "error": logging.ERROR, "fatal": logging.CRITICAL}
#: rosgraph_msgs/Log's level constants (DEBUG=1 ... FATAL=16), by Python level.
LOG_LEVEL_BYTE = {logging.DEBUG: 1, logging.INFO: 2, logging.WARNING: 4, logging.ERROR: 8,
                  logging.CRITICAL: 16}


def ros_level_name(level: int) -> str:
    """The ROS name of a Python level (the nearest one at or below it)."""
    for name, value in sorted(ROS_LEVELS.items(), key=lambda kv: -kv[1]):
        if level >= value:
            return name
    return "debug"


def log_message(node_name: str, record: logging.LogRecord, topics: list[str]) -> dict[str, Any]:
    """A ``rosgraph_msgs/Log`` value for ``record`` (rospy fills the same fields)."""
    secs = int(record.created)
    byte = max((b for lvl, b in LOG_LEVEL_BYTE.items() if record.levelno >= lvl), default=1)
    return {
        "header": {"seq": 0, "stamp": {"secs": secs, "nsecs": int((record.created - secs) * 1e9)},
                   "frame_id": ""},
        "level": byte, "name": node_name, "msg": record.getMessage(), "file": record.pathname,
        "function": record.funcName or "", "line": record.lineno, "topics": topics,
    }


class RosoutHandler(logging.Handler):
    """Publishes every record it gets on a node's ``/rosout`` publisher."""

    def __init__(self, node_name: str, publisher: Publisher, topics: Any) -> None:
        super().__init__()
        self.node_name = node_name
        self.publisher = publisher
        self.topics = topics
        self._inside = threading.local()

    def emit(self, record: logging.LogRecord) -> None:
        if getattr(self._inside, "busy", False) or self.publisher.closed:
            return  # a record logged while publishing one is not published again
        self._inside.busy = True
        try:
            self.publisher.publish(log_message(self.node_name, record, sorted(self.topics())))
        except Exception:  # logging must never fail the caller
            pass
        finally:
            self._inside.busy = False


def lab_loggers() -> dict[str, logging.Logger]:
    """The lab's loggers that exist now, by name (``rosfpga_lab`` and below)."""
    out = {LAB_LOGGER: logging.getLogger(LAB_LOGGER)}
    for name, obj in list(logging.Logger.manager.loggerDict.items()):
        if isinstance(obj, logging.Logger) and name.startswith(LAB_LOGGER + "."):
            out[name] = obj
    return out


def get_loggers(_request: dict) -> dict:
    """``~get_loggers``: every lab logger with its effective ROS level."""
    return {"loggers": [{"name": name, "level": ros_level_name(lg.getEffectiveLevel())}
                        for name, lg in sorted(lab_loggers().items())]}


def set_logger_level(request: dict) -> dict:
    """``~set_logger_level``: set one lab logger's level.

    Raises:
        GraphError: unknown logger or level (the caller gets the text, ``ok=0``).
    """
    name, level = request.get("logger", ""), str(request.get("level", "")).lower()
    loggers = lab_loggers()
    if name not in loggers:
        raise GraphError(f"logger [{name}] does not exist; the lab's loggers: {', '.join(sorted(loggers))}")
    if level not in ROS_LEVELS:
        raise GraphError(f"level [{level}] is not one of {', '.join(ROS_LEVELS)}")
    loggers[name].setLevel(ROS_LEVELS[level])
    return {}


class LoggingNode(Protocol):
    """What :func:`start_node_logging` needs of a node (a :class:`~rosfpga_lab.graph.node.Node`
    is one; this module does not import it, so the node can import this one)."""

    name: str

    @property
    def publishers(self) -> Mapping[str, Publisher]: ...

    def advertise(self, topic: str, type_name: str, queue_size: int = ...,
                  latch: bool = ...) -> Publisher: ...

    def advertise_service(self, service: str, srv_type: str,
                          handler: Callable[[dict], dict]) -> str: ...


def start_node_logging(node: LoggingNode) -> RosoutHandler:
    """Advertise ``/rosout`` and the two logger services for ``node``; return the handler
    attached to the lab's logger (the node removes it when it shuts down)."""
    node.advertise_service("~get_loggers", "roscpp/GetLoggers", get_loggers)
    node.advertise_service("~set_logger_level", "roscpp/SetLoggerLevel", set_logger_level)
    pub = node.advertise(ROSOUT_TOPIC, ROSOUT_TYPE, queue_size=100)
    handler = RosoutHandler(node.name, pub, lambda: [t for t in node.publishers if t != ROSOUT_TOPIC])
    logging.getLogger(LAB_LOGGER).addHandler(handler)
    return handler


def stop_node_logging(handler: RosoutHandler | None) -> None:
    """Detach a node's handler from the lab's logger."""
    if handler is not None:
        logging.getLogger(LAB_LOGGER).removeHandler(handler)


__all__ = ["LAB_LOGGER", "ROS_LEVELS", "LoggingNode", "RosoutHandler", "get_loggers", "log_message",
           "set_logger_level", "start_node_logging", "stop_node_logging"]
