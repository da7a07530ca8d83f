"""The component's private parameters (issue 23, item 4): runtime settings from ``~model``,
``~input_queue``, ``~output_queue``; circuit parameters (``~ksize`` ...) accepted only when they
equal the YAML, refused with a clear message otherwise; as ``_name:=value`` and on the server."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosfpga_lab.cli import main
from rosfpga_lab.config import ConfigError, load_config
from rosfpga_lab.config.params import ParamSource, runtime_settings
from rosfpga_lab.graph import EmbeddedMaster

CONFIG = Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml"


def src(values: dict, where: str = "the command line", prefix: str = "_") -> ParamSource:
    return ParamSource(values, where, prefix)


def test_runtime_parameters_are_returned_and_later_sources_win() -> None:
    cfg = load_config(CONFIG)
    server = src({"model": "reference", "input_queue": 4}, "the parameter server", "/x/")
    assert runtime_settings(cfg, server, src({"input_queue": 8})) == {
        "model": "reference", "input_queue": 8}
    # circuit parameters equal to the YAML are accepted (the launch file agrees with it)
    assert runtime_settings(cfg, src({"ksize": 3, "op": "dilate", "width": 640,
                                      "encoding": "rgba8", "clock_mhz": 100})) == {}


@pytest.mark.parametrize("values,match", [
    ({"ksize": 5}, r"parameter _ksize is 5 in the command line, but the circuit was built with "
                   r"application.ksize: 3 \(.*fpga_dilate_rgba8.yaml\).*rosfpga-lab generate"),
    ({"op": "erode"}, "application.op: 'dilate'"),
    ({"width": 320}, "image.width: 640"),
    ({"ksize": True}, "application.ksize: 3"),
    ({"model": "slow"}, r"_model \(the circuit model \(--model\)\).*want one of fast, reference"),
    ({"input_queue": 0}, "want a whole number of at least 1, got 0"),
    ({"kszie": 3}, "unknown parameter _kszie in the command line"),
])
def test_wrong_parameters_are_refused_with_what_and_where(values, match) -> None:
    with pytest.raises(ConfigError, match=match):
        runtime_settings(load_config(CONFIG), src(values))


def test_node_command_refuses_a_ksize_the_circuit_does_not_have(capsys) -> None:
    with EmbeddedMaster(port=0) as master:
        assert main(["node", str(CONFIG), "--master-uri", master.uri, "--duration", "0.3",
                     "-q", "_ksize:=5"]) == 1
        assert master.getSystemState("/t")[2] == [[], [], []]   # it never registered
    err = capsys.readouterr().err
    assert "parameter _ksize is 5 in the command line, but the circuit was built with " \
           "application.ksize: 3" in err


def test_node_command_reads_the_parameter_server_and_puts_command_line_params_there(
        capsys) -> None:
    with EmbeddedMaster(port=0) as master:
        master.setParam("/t", "/fpga_dilate/model", "reference")
        master.setParam("/t", "/fpga_dilate/ksize", 3)
        assert main(["node", str(CONFIG), "--master-uri", master.uri, "--duration", "0.3",
                     "-q", "_output_queue:=4"]) == 0
        assert master.getParam("/t", "/fpga_dilate/output_queue")[2] == 4
        master.setParam("/t", "/fpga_dilate/ksize", 7)
        assert main(["node", str(CONFIG), "--master-uri", master.uri, "--duration", "0.3",
                     "-q"]) == 1
    out, err = capsys.readouterr()
    assert "/image_raw -> dilate (reference model, host timing) -> /image_dilated" in out
    assert "parameter /fpga_dilate/ksize is 7 in the parameter server" in err
