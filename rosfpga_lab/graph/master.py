"""An embedded ROS Master and Parameter Server: what ``roscore`` gives nodes.

How it works: an :class:`~rosfpga_lab.graph.xmlrpc.XmlRpcServer` answers the Master API and
Parameter Server API with the same ``[code, status, value]`` replies as Noetic's rosmaster
(status texts included). Registrations live in dicts under one lock. Whenever a topic's
publisher list changes, every subscriber of that topic gets ``publisherUpdate``, as rosmaster
does; parameter subscribers get ``paramUpdate``; a node that registers under a name already
taken by another URI makes the master tell the old one to ``shutdown``. Real rospy, roscpp,
rostopic and rosnode work against it unchanged.

Notifications go out from :data:`NOTIFY_WORKERS` threads, one node at a time per worker and in
order per node; a notification that replaces a still-waiting one for the same node and topic
(or key) takes its place (coalescing), so a silent node holds one worker and its own queue,
never the graph. Registrations and unregistrations are logged as rosmaster logs them (``+PUB
[/topic] /caller http://api``...) on the ``rosfpga_lab.graph.master`` logger, with the peer's
address; parameter values are refused when they hold ``<nil/>`` or integers outside XML-RPC's
32-bit range (rosmaster stores those and then fails every ``getParam`` that reaches them).
"""

from __future__ import annotations

import collections
import logging
import os
import threading
import uuid
import weakref
from typing import Any

from rosfpga_lab.config.limits import DEFAULT_MASTER_PORT
from rosfpga_lab.graph.apicheck import api_methods, checked
from rosfpga_lab.graph.errors import XmlRpcError
from rosfpga_lab.graph.limits import (
    JOIN_TIMEOUT,
    MAX_ERRORS_KEPT,
    MAX_NOTIFY_PENDING,
    MAX_XMLRPC_DEPTH,
    NOTIFY_TIMEOUT,
    NOTIFY_WORKERS,
)
from rosfpga_lab.graph.names import bind_address, canonical, resolve
from rosfpga_lab.graph.trace import Trace
from rosfpga_lab.graph.xmlrpc import XmlRpcServer, call, request_peer, unsupported
from rosfpga_lab.graph.xmlrpccodec import check_int_range, value_depth

MASTER_ID = "/master"
#: Masters running in this process, by URI (a node's watchdog asks them directly, untraced).
_local: weakref.WeakValueDictionary[str, EmbeddedMaster] = weakref.WeakValueDictionary()
#: What roscore's launch file puts in ``/rosdistro`` and ``/rosversion`` (``rosversion -d`` and
#: ``rosversion roslaunch``, each with its newline): the ROS release and the ros_comm version
#: whose master replies this one matches (the golden tests pin them against that rosmaster).
ROS_DISTRO = "noetic"
ROS_COMM_VERSION = "1.15.15"
log = logging.getLogger("rosfpga_lab.graph.master")


def check_param_value(value: Any) -> str | None:
    """Why the parameter server refuses ``value`` (rosmaster-style text), or None when fine.

    Refused: ``<nil/>`` anywhere, integers outside XML-RPC's 32-bit range, nesting deeper than
    :data:`MAX_XMLRPC_DEPTH`. Each would make later ``getParam`` calls fail for every node.
    """
    if value is None:
        return "ERROR: parameter [value] must be specified"  # rosmaster's text for <nil/>
    if value_depth(value, MAX_XMLRPC_DEPTH + 1) > MAX_XMLRPC_DEPTH:
        return f"ERROR: parameter [value] is nested deeper than {MAX_XMLRPC_DEPTH} levels"
    stack = [value]
    while stack:
        v = stack.pop()
        if v is None:
            return "ERROR: parameter [value] must not contain nil values"
        if isinstance(v, (list, tuple)):
            stack.extend(v)
        elif isinstance(v, dict):
            stack.extend(v.values())
    try:
        check_int_range(value)
    except XmlRpcError as exc:
        return f"ERROR: parameter [value]: {exc}"
    return None


class ParamTree:
    """The parameter store: a tree of dicts, keys are global names."""

    def __init__(self) -> None:
        self.root: dict[str, Any] = {}

    @staticmethod
    def _parts(key: str) -> list[str]:
        return [p for p in canonical(key).split("/") if p]

    def set(self, key: str, value: Any) -> None:
        parts = self._parts(key)
        if not parts:
            if not isinstance(value, dict):
                raise ValueError("cannot set root of parameter tree to non-dictionary")
            self.root = _copy(value)
            return
        node = self.root
        for p in parts[:-1]:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        node[parts[-1]] = _copy(value)

    def get(self, key: str) -> Any:
        node: Any = self.root
        for p in self._parts(key):
            if not isinstance(node, dict) or p not in node:
                raise KeyError(key)
            node = node[p]
        return _copy(node)

    def has(self, key: str) -> bool:
        try:
            self.get(key)
            return True
        except KeyError:
            return False

    def delete(self, key: str) -> None:
        parts = self._parts(key)
        if not parts:
            raise KeyError(key)
        node: Any = self.root
        for p in parts[:-1]:
            if not isinstance(node, dict) or p not in node:
                raise KeyError(key)
            node = node[p]
        if not isinstance(node, dict) or parts[-1] not in node:
            raise KeyError(key)
        del node[parts[-1]]

    def names(self) -> list[str]:
        out: list[str] = []

        def walk(prefix: str, node: dict) -> None:
            for k, v in node.items():
                if isinstance(v, dict):  # an empty dict is no name (rosmaster)
                    walk(prefix + k + "/", v)
                else:
                    out.append(prefix + k)

        walk("/", self.root)
        return out


def _copy(v: Any) -> Any:
    return {k: _copy(x) for k, x in v.items()} if isinstance(v, dict) else v


class EmbeddedMaster:
    """A ROS master in this process.

    Args:
        host: address to bind and advertise (127.0.0.1 by default; "0.0.0.0" binds every
            interface and warns: ROS 1 has no authentication).
        port: TCP port (11311 is roscore's; 0 picks a free one).
        trace: record every XML-RPC exchange here (a new Trace by default).
        allow_remote_shutdown: honour the ``shutdown`` API call (off by default).

    Example:
        >>> m = EmbeddedMaster(port=0); m.start(); m.uri  # doctest: +SKIP
        'http://127.0.0.1:41234/'
    """

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_MASTER_PORT, *, trace: Trace | None = None,
                 allow_remote_shutdown: bool = False) -> None:
        self.trace = trace if trace is not None else Trace()
        self.allow_remote_shutdown = allow_remote_shutdown
        self._server = XmlRpcServer(self._handle, host=bind_address(host), port=port,
                                    trace=self.trace, name=MASTER_ID, advertise_host=host)
        self._methods = api_methods(self)
        self._lock = threading.RLock()
        self.publishers: dict[str, dict[str, str]] = {}   # topic -> caller_id -> api
        self.subscribers: dict[str, dict[str, str]] = {}
        self.services: dict[str, dict[str, tuple[str, str]]] = {}  # service -> caller -> (service_api, api)
        self.param_subscribers: dict[str, dict[str, str]] = {}
        self.topic_types: dict[str, str] = {}
        self.nodes: dict[str, str] = {}                   # caller_id -> api
        self.params = ParamTree()
        self.params.set("/run_id", str(uuid.uuid1()))
        self.params.set("/rosdistro", ROS_DISTRO + "\n")
        self.params.set("/rosversion", ROS_COMM_VERSION + "\n")
        # api -> {(method, topic or key): args}, waiting; _ready: apis no worker serves yet
        self._pending: dict[str, dict[tuple[str, str], tuple]] = {}
        self._pending_count = 0
        self._ready: collections.deque[str] = collections.deque()
        self._serving: set[str] = set()
        self._notify_cond = threading.Condition()
        self._notifiers: list[threading.Thread] = []
        self._stopping = False
        self.notify_errors: list[str] = []
        #: notifications dropped because MAX_NOTIFY_PENDING were waiting
        self.notify_dropped = 0
        self.running = False

    # ------------------------------------------------------------------ life cycle
    @property
    def uri(self) -> str:
        """The master's URI (what ROS_MASTER_URI should say)."""
        return self._server.uri

    @property
    def port(self) -> int:
        """The bound port."""
        return self._server.port

    def start(self) -> EmbeddedMaster:
        """Start serving; returns self."""
        self._server.start()
        self.trace.names[self.uri] = MASTER_ID
        self._stopping = False
        self._notifiers = [threading.Thread(target=self._notify_loop, daemon=True,
                                            name=f"rosfpga-master-notify-{i}")
                           for i in range(NOTIFY_WORKERS)]
        for t in self._notifiers:
            t.start()
        self.running = True
        _local[self.uri] = self
        return self

    def stop(self) -> None:
        """Stop serving and join every thread."""
        if not self.running:
            return
        self.running = False
        if _local.get(self.uri) is self:
            del _local[self.uri]
        self._server.stop()
        with self._notify_cond:
            self._stopping = True
            self._notify_cond.notify_all()
        for t in self._notifiers:
            t.join(JOIN_TIMEOUT)

    def __enter__(self) -> EmbeddedMaster:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _handle(self, method: str, params: tuple) -> Any:
        f = self._methods.get(method)
        if f is None:
            raise unsupported(method)
        return f(*params)

    # ------------------------------------------------------------------ notifications
    def _notify(self, api: str, method: str, key: str, args: tuple) -> None:
        """Queue ``method(MASTER_ID, *args)`` to ``api``; replaces a waiting one with the same key."""
        with self._notify_cond:
            waiting = self._pending.setdefault(api, {})
            if (method, key) not in waiting:
                if self._pending_count >= MAX_NOTIFY_PENDING:
                    self.notify_dropped += 1
                    self._note_error(f"{method} to {api} dropped: {MAX_NOTIFY_PENDING} "
                                     "notifications already waiting")
                    if not waiting:
                        del self._pending[api]
                    return
                self._pending_count += 1
            waiting[(method, key)] = args
            if api not in self._serving and api not in self._ready:
                self._ready.append(api)
                self._notify_cond.notify()

    def _note_error(self, text: str) -> None:
        self.notify_errors.append(text)
        del self.notify_errors[:-MAX_ERRORS_KEPT]

    def _notify_loop(self) -> None:
        while True:
            with self._notify_cond:
                while not self._ready and not self._stopping:
                    self._notify_cond.wait()
                if self._stopping:
                    return
                api = self._ready.popleft()
                items = self._pending.pop(api, {})
                self._pending_count -= len(items)
                self._serving.add(api)
            for (method, _key), args in items.items():
                if self._stopping:
                    break
                try:
                    call(api, method, MASTER_ID, *args, trace=self.trace, caller=MASTER_ID,
                         timeout=NOTIFY_TIMEOUT)
                except Exception as exc:  # one bad node (e.g. an unusable URI) must not stop the rest
                    with self._notify_cond:
                        self._note_error(f"{method} to {api}: {type(exc).__name__}: {exc}")
            with self._notify_cond:
                self._serving.discard(api)
                if self._pending.get(api):  # more came while we were busy with this node
                    self._ready.append(api)
                    self._notify_cond.notify()

    def _notify_topic(self, topic: str) -> None:
        pubs = list(self.publishers.get(topic, {}).values())
        for api in self.subscribers.get(topic, {}).values():
            self._notify(api, "publisherUpdate", topic, (topic, pubs))

    def _register_node(self, caller_id: str, api: str) -> None:
        old = self.nodes.get(caller_id)
        if old is not None and old != api:
            log.info("node [%s] re-registered with %s (was %s): telling the old one to shut down "
                     "(from %s)", caller_id, api, old, request_peer())
            self._notify(old, "shutdown", "", ("[%s] Reason: new node registered with same name" % caller_id,))
            for table in (self.publishers, self.subscribers, self.param_subscribers):
                for regs in table.values():
                    if regs.get(caller_id) == old:
                        del regs[caller_id]
            # its services go too (rosmaster's unregister_all): a restarted node that no longer
            # offers one must not leave the dead process's rosrpc:// URI in lookupService
            for service, providers in list(self.services.items()):
                if caller_id in providers and providers[caller_id][1] == old:
                    del self.services[service]
        self.nodes[caller_id] = api
        self.trace.names[api] = caller_id

    def _forget_if_idle(self, caller_id: str) -> None:
        for table in (self.publishers, self.subscribers, self.param_subscribers):
            if any(caller_id in regs for regs in table.values()):
                return
        if any(caller_id in regs for regs in self.services.values()):
            return
        self.nodes.pop(caller_id, None)

    @staticmethod
    def _log(tag: str, key: str, caller_id: str, api: str, refused: str = "") -> None:
        """One rosmaster-style line: ``+PUB [/topic] /caller http://api (from host:port)``."""
        if refused:
            log.warning("%s [%s] %s %s (from %s): refused: %s", tag, key, caller_id, api,
                        request_peer() or "this process", refused)
        else:
            log.info("%s [%s] %s %s (from %s)", tag, key, caller_id, api,
                     request_peer() or "this process")

    # ------------------------------------------------------------------ master API
    @checked((), -1)
    def getPid(self, caller_id: str) -> tuple:
        return 1, "", os.getpid()

    @checked((), "")
    def getUri(self, caller_id: str) -> tuple:
        return 1, "", self.uri

    @checked((("msg", "any"),), 0)
    def shutdown(self, caller_id: str, msg: Any) -> tuple:
        if not self.allow_remote_shutdown:
            return -1, "remote shutdown of the embedded master is disabled", 0
        threading.Thread(target=self.stop, daemon=True).start()
        return 1, "shutdown", 0

    @checked((("topic", "topic"), ("topic_type", "type"), ("caller_api", "api")), [])
    def registerPublisher(self, caller_id: str, topic: str, topic_type: str, caller_api: str) -> tuple:
        with self._lock:
            self._register_node(caller_id, caller_api)
            self.publishers.setdefault(topic, {})[caller_id] = caller_api
            if topic_type != "*" or topic not in self.topic_types:
                self.topic_types[topic] = topic_type
            self._notify_topic(topic)
            subs = list(self.subscribers.get(topic, {}).values())
        self._log("+PUB", topic, caller_id, caller_api)
        return 1, f"Registered [{caller_id}] as publisher of [{topic}]", subs

    @checked((("topic", "topic"), ("caller_api", "api")), 0)
    def unregisterPublisher(self, caller_id: str, topic: str, caller_api: str) -> tuple:
        return self._unregister(self.publishers, "-PUB", caller_id, topic, caller_api, notify=True)

    @checked((("topic", "topic"), ("topic_type", "type"), ("caller_api", "api")), [])
    def registerSubscriber(self, caller_id: str, topic: str, topic_type: str, caller_api: str) -> tuple:
        with self._lock:
            self._register_node(caller_id, caller_api)
            self.subscribers.setdefault(topic, {})[caller_id] = caller_api
            if topic not in self.topic_types and topic_type != "*":
                self.topic_types[topic] = topic_type
            pubs = list(self.publishers.get(topic, {}).values())
        self._log("+SUB", topic, caller_id, caller_api)
        return 1, f"Subscribed to [{topic}]", pubs

    @checked((("topic", "topic"), ("caller_api", "api")), 0)
    def unregisterSubscriber(self, caller_id: str, topic: str, caller_api: str) -> tuple:
        return self._unregister(self.subscribers, "-SUB", caller_id, topic, caller_api)

    def _unregister(self, table: dict, tag: str, caller_id: str, key: str, api: str,
                    notify: bool = False) -> tuple:
        with self._lock:
            if caller_id not in self.nodes:
                self._log(tag, key, caller_id, api, "not a registered node")
                return 1, f"[{caller_id}] is not a registered node", 0
            regs = table.get(key, {})
            if regs.get(caller_id) != api:
                self._log(tag, key, caller_id, api, f"registered with {regs.get(caller_id)}")
                return 1, f"[{caller_id}] is not a known provider of [{key}]", 0
            self._log(tag, key, caller_id, api)
            del regs[caller_id]
            if not regs:
                table.pop(key, None)
            if notify:
                self._notify_topic(key)
            self._forget_if_idle(caller_id)
        return 1, f"Unregistered [{caller_id}] as provider of [{key}]", 1

    @checked((("service", "topic"), ("service_api", "api"), ("caller_api", "api")), 0)
    def registerService(self, caller_id: str, service: str, service_api: str, caller_api: str) -> tuple:
        with self._lock:
            self._register_node(caller_id, caller_api)
            self.services[service] = {caller_id: (service_api, caller_api)}
        self._log("+SERVICE", service, caller_id, caller_api)
        return 1, f"Registered [{caller_id}] as provider of [{service}]", 1

    @checked((("service", "topic"), ("service_api", "api")), 0)
    def unregisterService(self, caller_id: str, service: str, service_api: str) -> tuple:
        with self._lock:
            if caller_id not in self.nodes:  # rosmaster's two texts, same codes
                self._log("-SERVICE", service, caller_id, service_api, "not a registered node")
                return 1, f"[{caller_id}] is not a registered node", 0
            regs = self.services.get(service, {})
            if caller_id not in regs or regs[caller_id][0] != service_api:
                self._log("-SERVICE", service, caller_id, service_api, "not its provider")
                return 1, f"[{service_api}] is no longer the current service api handle for [{service}]", 0
            self._log("-SERVICE", service, caller_id, service_api)
            del self.services[service]
            self._forget_if_idle(caller_id)
        return 1, f"Unregistered [{caller_id}] as provider of [{service}]", 1

    @checked((("service", "topic"),), "")
    def lookupService(self, caller_id: str, service: str) -> tuple:
        with self._lock:
            regs = self.services.get(service)
            if regs:
                url = next(iter(regs.values()))[0]
                return 1, f"rosrpc URI: [{url}]", url
        return -1, "no provider", ""

    @checked((("node", "name"),), "")
    def lookupNode(self, caller_id: str, node: str) -> tuple:
        with self._lock:
            api = self.nodes.get(node)
        if api is None:
            return -1, f"unknown node [{node}]", ""
        return 1, "node api", api

    @checked((("subgraph", "opt_name"),), 0)
    def getPublishedTopics(self, caller_id: str, subgraph: str) -> tuple:
        if subgraph and not subgraph.endswith("/"):
            subgraph += "/"
        with self._lock:
            topics = [[t, self.topic_types.get(t, "*")] for t in self.publishers if t.startswith(subgraph)]
        return 1, "current topics", topics

    @checked((), [])
    def getTopicTypes(self, caller_id: str) -> tuple:
        with self._lock:
            return 1, "current system state", [[t, ty] for t, ty in self.topic_types.items()]

    @checked((), [[], [], []])
    def getSystemState(self, caller_id: str) -> tuple:
        with self._lock:
            state = [
                [[t, sorted(r)] for t, r in self.publishers.items() if r],
                [[t, sorted(r)] for t, r in self.subscribers.items() if r],
                [[s, sorted(r)] for s, r in self.services.items() if r],
            ]
        return 1, "current system state", state

    # ------------------------------------------------------------------ parameter server
    @checked((("key", "key"),), 0)
    def deleteParam(self, caller_id: str, key: str) -> tuple:
        key = resolve(key, caller_id)
        with self._lock:
            try:
                self.params.delete(key)
            except KeyError:
                return -1, f"parameter [{key}] is not set", 0
            self._notify_params(key, {})
        log.info("-PARAM [%s] by %s (from %s)", key, caller_id, request_peer() or "this process")
        return 1, f"parameter {key} deleted", 0

    @checked((("key", "key"), ("value", "any")), 0)
    def setParam(self, caller_id: str, key: str, value: Any) -> tuple:
        key = resolve(key, caller_id)
        problem = check_param_value(value)
        if problem is not None:
            self._log("+PARAM", key, caller_id, "", problem)
            return -1, problem, 0
        with self._lock:
            try:
                self.params.set(key, value)
            except ValueError as exc:
                return -1, f"Error: invalid arguments: {exc}", 0
            self._notify_params(key, value, ignore=caller_id)
        log.info("+PARAM [%s] by %s (from %s)", key, caller_id, request_peer() or "this process")
        return 1, f"parameter {key} set", 0

    @checked((("key", "key"),), 0)
    def getParam(self, caller_id: str, key: str) -> tuple:
        key = resolve(key, caller_id)
        with self._lock:
            try:
                return 1, f"Parameter [{key}]", self.params.get(key)
            except KeyError:
                return -1, f"Parameter [{key}] is not set", 0

    @checked((("key", "key"),), 0)
    def searchParam(self, caller_id: str, key: str) -> tuple:
        """rosmaster's search: a relative key's first part is looked for in ``caller_id`` itself
        (the node's private namespace: roscpp's ``NodeHandle("~").searchParam`` relies on it),
        then in each namespace above it; the answer joins the found namespace and the key as
        given. A ``~`` key or a relative caller is rosmaster's code-0 internal failure."""
        if key.startswith("~"):
            return 0, "Internal failure: invalid key", 0
        if not caller_id.startswith("/"):
            return 0, "Internal failure: namespace must be global", 0
        if key.startswith("/"):
            with self._lock:
                found = self.params.has(key)
            return (1, f"Found [{key}]", key) if found else \
                (-1, f"Cannot find parameter [{key}] in an upwards search", "")
        first = next((p for p in key.split("/") if p), key)
        parts = [p for p in caller_id.split("/") if p]
        with self._lock:
            for depth in range(len(parts), -1, -1):
                ns = "/" + "".join(p + "/" for p in parts[:depth])
                if self.params.has(ns + first):
                    return 1, f"Found [{ns + key}]", ns + key
        return -1, f"Cannot find parameter [{key}] in an upwards search", ""

    @checked((("caller_api", "api"), ("key", "key")), 0)
    def subscribeParam(self, caller_id: str, caller_api: str, key: str) -> tuple:
        key = resolve(key, caller_id)
        with self._lock:
            self._register_node(caller_id, caller_api)
            self.param_subscribers.setdefault(key, {})[caller_id] = caller_api
            self._log("+CACHEDPARAM", key, caller_id, caller_api)
            try:
                value = self.params.get(key)
            except KeyError:
                value = {}
        return 1, f"Subscribed to parameter [{key}]", value

    @checked((("caller_api", "api"), ("key", "key")), 0)
    def unsubscribeParam(self, caller_id: str, caller_api: str, key: str) -> tuple:
        key = resolve(key, caller_id)
        self._unregister(self.param_subscribers, "-CACHEDPARAM", caller_id, key, caller_api)
        return 1, f"Unsubscribe to parameter [{key}]", 1  # rosmaster always answers 1

    @checked((("key", "key"),), False)
    def hasParam(self, caller_id: str, key: str) -> tuple:
        key = resolve(key, caller_id)
        with self._lock:
            return 1, key, self.params.has(key)

    @checked((), [])
    def getParamNames(self, caller_id: str) -> tuple:
        with self._lock:
            return 1, "Parameter names", self.params.names()

    def _notify_params(self, key: str, value: Any, ignore: str | None = None) -> None:
        """Queue ``paramUpdate`` for every subscriber the change of ``key`` concerns, with the
        key and value rosmaster's ``compute_param_updates`` sends (``ignore``: the setter's
        caller_id, not told of its own change by the first rule, as rosmaster does)."""
        for _sub, api, update_key, update_value in param_updates(
                self.param_subscribers, key, value, ignore):
            self._notify(api, "paramUpdate", update_key, (update_key, update_value))


def _all_keys(prefix: str, tree: dict, out: list[str]) -> list[str]:
    """Every key under ``prefix`` in ``tree``, each ending in "/" (rosmaster's _compute_all_keys)."""
    stack = [(prefix, tree)]
    while stack:
        p, d = stack.pop()
        for k, v in d.items():
            key = p.rstrip("/") + "/" + k + "/"
            out.append(key)
            if isinstance(v, dict):
                stack.append((key, v))
    return out


def param_updates(subscribers: dict[str, dict[str, str]], key: str, value: Any,
                  ignore: str | None = None) -> list[tuple[str, str, str, Any]]:
    """``(subscribed key, api, key sent, value sent)`` for each paramUpdate that setting (or,
    with ``value == {}``, deleting) ``key`` causes: rosmaster 1.15's rules. A subscriber of the
    key or of a namespace above it gets the changed key (with a trailing "/") and its new
    value; when a dict is set, a subscriber below it gets its own key with the value found
    there, or ``{}`` when the new dict no longer holds it."""
    param_key = key if key == "/" else canonical(key).rstrip("/") + "/"
    all_keys = set(_all_keys(param_key, value, [])) if isinstance(value, dict) else None
    out: list[tuple[str, str, str, Any]] = []
    for sub_key, regs in subscribers.items():
        ns_key = sub_key if sub_key.endswith("/") else sub_key + "/"
        if param_key.startswith(ns_key):
            out.extend((sub_key, api, param_key, value) for cid, api in regs.items() if cid != ignore)
        elif all_keys is not None and ns_key.startswith(param_key):
            if ns_key in all_keys:
                found: Any = value
                for part in [x for x in ns_key[len(param_key):].split("/") if x]:
                    found = found[part]
                out.extend((sub_key, api, ns_key, _copy(found)) for api in regs.values())
            else:
                out.extend((sub_key, api, ns_key, {}) for api in regs.values())
    return out


def knows_node(master_uri: str, name: str, api: str, timeout: float) -> bool | None:
    """Whether the master at ``master_uri`` has ``name`` registered with ``api`` (None: with
    another API: someone took the name). A master running in this process is asked directly
    (no XML-RPC, nothing in any trace); another one by an untraced ``lookupNode``.

    Raises:
        GraphError: the master cannot be reached.
    """
    local = _local.get(master_uri)
    if local is not None and local.running:
        with local._lock:
            known = local.nodes.get(name)
    else:
        reply = call(master_uri, "lookupNode", name, name, timeout=timeout)
        known = reply[2] if isinstance(reply, list) and len(reply) == 3 and reply[0] == 1 else None
    if known is None:
        return False
    return True if known == api else None
