"""One engine (issue 28): no library module outside the exhibit names a field of a particular
message type, except the owners listed below, each for a stated reason.

What counts as naming a field: a string constant in the code (docstrings aside) equal to a field
path of ``sensor_msgs/Image``, ``sensor_msgs/LaserScan`` or the shipped custom example
``lab_msgs/Samples`` (nested paths included: ``header.frame_id``, ``calibration.sensor_name``,
``header.stamp.secs``) or to the last name of a nested one (``frame_id``, ``sensor_name``), or
to a path as a layout ident (``header_stamp_secs``). The paths are read from the message
definitions, not listed here.

Field names that are also ordinary words of the lab (:data:`GENERIC`: ``data``, ``header``,
``width``, ``height``, ``encoding``, ``step``, ``seq``, ``stamp``, ...) cannot be told apart
from configuration keys (``image.width``), CLI options or prose by a text scan, so they count
only inside a nested path (``header.seq`` counts, ``"seq"`` alone does not). That leaves the
test blind to a module that walks Image by ``msg["width"]``; it catches the names only a
type-specific path uses (``is_bigendian``, ``frame_id``, ``angle_min``, ``ranges``,
``thresholds``, ``sensor_name``, every dotted path).
"""

from __future__ import annotations

import ast
from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.msg import MsgRegistry

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "rosfpga_lab"
EXHIBIT = PACKAGE / "rtl" / "exhibit"
TYPES = ("sensor_msgs/Image", "sensor_msgs/LaserScan", "lab_msgs/Samples")
#: Field names that are also ordinary words of the lab (config keys, options, prose).
GENERIC = frozenset({"data", "header", "width", "height", "encoding", "step", "seq", "stamp",
                     "label", "valid", "mode", "offset", "period", "samples", "secs", "nsecs"})
#: Modules allowed to name such fields, and why (paths below rosfpga_lab/).
OWNERS = {
    # the engine's Header rules, for every type with a std_msgs/Header: the TCPROS publisher
    # numbers header.seq (NUMBERED_FIELD), a result reports header.stamp (STAMP_FIELDS)
    "hw/circuit.py": "Header rules of the engine",
    # the configuration's frame_id_max bounds header.frame_id of any type with a Header
    "hw/layoutderive.py": "frame_id_max names the field it bounds",
    # makers of sample Image frames for tests, notebooks and benchmarks (message producers,
    # not circuit paths)
    "hw/sample.py": "sample Image frames",
    "msg/bench.py": "benchmark messages",
    "widgets/bench.py": "benchmark messages",
    # ROS nodes that publish or check a message of their own type (not circuit paths): the
    # checker compares a received Image with OpenCV's, the ROS 2 node re-stamps the Image it
    # publishes, rosout fills a rosgraph_msgs/Log's header
    "component/checker.py": "checks a received Image",
    "component/ros2.py": "re-stamps a published Image",
    "graph/rosout.py": "fills a Log's header",
    # notebook 12's shipped run publishes one LaserScan sample of its own into the fabric top
    # (a message producer; the circuit and its parameters come from the generic flow)
    "rtl/fabricdemo.py": "the fabric demo's LaserScan sample",
}


def _paths(reg: MsgRegistry, type_name: str, prefix: str = "") -> set[str]:
    spec = reg.get(type_name)
    out = set()
    for name, ftype in zip(spec.field_names, spec.field_types):
        path = prefix + name
        out.add(path)
        base = ftype.split("[")[0]
        if base in ("time", "duration"):
            out |= {f"{path}.secs", f"{path}.nsecs"}
            continue
        sub = "std_msgs/Header" if base == "Header" else base
        if "/" not in sub:
            sub = f"{spec.package}/{sub}"
        try:
            out |= _paths(reg, sub, path + ".")
        except Exception:   # a primitive type: no fields below it
            pass
    return out


def field_names() -> frozenset[str]:
    """The forbidden strings: every field path of :data:`TYPES` (generic words only nested) and
    their layout idents."""
    reg = load_config(ROOT / "data" / "fpga_samples_dilate.yaml").registry()
    paths = set().union(*(_paths(reg, t) for t in TYPES))
    names = {p for p in paths if p not in GENERIC}
    names |= {p.rsplit(".", 1)[1] for p in paths if "." in p} - GENERIC
    return frozenset(names | {p.replace(".", "_") for p in names})


def _code_strings(tree: ast.AST) -> list[tuple[int, str]]:
    docs = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docs.add(id(body[0].value))
    return [(n.lineno, n.value) for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs]


def namings(package: Path = PACKAGE) -> dict[str, list[tuple[int, str]]]:
    """``{module: [(line, field name)]}`` of every library module outside the exhibit."""
    forbidden = field_names()
    found: dict[str, list[tuple[int, str]]] = {}
    for path in sorted(package.rglob("*.py")):
        if EXHIBIT in path.parents or "__pycache__" in path.parts:
            continue
        hits = [(line, s) for line, s in _code_strings(ast.parse(path.read_text()))
                if s in forbidden]
        if hits:
            found[path.relative_to(package).as_posix()] = hits
    return found


def test_the_forbidden_names_are_read_from_the_definitions() -> None:
    names = field_names()
    assert {"is_bigendian", "header.frame_id", "frame_id", "header_stamp_secs", "angle_min",
            "ranges", "calibration.sensor_name", "sensor_name", "thresholds"} <= names
    assert not names & GENERIC


def test_no_module_outside_the_exhibit_names_a_field_of_a_particular_type() -> None:
    found = namings()
    strays = {m: hits for m, hits in found.items() if m not in OWNERS}
    assert not strays, f"modules naming a field of {', '.join(TYPES)}: {strays}"
    # every owner still names one (an owner that no longer does leaves the list)
    assert set(OWNERS) <= set(found), set(OWNERS) - set(found)


def test_a_planted_module_naming_a_field_is_caught(tmp_path: Path) -> None:
    """The scan on a copy of a small package with a planted module: a LaserScan field in code is
    found, the same name in a docstring is not."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "probe.py").write_text('"""ranges in prose."""\n\nLIMIT = {"range_max": 1}\n')
    (pkg / "clean.py").write_text('"""is_bigendian in prose."""\n\nX = "width"\n')
    assert namings(pkg) == {"probe.py": [(3, "range_max")]}
