"""The ROS command line (``from:=to``, ``__name:=``, ``_param:=``) and ROS_NAMESPACE, sans-IO.

Expected values are rospy's and roscpp's documented behaviour (rosgraph.names, roscpp's
``this_node::init`` and ``network::init``), written out by hand; the graph-level tests that run
the lab's commands under real roslaunch are in ``flow/test_ros_package.py``.
"""

from __future__ import annotations

import pytest

from rosfpga_lab.config import ConfigError
from rosfpga_lab.config.rosargs import (
    RosArgs, advertise_host, component_names, node_name, remap, split_ros_args,
)


def test_split_takes_what_roslaunch_appends_and_keeps_the_rest_in_order() -> None:
    rest, ros = split_ros_args(["cfg.yaml", "image_raw:=/cam/image", "--model", "fast",
                                "__name:=fpga", "__log:=/tmp/x/fpga-1.log", "_ksize:=5",
                                "_op:=dilate", "_scale:=0.5", "_label:='5'"])
    assert rest == ["cfg.yaml", "--model", "fast"]
    assert ros.remappings == {"image_raw": "/cam/image"}
    assert ros.special == {"__name": "fpga", "__log": "/tmp/x/fpga-1.log"}
    # values are YAML, as rospy reads them: 5 is an int, '5' a string
    assert ros.params == {"ksize": 5, "op": "dilate", "scale": 0.5, "label": "5"}
    assert bool(ros) and not bool(split_ros_args(["a"])[1])


@pytest.mark.parametrize("word,match", [
    (":=x", "both sides"), ("a:=", "both sides"), ("__nme:=x", "unknown special key"),
    ("__name:=a/b", "base name"), ("__name:=1a", "base name"), ("a b:=c", "not allowed"),
    ("a:=b c", "not allowed"), ("_a/b:=1", "private parameter"), ("__master:=foo", "http://"),
])
def test_malformed_ros_words_are_refused_with_the_word(word, match) -> None:
    with pytest.raises(ConfigError, match=match) as info:
        split_ros_args([word])
    assert repr(word) in str(info.value)


def test_a_key_given_twice_with_different_values_is_refused() -> None:
    with pytest.raises(ConfigError, match="already given"):
        split_ros_args(["a:=b", "a:=c"])
    assert split_ros_args(["a:=b", "a:=b"])[1].remappings == {"a": "b"}


@pytest.mark.parametrize("configured,words,env,expected", [
    ("/fpga_dilate", [], {}, "/fpga_dilate"),
    ("fpga_dilate", [], {"ROS_NAMESPACE": "ns1"}, "/ns1/fpga_dilate"),      # issue 23 item 3
    ("fpga_dilate", [], {"ROS_NAMESPACE": "/ns1/"}, "/ns1/fpga_dilate"),
    ("/fpga_dilate", [], {"ROS_NAMESPACE": "/ns1"}, "/fpga_dilate"),        # global stays
    ("/fpga_dilate", ["__name:=foo"], {}, "/foo"),
    ("/fpga_dilate", ["__name:=foo"], {"ROS_NAMESPACE": "/ns1"}, "/ns1/foo"),  # roslaunch ns=
    ("fpga", ["__ns:=/a"], {"ROS_NAMESPACE": "/b"}, "/a/fpga"),             # __ns beats the env
    ("a/fpga", [], {"ROS_NAMESPACE": "/b"}, "/b/a/fpga"),
])
def test_node_name_follows_roscpp(configured, words, env, expected) -> None:
    assert node_name(configured, split_ros_args(words)[1], env) == expected


@pytest.mark.parametrize("name,node,words,expected", [
    ("image_raw", "/ns1/fpga", ["image_raw:=/cam/image"], "/cam/image"),
    ("/image_raw", "/fpga", ["image_raw:=/cam/image"], "/cam/image"),
    ("/image_raw", "/ns1/fpga", ["image_raw:=/cam/image"], "/image_raw"),  # key is /ns1/image_raw
    ("/image_raw", "/ns1/fpga", ["/image_raw:=cam"], "/ns1/cam"),          # value resolves too
    ("~out", "/ns1/fpga", ["~out:=/o"], "/o"),
    ("~out", "/ns1/fpga", [], "/ns1/fpga/out"),
    ("image", "/ns1/fpga", [], "/ns1/image"),
])
def test_remapping_resolves_both_sides_against_the_node(name, node, words, expected) -> None:
    assert remap(name, node, split_ros_args(words)[1]) == expected


@pytest.mark.parametrize("words,env,configured,expected", [
    ([], {}, None, ("127.0.0.1", "the lab's default (loopback)")),
    ([], {}, "10.0.0.5", ("10.0.0.5", "the configuration's node.ip_address")),
    ([], {"ROS_IP": "127.0.0.2"}, "10.0.0.5", ("127.0.0.2", "ROS_IP")),
    ([], {"ROS_IP": "127.0.0.2", "ROS_HOSTNAME": "localhost"}, None, ("localhost", "ROS_HOSTNAME")),
    (["__ip:=127.0.0.3"], {"ROS_HOSTNAME": "localhost"}, None, ("127.0.0.3", "__ip:=")),
    (["__ip:=127.0.0.3", "__hostname:=localhost"], {}, None, ("localhost", "__hostname:=")),
    (["__ip:=::1"], {}, None, ("::1", "__ip:=")),
])
def test_advertised_address_order_is_roscpps(words, env, configured, expected) -> None:
    choice = advertise_host(split_ros_args(words)[1], configured, env)
    assert (choice.host, choice.source) == expected


@pytest.mark.parametrize("var,value", [("ROS_HOSTNAME", "http://x"), ("ROS_HOSTNAME", "x:11311"),
                                       ("ROS_IP", "http://127.0.0.1")])
def test_an_address_with_a_scheme_or_port_is_refused(var, value) -> None:
    with pytest.raises(ConfigError, match=var):
        advertise_host(RosArgs(), None, {var: value})


def test_component_names_in_a_namespace_with_a_remap() -> None:
    from rosfpga_lab.config import parse_config

    cfg = parse_config("node: {name: fpga_dilate}\nsubscriber: {topic: image_raw}\n"
                       "publisher: {topic: image_dilated}\n"
                       "image: {width: 8, height: 8, encoding: mono8}\n")
    ros = split_ros_args(["image_raw:=/cam/image"])[1]
    names = component_names(cfg, ros, {"ROS_NAMESPACE": "ns1"})
    assert (names.node, names.input, names.output) == (
        "/ns1/fpga_dilate", "/cam/image", "/ns1/image_dilated")
    with pytest.raises(ConfigError, match="publish to the topic it subscribes"):
        component_names(cfg, split_ros_args(["image_raw:=image_dilated"])[1], {})


def test_the_command_line_refuses_ros_words_where_no_node_runs(capsys) -> None:
    from rosfpga_lab.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main(["msg", "md5", "std_msgs/String", "a:=b"])
    assert exit_info.value.code == 2
    assert "a:=b: ROS arguments (NAME:=VALUE) are for the commands that run a ROS node" in \
        capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["node", "x.yaml", "__bad:=1"])
    assert "unknown special key '__bad'" in capsys.readouterr().err
