"""The composed YAML of a configuration, walked with its line numbers.

How this works: the YAML is *composed* (not just loaded) so every key and value keeps its line
number; these helpers read mappings, scalars and lists from the nodes, refusing unknown,
duplicate and mistyped keys, and every problem is a :class:`~rosfpga_lab.config.errors.ConfigError`
naming the file (:class:`Ctx`), the line and the dotted key.
"""

from __future__ import annotations

import difflib
from typing import Any

import yaml

from rosfpga_lab.config.errors import ConfigError

#: A section's values (defaults filled in) and the YAML node of each value given.
Section = tuple[dict[str, Any], dict[str, yaml.Node]]
#: A mapping's keys -> (key node, value node).
Nodes = dict[str, tuple[yaml.Node, yaml.Node]]


class Ctx:
    """Where we are: the file name, for error messages."""

    def __init__(self, source: str) -> None:
        self.source = source

    def error(self, message: str, node: yaml.Node | None = None, key: str = "") -> ConfigError:
        line = node.start_mark.line + 1 if node is not None else 0
        return ConfigError(message, path=self.source, line=line, key=key)


def scalar(ctx: Ctx, node: yaml.Node, key: str) -> Any:
    """The value of a scalar node (``key`` names it in an error: a mapping or a list)."""
    if not isinstance(node, yaml.ScalarNode):
        raise ctx.error("expected a single value, found a "
                        + ("mapping" if isinstance(node, yaml.MappingNode) else "list"), node, key)
    return yaml.constructor.SafeConstructor().construct_object(node, deep=True)


def mapping(ctx: Ctx, node: yaml.Node, key: str, allowed: dict[str, Any]) -> Nodes:
    """Keys of a mapping node -> (key node, value node); unknown or duplicate keys refused."""
    if not isinstance(node, yaml.MappingNode):
        where = f"section {key!r}" if key else "the file"
        raise ctx.error(f"{where} must be a mapping of 'key: value' lines", node, key)
    out: Nodes = {}
    for knode, vnode in node.value:
        name = knode.value if isinstance(knode, yaml.ScalarNode) else None
        dotted = f"{key}.{name}" if key else str(name)
        if not isinstance(name, str):
            raise ctx.error("keys must be plain names", knode, key)
        if name in out:
            first = out[name][0].start_mark.line + 1
            raise ctx.error(f"duplicate key (first given on line {first})", knode, dotted)
        if name not in allowed:
            close = difflib.get_close_matches(name, list(allowed), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ctx.error(f"unknown key{hint} (known: {', '.join(allowed)})", knode, dotted)
        out[name] = (knode, vnode)
    return out


def typed(ctx: Ctx, vnode: yaml.Node, dotted: str, kind: type | tuple[type, ...]) -> Any:
    """A scalar's value, refused unless it is of ``kind`` (a bool is never an int here)."""
    value = scalar(ctx, vnode, dotted)
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if isinstance(value, bool) or not isinstance(value, kinds):
        names = " or ".join("null" if k is type(None) else k.__name__ for k in kinds)
        raise ctx.error(f"expected {names}, got {value!r}", vnode, dotted)
    return value


def check(ctx: Ctx, ok: bool, message: str, nodes: dict[str, yaml.Node], key: str,
          section: str) -> None:
    """Raise ``message`` at ``section.key``'s line unless ``ok``."""
    if not ok:
        raise ctx.error(message, nodes.get(key), f"{section}.{key}")


def _given(top: Nodes, name: str) -> yaml.Node | None:
    """The value node of top-level key ``name``; None when it is absent or null."""
    if name not in top:
        return None
    vnode = top[name][1]
    if isinstance(vnode, yaml.ScalarNode) and vnode.tag.endswith(":null"):
        return None
    return vnode


def free_mapping(ctx: Ctx, top: Nodes, name: str) -> list[tuple[str, yaml.Node, Any]]:
    """``(key, value node, value)`` of a top-level mapping whose keys are field paths."""
    vnode = _given(top, name)
    if vnode is None:
        return []
    if not isinstance(vnode, yaml.MappingNode):
        raise ctx.error("must be a mapping of 'field: value' lines", vnode, name)
    out: list[tuple[str, yaml.Node, Any]] = []
    seen: dict[str, int] = {}
    for knode, node in vnode.value:
        key = knode.value if isinstance(knode, yaml.ScalarNode) else None
        if not isinstance(key, str) or not key:
            raise ctx.error("keys must be field paths like header.frame_id", knode, name)
        dotted = f"{name}.{key}"
        if key in seen:
            raise ctx.error(f"duplicate key (first given on line {seen[key]})", knode, dotted)
        seen[key] = knode.start_mark.line + 1
        if isinstance(node, yaml.MappingNode):
            value: Any = {}
            for bk, bv in node.value:
                bname = bk.value if isinstance(bk, yaml.ScalarNode) else None
                if bname not in ("min", "max") or bname in value:
                    raise ctx.error("a bound is {min: LOW, max: HIGH} (either may be left out)",
                                    bk, dotted)
                value[bname] = scalar(ctx, bv, dotted)
        else:
            value = scalar(ctx, node, dotted)
        out.append((key, node, value))
    return out


def string_list(ctx: Ctx, top: Nodes, name: str) -> list[tuple[str, yaml.Node]]:
    """``(name, node)`` of each item of a top-level list of names (none when absent or null)."""
    vnode = _given(top, name)
    if vnode is None:
        return []
    if not isinstance(vnode, yaml.SequenceNode):
        raise ctx.error("must be a list, e.g. [a, b]", vnode, name)
    out = []
    for item in vnode.value:
        value = scalar(ctx, item, name)
        if not isinstance(value, str) or not value:
            raise ctx.error(f"expected a name, got {value!r}", item, name)
        out.append((value, item))
    return out


__all__ = ["Ctx", "Nodes", "Section", "check", "free_mapping", "mapping", "scalar", "string_list",
           "typed"]
