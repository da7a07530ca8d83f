"""The configuration file's schema: its sections, keys, types and defaults, in one table.

A section's keys are checked here for presence and type (:func:`section`); what a value may
be is checked by the section's parser (:mod:`~rosfpga_lab.config.sections`).
"""

from __future__ import annotations

from typing import Any

import yaml

from rosfpga_lab.config import limits
from rosfpga_lab.config.vocabulary import DEFAULT_HLS_FLAVOUR, DEFAULT_OP, DEFAULT_WIRE
from rosfpga_lab.config.yamlwalk import Ctx, Nodes, Section, mapping, typed

#: The default of a key that must be given.
REQUIRED = object()
#: Section -> key -> (Python type, default or REQUIRED). Each section is one record of
#: :mod:`~rosfpga_lab.config.node`.
SCHEMA: dict[str, dict[str, tuple[type | tuple[type, ...], Any]]] = {
    "node": {"name": (str, REQUIRED), "master_uri": (str, limits.DEFAULT_MASTER_URI),
             "ip_address": (str, limits.DEFAULT_IP_ADDRESS), "xmlrpc_port": (int, 0),
             "tcpros_port": (int, 0)},
    "subscriber": {"topic": (str, REQUIRED), "type": (str, limits.IMAGE_TYPE)},
    "publisher": {"topic": (str, REQUIRED), "type": ((str, type(None)), None)},
    "image": {"width": (int, REQUIRED), "height": (int, REQUIRED), "encoding": (str, REQUIRED)},
    "application": {"op": (str, DEFAULT_OP), "ksize": (int, 3), "source": ((str, type(None)), None)},
    "fifo": {"input_depth": (int, limits.DEFAULT_INPUT_FIFO_DEPTH),
             "output_depth": (int, limits.DEFAULT_OUTPUT_FIFO_DEPTH),
             "axis_depth": (int, limits.DEFAULT_AXIS_FIFO_DEPTH)},
    "stream": {"field": (str, REQUIRED), "length": ((int, type(None)), None)},
    "hls": {"flavour": (str, DEFAULT_HLS_FLAVOUR)},
}
#: Top-level keys read by their own code (lists and free mappings of field paths).
FREE_KEYS = ("msg_path", "checks", "limits", "skip")
#: Top-level single values -> (Python type, default).
TOP_SCALARS: dict[str, tuple[type | tuple[type, ...], Any]] = {
    "clock_mhz": ((int, float), limits.DEFAULT_CLOCK_MHZ),
    "frame_id_max": (int, limits.DEFAULT_FRAME_ID_MAX),
    "part": (str, limits.DEFAULT_PART),
    "wire": (str, DEFAULT_WIRE),
}
#: Sections a file must have.
REQUIRED_SECTIONS = ("node", "subscriber", "publisher")
#: Sections that are left out unless given (no defaults to fill).
OPTIONAL_SECTIONS = ("image", "stream")


def section(ctx: Ctx, top: Nodes, name: str) -> Section:
    """Values of one section with defaults filled in, and the node of each given value."""
    schema = SCHEMA[name]
    if name not in top and name in OPTIONAL_SECTIONS:
        return {}, {}
    if name not in top:
        if name in REQUIRED_SECTIONS:
            raise ctx.error(f"missing section '{name}:' (keys: {', '.join(schema)})", None, name)
        return {k: d for k, (_t, d) in schema.items()}, {}
    knode, vnode = top[name]
    if isinstance(vnode, yaml.ScalarNode) and vnode.value == "" and vnode.tag.endswith(":null"):
        vnode = yaml.MappingNode("tag:yaml.org,2002:map", [], knode.start_mark, knode.end_mark)
    given = mapping(ctx, vnode, name, schema)
    values: dict[str, Any] = {}
    nodes: dict[str, yaml.Node] = {}
    for key, (kind, default) in schema.items():
        dotted = f"{name}.{key}"
        if key in given:
            values[key] = typed(ctx, given[key][1], dotted, kind)
            nodes[key] = given[key][1]
        elif default is REQUIRED:
            raise ctx.error(f"missing key '{key}' in section '{name}'", knode, dotted)
        else:
            values[key] = default
    return values, nodes


__all__ = ["FREE_KEYS", "OPTIONAL_SECTIONS", "REQUIRED", "REQUIRED_SECTIONS", "SCHEMA",
           "TOP_SCALARS", "section"]
