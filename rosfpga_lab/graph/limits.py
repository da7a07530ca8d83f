"""Limits and defaults of the graph layer (XML-RPC master/slave, node runtime), in one place."""

from __future__ import annotations

#: Largest HTTP request/response body accepted (XML-RPC payloads are small; 8 MiB leaves room
#: for a big getSystemState or parameter tree).
MAX_XMLRPC_BODY = 8 << 20
#: Bytes of request bodies one XML-RPC server holds at once, all connections together: a
#: request whose declared body would pass it is refused at once ("503", before its body is
#: read), so 64 concurrent 8 MiB bodies cannot make a master hold half a gigabyte (each body
#: also costs its parsed values). Legitimate calls are a few kilobytes.
MAX_XMLRPC_BODIES_IN_FLIGHT = 64 << 20
#: Largest XML-RPC reply body a client call accepts. A master's ``getSystemState`` grows with the
#: graph (900 topics with long names pass 8 MiB) and rosmaster sets no limit, so replies get more
#: room than requests; the cap only bounds what a broken or hostile server can make us hold.
MAX_XMLRPC_REPLY = 64 << 20
#: Calls one ``system.multicall`` may batch (roslaunch batches a handful, rospy one per
#: registration at shutdown); a longer list is refused whole with a fault.
MAX_XMLRPC_MULTICALL = 1000
#: Connections the kernel queues for a server socket before accept() takes them (the kernel
#: caps it at net.core.somaxconn). A burst larger than the queue loses SYNs, and each lost SYN
#: costs its client a 1 s retransmit: 64 made the slowest of 250 concurrent calls 1.1-1.3 s.
LISTEN_BACKLOG = 1024
#: Largest HTTP head (request line + headers).
MAX_HTTP_HEAD = 16 << 10
#: Seconds an XML-RPC call (connect + request + reply) may take.
XMLRPC_TIMEOUT = 10.0
#: Seconds an idle keep-alive XML-RPC connection stays open on our servers.
XMLRPC_IDLE_TIMEOUT = 30.0
#: Seconds a server gives one whole request (head and body) once its first byte arrived: a
#: peer dripping bytes cannot hold a connection longer than this.
XMLRPC_REQUEST_TIMEOUT = 10.0
#: Open XML-RPC connections a server keeps at once. A new one beyond this evicts the
#: connection that has waited longest for request bytes; only when every one is busy in a
#: handler does the newcomer get "503".
MAX_XMLRPC_CONNECTIONS = 128
#: Deepest nesting of arrays/structs accepted in an XML-RPC document (a parameter tree is a
#: few levels; deeper documents are refused before any handler or trace sees them).
MAX_XMLRPC_DEPTH = 64
#: TCPROS connections still in their handshake a node keeps at once; a new one beyond this
#: evicts the oldest (an honest subscriber sends its header at once, a silent one waits).
MAX_PENDING_HANDSHAKES = 64
#: Accept loops: first pause after a failed accept() (out of file descriptors, aborted
#: connection ...) and the longest pause; the pause doubles while accept keeps failing.
ACCEPT_BACKOFF_FIRST = 0.01
ACCEPT_BACKOFF_MAX = 0.5
#: Seconds between two log lines about failing accept() calls of one server (the ones between
#: are counted and reported with the next line).
ACCEPT_LOG_INTERVAL = 10.0
#: Publishers one subscriber links to at once (each link is a thread and a socket); URIs past
#: this in a publisher list are ignored and logged. ``Node.subscribe(max_publishers=)``.
MAX_PUBLISHERS_PER_TOPIC = 100
#: Seconds to connect to a publisher's TCPROS port.
CONNECT_TIMEOUT = 5.0
#: Reconnect back-off after a publisher vanishes: first delay, factor, cap (roscpp: 0.1 s x2 up to 20 s).
RECONNECT_FIRST = 0.1
RECONNECT_FACTOR = 2.0
RECONNECT_MAX = 5.0
#: Service connections a node's service port serves at once; a new one beyond this evicts the
#: connection idle longest (a call in progress is never evicted).
MAX_SERVICE_CONNECTIONS = 64
#: Seconds a persistent service connection may wait for its next request.
SERVICE_IDLE_TIMEOUT = 30.0
#: Seconds one service call (connect, header, request, handler, response) may take by default.
SERVICE_CALL_TIMEOUT = 10.0
#: Seconds between two checks that the master still knows a registered node (a node the master
#: forgot, after a restart, registers again), and how long one check may take.
MASTER_CHECK_PERIOD = 1.0
MASTER_CHECK_TIMEOUT = 2.0
#: Seconds stop()/shutdown() waits for each worker thread.
JOIN_TIMEOUT = 5.0
#: Seconds the master waits on one publisherUpdate/paramUpdate/shutdown notification.
NOTIFY_TIMEOUT = 5.0
#: Threads the master notifies nodes with (each serves one node at a time, so a silent node
#: holds one worker, not the graph; rosmaster's pool has 10).
NOTIFY_WORKERS = 10
#: Notifications waiting in the master at once (after coalescing: one per node, method and
#: topic or key); more are dropped and counted in ``notify_errors``.
MAX_NOTIFY_PENDING = 10_000
#: Error texts kept by a subscriber (``stats.errors``) and by the master (``notify_errors``):
#: the most recent ones.
MAX_ERRORS_KEPT = 50
#: A trace's default budget: events kept, bytes they hold (raw bytes plus an estimate of the
#: decoded arguments and results), and bytes of one payload (an HTTP message, a connection
#: header) kept as its excerpt; ``size`` always tells the full length.
TRACE_MAX_EVENTS = 20_000
TRACE_MAX_BYTES = 16 << 20
TRACE_EXCERPT_BYTES = 64 << 10
#: Closed connections whose counters a publisher's ``stats.links`` still reports.
MAX_CLOSED_LINKS_KEPT = 64
#: Arrays longer than this are summarised by ``tools.format_message`` (rostopic echo --noarr style).
MAX_ARRAY_SHOWN = 64
#: Arrival times a :class:`~rosfpga_lab.graph.rate.RateMeter` keeps unless told otherwise.
RATE_SAMPLES = 1000
#: Seconds between two asks of the master while waiting for a topic to appear (rostopic: 0.1).
TOPIC_POLL = 0.1

#: Most bytes one direction of one connection may hold when read from a capture.
CAPTURE_MAX_STREAM_BYTES = 256 * 1024 * 1024

#: At most this many bytes of one table are read (a busy server lists thousands of sockets).
OWNER_MAX_TABLE_BYTES = 8 * 2**20

# ---- the ROS 2 node (graph.ros2) ----
#: Socket buffer sizes a ROS 2 node asks for (a 640x480 frame is ~1.2 MB of fragments).
ROS2_SOCKET_BUFFER_BYTES = 8 << 20
#: Longest wait between two ticks of the participant (SPDP, HEARTBEATs, leases).
ROS2_TICK_SECONDS = 0.01
