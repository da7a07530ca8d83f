"""The node configuration's records: one YAML file describes one ROS-compliant FPGA component.

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
      source: null        # C++ file of stream_filter(), relative to this file (op: custom)
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

The records are frozen dataclasses, one per section;
:func:`~rosfpga_lab.config.parse.parse_config` and :func:`~rosfpga_lab.config.parse.load_config`
(module ``parse``) read and check a file into them, section by section (module ``sections``,
with the schema table of module ``schema``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from rosfpga_lab.config import limits
from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.vocabulary import DEFAULT_HLS_FLAVOUR, DEFAULT_OP, DEFAULT_WIRE, ENCODINGS

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
        source: for ``custom``, the C++ file defining ``stream_filter()`` (absolute path).
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


__all__ = ["ApplicationConfig", "CheckConfig", "FifoConfig", "HlsConfig", "ImageConfig", "NoImage",
           "NodeConfig", "NodeSection", "StreamConfig", "TopicConfig"]
