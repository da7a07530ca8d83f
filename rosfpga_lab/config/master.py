"""Which ROS master a program talks to: one rule for the whole lab.

The precedence, first that applies wins:

1. an explicit URI (``master_uri=`` of a function, ``--master-uri`` of a command);
2. the ``ROS_MASTER_URI`` environment variable (when set and not blank);
3. a node configuration's ``node.master_uri`` (when the program was given one);
4. :data:`~rosfpga_lab.config.limits.DEFAULT_MASTER_URI` (roscore's ``http://127.0.0.1:11311/``).

Every command and :class:`~rosfpga_lab.graph.Node`'s default go through :func:`master_uri`
(a bare ``Node`` adds one step after 2: when nothing answers on the default URI it starts the
process's own embedded master; see :func:`rosfpga_lab.graph.default_master_uri`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

from rosfpga_lab.config.limits import DEFAULT_MASTER_URI

if TYPE_CHECKING:
    from rosfpga_lab.config.node import NodeConfig


def master_uri_from_env(environ: Mapping[str, str] | None = None) -> str | None:
    """``ROS_MASTER_URI`` if set and non-blank, else None.

    Args:
        environ: the environment to read (default: ``os.environ``).
    """
    value = (os.environ if environ is None else environ).get("ROS_MASTER_URI", "").strip()
    return value or None


def master_uri(explicit: str | None = None, config: NodeConfig | None = None,
               environ: Mapping[str, str] | None = None) -> str:
    """The master to use: ``explicit``, else ``ROS_MASTER_URI``, else the configuration's
    ``node.master_uri``, else :data:`DEFAULT_MASTER_URI`.

    Args:
        explicit: a URI the user gave (``--master-uri``); None or empty when not given.
        config: the node configuration the program runs, if any.
        environ: the environment to read (default: ``os.environ``; pass ``{}`` to ignore it).
    """
    if explicit:
        return explicit
    from_env = master_uri_from_env(environ)
    if from_env:
        return from_env
    if config is not None:
        return config.node.master_uri
    return DEFAULT_MASTER_URI
