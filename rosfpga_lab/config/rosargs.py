"""The ROS 1 command line: remappings, special keys and private parameters, as rospy/roscpp take them.

How this works: a ROS node's arguments may hold, anywhere among its own options, words of the
form ``from:=to`` (rosgraph's ``myargv`` drops every word containing ``:=`` before a program
parses its options; this module does the same with :func:`split_ros_args`). Three kinds:

* special keys ``__name``, ``__ns``, ``__log``, ``__ip``, ``__hostname``, ``__master``
  (roslaunch appends ``__name:=`` and ``__log:=`` to every ``<node>``);
* private parameters ``_name:=value`` (the value read as YAML, as rospy does: ``_ksize:=5`` is
  the int 5), which a node puts on the parameter server as ``~name``;
* remappings ``from:=to`` of graph names. Both sides resolve against the node's own name (so
  ``~x`` is private, ``x`` is in the node's namespace), then a name the node uses is first
  resolved, then looked up among the remappings (rospy's ``rospy.names.resolve_name``).

The node's own name follows roscpp's ``this_node::init``: ``__name`` replaces the given name, the
namespace is ``__ns``, else ``ROS_NAMESPACE``, else ``/``, and a relative name resolves in it
(a global name in a node configuration stays global unless ``__name`` is given).
Which address a node advertises follows roscpp and rospy too (:func:`advertise_host`).

Sans-IO: the environment is an argument; nothing here touches sockets or the process.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import yaml

from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.names import canonical, name_problem

if TYPE_CHECKING:
    from rosfpga_lab.config.node import NodeConfig

#: The special keys rospy and roscpp take (``__name:=`` ...), and what each sets.
SPECIAL_KEYS: dict[str, str] = {
    "__name": "the node's name (replaces the configured one)",
    "__ns": "the node's namespace (beats ROS_NAMESPACE)",
    "__log": "the node's log file (roslaunch gives it; the lab logs to stderr)",
    "__ip": "the address the node advertises (like ROS_IP)",
    "__hostname": "the host name the node advertises (like ROS_HOSTNAME)",
    "__master": "the ROS master's URI (like ROS_MASTER_URI)",
}
#: The separator of a ROS command-line word.
ASSIGN = ":="


@dataclass(frozen=True)
class RosArgs:
    """What the ROS words of a command line say.

    Attributes:
        remappings: ``from -> to`` as written (unresolved; see :meth:`resolved_remappings`).
        special: ``__name``, ``__ns``, ... -> value.
        params: private parameter name (without ``_`` or ``~``) -> value (YAML-typed).
        words: the ROS words themselves, in order (for messages).
    """

    remappings: dict[str, str] = field(default_factory=dict)
    special: dict[str, str] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    words: tuple[str, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.words)

    def resolved_remappings(self, node_name: str) -> dict[str, str]:
        """The remappings with both sides resolved against ``node_name`` (rospy's
        ``initialize_mappings``)."""
        return {resolve_name(k, node_name): resolve_name(v, node_name)
                for k, v in self.remappings.items()}


def is_ros_arg(word: str) -> bool:
    """True for a word rosgraph's ``myargv`` would drop (it contains ``:=``)."""
    return ASSIGN in word


def split_ros_args(argv: Sequence[str]) -> tuple[list[str], RosArgs]:
    """Separate a program's own arguments from the ROS words and parse those.

    Args:
        argv: the command line (without the program name).

    Returns:
        The other arguments in order, and the parsed :class:`RosArgs`.

    Raises:
        ConfigError: a ROS word is malformed (``:=x``, ``a:=``), names an unknown special key,
            remaps an illegal name, or repeats a key with another value.
    """
    rest: list[str] = []
    remappings: dict[str, str] = {}
    special: dict[str, str] = {}
    params: dict[str, Any] = {}
    words: list[str] = []
    for word in argv:
        if not is_ros_arg(word):
            rest.append(word)
            continue
        words.append(word)
        key, _, value = word.partition(ASSIGN)
        where = f"ROS argument {word!r}"
        if not key or not value:
            raise ConfigError(f"{where}: write NAME:=VALUE (both sides non-empty)")
        if key.startswith("__"):
            if key not in SPECIAL_KEYS:
                raise ConfigError(f"{where}: unknown special key {key!r} (known: "
                                  f"{', '.join(SPECIAL_KEYS)})")
            _put(special, key, value, where)
        elif key.startswith("_"):
            name = key[1:]
            problem = name_problem(name)
            if problem or "/" in name:
                raise ConfigError(f"{where}: a private parameter is _NAME:=VALUE with a plain "
                                  f"name ({problem or 'no /'})")
            try:
                parsed = yaml.safe_load(value)
            except yaml.YAMLError:
                parsed = value   # rospy keeps a value YAML cannot read as the string
            _put(params, name, parsed, where)
        else:
            for side in (key, value):
                problem = name_problem(side)
                if problem:
                    raise ConfigError(f"{where}: {problem}: {side!r}")
            _put(remappings, key, value, where)
    _check_special(special)
    return rest, RosArgs(remappings, special, params, tuple(words))


def _put(table: dict[str, Any], key: str, value: Any, where: str) -> None:
    if key in table and table[key] != value:
        raise ConfigError(f"{where}: {key} was already given as {table[key]!r}")
    table[key] = value


def _check_special(special: Mapping[str, str]) -> None:
    name = special.get("__name")
    if name is not None and (name_problem(name, node_name=True) or "/" in name or "~" in name):
        raise ConfigError(f"ROS argument {'__name:=' + name!r}: a node name here is a base name "
                          "(a letter, then letters, digits and '_'; no '/' or '~'), as roscpp "
                          "requires")
    ns = special.get("__ns")
    if ns is not None and name_problem(ns) and ns != "/":
        raise ConfigError(f"ROS argument {'__ns:=' + ns!r}: {name_problem(ns)}")
    master = special.get("__master")
    if master is not None and not master.startswith("http://"):
        raise ConfigError(f"ROS argument {'__master:=' + master!r}: expected http://HOST:PORT/")


def namespace_of(name: str) -> str:
    """``/a/b/c`` -> ``/a/b/``; ``/c`` -> ``/`` (rosgraph's ``namespace``)."""
    name = canonical(name)
    return name[: name.rfind("/") + 1] if "/" in name else "/"


def resolve_name(name: str, node_name: str) -> str:
    """rosgraph's ``resolve_name`` without remappings: global stays, ``~x`` goes under the
    node, anything else into the node's namespace."""
    if not name:
        return namespace_of(node_name)
    if name.startswith("/"):
        return canonical(name)
    if name.startswith("~"):
        return canonical(canonical(node_name) + "/" + name[1:])
    return canonical(namespace_of(node_name) + name)


def node_namespace(ros: RosArgs, environ: Mapping[str, str] | None = None) -> str:
    """``__ns``, else ``ROS_NAMESPACE``, else ``/``; always global, with a trailing ``/``."""
    env = os.environ if environ is None else environ
    ns = ros.special.get("__ns") or env.get("ROS_NAMESPACE", "").strip() or "/"
    problem = name_problem(ns) if ns != "/" else None
    if problem:
        raise ConfigError(f"ROS_NAMESPACE={ns!r}: {problem}")
    ns = canonical("/" + ns)
    return ns if ns.endswith("/") else ns + "/"


def node_name(configured: str, ros: RosArgs, environ: Mapping[str, str] | None = None) -> str:
    """The node's global name: ``__name`` (or ``configured``) resolved in the namespace.

    A relative ``configured`` name (``fpga``) lands in ``__ns`` or ``ROS_NAMESPACE``; a global
    one (``/fpga``) stays where it is, unless ``__name`` replaces it (roslaunch always gives
    ``__name``, so a launch file's ``ns=`` and ``name=`` decide).
    """
    ns = node_namespace(ros, environ)
    name = ros.special.get("__name", configured)
    if name.startswith("/"):
        return canonical(name)
    return canonical(ns + name)


def remap(name: str, node: str, ros: RosArgs) -> str:
    """The graph name a node called ``node`` uses for ``name``: resolved, then remapped."""
    resolved = resolve_name(name, node)
    return ros.resolved_remappings(node).get(resolved, resolved)


@dataclass(frozen=True)
class NodeNames:
    """A node configuration's names after the ROS command line and the environment.

    Attributes:
        node: the node's global name.
        input: the subscribed topic (resolved, remapped).
        output: the published topic (resolved, remapped).
    """

    node: str
    input: str
    output: str


def component_names(config: NodeConfig, ros: RosArgs,
                    environ: Mapping[str, str] | None = None) -> NodeNames:
    """The component's node and topic names: :func:`node_name`, then :func:`remap` of each topic.

    Raises:
        ConfigError: the remapped topics are the same (the node would hear itself).
    """
    node = node_name(config.node.name, ros, environ)
    names = NodeNames(node, remap(config.subscriber.topic, node, ros),
                      remap(config.publisher.topic, node, ros))
    if names.input == names.output:
        raise ConfigError(f"after remapping, the node would publish to the topic it subscribes "
                          f"to ({names.input})")
    return names


@dataclass(frozen=True)
class HostChoice:
    """The address a node advertises and where it came from (for the start-up line)."""

    host: str
    source: str


def advertise_host(ros: RosArgs, configured: str | None,
                   environ: Mapping[str, str] | None = None, default: str = "127.0.0.1",
                   ) -> HostChoice:
    """Which address a node binds and advertises, first that is set wins.

    roscpp's order (rospy's differs only in taking the first of ``__hostname``/``__ip`` on the
    command line): ``__hostname``, ``__ip``, ``ROS_HOSTNAME``, ``ROS_IP``; then the node
    configuration's ``node.ip_address`` (``configured``); then ``default`` (loopback: a
    workshop network should not see students' nodes by accident; ROS would use the hostname).

    Raises:
        ConfigError: ``ROS_HOSTNAME`` or ``ROS_IP`` holds a scheme or a port (rospy refuses them too).
    """
    env = os.environ if environ is None else environ
    for key in ("__hostname", "__ip"):
        if ros.special.get(key):
            return HostChoice(ros.special[key], f"{key}:=")
    for var in ("ROS_HOSTNAME", "ROS_IP"):
        value = env.get(var, "").strip()
        if value:
            if "://" in value or (value.count(":") == 1 and var == "ROS_HOSTNAME"):
                raise ConfigError(f"invalid {var}={value!r}: give a host name or address only "
                                  "(no protocol, no port)")
            return HostChoice(value, var)
    if configured:
        return HostChoice(configured, "the configuration's node.ip_address")
    return HostChoice(default, "the lab's default (loopback)")
