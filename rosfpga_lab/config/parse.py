"""Reading a configuration: YAML text in, a checked :class:`~rosfpga_lab.config.node.NodeConfig` out.

How this works: the YAML is *composed* (not just loaded) so every key and value keeps its line
number (:mod:`~rosfpga_lab.config.yamlwalk`); each section is checked against the schema table
(:mod:`~rosfpga_lab.config.schema`: key -> type, default), refusing unknown, duplicate, missing
and mistyped keys, then each section's parser (:mod:`~rosfpga_lab.config.sections`) checks its
values (ROS names, ports, sizes, encodings, the message type against the message registry, the
application file) and builds its record. Every problem is a :class:`ConfigError` naming the
file, line and dotted key, raised before the caller writes anything.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import replace
from pathlib import Path

import yaml

from rosfpga_lab.config import limits
from rosfpga_lab.config import sections as s
from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.node import NodeConfig, NoImage, StreamConfig
from rosfpga_lab.config.schema import FREE_KEYS, SCHEMA, TOP_SCALARS, section
from rosfpga_lab.config.yamlwalk import Ctx, Nodes, mapping


def _compose(text: str, source: str) -> yaml.Node:
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else 0
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(f"not valid YAML: {problem}", path=source, line=line) from None
    if root is None:
        raise ConfigError("the configuration is empty", path=source)
    return root


def parse_config(text: str, *, source: str = "<string>", base_dir: Path | None = None,
                 known_type: Callable[[str], bool] | None = None,
                 msg_path: Iterable[str | Path] = ()) -> NodeConfig:
    """Parse and validate configuration text.

    Args:
        text: the YAML text.
        source: file name used in error messages.
        base_dir: directory that ``application.source`` is relative to (default: cwd).
        known_type: predicate "is this message type known" (default: the lab's registry
            with ``msg_path:`` and ``msg_path``).
        msg_path: more folders of ``.msg`` packages (the command line's ``--msg-path``), after
            the file's ``msg_path:``.

    Returns:
        The validated configuration (``path`` is None; :func:`load_config` sets it).

    Raises:
        ConfigError: the text is not YAML, or a key or value is wrong (file:line and key given).
    """
    ctx = Ctx(source)
    allowed = {**{k: None for k in SCHEMA}, **TOP_SCALARS, **{k: None for k in FREE_KEYS}}
    top: Nodes = mapping(ctx, _compose(text, source), "", allowed)
    sec = {name: section(ctx, top, name) for name in SCHEMA}
    values = s.top_values(ctx, top)
    node = s.node_section(ctx, sec["node"])
    root_dir = base_dir or Path.cwd()
    folders, folder_nodes = s.message_folders(ctx, top, root_dir, msg_path)
    reg = s.registry(ctx, folders, folder_nodes)
    known = known_type or (reg.__contains__ if folders else s.known_type)
    subscriber, publisher = s.topics(ctx, sec["subscriber"], sec["publisher"], known)
    s.check_definitions(ctx, reg, sec["subscriber"], sec["publisher"])
    in_type = subscriber.type
    image = s.image_section(ctx, top, sec["image"], in_type)
    if in_type in reg:
        stream = s.stream_section(ctx, reg, in_type, sec["stream"], image)
        checks = s.checks_section(ctx, reg, in_type, top, stream, image)
        maxima = s.limits_section(ctx, reg, in_type, top, stream)
        skip = s.skip_section(ctx, reg, in_type, top, stream)
        s.check_output_type(ctx, reg, in_type, publisher.type, stream, sec["publisher"][1])
    else:  # a caller's known_type accepted a type the registry lacks: no field to check
        stream, checks, maxima, skip = StreamConfig(limits.IMAGE_STREAM_FIELD, 0), (), (), ()
    application = s.application_section(ctx, sec["application"], root_dir)
    fifo = s.fifo_section(ctx, sec["fifo"])
    s.check_top_values(ctx, top, values)
    hls = s.hls_section(ctx, sec["hls"])
    return NodeConfig(
        node=node, subscriber=subscriber, publisher=publisher,
        image=image if image is not None else NoImage(in_type), application=application,
        fifo=fifo, clock_mhz=float(values["clock_mhz"]), frame_id_max=values["frame_id_max"],
        part=values["part"], wire=values["wire"], hls=hls, msg_path=tuple(folders),
        stream=stream, checks=checks, limits=maxima, skip=skip,
    )


def load_config(path: str | Path, *, msg_path: Iterable[str | Path] = ()) -> NodeConfig:
    """Read and validate a node configuration file.

    Args:
        path: the YAML file. ``application.source`` and ``msg_path:`` are relative to its
            directory.
        msg_path: more folders of ``.msg`` packages (``--msg-path``).

    Returns:
        The validated, frozen :class:`NodeConfig` (its ``path`` set).

    Raises:
        ConfigError: the file is missing, too large, not YAML, or a key or value is wrong.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read the configuration: {exc.strerror}", path=str(p)) from None
    if len(raw) > limits.MAX_CONFIG_BYTES:
        raise ConfigError(f"file is larger than {limits.MAX_CONFIG_BYTES} bytes", path=str(p))
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"not UTF-8 text (byte {exc.start})", path=str(p)) from None
    config = parse_config(text, source=str(p), base_dir=p.resolve().parent, msg_path=msg_path)
    return replace(config, path=p.resolve())


__all__ = ["load_config", "parse_config"]
