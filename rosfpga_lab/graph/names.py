"""ROS graph names and the environment (ROS_MASTER_URI, ROS_IP, ROS_HOSTNAME).

Names follow rosgraph.names: ``/ns/name`` is global, ``name`` is relative to the caller's
namespace, ``~name`` is private (under the caller's own name). Which names are legal is decided
by :mod:`rosfpga_lab.config.names` (the lab's one validator); this module resolves them.
"""

from __future__ import annotations

import ipaddress
import os
import re
import socket
import time
import warnings

from rosfpga_lab.config.master import master_uri_from_env  # noqa: F401  (re-exported; the rule's owner)
from rosfpga_lab.config.names import canonical, is_legal_name, name_problem  # noqa: F401  (re-exported)
from rosfpga_lab.config.rosargs import RosArgs, advertise_host
from rosfpga_lab.config.rosargs import namespace_of, resolve_name  # noqa: F401  (re-exported)
from rosfpga_lab.graph.errors import ConfigError

ALL_INTERFACES = ("0.0.0.0", "", "::")


def anonymous_name(base: str) -> str:
    """``base`` made unique as rospy's ``init_node(anonymous=True)`` does: ``base_PID_MS``.

    The process id keeps two tools started in the same millisecond apart (a name registered
    twice makes the master shut the first node down)."""
    return f"{base}_{os.getpid()}_{int(time.time() * 1000)}"


class OpenBindWarning(UserWarning):
    """Binding to every network interface: ROS 1 has no authentication."""


def resolve(name: str, caller_id: str = "/") -> str:
    """Resolve ``name`` against ``caller_id`` the way the master and rospy do (the rule's owner:
    :func:`rosfpga_lab.config.rosargs.resolve_name`)."""
    return resolve_name(name, caller_id)


def check_node_name(name: str) -> str:
    """Return the canonical global node name.

    Raises:
        ConfigError: not a legal node name (:func:`rosfpga_lab.config.names.name_problem`).
    """
    problem = name_problem(name, node_name=True)
    if problem:
        raise ConfigError(f"illegal node name {name!r}: {problem}")
    return resolve(name, "/")


def check_topic_name(name: str, caller_id: str = "/") -> str:
    """Return ``name`` resolved against ``caller_id`` (see :func:`resolve`).

    Raises:
        ConfigError: not a legal ROS name (:func:`rosfpga_lab.config.names.name_problem`).
    """
    problem = name_problem(name)
    if problem:
        raise ConfigError(f"illegal topic name {name!r}: {problem}")
    return resolve(name, caller_id)


def default_host() -> str:
    """The address nodes bind to and advertise: ROS_HOSTNAME, then ROS_IP (roscpp's and rospy's
    order), else 127.0.0.1 (:func:`rosfpga_lab.config.rosargs.advertise_host` owns the rule).

    Unlike ROS (which defaults to the machine's hostname, reachable from the network), the lab
    defaults to loopback: a workshop network should not see students' nodes by accident.
    """
    return advertise_host(RosArgs(), None).host


def is_ipv6_literal(host: str) -> bool:
    """True for an IPv6 address such as ``::1`` (brackets allowed, as in a URI)."""
    try:
        return ipaddress.ip_address(host.strip("[]")).version == 6
    except ValueError:
        return False


def address_family(bind: str) -> socket.AddressFamily:
    """The socket family that binds ``bind`` (IPv6 for an IPv6 literal, else IPv4)."""
    return socket.AF_INET6 if is_ipv6_literal(bind) else socket.AF_INET


def uri_host(host: str) -> str:
    """``host`` as written in a URI: an IPv6 literal in brackets (``[::1]``)."""
    return f"[{host.strip('[]')}]" if is_ipv6_literal(host) else host


def bind_address(host: str) -> str:
    """The address to bind for an advertised ``host``: the address itself (IPv4 or IPv6, never
    widened), or every interface with a warning when asked (``0.0.0.0``, ``::``) or when
    ``host`` is a host name (it may resolve to any interface, as for roscpp)."""
    if host in ALL_INTERFACES:
        warnings.warn(
            "binding to all network interfaces: ROS 1 has no authentication, anyone who can "
            "reach this machine can publish, subscribe and stop nodes. Use 127.0.0.1 unless "
            "you need other machines.", OpenBindWarning, stacklevel=3)
        return "::" if host == "::" else "0.0.0.0"
    if host in ("localhost",):
        return "127.0.0.1"
    if re.fullmatch(r"[0-9.]+", host):
        return host
    if is_ipv6_literal(host):
        return host.strip("[]")
    # a hostname (ROS_HOSTNAME): bind every interface it may resolve to, like roscpp does
    warnings.warn(f"binding to all interfaces to serve the hostname {host!r}; ROS 1 has no "
                  "authentication", OpenBindWarning, stacklevel=3)
    return "0.0.0.0"
