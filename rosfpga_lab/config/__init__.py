"""The node configuration and the lab's shared vocabulary, light enough to load anywhere.

One YAML file describes one ROS-compliant FPGA component (:func:`load_config`); the generator
(``hls``), the RTL (``rtl``), the emulated node (``component``), the benchmarks and the exercise
checks all read it through this package. Loading a configuration imports neither OpenCV nor
Jinja2 (a test holds that)::

    from rosfpga_lab.config import load_config
    config = load_config("data/fpga_dilate_rgba8.yaml")
    config.image.width, config.application.op, config.node.master_uri

The same package owns what every layer shares: the encodings and operations (``dilate``,
``erode``, ``passthrough``, ``custom``), the ROS name rules (rosgraph's, ASCII letters only, as
roscpp) and the one rule for which master a command talks to (:func:`master_uri`).

Owners: :mod:`~rosfpga_lab.config.vocabulary` (encodings and operations),
:mod:`~rosfpga_lab.config.limits` (limits and defaults), :mod:`~rosfpga_lab.config.master` (which
ROS master a program talks to), :mod:`~rosfpga_lab.config.names` (ROS names),
:mod:`~rosfpga_lab.config.node` (the file's format and its records, the dataclasses),
:mod:`~rosfpga_lab.config.parse` (:func:`parse_config`, :func:`load_config`),
:mod:`~rosfpga_lab.config.schema` (sections, keys, types, defaults),
:mod:`~rosfpga_lab.config.sections` (one parser per section),
:mod:`~rosfpga_lab.config.yamlwalk` (the composed YAML, with line numbers).
"""

from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.master import master_uri, master_uri_from_env
from rosfpga_lab.config.names import ros_name_problem
from rosfpga_lab.config.node import (
    ApplicationConfig, FifoConfig, HlsConfig, ImageConfig, NodeConfig, NodeSection, TopicConfig,
)
from rosfpga_lab.config.node import CheckConfig, NoImage, StreamConfig
from rosfpga_lab.config.parse import load_config, parse_config
from rosfpga_lab.config.vocabulary import (
    CUSTOM, DEFAULT_ENCODING, DEFAULT_OP, ENCODINGS, MODEL_OPS, OPS, PASSTHROUGH, PIXEL_FORMATS, PixelFormat,
    canonical_op, model_ksize,
)

__all__ = [
    "CUSTOM", "DEFAULT_ENCODING", "DEFAULT_OP", "ENCODINGS", "MODEL_OPS", "OPS", "PASSTHROUGH", "PIXEL_FORMATS", "ApplicationConfig", "ConfigError", "FifoConfig", "HlsConfig",
    "ImageConfig", "NodeConfig", "NodeSection", "PixelFormat", "TopicConfig", "load_config",
    "parse_config", "ros_name_problem", "canonical_op", "master_uri", "master_uri_from_env",
    "model_ksize", "CheckConfig", "NoImage", "StreamConfig",
]
