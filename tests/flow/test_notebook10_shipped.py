"""data/notebook10_sim.json (what notebook 10 shows without g++ or Icarus Verilog) belongs to the
notebook's message and configuration, says what the models say, and is what
data/make_notebook10_sim.py makes again with the tools (C and RTL simulation)."""

from __future__ import annotations

import hashlib
import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

from tests.support.realros import require_cxx
from tests.support.rtltools import require_iverilog
from rosfpga_lab.config import parse_config
from rosfpga_lab.hls.vectors import sample_frames_generic
from rosfpga_lab.hw.layout import layout_from_config

DATA = Path(__file__).resolve().parents[2] / "data"


def script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_notebook10_sim", DATA / "make_notebook10_sim.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def shipped() -> dict:
    return json.loads((DATA / "notebook10_sim.json").read_text(encoding="utf-8"))


def test_the_shipped_result_is_for_the_notebooks_texts_and_equals_the_models(tmp_path: Path) -> None:
    make = script()
    texts = make.notebook_texts()
    result = shipped()
    assert (result["msg_text"], result["config_text"]) == (texts["MSG_TEXT"], texts["CONFIG_TEXT"])
    (tmp_path / make.MSG_FILE).parent.mkdir(parents=True)
    (tmp_path / make.MSG_FILE).write_text(texts["MSG_TEXT"])
    config = parse_config(texts["CONFIG_TEXT"], source="test", base_dir=tmp_path)
    frames, expected = sample_frames_generic(layout_from_config(config), config.application.op,
                                             config.application.ksize)
    assert result["input_sha256"] == hashlib.sha256(frames).hexdigest()
    assert result["expected_sha256"] == hashlib.sha256(expected).hexdigest()
    for run in ("csim", "rtlsim"):
        assert result[run]["output_sha256"] == result["expected_sha256"], run
        assert result[run]["output_bytes"] == len(expected) > 0
        # the testbench's frames: a good one, one with a values array one element short, a good one
        assert result[run]["statuses"] == ["SUB_OK", "SUB_BAD_VALUES_LENGTH", "SUB_OK"], run


def test_the_script_makes_the_same_result_with_the_tools() -> None:
    require_cxx()
    require_iverilog()
    make = script()
    assert make.make_result(make.notebook_texts()) == shipped()


def test_the_script_names_a_missing_text(tmp_path: Path) -> None:
    nb = {"cells": [{"cell_type": "code", "source": ["EXAMPLE_MSG_TEXT = 'Header header\\n'\n"]}]}
    (tmp_path / "nb.ipynb").write_text(json.dumps(nb))
    with pytest.raises(SystemExit, match="no cell assigns EXAMPLE_CONFIG_TEXT a string"):
        script().notebook_texts(tmp_path / "nb.ipynb")
