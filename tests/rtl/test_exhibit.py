"""The exhibit (``rosfpga_lab/rtl/exhibit/``): the hand-written Image circuit, Table 1's
conventional design, held equal to the generated Image circuit, and held apart from the library.

(a) The same Image frames (good ones in rgba8, rgb8 and mono8, and refused ones: a column too
narrow, and for mono8 every refusal reason of its status table) run through the exhibit's
``rfl_top`` and through the generated top ``rfl_gtop`` of the same configuration, with the same
random input gaps and output backpressure, and give the same output bytes and accept the same
frames (each also equal to the Python models' output, so two empty outputs cannot agree).
(b) No module of the library outside the exhibit imports its parameters or names its files;
``rtl/sloc.py`` alone reads them (Table 1's count). (c) Its status include is generated from its
status table and its formal checks hold (run here, not by ``rtl prove``).
"""

from __future__ import annotations

import ast
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from rosfpga_lab.hw import image_frame
from rosfpga_lab.rtl import build, run
from rosfpga_lab.rtl.exhibit.params import (
    EXHIBIT_DIR, EXHIBIT_PROOFS, STATUS_HEADER, SUBSCRIBER_STATUSES, rtl_params, status_header,
)
from rosfpga_lab.rtl.proofs import format_results, prove
from rosfpga_lab.rtl.sim import OwnSources, design_from_config
from tests.rtl.test_sim import model_output, random_image, refusal_frames, small_config
from tests.support.realros import require_rtl
from tests.support.rtltools import require_formal

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "rosfpga_lab"
#: The one library module allowed to read the exhibit's files (Table 1's line count).
SLOC = PACKAGE / "rtl" / "sloc.py"
#: The exhibit's Verilog modules (file stems), found in its folder, not listed here.
EXHIBIT_MODULES = sorted(p.stem for p in EXHIBIT_DIR.glob("rfl_*.v"))


def _accepted(status: tuple[tuple[int, str], ...]) -> list[tuple[int, bool]]:
    """Offset and accepted-or-not per frame (the two tables name their refusals differently)."""
    return [(offset, name == "SUB_OK") for offset, name in status]


def _frames(encoding: str) -> tuple[object, list[bytes]]:
    """A 16x8 configuration and its frames: for mono8 every refusal reason, each followed by a
    good frame; else two good frames around one a column too narrow."""
    if encoding == "mono8":
        config = small_config(encoding, width=16, height=8, frame_id_max=16)
        frames, _ = refusal_frames(config)
        return config, frames
    config = small_config(encoding, width=16, height=8)
    a, b = random_image(config, 31), random_image(config, 32)
    return config, [image_frame(a, encoding, frame_id="a"),
                    image_frame(b[:, :-1], encoding, frame_id="narrow"),
                    image_frame(b, encoding, seq=7, frame_id="bb")]


@pytest.mark.rtl
@pytest.mark.parametrize("encoding", ["rgba8", "rgb8", "mono8"])
def test_the_exhibit_equals_the_generated_image_circuit(encoding: str, tmp_path: Path) -> None:
    sim_name = require_rtl("iverilog")   # small sources: Icarus builds in about a second
    config, frames = _frames(encoding)
    data = b"".join(frames)
    exhibit = rtl_params(config)
    assert isinstance(exhibit, OwnSources)
    hand = run(build(exhibit, tmp_path / "hand", simulator=sim_name), data,
               seed=13, gap=250, bp=400)
    generated = run(build(design_from_config(config), tmp_path / "gen", simulator=sim_name), data,
                    seed=13, gap=250, bp=400)
    expected, verdicts = model_output(config, frames)
    assert "refused" in verdicts and verdicts.count("SUB_OK") >= 2
    assert hand.output == generated.output == expected
    assert _accepted(hand.status) == _accepted(generated.status)
    assert [ok for _, ok in _accepted(hand.status)] == [v == "SUB_OK" for v in verdicts]
    assert not hand.cut_short and not generated.cut_short


def test_the_exhibits_status_include_is_generated_from_its_status_table() -> None:
    assert (EXHIBIT_DIR / STATUS_HEADER).read_text() == status_header()
    assert status_header().count("localparam") == len(SUBSCRIBER_STATUSES)


def _code_strings(tree: ast.AST) -> list[str]:
    """String constants of a module that are not docstrings."""
    docs = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docs.add(id(body[0].value))
    return [n.value for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs]


def _imports(tree: ast.AST) -> list[str]:
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names.append("." * node.level + (node.module or ""))
            names += [f"{node.module or ''}.{a.name}" for a in node.names]
    return names


def _outside_exhibit(pattern: str) -> list[Path]:
    return sorted(p for p in PACKAGE.rglob(pattern)
                  if EXHIBIT_DIR not in p.parents and "__pycache__" not in p.parts)


def test_nothing_in_the_library_depends_on_the_exhibit() -> None:
    """No import of the exhibit's modules, no string of the code (docstrings aside) naming its
    folder or a module of it, and no Verilog, template or C++ outside it instantiating or
    including one; rtl/sloc.py, which counts its lines, alone names its folder and files (and
    imports nothing of it)."""
    assert {"rfl_subscriber", "rfl_publisher", "rfl_top"} <= set(EXHIBIT_MODULES)
    names = re.compile(r"\b(" + "|".join([*EXHIBIT_MODULES, "rfl_status"]) + r")\b")
    offenders = []
    for path in _outside_exhibit("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        rel = path.relative_to(ROOT)
        offenders += [f"{rel}: imports {m}" for m in _imports(tree)
                      if "exhibit" in m or m.endswith((".params.RtlParams", ".rtl_params"))]
        for text in _code_strings(tree):
            if path != SLOC and (names.search(text) or "exhibit" in text):
                offenders.append(f"{rel}: names {text!r}")
    for pattern in ("*.v", "*.sv", "*.vh", "*.j2", "*.cpp", "*.h", "*.tcl"):
        for path in _outside_exhibit(pattern):
            code = re.sub(r"//[^\n]*|/\*.*?\*/", "", path.read_text(encoding="utf-8"), flags=re.S)
            offenders += [f"{path.relative_to(ROOT)}: {m.group(0)}" for m in names.finditer(code)]
    assert offenders == []


def test_the_sloc_count_is_the_only_reader_of_the_exhibit() -> None:
    """Table 1's default count is the exhibit's files (the conventional design column)."""
    from rosfpga_lab.rtl.sloc import COUNTED, EXHIBIT_DIR as COUNTED_DIR, count_verilog

    assert COUNTED_DIR == EXHIBIT_DIR
    assert all((EXHIBIT_DIR / name).is_file() for files in COUNTED.values() for name in files)
    assert count_verilog().subscriber > 0 and count_verilog().publisher > 0


@pytest.mark.rtl
def test_the_exhibits_proofs_hold() -> None:
    """Its seven checks (as ``rtl prove`` ran them before the move), two at a time."""
    require_formal()
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(prove, EXHIBIT_PROOFS))
    table = format_results(results)
    assert [r.status for r in results] == ["PASS"] * len(EXHIBIT_PROOFS), table
    assert {p.name for p in EXHIBIT_PROOFS} == {m.removeprefix("rfl_") for m in EXHIBIT_MODULES}
