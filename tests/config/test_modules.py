"""config is cut at its seams (records, schema, YAML walk, a parser per section, the entry
points) with its public API unchanged: what ``rosfpga_lab.config`` exported before the cut it
exports still, from the module that owns it."""

from __future__ import annotations

import ast
from pathlib import Path

import rosfpga_lab.config as config

CONFIG = Path(config.__file__).resolve().parent

#: ``rosfpga_lab.config.__all__`` before the cut (3f3ff06).
API = {
    "CUSTOM", "DEFAULT_ENCODING", "DEFAULT_OP", "ENCODINGS", "MODEL_OPS", "OPS", "PASSTHROUGH",
    "PIXEL_FORMATS", "ApplicationConfig", "ConfigError", "FifoConfig", "HlsConfig", "ImageConfig",
    "NodeConfig", "NodeSection", "PixelFormat", "TopicConfig", "load_config", "parse_config",
    "ros_name_problem", "canonical_op", "master_uri", "master_uri_from_env", "model_ksize",
    "CheckConfig", "NoImage", "StreamConfig",
}


def test_the_public_api_is_unchanged() -> None:
    assert set(config.__all__) == API
    assert all(hasattr(config, name) for name in API)
    assert config.parse_config.__module__ == "rosfpga_lab.config.parse"
    assert config.NodeConfig.__module__ == "rosfpga_lab.config.node"
    assert config.ros_name_problem.__module__ == "rosfpga_lab.config.names"


def test_the_records_module_holds_records_only() -> None:
    """``config.node`` defines the dataclasses and imports neither YAML nor the parser (which
    imports it), so a record is read without the machinery that checks a file."""
    tree = ast.parse((CONFIG / "node.py").read_text(encoding="utf-8"))
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)} | {
        a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert "yaml" not in imported
    assert not imported & {"rosfpga_lab.config.parse", "rosfpga_lab.config.sections",
                           "rosfpga_lab.config.schema", "rosfpga_lab.config.yamlwalk"}
    functions = [n.name for n in tree.body if isinstance(n, ast.FunctionDef)]
    assert functions == []   # no parsing here: every top-level definition is a record


def test_no_function_of_config_is_longer_than_60_lines() -> None:
    long = []
    for path in sorted(CONFIG.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1  # type: ignore[operator]
                if lines > 60:
                    long.append(f"{path.name}:{node.lineno} {node.name} ({lines} lines)")
    assert long == []
