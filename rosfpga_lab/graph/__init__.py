"""The ROS graph on real sockets: embedded Master + Parameter Server, Slave API, nodes, trace.

Quick use::

    from rosfpga_lab.graph import EmbeddedMaster, Node
    with EmbeddedMaster(port=0) as master:
        talker = Node("/talker", master=master)
        listener = Node("/listener", master=master)
        sub = listener.subscribe("/chatter", "std_msgs/String", print)
        pub = talker.advertise("/chatter", "std_msgs/String")
        pub.wait_for_subscribers()
        pub.publish({"data": "hello"})
        ...
        talker.shutdown(); listener.shutdown()

Which master a :class:`Node` talks to: ``master=`` or ``master_uri=`` when given; else
``ROS_MASTER_URI``; else a master already answering on 127.0.0.1:11311 (roscore or
``rosfpga-lab master``) that runs as the same Unix user (on a shared server, another user's
master is never joined unasked: ``owner``); else this process's own embedded master (:func:`shared_master`),
started on 11311, or on a free port (with a RuntimeWarning) when 11311 is taken. The last
step is what makes a notebook work with nothing installed, but other processes find that
master only on 11311 (on a fallback port, nobody else does): a node there may be alone.
Programs that must join an existing graph pass ``master_uri`` explicitly instead, as
``rosfpga-lab topic`` does (``--master-uri``, else ``ROS_MASTER_URI``, else 11311; it stops
with an error and a hint when no master answers there).

``Trace`` records the whole conversation (``Node(..., trace=trace)``, ``EmbeddedMaster(...,
trace=trace)``); ``trace.summary()`` is the paper's Figure 2 from a real run. Real rospy, roscpp
and rostopic work against the lab's master, and lab nodes with a real roscore. Like rospy and
roscpp nodes, every lab node publishes ``rosgraph_msgs/Log`` on ``/rosout`` and serves
``~get_loggers`` and ``~set_logger_level``; services are TCPROS on the node's own service port
(``node.advertise_service(name, type, handler)``, ``node.call_service(name, type, request)``;
codec ``tcpros.service``, shipped types ``msg.srv``). After a master restart every lab node
registers again and says so once. The master answers ``system.multicall`` and matches rosmaster
1.15's replies (golden-tested). The XML-RPC limits (backlog, body sizes, bodies in flight, reply
cap) are the constants of module ``limits``; ``tests/benchmarks/bench_master_load.py`` measures
them beside rosmaster. Deliberate differences from real ROS: no UDPROS; the lab's publisher
answers a malformed header with an ``error=`` header where roscpp just drops the connection; the
lab's subscriber also checks the publisher's md5; both sides time the handshake out
(``tcpros.limits``); the default host is 127.0.0.1 rather than the machine's hostname.

Modules: ``xmlrpc`` (safe HTTP/XML-RPC client and server: the sockets), ``xmlrpccodec``
(its sans-IO XML-RPC documents: parse, marshal, faults, int32), ``http`` (its sans-IO HTTP
messages: the decoder, the request and the reply), ``master`` (EmbeddedMaster),
``node`` (Node, Slave API, TCPROS server), ``publisher``, ``subscriber``, ``trace`` (the recorded
conversation; its docstring documents the format), ``names`` (names, ROS_* environment),
``owner`` (which Unix user listens on a port), ``service`` (TCPROS services), ``rosout``
(/rosout and the logger services), ``watchdog`` (registering again after a master restart), ``rate`` (RateMeter, every events-per-second
figure), ``errors`` (errors), ``limits`` (limits).
"""

from rosfpga_lab.graph.errors import (
    ApiArgumentError,
    ConfigError,
    GraphError,
    MasterError,
    ServiceError,
    XmlRpcError,
    XmlRpcTooLargeError,
)
from rosfpga_lab.graph.limits import (
    CONNECT_TIMEOUT,
    MAX_HTTP_HEAD,
    MAX_XMLRPC_BODY,
    MAX_XMLRPC_REPLY,
    RECONNECT_FIRST,
    RECONNECT_MAX,
    XMLRPC_TIMEOUT,
)
from rosfpga_lab.graph.master import EmbeddedMaster, ParamTree
from rosfpga_lab.graph.names import OpenBindWarning, default_host, master_uri_from_env, resolve
from rosfpga_lab.graph.node import Node, default_master_uri, shared_master, stop_shared_master
from rosfpga_lab.graph.publisher import LinkStats, Publisher, PublisherStats
from rosfpga_lab.graph.rate import RateMeter
from rosfpga_lab.graph.subscriber import MessageInfo, Subscriber, SubscriberStats
from rosfpga_lab.graph.trace import KINDS, Trace, TraceEvent
from rosfpga_lab.graph.xmlrpc import XmlRpcServer, call
from rosfpga_lab.graph.xmlrpccodec import parse_xmlrpc

__all__ = [
    "CONNECT_TIMEOUT", "KINDS", "MAX_HTTP_HEAD", "MAX_XMLRPC_BODY", "MAX_XMLRPC_REPLY", "RECONNECT_FIRST",
    "RECONNECT_MAX", "XMLRPC_TIMEOUT", "ApiArgumentError", "ConfigError", "EmbeddedMaster",
    "GraphError", "LinkStats", "MasterError", "MessageInfo", "Node", "OpenBindWarning",
    "ParamTree", "Publisher", "PublisherStats", "RateMeter", "Subscriber", "SubscriberStats", "Trace",
    "TraceEvent", "XmlRpcError", "XmlRpcTooLargeError", "XmlRpcServer", "call", "default_host", "default_master_uri", "master_uri_from_env",
    "parse_xmlrpc", "resolve", "shared_master", "stop_shared_master", "ServiceError",
]
