"""One parser per section of a configuration: values checked, records built.

Each function takes the section's values and nodes (:func:`~rosfpga_lab.config.schema.section`
filled the defaults and checked the types) and checks what the values may be: ROS names, ports,
sizes, encodings, the message types against the message registry, field paths against the
type, the application file. It returns the section's record of :mod:`~rosfpga_lab.config.node`;
a problem is a :class:`~rosfpga_lab.config.errors.ConfigError` at the value's line.
:func:`~rosfpga_lab.config.parse.parse_config` calls them in file order.
"""

from __future__ import annotations

import ipaddress
import re
import urllib.parse
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from rosfpga_lab.config import limits
from rosfpga_lab.config.fields import (
    FieldPathError, check_field, check_value_problem, limit_field, resolve_field, stream_field,
)
from rosfpga_lab.config.names import ros_name_problem
from rosfpga_lab.config.node import (
    ApplicationConfig, CheckConfig, FifoConfig, HlsConfig, ImageConfig, NodeSection, StreamConfig,
    TopicConfig,
)
from rosfpga_lab.config.schema import TOP_SCALARS
from rosfpga_lab.config.vocabulary import CUSTOM, ENCODINGS, HLS_FLAVOURS, OPS, WIRES
from rosfpga_lab.config.yamlwalk import (
    Ctx, Nodes, Section, check, free_mapping, string_list, typed,
)

if TYPE_CHECKING:
    from rosfpga_lab.msg import MsgRegistry


def node_section(ctx: Ctx, sec: Section) -> NodeSection:
    """``node:``: a legal node name, an ``http://HOST:PORT/`` master, an IPv4 address, ports."""
    n, nn = sec
    problem = ros_name_problem(n["name"], node_name=True)
    check(ctx, problem is None, f"{problem}: {n['name']!r}", nn, "name", "node")
    uri = urllib.parse.urlsplit(n["master_uri"])
    try:
        uri_port = uri.port
    except ValueError:
        uri_port = None
    check(ctx, uri.scheme == "http" and bool(uri.hostname) and uri_port is not None,
          f"expected http://HOST:PORT/, got {n['master_uri']!r}", nn, "master_uri", "node")
    try:
        ipaddress.IPv4Address(n["ip_address"])
        ip_ok = True
    except ValueError:
        ip_ok = False
    check(ctx, ip_ok, f"expected an IPv4 address like 127.0.0.1, got {n['ip_address']!r}",
          nn, "ip_address", "node")
    for key in ("xmlrpc_port", "tcpros_port"):
        check(ctx, 0 <= n[key] <= 65535, f"port must be 0..65535 (0 = any free port), got {n[key]}",
              nn, key, "node")
    check(ctx, n["xmlrpc_port"] == 0 or n["xmlrpc_port"] != n["tcpros_port"],
          "the XML-RPC and TCPROS ports must differ", nn, "tcpros_port", "node")
    return NodeSection(**n)


def message_folders(ctx: Ctx, top: Nodes, base_dir: Path,
                    msg_path: Iterable[str | Path]) -> tuple[list[Path], list[yaml.Node | None]]:
    """``msg_path:`` (relative to ``base_dir``, each folder must exist), then ``msg_path``."""
    folders: list[Path] = []
    nodes: list[yaml.Node | None] = []
    for name, node in string_list(ctx, top, "msg_path"):
        folder = (base_dir / name).resolve()
        if not folder.is_dir():
            raise ctx.error(f"message folder not found: {folder} (PKG/msg/NAME.msg files go "
                            "under it; relative to the configuration file)", node, "msg_path")
        folders.append(folder)
        nodes.append(node)
    for extra in msg_path:
        folders.append(Path(extra).resolve())
        nodes.append(None)
    return folders, nodes


def registry(ctx: Ctx, folders: list[Path], nodes: list[yaml.Node | None]) -> MsgRegistry:
    """The shipped types plus the ``.msg`` packages under ``folders``."""
    from rosfpga_lab.msg import MsgError, MsgRegistry, default_registry

    if not folders:
        return default_registry()
    reg = MsgRegistry.with_defaults()
    for folder, node in zip(folders, nodes):
        try:
            reg.load_path(folder)
        except MsgError as exc:
            raise ctx.error(str(exc), node, "msg_path") from None
    return reg


def known_type(type_name: str) -> bool:
    """Whether the lab's shipped registry knows ``type_name``."""
    from rosfpga_lab.msg import default_registry

    return type_name in default_registry()


def topics(ctx: Ctx, sub: Section, pub: Section,
           known: Callable[[str], bool]) -> tuple[TopicConfig, TopicConfig]:
    """``subscriber:`` and ``publisher:`` (whose type defaults to the subscriber's): legal,
    different topics of known types."""
    pub[0]["type"] = pub[0]["type"] or sub[0]["type"]
    for section, (t, tn) in (("subscriber", sub), ("publisher", pub)):
        problem = ros_name_problem(t["topic"])
        check(ctx, problem is None, f"{problem}: {t['topic']!r}", tn, "topic", section)
        if not known(t["type"]):
            raise ctx.error(f"unknown message type {t['type']!r} (not in the lab's message "
                            "registry nor under msg_path)", tn.get("type"), f"{section}.type")
    if sub[0]["topic"] == pub[0]["topic"]:
        raise ctx.error("the node would publish to the topic it subscribes to",
                        pub[1].get("topic"), "publisher.topic")
    return TopicConfig(**sub[0]), TopicConfig(**pub[0])


def check_definitions(ctx: Ctx, reg: MsgRegistry, sub: Section, pub: Section) -> None:
    """Every type the definitions of the two topics use is known (a misspelt field type,
    ``flaot32``, names its ``.msg`` file and line, and the primitive it is close to)."""
    from rosfpga_lab.msg import MsgError

    for section, (t, tn) in (("subscriber", sub), ("publisher", pub)):
        if t["type"] not in reg:
            continue
        try:
            reg.md5(t["type"])
        except MsgError as exc:
            raise ctx.error(str(exc), tn.get("type"), f"{section}.type") from None


def image_section(ctx: Ctx, top: Nodes, sec: Section, in_type: str) -> ImageConfig | None:
    """``image:``, which ``sensor_msgs/Image`` needs and no other type may have."""
    im, imn = sec
    is_image = in_type == limits.IMAGE_TYPE
    if not is_image and im:
        raise ctx.error(f"image: is the geometry of {limits.IMAGE_TYPE} only; for "
                        f"{in_type} say stream: {{field: ARRAY, length: N}}",
                        top["image"][0], "image")
    if not is_image:
        return None
    if not im:
        raise ctx.error("missing section 'image:' (keys: width, height, encoding)", None, "image")
    check(ctx, limits.MIN_WIDTH <= im["width"] <= limits.MAX_WIDTH,
          f"width must be {limits.MIN_WIDTH}..{limits.MAX_WIDTH}, got {im['width']}",
          imn, "width", "image")
    check(ctx, limits.MIN_HEIGHT <= im["height"] <= limits.MAX_HEIGHT,
          f"height must be {limits.MIN_HEIGHT}..{limits.MAX_HEIGHT}, got {im['height']}",
          imn, "height", "image")
    check(ctx, im["encoding"] in ENCODINGS,
          f"encoding {im['encoding']!r} is not one the circuit can pack (supported: "
          f"{', '.join(ENCODINGS)})", imn, "encoding", "image")
    return ImageConfig(**im)


def stream_section(ctx: Ctx, reg: MsgRegistry, type_name: str, sec: Section,
                   image: ImageConfig | None) -> StreamConfig:
    """``stream:``: the array the application processes (for an Image, ``data``, implied)."""
    st, stn = sec
    if image is not None:
        default = StreamConfig(limits.IMAGE_STREAM_FIELD, image.data_bytes)
        if st and (st["field"] != default.field or st["length"] not in (None, default.length)):
            raise ctx.error(f"a {limits.IMAGE_TYPE} streams {default.field!r} with "
                            f"image.width x height x bytes per pixel = {default.length} elements",
                            stn.get("field"), "stream.field")
        return default
    if not st:
        raise ctx.error(f"missing section 'stream:' ({{field: ARRAY, length: N}}): which "
                        f"array of {type_name} the application processes", None, "stream")
    try:
        f = stream_field(reg, type_name, st["field"])
    except FieldPathError as exc:
        raise ctx.error(str(exc), stn.get("field"), "stream.field") from None
    length = st["length"]
    if f.array_length is not None:
        if length not in (None, f.array_length):
            raise ctx.error(f"{st['field']} is a {f.type}: its length is "
                            f"{f.array_length}", stn.get("length"), "stream.length")
        length = f.array_length
    if length is None or not 1 <= length <= limits.MAX_STREAM_LENGTH:
        raise ctx.error(f"give the element count of {st['field']}, 1.."
                        f"{limits.MAX_STREAM_LENGTH}", stn.get("length") or stn.get("field"),
                        "stream.length")
    return StreamConfig(st["field"], length)


def checks_section(ctx: Ctx, reg: MsgRegistry, type_name: str, top: Nodes, stream: StreamConfig,
                   image: ImageConfig | None) -> tuple[CheckConfig, ...]:
    """``checks:``: a field path of the type, and a value or ``{min, max}`` bounds it must hold."""
    checks = []
    for path, node, value in free_mapping(ctx, top, "checks"):
        key = f"checks.{path}"
        if image is not None and path in limits.IMAGE_IMPLIED_CHECKS:
            raise ctx.error(f"{path} is checked against image: already", node, key)
        if path == stream.field:
            raise ctx.error("is the stream: its length is stream.length", node, key)
        try:
            f = check_field(reg, type_name, path)
        except FieldPathError as exc:
            raise ctx.error(str(exc), node, key) from None
        bounds = value if isinstance(value, dict) else None
        if bounds is not None and f.base_type in ("string", "bool"):
            raise ctx.error(f"a {f.base_type} can only be checked for equality", node, key)
        for v in (bounds or {"value": value}).values():
            problem = check_value_problem(f.base_type, v)
            if problem:
                raise ctx.error(problem, node, key)
        if bounds is None:
            checks.append(CheckConfig(path, value=value))
            continue
        if not bounds:
            raise ctx.error("a bound needs min or max", node, key)
        low, high = bounds.get("min"), bounds.get("max")
        if low is not None and high is not None and low > high:
            raise ctx.error(f"min {low} is above max {high}", node, key)
        checks.append(CheckConfig(path, low=low, high=high))
    return tuple(checks)


def limits_section(ctx: Ctx, reg: MsgRegistry, type_name: str, top: Nodes,
                   stream: StreamConfig) -> tuple[tuple[str, int], ...]:
    """``limits:``: the longest a string or array of the type may be (not the stream's)."""
    maxima = []
    for path, node, value in free_mapping(ctx, top, "limits"):
        key = f"limits.{path}"
        try:
            limit_field(reg, type_name, path.removesuffix("[]"))
        except FieldPathError as exc:
            raise ctx.error(str(exc), node, key) from None
        if path == stream.field:
            raise ctx.error("is the stream: its length is stream.length", node, key)
        if isinstance(value, bool) or not isinstance(value, int) or \
                not 0 <= value <= limits.MAX_LIMIT:
            raise ctx.error(f"expected 0..{limits.MAX_LIMIT}, got {value!r}", node, key)
        maxima.append((path, value))
    return tuple(maxima)


def skip_section(ctx: Ctx, reg: MsgRegistry, type_name: str, top: Nodes,
                 stream: StreamConfig) -> tuple[str, ...]:
    """``skip:``: fields of the type the circuit drops (never the stream or what holds it)."""
    skip = []
    for path, node in string_list(ctx, top, "skip"):
        try:
            resolve_field(reg, type_name, path)
        except FieldPathError as exc:
            raise ctx.error(str(exc), node, "skip") from None
        if path == stream.field or stream.field.startswith(path + "."):
            raise ctx.error(f"{path}: the stream cannot be skipped", node, "skip")
        skip.append(path)
    return tuple(skip)


def check_output_type(ctx: Ctx, reg: MsgRegistry, in_type: str, out_type: str,
                      stream: StreamConfig, nodes: dict[str, yaml.Node]) -> None:
    """The publisher's type must have the stream's array, of the same element type."""
    if out_type == in_type:
        return
    try:
        f = stream_field(reg, out_type, stream.field)
        g = stream_field(reg, in_type, stream.field)
    except FieldPathError as exc:
        raise ctx.error(f"{out_type} cannot stream the output: {exc}", nodes.get("type"),
                        "publisher.type") from None
    if f.base_type != g.base_type or f.array_length not in (None, stream.length):
        raise ctx.error(f"{out_type} cannot stream the output: its {stream.field} is a {f.type}, "
                        f"the input's a {g.type}", nodes.get("type"), "publisher.type")


def application_section(ctx: Ctx, sec: Section, base_dir: Path) -> ApplicationConfig:
    """``application:``: a known operation, an odd kernel size, and for ``custom`` its C++ file
    (relative to ``base_dir``), which no other operation takes."""
    ap, apn = sec
    check(ctx, ap["op"] in OPS, f"op must be one of {', '.join(OPS)}, got {ap['op']!r}",
          apn, "op", "application")
    check(ctx, ap["ksize"] % 2 == 1 and 1 <= ap["ksize"] <= limits.MAX_KSIZE,
          f"ksize must be odd, 1..{limits.MAX_KSIZE}, got {ap['ksize']}", apn, "ksize",
          "application")
    source_path: Path | None = None
    if ap["op"] == CUSTOM:
        check(ctx, bool(ap["source"]), "op 'custom' needs 'source: FILE.cpp' (the C++ file "
              "defining stream_filter)", apn, "op", "application")
        source_path = (base_dir / ap["source"]).resolve()
        check(ctx, source_path.is_file(), f"application file not found: {source_path}",
              apn, "source", "application")
    else:
        check(ctx, ap["source"] is None, f"'source' is only used with op 'custom' (op is "
              f"{ap['op']!r})", apn, "source", "application")
    return ApplicationConfig(op=ap["op"], ksize=ap["ksize"], source=source_path)


def fifo_section(ctx: Ctx, sec: Section) -> FifoConfig:
    """``fifo:``: every depth 2..MAX_FIFO_DEPTH."""
    f, fn = sec
    for key in ("input_depth", "output_depth", "axis_depth"):
        check(ctx, 2 <= f[key] <= limits.MAX_FIFO_DEPTH,
              f"FIFO depth must be 2..{limits.MAX_FIFO_DEPTH}, got {f[key]}", fn, key, "fifo")
    return FifoConfig(**f)


def hls_section(ctx: Ctx, sec: Section) -> HlsConfig:
    """``hls:``: a flavour the generator writes."""
    hl, hln = sec
    check(ctx, hl["flavour"] in HLS_FLAVOURS, f"flavour must be one of "
          f"{', '.join(HLS_FLAVOURS)} (vitis: Vitis HLS 2020.2 on; vivado: Vivado HLS up to "
          f"2019.2), got {hl['flavour']!r}", hln, "flavour", "hls")
    return HlsConfig(**hl)


def top_values(ctx: Ctx, top: Nodes) -> dict[str, Any]:
    """``clock_mhz``, ``frame_id_max``, ``part`` and ``wire``, typed, defaults filled."""
    return {key: typed(ctx, top[key][1], key, kind) if key in top else default
            for key, (kind, default) in TOP_SCALARS.items()}


def check_top_values(ctx: Ctx, top: Nodes, values: dict[str, Any]) -> None:
    """The clock and ``frame_id_max`` in their ranges, a plausible part name, a known wire."""
    nodes = {key: value[1] for key, value in top.items()}
    if not limits.MIN_CLOCK_MHZ <= values["clock_mhz"] <= limits.MAX_CLOCK_MHZ:
        raise ctx.error(f"clock must be {limits.MIN_CLOCK_MHZ:g}..{limits.MAX_CLOCK_MHZ:g} MHz, "
                        f"got {values['clock_mhz']}", nodes.get("clock_mhz"), "clock_mhz")
    if not 1 <= values["frame_id_max"] <= limits.MAX_FRAME_ID_MAX:
        raise ctx.error(f"must be 1..{limits.MAX_FRAME_ID_MAX}, got {values['frame_id_max']}",
                        nodes.get("frame_id_max"), "frame_id_max")
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", values["part"]):
        raise ctx.error(f"expected an FPGA part name like xc7z020clg400-1, got {values['part']!r}",
                        nodes.get("part"), "part")
    if values["wire"] not in WIRES:
        raise ctx.error(f"wire must be one of {', '.join(WIRES)}, got {values['wire']!r}",
                        nodes.get("wire"), "wire")


__all__ = ["application_section", "check_definitions", "check_output_type",
           "check_top_values", "checks_section", "fifo_section", "hls_section",
           "image_section", "known_type", "limits_section", "message_folders",
           "node_section", "registry", "skip_section", "stream_section", "top_values",
           "topics"]
