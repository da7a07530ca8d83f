"""Checks of notebook 6: the design flow (node configuration, generated code, Table 1)."""

from __future__ import annotations

from typing import Any

from rosfpga_lab.checks._core import CheckResult, fail, require_type
from rosfpga_lab.config import ConfigError, parse_config
from rosfpga_lab.hls import sloc

#: Exercise 6.1: what the reader's configuration must say (dotted key -> value).
EROSION_NODE = {
    "node.name": "/fpga_erode",
    "subscriber.topic": "/camera/image_mono",
    "publisher.topic": "/camera/image_eroded",
    "image.width": 320,
    "image.height": 240,
    "image.encoding": "mono8",
    "application.op": "erode",
    "application.ksize": 5,
}


def _get(config: Any, dotted: str) -> Any:
    value = config
    for part in dotted.split("."):
        value = getattr(value, part)
    return value


def _written(text: str, dotted: str) -> bool:
    """True when the YAML ``text`` spells out the key ``dotted`` (rather than leaving a default)."""
    import yaml

    try:
        value: Any = yaml.safe_load(text)
    except yaml.YAMLError:
        return True
    for part in dotted.split("."):
        if not isinstance(value, dict) or part not in value:
            return False
        value = value[part]
    return True


def check_node_config(text: Any, expected: dict[str, Any] | None = None) -> CheckResult:
    """Exercise 6.1: a node configuration (YAML text) for a given component.

    Args:
        text: the reader's YAML.
        expected: dotted key -> value (default :data:`EROSION_NODE`).

    Raises:
        ExerciseError: the configuration does not load (file line and key given) or a value
            differs from the specification.
    """
    ex = "6.1 (a node configuration)"
    require_type(ex, "config_text", text, str)
    want = expected or EROSION_NODE
    try:
        config = parse_config(text, source="config_text")
    except ConfigError as exc:
        raise fail(ex, f"the configuration does not load: {exc}") from None
    problems = []
    for key, value in want.items():
        have = _get(config, key)
        if have != value:
            hint = ""
            if not _written(text, key):
                hint = f" (the default: the key {key.split('.')[-1]} is missing from the text)"
            problems.append(f"{key} is {have!r}, expected {value!r}{hint}")
    if problems:
        raise fail(ex, *problems)
    return CheckResult(ex, [f"{config.node.name}: {config.subscriber.topic} -> "
                            f"{config.application.op} {config.application.ksize}x"
                            f"{config.application.ksize} -> {config.publisher.topic}, "
                            f"{config.image.width}x{config.image.height} {config.image.encoding}"])


def check_sloc(answer: Any, source: str) -> CheckResult:
    """Exercise 6.2: count the source lines of C++ text as Table 1 does.

    Non-blank lines that hold something besides comments count (``#pragma`` lines count).

    Raises:
        ExerciseError: a wrong count, with what it seems to include or leave out.
    """
    ex = "6.2 (count lines like Table 1)"
    require_type(ex, "lines", answer, int)
    want = sloc(source)
    if answer == want:
        return CheckResult(ex, [f"{want} lines of code: blank and comment-only lines do not count, "
                                "#pragma HLS lines do"])
    lines = source.splitlines()
    blank = sum(1 for line in lines if not line.strip())
    pragmas = sum(1 for line in lines if line.strip().startswith("#pragma"))
    directives = sum(1 for line in lines if line.strip().startswith("#"))
    hints = {  # later entries win when two slips give the same number
        len(lines): "that is every line; leave out blank and comment-only lines.",
        len(lines) - blank: "that leaves out blank lines but still counts comment-only lines "
                            "(// ... and inside /* ... */).",
        want - directives: "that leaves out the preprocessor lines; #include and #pragma HLS "
                           "lines count.",
        want - pragmas: "that leaves out the #pragma HLS lines; they count (they are code: they "
                        "tell HLS how to build the circuit).",
    }
    direction = ("too many: is a line inside a /* ... */ comment counted?" if answer > want else
                 "too few: a line with code before a // comment counts.")
    raise fail(ex, f"you counted {answer}, expected another number: "
                   + hints.get(answer, f"{direction} Count the lines that hold code after removing "
                                       "comments."))
