"""The node configuration: one YAML file describes one ROS-compliant FPGA component.

The same file drives the generator (``rosfpga-lab generate``) and the emulated FPGA node
(``rosfpga_lab.component``). It holds the paper's input (b) -- node name, topic names, master
URI, IP address and ports -- plus what the circuit fixes at synthesis time: image size and
encoding, the application, FIFO depths and the clock. Example (every key but ``node.name``,
``subscriber.topic``, ``publisher.topic`` and ``image`` has a default)::

    node:
      name: /fpga_dilate                  # ROS node name
      master_uri: http://127.0.0.1:11311/ # where the ROS master listens
      ip_address: 127.0.0.1               # address the node binds and advertises
      xmlrpc_port: 0                      # slave API port; 0 = any free port
      tcpros_port: 0                      # TCPROS server port; 0 = any free port
    subscriber:
      topic: /image_raw
      type: sensor_msgs/Image
    publisher:
      topic: /image_dilated
      type: sensor_msgs/Image           # default: the subscriber's type
    image: {width: 640, height: 480, encoding: rgba8}   # sensor_msgs/Image only
    application:
      op: dilate          # dilate | erode | passthrough | custom
      ksize: 3            # odd, 1..15 (dilate and erode)
      source: null        # C++ file of image_filter(), relative to this file (op: custom)
    fifo: {input_depth: 2048, output_depth: 2048, axis_depth: 16}
    clock_mhz: 100
    frame_id_max: 256     # longest header.frame_id the circuit keeps
    part: xc7z020clg400-1 # FPGA part for the HLS project script (Zynq-7020)
    wire: tcpros          # tcpros | cdr: the generated circuit reads ROS 1 frames or ROS 2 samples
    hls: {flavour: vitis} # vitis (Vitis HLS 2020.2 on) | vivado (the paper's Vivado HLS <= 2019.2)

Any other message type names the array the application processes and, if it likes, checks,
maxima and fields to drop (paths are dotted field names; ``msg_path`` folders, relative to this
file, hold the user's ``PKG/msg/NAME.msg`` files)::

    subscriber: {topic: /scan, type: sensor_msgs/LaserScan}
    publisher: {topic: /scan_min}                # same type
    msg_path: [msg]                              # optional
    stream: {field: ranges, length: 360}         # the array and its element count
    checks: {angle_min: -3.14, range_max: {max: 100}}   # equal, or {min, max} bounds
    limits: {header.frame_id: 64, intensities: 360}     # default: DEFAULT_STRING_MAX bytes,
                                                        # DEFAULT_ARRAY_MAX elements
    skip: [intensities]                          # dropped; the output gets the default
    application: {op: erode, ksize: 5}           # 1-D: min over 5 elements

For ``sensor_msgs/Image`` the stream is ``data`` with ``image:``'s size (a ``stream:`` may say
so, and must agree) and the image checks are implied.

How this works: the YAML is *composed* (not just loaded) so every key and value keeps its line
number; a small walker checks each section against a schema table (key -> type, default),
refusing unknown, duplicate, missing and mistyped keys, then checks values (ROS names, ports,
sizes, encodings, the message type against the message registry, the application file).
Every problem is a :class:`ConfigError` naming the file, line and dotted key, raised before the
caller writes anything.
"""

from __future__ import annotations

import difflib
import ipaddress
import re
import urllib.parse
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import yaml

from rosfpga_lab.config import limits
from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.fields import (
    FieldPathError, check_field, check_value_problem, limit_field, resolve_field, stream_field,
)
from rosfpga_lab.config.names import canonical, name_problem
from rosfpga_lab.config.vocabulary import (
    CUSTOM, DEFAULT_HLS_FLAVOUR, DEFAULT_OP, DEFAULT_WIRE, ENCODINGS, HLS_FLAVOURS, OPS, WIRES,
)

if TYPE_CHECKING:
    from rosfpga_lab.msg import MsgRegistry

@dataclass(frozen=True)
class NodeSection:
    """The ROS side of the node (the paper's input (b)).

    Attributes:
        name: node name, e.g. ``/fpga_dilate`` (a relative name is taken in the root namespace).
        master_uri: the ROS master's XML-RPC URI.
        ip_address: IPv4 address the node binds and advertises (loopback by default).
        xmlrpc_port: port of the node's XML-RPC slave API; 0 = any free port.
        tcpros_port: port of the node's TCPROS server (its publisher); 0 = any free port.
    """

    name: str
    master_uri: str = limits.DEFAULT_MASTER_URI
    ip_address: str = limits.DEFAULT_IP_ADDRESS
    xmlrpc_port: int = 0
    tcpros_port: int = 0

    @property
    def global_name(self) -> str:
        """The node name resolved in the root namespace (``fpga`` -> ``/fpga``)."""
        return self.name if self.name.startswith("/") else "/" + self.name


@dataclass(frozen=True)
class TopicConfig:
    """One topic of the node.

    Attributes:
        topic: topic name, e.g. ``/image_raw``.
        type: message type, ``package/Name`` (the shipped types or the ``msg_path`` ones).
    """

    topic: str
    type: str = limits.IMAGE_TYPE


@dataclass(frozen=True)
class ImageConfig:
    """The image geometry fixed at synthesis time.

    Attributes:
        width: pixels per line.
        height: lines per frame.
        encoding: ROS encoding (``rgba8``, ``bgra8``, ``rgb8``, ``bgr8``, ``mono8``).
    """

    width: int
    height: int
    encoding: str

    @property
    def bytes_per_pixel(self) -> int:
        return ENCODINGS[self.encoding]

    @property
    def step(self) -> int:
        """Bytes per line (``sensor_msgs/Image.step``)."""
        return self.width * self.bytes_per_pixel

    @property
    def data_bytes(self) -> int:
        """Bytes of ``sensor_msgs/Image.data``."""
        return self.step * self.height


@dataclass(frozen=True)
class ApplicationConfig:
    """The application circuit between fifo2axi and axi2fifo (the paper's input (c)).

    Attributes:
        op: ``dilate`` | ``erode`` | ``passthrough`` | ``custom``.
        ksize: side of the square structuring element (dilate, erode).
        source: for ``custom``, the C++ file defining ``image_filter()`` (absolute path).
    """

    op: str = DEFAULT_OP
    ksize: int = 3
    source: Path | None = None


class NoImage(ImageConfig):
    """The ``image`` of a configuration whose type is not ``sensor_msgs/Image``.

    Every public attribute raises :class:`ConfigError` naming the type, so code that only knows
    images fails with a clear message instead of using made-up geometry.
    """

    def __init__(self, type_name: str) -> None:  # no dataclass fields set on purpose
        object.__setattr__(self, "_type_name", type_name)

    def __getattribute__(self, name: str) -> Any:
        if name.startswith("_"):
            return object.__getattribute__(self, name)
        type_name = object.__getattribute__(self, "_type_name")
        raise ConfigError(f"{type_name} has no image geometry (image.{name}): this needs a "
                          f"{limits.IMAGE_TYPE} configuration", key="image")

    def __repr__(self) -> str:
        return f"NoImage({object.__getattribute__(self, '_type_name')!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, NoImage) and repr(self) == repr(other)

    def __hash__(self) -> int:
        return hash(repr(self))


@dataclass(frozen=True)
class StreamConfig:
    """The one array the application processes.

    Attributes:
        field: its dotted path in the subscribed message (``data``, ``ranges``).
        length: its element count, fixed at synthesis time.
    """

    field: str
    length: int


class CheckConfig(NamedTuple):
    """One ``checks:`` entry: ``value`` (equality) or the bounds ``low``/``high`` (``None``: open)."""

    path: str
    value: Any = None
    low: Any = None
    high: Any = None

    @property
    def spec(self) -> Any:
        """As the layout takes it: the value, or ``{"min": low, "max": high}``."""
        if self.value is not None:
            return self.value
        return {k: v for k, v in (("min", self.low), ("max", self.high)) if v is not None}


@dataclass(frozen=True)
class FifoConfig:
    """FIFO depths of the circuit (items).

    Attributes:
        input_depth: the 8-bit FIFO between the network and the subscriber (bytes).
        output_depth: the 8-bit FIFO between the publisher and the network (bytes).
        axis_depth: the AXI4-Stream FIFOs around the application (beats).
    """

    input_depth: int = limits.DEFAULT_INPUT_FIFO_DEPTH
    output_depth: int = limits.DEFAULT_OUTPUT_FIFO_DEPTH
    axis_depth: int = limits.DEFAULT_AXIS_FIFO_DEPTH


@dataclass(frozen=True)
class HlsConfig:
    """What the generated HLS C++ is written for.

    Attributes:
        flavour: ``vitis`` (Vitis HLS) or ``vivado`` (Vivado HLS up to 2019.2, the paper's);
            :data:`rosfpga_lab.config.vocabulary.HLS_FLAVOURS`.
    """

    flavour: str = DEFAULT_HLS_FLAVOUR


@dataclass(frozen=True)
class NodeConfig:
    """One ROS-compliant FPGA component, as read from its YAML file.

    Attributes:
        node: the ROS node (name, master, address, ports).
        subscriber: the topic the circuit consumes (its subscriber, paper's (d)).
        publisher: the topic the circuit produces (its publisher, paper's (e)).
        image: geometry and encoding. A configuration of another type holds a stand-in
            (:class:`NoImage`) whose every attribute raises :class:`ConfigError`: Image-only
            code refuses it clearly; :attr:`is_image` tells them apart.
        application: what the circuit does to the image.
        fifo: FIFO depths.
        clock_mhz: the circuit's clock (MHz).
        frame_id_max: longest ``header.frame_id`` kept (longer frames are refused).
        part: the FPGA part named in the HLS project script.
        wire: the wire format the circuit reads and writes (``tcpros`` or ``cdr``).
        hls: the HLS tool the generated C++ is written for.
        path: the file it was read from (None when parsed from a string).
        msg_path: folders of the user's ``.msg`` packages (absolute).
        stream: the streamed array (for Image: ``data``, ``image.data_bytes`` elements).
        checks: ``checks:`` entries, in file order (Image's implied ones not included).
        limits: ``limits:`` entries ``(path, max)``, in file order.
        skip: fields the circuit drops.
    """

    node: NodeSection
    subscriber: TopicConfig
    publisher: TopicConfig
    image: ImageConfig
    application: ApplicationConfig = ApplicationConfig()
    fifo: FifoConfig = FifoConfig()
    clock_mhz: float = limits.DEFAULT_CLOCK_MHZ
    frame_id_max: int = limits.DEFAULT_FRAME_ID_MAX
    part: str = limits.DEFAULT_PART
    wire: str = DEFAULT_WIRE
    hls: HlsConfig = HlsConfig()
    path: Path | None = None
    msg_path: tuple[Path, ...] = ()
    stream: StreamConfig | None = None
    checks: tuple[CheckConfig, ...] = ()
    limits: tuple[tuple[str, int], ...] = ()
    skip: tuple[str, ...] = ()

    @property
    def is_image(self) -> bool:
        """True when the circuit subscribes to ``sensor_msgs/Image`` (the video path)."""
        return not isinstance(self.image, NoImage)

    def registry(self) -> "MsgRegistry":
        """The message registry of this configuration: the shipped types plus ``msg_path``."""
        from rosfpga_lab.msg import registry_with

        return registry_with(self.msg_path)


# ---------------------------------------------------------------------------------------------
# Schema: section -> key -> (python type, default or _REQUIRED). Sections map to dataclasses.

_REQUIRED = object()
_SCHEMA: dict[str, dict[str, tuple[type | tuple[type, ...], Any]]] = {
    "node": {"name": (str, _REQUIRED), "master_uri": (str, limits.DEFAULT_MASTER_URI),
             "ip_address": (str, limits.DEFAULT_IP_ADDRESS), "xmlrpc_port": (int, 0),
             "tcpros_port": (int, 0)},
    "subscriber": {"topic": (str, _REQUIRED), "type": (str, limits.IMAGE_TYPE)},
    "publisher": {"topic": (str, _REQUIRED), "type": ((str, type(None)), None)},
    "image": {"width": (int, _REQUIRED), "height": (int, _REQUIRED), "encoding": (str, _REQUIRED)},
    "application": {"op": (str, DEFAULT_OP), "ksize": (int, 3), "source": ((str, type(None)), None)},
    "fifo": {"input_depth": (int, limits.DEFAULT_INPUT_FIFO_DEPTH),
             "output_depth": (int, limits.DEFAULT_OUTPUT_FIFO_DEPTH),
             "axis_depth": (int, limits.DEFAULT_AXIS_FIFO_DEPTH)},
    "stream": {"field": (str, _REQUIRED), "length": ((int, type(None)), None)},
    "hls": {"flavour": (str, DEFAULT_HLS_FLAVOUR)},
}
#: Top-level keys read by their own code (lists and free mappings of field paths).
_FREE_KEYS = ("msg_path", "checks", "limits", "skip")
_TOP_SCALARS: dict[str, tuple[type | tuple[type, ...], Any]] = {
    "clock_mhz": ((int, float), limits.DEFAULT_CLOCK_MHZ),
    "frame_id_max": (int, limits.DEFAULT_FRAME_ID_MAX),
    "part": (str, limits.DEFAULT_PART),
    "wire": (str, DEFAULT_WIRE),
}
_REQUIRED_SECTIONS = ("node", "subscriber", "publisher")
#: Sections that are left out unless given (no defaults to fill).
_OPTIONAL_SECTIONS = ("image", "stream")


class _Ctx:
    """Where we are: the file name, for error messages."""

    def __init__(self, source: str) -> None:
        self.source = source

    def error(self, message: str, node: yaml.Node | None = None, key: str = "") -> ConfigError:
        line = node.start_mark.line + 1 if node is not None else 0
        return ConfigError(message, path=self.source, line=line, key=key)


def _scalar(ctx: _Ctx, node: yaml.Node, key: str) -> Any:
    if not isinstance(node, yaml.ScalarNode):
        raise ctx.error("expected a single value, found a "
                        + ("mapping" if isinstance(node, yaml.MappingNode) else "list"), node, key)
    return yaml.constructor.SafeConstructor().construct_object(node, deep=True)


def _mapping(ctx: _Ctx, node: yaml.Node, key: str,
             allowed: dict[str, Any]) -> dict[str, tuple[yaml.Node, yaml.Node]]:
    """Keys of a mapping node -> (key node, value node); unknown or duplicate keys refused."""
    if not isinstance(node, yaml.MappingNode):
        where = f"section {key!r}" if key else "the file"
        raise ctx.error(f"{where} must be a mapping of 'key: value' lines", node, key)
    out: dict[str, tuple[yaml.Node, yaml.Node]] = {}
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


def _typed(ctx: _Ctx, vnode: yaml.Node, dotted: str, kind: type | tuple[type, ...]) -> Any:
    value = _scalar(ctx, vnode, dotted)
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if isinstance(value, bool) or not isinstance(value, kinds):
        names = " or ".join("null" if k is type(None) else k.__name__ for k in kinds)
        raise ctx.error(f"expected {names}, got {value!r}", vnode, dotted)
    return value


def _section(ctx: _Ctx, top: dict[str, tuple[yaml.Node, yaml.Node]], name: str,
             ) -> tuple[dict[str, Any], dict[str, yaml.Node]]:
    """Values of one section with defaults filled in, and the node of each given value."""
    schema = _SCHEMA[name]
    if name not in top and name in _OPTIONAL_SECTIONS:
        return {}, {}
    if name not in top:
        if name in _REQUIRED_SECTIONS:
            raise ctx.error(f"missing section '{name}:' (keys: {', '.join(schema)})", None, name)
        return {k: d for k, (_t, d) in schema.items()}, {}
    knode, vnode = top[name]
    if isinstance(vnode, yaml.ScalarNode) and vnode.value == "" and vnode.tag.endswith(":null"):
        vnode = yaml.MappingNode("tag:yaml.org,2002:map", [], knode.start_mark, knode.end_mark)
    given = _mapping(ctx, vnode, name, schema)
    values: dict[str, Any] = {}
    nodes: dict[str, yaml.Node] = {}
    for key, (kind, default) in schema.items():
        dotted = f"{name}.{key}"
        if key in given:
            values[key] = _typed(ctx, given[key][1], dotted, kind)
            nodes[key] = given[key][1]
        elif default is _REQUIRED:
            raise ctx.error(f"missing key '{key}' in section '{name}'", knode, dotted)
        else:
            values[key] = default
    return values, nodes


def _check(ctx: _Ctx, ok: bool, message: str, nodes: dict[str, yaml.Node], key: str,
           section: str) -> None:
    if not ok:
        raise ctx.error(message, nodes.get(key), f"{section}.{key}")


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


def _check_type(ctx: _Ctx, type_name: str, nodes: dict[str, yaml.Node], section: str,
                known: Callable[[str], bool]) -> None:
    if not known(type_name):
        raise ctx.error(f"unknown message type {type_name!r} (not in the lab's message registry "
                        "nor under msg_path)", nodes.get("type"), f"{section}.type")


def _check_definition(ctx: _Ctx, reg: "MsgRegistry", type_name: str,
                      nodes: dict[str, yaml.Node], section: str) -> None:
    """Every type the definition of ``type_name`` uses is known (a misspelt field type,
    ``flaot32``, names its ``.msg`` file and line, and the primitive it is close to)."""
    from rosfpga_lab.msg import MsgError

    if type_name not in reg:
        return
    try:
        reg.md5(type_name)
    except MsgError as exc:
        raise ctx.error(str(exc), nodes.get("type"), f"{section}.type") from None


def _known_type(type_name: str) -> bool:
    from rosfpga_lab.msg import default_registry

    return type_name in default_registry()


def _free_mapping(ctx: _Ctx, top: dict[str, tuple[yaml.Node, yaml.Node]], name: str
                  ) -> list[tuple[str, yaml.Node, Any]]:
    """``(key, value node, value)`` of a top-level mapping whose keys are field paths."""
    if name not in top:
        return []
    vnode = top[name][1]
    if isinstance(vnode, yaml.ScalarNode) and vnode.tag.endswith(":null"):
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
                value[bname] = _scalar(ctx, bv, dotted)
        else:
            value = _scalar(ctx, node, dotted)
        out.append((key, node, value))
    return out


def _string_list(ctx: _Ctx, top: dict[str, tuple[yaml.Node, yaml.Node]], name: str
                 ) -> list[tuple[str, yaml.Node]]:
    if name not in top:
        return []
    vnode = top[name][1]
    if isinstance(vnode, yaml.ScalarNode) and vnode.tag.endswith(":null"):
        return []
    if not isinstance(vnode, yaml.SequenceNode):
        raise ctx.error("must be a list, e.g. [a, b]", vnode, name)
    out = []
    for item in vnode.value:
        value = _scalar(ctx, item, name)
        if not isinstance(value, str) or not value:
            raise ctx.error(f"expected a name, got {value!r}", item, name)
        out.append((value, item))
    return out


def _registry(ctx: _Ctx, folders: list[Path], nodes: list[yaml.Node | None]) -> "MsgRegistry":
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


def _message_keys(ctx: _Ctx, reg: "MsgRegistry", type_name: str, top: dict[str, Any],
                  sec: dict[str, tuple[dict[str, Any], dict[str, yaml.Node]]],
                  image: ImageConfig | None) -> tuple[StreamConfig, tuple[CheckConfig, ...],
                                                      tuple[tuple[str, int], ...], tuple[str, ...]]:
    """``stream``, ``checks``, ``limits`` and ``skip``, each field path checked against the type."""
    st, stn = sec["stream"]
    if image is not None:
        default = StreamConfig(limits.IMAGE_STREAM_FIELD, image.data_bytes)
        if st and (st["field"] != default.field or st["length"] not in (None, default.length)):
            raise ctx.error(f"a {limits.IMAGE_TYPE} streams {default.field!r} with "
                            f"image.width x height x bytes per pixel = {default.length} elements",
                            stn.get("field"), "stream.field")
        stream = default
    else:
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
        stream = StreamConfig(st["field"], length)
    checks = []
    for path, node, value in _free_mapping(ctx, top, "checks"):
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
        if bounds is not None:
            if not bounds:
                raise ctx.error("a bound needs min or max", node, key)
            low, high = bounds.get("min"), bounds.get("max")
            if low is not None and high is not None and low > high:
                raise ctx.error(f"min {low} is above max {high}", node, key)
            checks.append(CheckConfig(path, low=low, high=high))
        else:
            checks.append(CheckConfig(path, value=value))
    maxima = []
    for path, node, value in _free_mapping(ctx, top, "limits"):
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
    skip = []
    for path, node in _string_list(ctx, top, "skip"):
        try:
            resolve_field(reg, type_name, path)
        except FieldPathError as exc:
            raise ctx.error(str(exc), node, "skip") from None
        if path == stream.field or stream.field.startswith(path + "."):
            raise ctx.error(f"{path}: the stream cannot be skipped", node, "skip")
        skip.append(path)
    return stream, tuple(checks), tuple(maxima), tuple(skip)


def _check_image(ctx: _Ctx, im: dict[str, Any], imn: dict[str, yaml.Node]) -> None:
    _check(ctx, limits.MIN_WIDTH <= im["width"] <= limits.MAX_WIDTH,
           f"width must be {limits.MIN_WIDTH}..{limits.MAX_WIDTH}, got {im['width']}",
           imn, "width", "image")
    _check(ctx, limits.MIN_HEIGHT <= im["height"] <= limits.MAX_HEIGHT,
           f"height must be {limits.MIN_HEIGHT}..{limits.MAX_HEIGHT}, got {im['height']}",
           imn, "height", "image")
    _check(ctx, im["encoding"] in ENCODINGS,
           f"encoding {im['encoding']!r} is not one the circuit can pack (supported: "
           f"{', '.join(ENCODINGS)})", imn, "encoding", "image")


def _check_output_type(ctx: _Ctx, reg: "MsgRegistry", in_type: str, out_type: str,
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
    ctx = _Ctx(source)
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else 0
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(f"not valid YAML: {problem}", path=source, line=line) from None
    if root is None:
        raise ConfigError("the configuration is empty", path=source)
    allowed = {**{k: None for k in _SCHEMA}, **_TOP_SCALARS, **{k: None for k in _FREE_KEYS}}
    top = _mapping(ctx, root, "", allowed)
    sec = {name: _section(ctx, top, name) for name in _SCHEMA}
    scalars: dict[str, Any] = {}
    for key, (kind, default) in _TOP_SCALARS.items():
        scalars[key] = _typed(ctx, top[key][1], key, kind) if key in top else default
    top_nodes = {k: v[1] for k, v in top.items()}

    # node
    n, nn = sec["node"]
    problem = ros_name_problem(n["name"], node_name=True)
    _check(ctx, problem is None, f"{problem}: {n['name']!r}", nn, "name", "node")
    uri = urllib.parse.urlsplit(n["master_uri"])
    try:
        uri_port = uri.port
    except ValueError:
        uri_port = None
    _check(ctx, uri.scheme == "http" and bool(uri.hostname) and uri_port is not None,
           f"expected http://HOST:PORT/, got {n['master_uri']!r}", nn, "master_uri", "node")
    try:
        ipaddress.IPv4Address(n["ip_address"])
        ip_ok = True
    except ValueError:
        ip_ok = False
    _check(ctx, ip_ok, f"expected an IPv4 address like 127.0.0.1, got {n['ip_address']!r}",
           nn, "ip_address", "node")
    for key in ("xmlrpc_port", "tcpros_port"):
        _check(ctx, 0 <= n[key] <= 65535, f"port must be 0..65535 (0 = any free port), got {n[key]}",
               nn, key, "node")
    _check(ctx, n["xmlrpc_port"] == 0 or n["xmlrpc_port"] != n["tcpros_port"],
           "the XML-RPC and TCPROS ports must differ", nn, "tcpros_port", "node")

    # message path, topics
    root_dir = base_dir or Path.cwd()
    folders: list[Path] = []
    folder_nodes: list[yaml.Node | None] = []
    for name, node in _string_list(ctx, top, "msg_path"):
        folder = (root_dir / name).resolve()
        if not folder.is_dir():
            raise ctx.error(f"message folder not found: {folder} (PKG/msg/NAME.msg files go "
                            "under it; relative to the configuration file)", node, "msg_path")
        folders.append(folder)
        folder_nodes.append(node)
    for extra in msg_path:
        folders.append(Path(extra).resolve())
        folder_nodes.append(None)
    reg = _registry(ctx, folders, folder_nodes)
    known = known_type or (reg.__contains__ if folders else _known_type)
    sec["publisher"][0]["type"] = sec["publisher"][0]["type"] or sec["subscriber"][0]["type"]
    for section in ("subscriber", "publisher"):
        t, tn = sec[section]
        problem = ros_name_problem(t["topic"])
        _check(ctx, problem is None, f"{problem}: {t['topic']!r}", tn, "topic", section)
        _check_type(ctx, t["type"], tn, section, known)
        _check_definition(ctx, reg, t["type"], tn, section)
    if sec["subscriber"][0]["topic"] == sec["publisher"][0]["topic"]:
        raise ctx.error("the node would publish to the topic it subscribes to",
                        sec["publisher"][1].get("topic"), "publisher.topic")
    in_type, out_type = sec["subscriber"][0]["type"], sec["publisher"][0]["type"]
    is_image = in_type == limits.IMAGE_TYPE

    # image
    im, imn = sec["image"]
    if not is_image and im:
        raise ctx.error(f"image: is the geometry of {limits.IMAGE_TYPE} only; for "
                        f"{in_type} say stream: {{field: ARRAY, length: N}}",
                        top["image"][0], "image")
    if is_image and not im:
        raise ctx.error("missing section 'image:' (keys: width, height, encoding)", None, "image")
    if is_image:
        _check_image(ctx, im, imn)
    image = ImageConfig(**im) if is_image else None
    if in_type in reg:
        stream, checks, maxima, skip = _message_keys(ctx, reg, in_type, top, sec, image)
        _check_output_type(ctx, reg, in_type, out_type, stream, sec["publisher"][1])
    else:  # a caller's known_type accepted a type the registry lacks: no field to check
        stream, checks, maxima, skip = StreamConfig(limits.IMAGE_STREAM_FIELD, 0), (), (), ()

    # application
    ap, apn = sec["application"]
    _check(ctx, ap["op"] in OPS, f"op must be one of {', '.join(OPS)}, got {ap['op']!r}",
           apn, "op", "application")
    _check(ctx, ap["ksize"] % 2 == 1 and 1 <= ap["ksize"] <= limits.MAX_KSIZE,
           f"ksize must be odd, 1..{limits.MAX_KSIZE}, got {ap['ksize']}", apn, "ksize",
           "application")
    source_path: Path | None = None
    if ap["op"] == CUSTOM:
        _check(ctx, bool(ap["source"]), "op 'custom' needs 'source: FILE.cpp' (the C++ file "
               "defining image_filter)", apn, "op", "application")
        source_path = ((base_dir or Path.cwd()) / ap["source"]).resolve()
        _check(ctx, source_path.is_file(), f"application file not found: {source_path}",
               apn, "source", "application")
    else:
        _check(ctx, ap["source"] is None, f"'source' is only used with op 'custom' (op is "
               f"{ap['op']!r})", apn, "source", "application")

    # fifo, clock, limits
    f, fn = sec["fifo"]
    for key in ("input_depth", "output_depth", "axis_depth"):
        _check(ctx, 2 <= f[key] <= limits.MAX_FIFO_DEPTH,
               f"FIFO depth must be 2..{limits.MAX_FIFO_DEPTH}, got {f[key]}", fn, key, "fifo")
    if not limits.MIN_CLOCK_MHZ <= scalars["clock_mhz"] <= limits.MAX_CLOCK_MHZ:
        raise ctx.error(f"clock must be {limits.MIN_CLOCK_MHZ:g}..{limits.MAX_CLOCK_MHZ:g} MHz, "
                        f"got {scalars['clock_mhz']}", top_nodes.get("clock_mhz"), "clock_mhz")
    if not 1 <= scalars["frame_id_max"] <= limits.MAX_FRAME_ID_MAX:
        raise ctx.error(f"must be 1..{limits.MAX_FRAME_ID_MAX}, got {scalars['frame_id_max']}",
                        top_nodes.get("frame_id_max"), "frame_id_max")
    hl, hln = sec["hls"]
    _check(ctx, hl["flavour"] in HLS_FLAVOURS, f"flavour must be one of "
           f"{', '.join(HLS_FLAVOURS)} (vitis: Vitis HLS 2020.2 on; vivado: Vivado HLS up to "
           f"2019.2), got {hl['flavour']!r}", hln, "flavour", "hls")
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", scalars["part"]):
        raise ctx.error(f"expected an FPGA part name like xc7z020clg400-1, got {scalars['part']!r}",
                        top_nodes.get("part"), "part")
    if scalars["wire"] not in WIRES:
        raise ctx.error(f"wire must be one of {', '.join(WIRES)}, got {scalars['wire']!r}",
                        top_nodes.get("wire"), "wire")

    return NodeConfig(
        node=NodeSection(**n),
        subscriber=TopicConfig(**sec["subscriber"][0]),
        publisher=TopicConfig(**sec["publisher"][0]),
        image=image if image is not None else NoImage(in_type),
        application=ApplicationConfig(op=ap["op"], ksize=ap["ksize"], source=source_path),
        fifo=FifoConfig(**f),
        clock_mhz=float(scalars["clock_mhz"]),
        frame_id_max=scalars["frame_id_max"],
        part=scalars["part"],
        wire=scalars["wire"],
        hls=HlsConfig(**hl),
        msg_path=tuple(folders),
        stream=stream,
        checks=checks,
        limits=maxima,
        skip=skip,
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
    return _with_path(config, p.resolve())


def _with_path(config: NodeConfig, path: Path) -> NodeConfig:
    from dataclasses import replace

    return replace(config, path=path)
