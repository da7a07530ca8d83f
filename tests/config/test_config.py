"""The node configuration: the shipped examples load, and every bad input is a ConfigError that
names the key and the file:line, raised before anything is written."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from rosfpga_lab.errors import LabError
from rosfpga_lab.config import ConfigError, load_config, parse_config, ros_name_problem

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"

GOOD = """\
node:
  name: /fpga_test
  master_uri: http://127.0.0.1:11311/
  ip_address: 127.0.0.1
  xmlrpc_port: 45100
  tcpros_port: 45101
subscriber:
  topic: /in
  type: sensor_msgs/Image
publisher:
  topic: /out
  type: sensor_msgs/Image
image:
  width: 64
  height: 48
  encoding: mono8
application:
  op: erode
  ksize: 5
fifo:
  input_depth: 512
  output_depth: 1024
  axis_depth: 8
clock_mhz: 150
frame_id_max: 32
"""


def test_shipped_examples_load() -> None:
    paper = load_config(DATA / "fpga_dilate_rgba8.yaml")
    assert (paper.image.width, paper.image.height, paper.image.encoding) == (640, 480, "rgba8")
    assert (paper.application.op, paper.application.ksize) == ("dilate", 3)
    assert paper.image.data_bytes == 1_228_800  # DESIGN.md: a 640x480 rgba8 frame
    assert paper.node.name == "/fpga_dilate" and paper.subscriber.type == "sensor_msgs/Image"
    mono = load_config(DATA / "fpga_erode_mono8.yaml")
    assert (mono.image.encoding, mono.application.op, mono.application.ksize) == ("mono8", "erode", 5)
    rgb = load_config(DATA / "fpga_passthrough_rgb8.yaml")
    assert (rgb.image.encoding, rgb.application.op, rgb.image.step) == ("rgb8", "passthrough", 480)
    assert paper.path == (DATA / "fpga_dilate_rgba8.yaml").resolve()


def test_every_key_is_read_and_defaults_fill_the_rest() -> None:
    c = parse_config(GOOD)
    assert (c.node.xmlrpc_port, c.node.tcpros_port, c.node.ip_address) == (45100, 45101, "127.0.0.1")
    assert (c.fifo.input_depth, c.fifo.output_depth, c.fifo.axis_depth) == (512, 1024, 8)
    assert (c.clock_mhz, c.frame_id_max, c.image.step, c.image.data_bytes) == (150.0, 32, 64, 64 * 48)
    minimal = parse_config("node: {name: fpga}\nsubscriber: {topic: a}\npublisher: {topic: b}\n"
                           "image: {width: 8, height: 8, encoding: rgb8}\n")
    assert minimal.node.master_uri == "http://127.0.0.1:11311/"
    assert minimal.node.ip_address == "127.0.0.1"  # loopback unless told otherwise
    assert minimal.node.global_name == "/fpga"
    assert (minimal.application.op, minimal.application.ksize) == ("dilate", 3)
    assert minimal.subscriber.type == "sensor_msgs/Image"


def test_config_is_frozen() -> None:
    c = parse_config(GOOD)
    with pytest.raises(AttributeError):
        c.image.width = 1  # type: ignore[misc]


def _replace(old: str, new: str) -> str:
    assert old in GOOD, old
    return GOOD.replace(old, new, 1)


# (case, text, dotted key, line, words the message must contain)
BAD = [
    ("mistyped key", _replace("  ksize: 5", "  ksise: 5"), "application.ksise", 19, "did you mean 'ksize'"),
    ("unknown section", GOOD + "extra:\n  a: 1\n", "extra", 26, "unknown key"),
    ("missing key", _replace("  width: 64\n", ""), "image.width", 13, "missing key 'width'"),
    ("missing section", GOOD.replace("publisher:\n  topic: /out\n  type: sensor_msgs/Image\n", ""),
     "publisher", 0, "missing section"),
    ("duplicate key", _replace("  height: 48\n", "  height: 48\n  height: 50\n"), "image.height", 16,
     "duplicate key"),
    ("wrong type", _replace("  width: 64", "  width: sixty-four"), "image.width", 14, "expected int"),
    ("bool is not int", _replace("  width: 64", "  width: true"), "image.width", 14, "expected int"),
    ("section not a mapping", _replace("image:\n  width: 64\n  height: 48\n  encoding: mono8\n",
                                       "image: 5\n"), "image", 13, "mapping"),
    ("unknown message type", _replace("  type: sensor_msgs/Image\npublisher", "  type: sensor_msgs/Imag\npublisher"),
     "subscriber.type", 9, "unknown message type"),
    ("type the templates cannot stream", _replace("  topic: /out\n  type: sensor_msgs/Image",
                                                  "  topic: /out\n  type: std_msgs/String"),
     "publisher.type", 12, "cannot stream"),
    ("node name with a space", _replace("/fpga_test", "/fpga test"), "node.name", 2, "' '"),
    ("private node name", _replace("/fpga_test", "~fpga"), "node.name", 2, "private"),
    ("topic starting with a digit", _replace("  topic: /in", "  topic: 9in"), "subscriber.topic", 8,
     "starts with a letter"),
    ("topic with //", _replace("  topic: /out", "  topic: /a//b"), "publisher.topic", 11, "'//'"),
    ("node base name starting with a digit", _replace("/fpga_test", "/ns/9fpga"), "node.name", 2,
     "must start with a letter"),
    ("topic with a trailing slash", _replace("  topic: /out", "  topic: /out/"), "publisher.topic",
     11, "canonical form"),
    ("non-ASCII topic", _replace("  topic: /out", "  topic: /kamera_ü"), "publisher.topic", 11,
     "'ü'"),
    ("topic with a dash", _replace("  topic: /out", "  topic: /my-topic"), "publisher.topic", 11, "'-'"),
    ("same topic in and out", _replace("  topic: /out", "  topic: /in"), "publisher.topic", 11,
     "subscribes to"),
    ("bad master URI", _replace("http://127.0.0.1:11311/", "127.0.0.1:11311"), "node.master_uri", 3,
     "http://HOST:PORT/"),
    ("bad IP address", _replace("ip_address: 127.0.0.1", "ip_address: 127.0.0.300"), "node.ip_address",
     4, "IPv4"),
    ("port out of range", _replace("xmlrpc_port: 45100", "xmlrpc_port: 70000"), "node.xmlrpc_port", 5,
     "0..65535"),
    ("same ports", _replace("tcpros_port: 45101", "tcpros_port: 45100"), "node.tcpros_port", 6, "differ"),
    ("width zero", _replace("  width: 64", "  width: 0"), "image.width", 14, "width must be"),
    ("height too large", _replace("  height: 48", "  height: 100000"), "image.height", 15, "height must be"),
    ("unsupported encoding", _replace("encoding: mono8", "encoding: yuv422"), "image.encoding", 16,
     "supported: rgba8"),
    ("16-bit encoding", _replace("encoding: mono8", "encoding: mono16"), "image.encoding", 16, "can pack"),
    ("unknown op", _replace("op: erode", "op: blur"), "application.op", 18, "dilate, erode"),
    ("even kernel", _replace("ksize: 5", "ksize: 4"), "application.ksize", 19, "odd"),
    ("custom without source", _replace("op: erode", "op: custom"), "application.op", 18, "source"),
    ("missing application file", _replace("  op: erode\n", "  op: custom\n  source: no_such_filter.cpp\n"),
     "application.source", 19, "not found"),
    ("source without custom", _replace("  ksize: 5\n", "  ksize: 5\n  source: f.cpp\n"),
     "application.source", 20, "only used with op 'custom'"),
    ("FIFO too shallow", _replace("axis_depth: 8", "axis_depth: 1"), "fifo.axis_depth", 23, "2.."),
    ("clock out of range", _replace("clock_mhz: 150", "clock_mhz: 0.1"), "clock_mhz", 24, "MHz"),
    ("frame_id_max too large", _replace("frame_id_max: 32", "frame_id_max: 100000"), "frame_id_max", 25,
     "1..256"),
]


@pytest.mark.parametrize("case,text,key,line,words", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_key_and_line(tmp_path: Path, case: str, text: str, key: str, line: int,
                                      words: str) -> None:
    path = tmp_path / "node.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    err = info.value
    assert isinstance(err, LabError)
    assert err.key == key, str(err)
    assert err.line == line, str(err)
    assert words in str(err), str(err)
    where = f"{path}:{line}: " if line else f"{path}: "
    assert str(err).startswith(where + key), str(err)


@pytest.mark.parametrize("text,words", [
    ("", "empty"),
    ("node: [1, 2\n", "not valid YAML"),
    ("- a\n- b\n", "mapping"),
])
def test_not_a_configuration(tmp_path: Path, text: str, words: str) -> None:
    path = tmp_path / "node.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=words):
        load_config(path)


def test_missing_file_and_binary_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path / "nope.yaml")
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_config(tmp_path / "bin.yaml")


def test_custom_source_is_relative_to_the_config(tmp_path: Path) -> None:
    (tmp_path / "apps").mkdir()
    (tmp_path / "apps" / "f.cpp").write_text("// filter\n")
    path = tmp_path / "node.yaml"
    path.write_text(_replace("  op: erode\n", "  op: custom\n  source: apps/f.cpp\n"))
    assert load_config(path).application.source == (tmp_path / "apps" / "f.cpp").resolve()


@pytest.mark.parametrize("name,ok", [
    ("/image_raw", True), ("image", True), ("~private", True), ("/a/b_c/d2", True), ("/", True),
    ("", False), ("/a b", False), ("2abc", False), ("/a//b", False), ("/a/", False), ("/a~b", False),
    ("/a/_b", True), ("/1a", True), ("/ä", False), ("/kamera_ü", False),
])
def test_ros_names(name: str, ok: bool) -> None:
    assert (ros_name_problem(name) is None) is ok


def test_cli_refuses_bad_config_before_writing(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(_replace("encoding: mono8", "encoding: yuv422"))
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(bad), "-o", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 1
    assert f"{bad}:16: image.encoding" in proc.stderr
    assert not out.exists()


def test_one_vocabulary_for_operations_and_encodings() -> None:
    """Every layer takes its operations and encodings from config.vocabulary: the identity op is
    "passthrough" from the YAML file to the models' name, and "copy" is only an accepted alias."""
    import argparse

    from rosfpga_lab.cli import camera as cli_camera
    from rosfpga_lab.component.checker import expected_output
    from rosfpga_lab.config import ENCODINGS, MODEL_OPS, OPS, canonical_op
    from rosfpga_lab.hw import OPS as HW_OPS
    from rosfpga_lab.hw import MessagePipeline

    assert OPS == ("dilate", "erode", "passthrough", "custom") and HW_OPS == MODEL_OPS == OPS[:3]
    assert canonical_op("copy") == "passthrough" and canonical_op("erode") == "erode"
    config = load_config(DATA / "fpga_passthrough_rgb8.yaml")
    assert MessagePipeline.from_config(config).op == "passthrough"
    import numpy as np

    image = np.arange(12, dtype=np.uint8).reshape(2, 2, 3)
    assert expected_output(image, config.application.op, (3, 3)) is image
    parser = argparse.ArgumentParser()
    cli_camera.register(parser.add_subparsers())
    enc_action = next(a for a in parser._subparsers._group_actions[0].choices["camera"]._actions
                      if a.dest == "encoding")
    assert tuple(enc_action.choices) == tuple(ENCODINGS)


def test_one_master_uri_rule() -> None:
    """explicit > ROS_MASTER_URI > the configuration's node.master_uri > roscore's default."""
    from rosfpga_lab.config import master_uri
    from rosfpga_lab.config.limits import DEFAULT_MASTER_URI

    cfg = parse_config(GOOD.replace("master_uri: http://127.0.0.1:11311/", "master_uri: http://10.0.0.2:1/"))
    env = {"ROS_MASTER_URI": "http://10.0.0.3:2/"}
    assert DEFAULT_MASTER_URI == "http://127.0.0.1:11311/"
    assert master_uri("http://10.0.0.1:9/", cfg, env) == "http://10.0.0.1:9/"
    assert master_uri(None, cfg, env) == "http://10.0.0.3:2/"
    assert master_uri(None, cfg, {"ROS_MASTER_URI": "  "}) == "http://10.0.0.2:1/"
    assert master_uri("", cfg, {}) == "http://10.0.0.2:1/"
    assert master_uri(None, None, {}) == DEFAULT_MASTER_URI
    assert master_uri(None, None, env) == "http://10.0.0.3:2/"


# Names and what rosgraph.names says of them (is_legal_name, is_legal_base_name); the table is
# checked against real rosgraph below. Non-ASCII names are the one deliberate difference.
NAME_TABLE = [
    "", "/", "~", "a", "/a", "~a", "/a/b", "a/b", "/a/", "a_b", "/a_b2/c3", "/1a", "1a", "/a/1b",
    "/a/_b", "_a", "__a", "/a//b", "//a", "/a b", "/a-b", "/a.b", "/a~b", "~/a", "~a/b", "/a\n",
    "a\n", "/kamera_ü", "kamera_ü", "/ä", "é", "/a:b", "Ab9_", "9", "/a/b/", "~~a",
]


def test_lab_names_follow_rosgraph_table() -> None:
    """The lab's one validator: rosgraph's rules, ASCII letters only; used by config and graph."""
    from rosfpga_lab.config.names import is_legal_base_name, is_legal_name, name_problem
    from rosfpga_lab.graph.errors import ConfigError as GraphConfigError
    from rosfpga_lab.graph.names import check_node_name, check_topic_name

    for name in NAME_TABLE:
        assert (name_problem(name) is None) == (bool(name) and is_legal_name(name)), name
        if name and is_legal_name(name):
            assert check_topic_name(name) is not None
        elif name:
            with pytest.raises(GraphConfigError):
                check_topic_name(name)
    assert not is_legal_name("/kamera_ü") and is_legal_name("/1a") and not is_legal_base_name("1a")
    assert name_problem("/1a", node_name=True) == "a node's base name must start with a letter, got '1a'"
    with pytest.raises(GraphConfigError, match="kamera"):
        check_node_name("/kamera_ü")
    assert check_node_name("/ns/cam_2/") == "/ns/cam_2"
    # the configuration adds one rule of its own: canonical form
    assert ros_name_problem("/a/") is not None and name_problem("/a/") is None


def test_lab_names_match_real_rosgraph() -> None:
    """Run the table through real rosgraph.names under ROS's own Python."""
    import json

    from tests.support.realros import ROS_PYTHON, require_ros

    from rosfpga_lab.config.names import is_legal_base_name, is_legal_name

    require_ros()
    program = ("import json, sys, rosgraph.names as n; names = json.load(sys.stdin); "
               "print(json.dumps([[n.is_legal_name(x), n.is_legal_base_name(x)] for x in names]))")
    done = subprocess.run([ROS_PYTHON, "-c", program], input=json.dumps(NAME_TABLE),
                          capture_output=True, text=True, timeout=60, check=True)
    theirs = json.loads(done.stdout)
    for name, (legal, base) in zip(NAME_TABLE, theirs, strict=True):
        if name.isascii():
            assert (is_legal_name(name), is_legal_base_name(name)) == (legal, base), name
        else:  # rosgraph's \w is Unicode in Python 3; roscpp and the lab allow ASCII only
            assert not is_legal_name(name) and not is_legal_base_name(name), name
    assert dict(zip(NAME_TABLE, theirs))["/kamera_ü"] == [True, False]  # the difference, documented
