"""ROS 1 graph resource names: the lab's one validator, following ``rosgraph.names``.

The rules are rosgraph's (``rosgraph.names.is_legal_name`` / ``is_legal_base_name``, the ROS
wiki's "Names" page): a name is empty (it resolves to the caller's namespace) or starts with a
letter, ``/`` or ``~`` and goes on with letters, digits, ``_`` and ``/``, never ``//``; a *base
name* (a node's own name, no namespace) is a letter followed by letters, digits and ``_``.
So ``/1a`` is a legal topic but not a legal node name, and ``/a/`` is legal (it canonicalises to
``/a``).

One deliberate difference: letters and digits are ASCII only. rosgraph's pattern uses ``\\w``,
which in Python 3 also matches ``ü``; roscpp (``ros::names::validate``), the wiki and the
generated circuit allow ASCII only, so a name legal here works with every ROS client. A test
compares these functions with real rosgraph on a table of names.
"""

from __future__ import annotations

import re

# rosgraph.names.NAME_LEGAL_CHARS_P and BASE_NAME_LEGAL_CHARS_P, with \w spelled out in ASCII.
_NAME = re.compile(r"[~/A-Za-z][A-Za-z0-9_/]*")
_BASE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
#: Characters a name may hold after its first.
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_/")


def is_legal_name(name: str) -> bool:
    """rosgraph's ``is_legal_name`` (ASCII letters and digits only); the empty name is legal."""
    return name == "" or (_NAME.fullmatch(name) is not None and "//" not in name)


def is_legal_base_name(name: str) -> bool:
    """rosgraph's ``is_legal_base_name`` (ASCII): a letter, then letters, digits and ``_``."""
    return _BASE_NAME.fullmatch(name) is not None


def canonical(name: str) -> str:
    """Collapse repeated slashes and drop a trailing one (except for the root)."""
    if not name:
        return name
    lead = "/" if name.startswith("/") else ""
    parts = [p for p in name.split("/") if p]
    return lead + "/".join(parts) if parts else "/"


def name_problem(name: str, *, node_name: bool = False) -> str | None:
    """Why ``name`` is not a legal topic (or node) name, or None when it is.

    Args:
        name: a graph resource name.
        node_name: apply the rules of node names too: not private (``~``), not the root, and the
            last part a legal base name (rosgraph's ``is_legal_base_name``).

    Returns:
        A sentence for an error message (without the name), or None.
    """
    if not name:
        return "a ROS name cannot be empty"
    if not is_legal_name(name):
        bad = next((c for c in name[1:] if c not in _NAME_CHARS), None)
        if not _NAME.fullmatch(name[0]):
            return "a ROS name starts with a letter, '/' or '~'"
        if bad is not None:
            return (f"character {bad!r} is not allowed in a ROS name (ASCII letters, digits, '_', "
                    "'/'; '~' only first)")
        return "a ROS name cannot contain '//'"
    if node_name:
        if name.startswith("~"):
            return "a node name cannot be private ('~')"
        base = canonical(name).rsplit("/", 1)[-1]
        if not base:
            return "a node name cannot be '/'"
        if not is_legal_base_name(base):
            return f"a node's base name must start with a letter, got {base!r}"
    return None


def ros_name_problem(name: str, *, node_name: bool = False) -> str | None:
    """Why ``name`` cannot be a topic (or node) name in a configuration, or None.

    The ROS rules of :func:`rosfpga_lab.config.names.name_problem`, plus one of the configuration:
    the name is written in canonical form (no trailing ``/``), as the circuit sends it verbatim
    in its connection headers.

    Args:
        name: a graph resource name (topic or node).
        node_name: apply the extra rules of node names (not private, base name legal).
    """
    problem = name_problem(name, node_name=node_name)
    if problem is None and name != canonical(name):
        return f"write the name in canonical form, {canonical(name)!r} (no trailing '/')"
    return problem
