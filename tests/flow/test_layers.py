"""A layer imports only the layers below it (DESIGN.md); this test keeps it so."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "rosfpga_lab"
# Bottom to top; names on one level may not import each other.
LEVELS = [
    {"errors"}, {"msg"}, {"tcpros", "rtps"}, {"config"}, {"graph"}, {"hw"}, {"hls"}, {"rtl"},
    {"component"},
    {"widgets", "checks"}, {"bench"}, {"cli"}, {"__main__"},
]
RANK = {name: level for level, names in enumerate(LEVELS) for name in names}


def _imported_layers(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "rosfpga_lab" and len(parts) > 1:
                found.add(parts[1])
    return found


def test_every_module_belongs_to_a_known_layer() -> None:
    for path in PACKAGE.iterdir():
        if path.name.startswith((".", "_")) and path.name != "__main__.py":
            continue
        if path.is_dir() or path.suffix == ".py":
            assert path.stem in RANK, f"{path.name} is in no layer of DESIGN.md"


def test_no_layer_imports_a_layer_above_it() -> None:
    offences = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).parts
        layer = parts[0].removesuffix(".py")
        if layer not in RANK:
            continue
        for dep in _imported_layers(path):
            if dep in RANK and RANK[dep] > RANK[layer]:
                offences.append(f"{path.relative_to(PACKAGE)}: {layer} imports {dep}")
            if dep in RANK and RANK[dep] == RANK[layer] and dep != layer:
                offences.append(f"{path.relative_to(PACKAGE)}: {layer} imports its sibling {dep}")
    assert offences == []


def test_loading_a_configuration_imports_neither_opencv_nor_jinja2() -> None:
    """The node configuration is read by every layer above it; it must stay light."""
    import subprocess
    import sys

    data = PACKAGE.parent / "data"
    code = (
        "import sys\n"
        "from rosfpga_lab.config import load_config\n"
        f"config = load_config({str(data / 'fpga_dilate_rgba8.yaml')!r})\n"
        "assert config.image.width == 640, config\n"
        "heavy = sorted(m for m in ('cv2', 'jinja2', 'numpy') if m in sys.modules)\n"
        "print(','.join(heavy))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "cv2" not in out.stdout and "jinja2" not in out.stdout, out.stdout


def test_limits_live_in_limits_modules() -> None:
    """One convention: a layer's limits are in its ``limits.py``; ``errors.py`` holds errors and
    neither defines nor re-exports a limit."""
    import re

    for path in sorted(PACKAGE.rglob("errors.py")):
        own = re.findall(r"^([A-Z][A-Z0-9_]*)\s*(?::[^=]*)?=", path.read_text(), flags=re.M)
        assert own == [], f"{path.relative_to(PACKAGE)} defines limits {own}: move them to limits.py"
        assert "limits import" not in path.read_text(), \
            f"{path.relative_to(PACKAGE)} re-exports limits: import them from limits.py"


def test_timeouts_and_maxima_live_in_limits_modules() -> None:
    """A time-out or a maximum set as a number belongs in its layer's ``limits.py``, where the
    next reader looks for it (``graph/realros.py`` keeps its own: it imports only the standard
    library, so tests without the lab's extras can use it; ``msg/strategies.py``'s sizes shape
    test data, they limit nothing)."""
    import re

    rule = re.compile(r"^((?=[A-Z])[A-Z0-9_]*(?:TIMEOUT|MAX)[A-Z0-9_]*)\s*(?::[^=]*)?=\s*[0-9]",
                      flags=re.M)
    allowed = {Path("graph/realros.py"), Path("msg/strategies.py")}
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE)
        if path.name == "limits.py" or rel in allowed:
            continue
        names = rule.findall(path.read_text())
        if names:
            found[str(rel)] = names
    assert found == {}, f"move these to the layer's limits.py: {found}"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph() -> dict[str, set[str]]:
    """Module -> the lab's modules it imports, from every import statement wherever it stands
    (module level, under ``if TYPE_CHECKING:``, inside a function: a lazy import is still a
    dependency). ``from package import name`` points at ``package.name`` when that is a module."""
    modules = {_module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package[:len(package) - node.level + 1]
                                    + ([node.module] if node.module else []))
                targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base
                           for alias in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, targets = work[-1]
            target = next(targets, None)
            if target is not None:
                if target not in index:
                    index[target] = low[target] = len(index)
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(graph[target]))))
                elif target in on_stack:
                    low[node] = min(low[node], index[target])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == node:
                        break
                if len(group) > 1:
                    cycles.append(sorted(group))
    return cycles


def test_the_cycle_finder_finds_a_cycle() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert import_cycles(graph) == [["a", "b", "c"]]


def test_no_import_cycles_among_the_labs_modules() -> None:
    """No module imports, directly or around a circle, a module that imports it; a collaborator
    a module needs only for its types is a ``typing.Protocol`` there (``graph/watchdog.py``'s
    ``WatchedNode``), not an import of the module above it."""
    graph = import_graph()
    assert len(graph) > 100 and sum(map(len, graph.values())) > 500   # the whole package read
    assert import_cycles(graph) == []
