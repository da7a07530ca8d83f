#!/usr/bin/env python3
"""Lay the tests out like the library (issue 29, item 5); run from anywhere in the repository.

    python tools/relayout_tests.py            # apply (git mv + rewrites); a no-op once applied
    python tools/relayout_tests.py --check    # only say what it would do; exit 1 if anything

The layout it makes:

* ``tests/<package>/test_<module>.py`` for a package of ``rosfpga_lab/`` (msg, tcpros, rtps,
  config, graph, hw, hls, rtl, component, widgets, checks, cli): the file drops the package
  prefix it had (``tests/test_msg_cdr.py`` -> ``tests/msg/test_cdr.py``);
* ``tests/flow/`` for what spans the lab: real-ROS interop of the whole component, notebooks,
  the course, the browser, packaging, the README and the other repository-wide checks;
* ``tests/support/`` for the helper modules (``from tests.support.realros import ...``);
  ``tests/conftest.py`` stays;
* ``tests/rtl/bench_<verilog module>.py`` for the cocotb benches; ``tests/benchmarks/``,
  ``tests/golden/``, ``tests/ros_programs/`` stay where they are.

Test files in different folders share names (``msg/test_cli.py``, ``graph/test_cli.py``) and
tests import each other (``from test_hw_walker import definitions``: 36 such imports), so
``tests/`` and each folder holding tests or helpers is a package (an ``__init__.py``): pytest's
default import mode names a module ``tests.msg.test_cli`` and puts only the repository's root on
``sys.path``; one test imports another by that same name (``from tests.hw.test_walker import
definitions``), so it is imported once. ``--import-mode=importlib`` would allow the same names
without packages, but a test could then import another only as a second copy (or not at all
under a plain ``pytest``), and a ``tests/`` on ``sys.path`` with ``tests/config/`` in it would
shadow any ``config`` module; one ``tests`` package shadows nothing else.

What it does, in order (it checks everything before it changes anything):

1. every ``tests/*.py`` and ``tests/rtl/*.py`` must be in MOVES (or be conftest.py, or already
   be a ``bench_*.py``); else it stops and lists them: add their rows and run it again;
2. ``git mv`` old -> new for each row whose old file is there; a row whose new file is there
   already is done; both there, or neither, stops it;
3. in each file it has just moved (only then, so a second run changes nothing): a
   ``Path(__file__)...parent`` chain gets one level more (``parent.parent`` -> ``parents[2]``),
   so it still names the folder it named; a bare name of an old test file (``test_msg_cdr.py``
   in a docstring, a ``SAMPLE`` list) becomes the new name, relative to ``tests/`` when the
   file named sits in another folder (``msg/test_cdr.py``);
4. everywhere, every run (each rewrite leaves nothing it would rewrite again): in
   ``tests/**/*.py`` the imports of the helpers (``from realros import x`` -> ``from
   tests.support.realros import x``, ``import cdrtypes`` -> ``from tests.support import
   cdrtypes``), of other tests (``from test_hw_walker import`` -> ``from tests.hw.test_walker
   import``) and of conftest; in every tracked text file the old paths (``tests/test_readme.py``
   -> ``tests/flow/test_readme.py``) and the benches' module names (``test_module="morph_cocotb"``);
   EDITS, the few literal edits (conftest's ``sys.path`` entry goes, the benchmarks' scripts put
   the root on ``sys.path`` instead of ``tests/``);
5. writes what the layout needs if it is missing: the ``__init__.py`` files, the layout's own
   test ``tests/flow/test_layout_of_tests.py``, and the rule's paragraph in ARCHITECTURE.md.

It lives in ``tools/`` (not ``tests/``): it is a one-off for the repository, not a test helper,
and may be deleted once applied.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"
SELF = Path(__file__).resolve()

#: The helper modules (they become the package tests/support/).
HELPERS = ["cdrtypes", "generictools", "proctools", "realros", "ros2tools", "rtltools", "wiretools"]

#: old path -> new path, both relative to tests/.
MOVES: dict[str, str] = {
    # support: the helpers
    **{f"{name}.py": f"support/{name}.py" for name in HELPERS},
    # rtl: cocotb benches, named after the Verilog module they drive (hdl_toplevel)
    "rtl/cocotb_rfl_node.py": "rtl/bench_rfl_node.py",
    "rtl/fifo2axi_cocotb.py": "rtl/bench_rfl_fifo2axi.py",
    "rtl/morph_cocotb.py": "rtl/bench_rfl_morph.py",
    "rtl/rtps_rx_cocotb.py": "rtl/bench_rfl_rtps_rx.py",
    "rtl/rtps_cdr_cocotb.py": "rtl/bench_rfl_rtps_to_cdr.py",
    # msg
    "test_msg_cdr.py": "msg/test_cdr.py",
    "test_msg_cli.py": "msg/test_cli.py",
    "test_msg_codec.py": "msg/test_codec.py",
    "test_msg_core.py": "msg/test_core.py",
    "test_msg_parse.py": "msg/test_parse.py",
    "test_msg_realros.py": "msg/test_realros.py",
    "test_msg_rosbags.py": "msg/test_rosbags.py",
    "test_bag.py": "msg/test_bag.py",                          # msg/bag.py
    "test_ros2_typehash.py": "msg/test_typehash_realros2.py",  # msg/typehash.py vs Jazzy's
    # tcpros
    "test_tcpros_codec.py": "tcpros/test_codec.py",
    "test_tcpros_handshake.py": "tcpros/test_handshake.py",
    # rtps
    "test_rtps.py": "rtps/test_rtps.py",
    "test_rtps_participant.py": "rtps/test_participant.py",
    "test_rtps_participant_frag.py": "rtps/test_participant_frag.py",
    "test_rtps_typehash.py": "rtps/test_typehash.py",
    "test_ros2_capture.py": "rtps/test_capture.py",            # the participant vs tshark
    "test_ros2_hardening.py": "rtps/test_hardening.py",        # hostile participants
    # config
    "test_config.py": "config/test_config.py",
    "test_config_message.py": "config/test_message.py",
    "test_config_modules.py": "config/test_modules.py",
    "test_config_params.py": "config/test_params.py",
    "test_config_rosargs.py": "config/test_rosargs.py",
    # graph
    "test_graph_busstats.py": "graph/test_busstats.py",
    "test_graph_capture.py": "graph/test_capture.py",
    "test_graph_capture_read.py": "graph/test_capture_read.py",
    "test_graph_cli.py": "graph/test_cli.py",
    "test_graph_hardening.py": "graph/test_hardening.py",
    "test_graph_http.py": "graph/test_http.py",
    "test_graph_ipv6.py": "graph/test_ipv6.py",
    "test_graph_jupyter.py": "graph/test_jupyter.py",
    "test_graph_load.py": "graph/test_load.py",
    "test_graph_master.py": "graph/test_master.py",
    "test_graph_master_parity.py": "graph/test_master_parity.py",
    "test_graph_node.py": "graph/test_node.py",
    "test_graph_owner.py": "graph/test_owner.py",
    "test_graph_realros.py": "graph/test_realros.py",
    "test_graph_restart.py": "graph/test_restart.py",
    "test_graph_services.py": "graph/test_services.py",
    "test_graph_subscriber_links.py": "graph/test_subscriber_links.py",
    "test_topic_tools.py": "graph/test_tools.py",              # graph/tools.py (topic echo/pub)
    "test_topic_realros.py": "graph/test_tools_realros.py",    # the same against rostopic
    "test_ros2_recording.py": "graph/test_ros2_recording.py",  # graph/ros2.py's Ros2Node.record
    # hw
    "test_hw_cdr.py": "hw/test_cdr.py",
    "test_hw_clocked.py": "hw/test_clocked.py",
    "test_hw_framing.py": "hw/test_framing.py",
    "test_hw_interpreter.py": "hw/test_interpreter.py",
    "test_hw_layout.py": "hw/test_layout.py",
    "test_hw_morph.py": "hw/test_morph.py",
    "test_hw_oracles.py": "hw/test_oracles.py",
    "test_hw_pipeline.py": "hw/test_pipeline.py",
    "test_hw_sample.py": "hw/test_sample.py",
    "test_hw_stages.py": "hw/test_stages.py",
    "test_hw_walker.py": "hw/test_walker.py",
    "test_layout_min_body.py": "hw/test_layout_min_body.py",   # hw/layout.py's min_body
    # hls
    "test_hls_csim.py": "hls/test_csim.py",
    "test_hls_generate.py": "hls/test_generate.py",
    "test_hls_headers.py": "hls/test_headers.py",
    "test_hls_realros.py": "hls/test_realros.py",
    "test_hls_vitis_rules.py": "hls/test_vitis_rules.py",
    "test_generic_project.py": "hls/test_generic_project.py",  # hls/generic.py's projects
    "test_generic_project_cdr.py": "hls/test_generic_project_cdr.py",
    "test_generic_project_cdr_image.py": "hls/test_generic_project_cdr_image.py",
    "test_generic_project_types.py": "hls/test_generic_project_types.py",
    # rtl
    "test_rtl_cocotb.py": "rtl/test_cocotb.py",
    "test_rtl_cycles.py": "rtl/test_cycles.py",
    "test_rtl_demo.py": "rtl/test_demo.py",
    "test_rtl_fifo2axi.py": "rtl/test_fifo2axi.py",
    "test_rtl_formal.py": "rtl/test_formal.py",
    "test_rtl_generic_elem.py": "rtl/test_generic_elem.py",
    "test_rtl_harness.py": "rtl/test_harness.py",
    "test_rtl_house_rules.py": "rtl/test_house_rules.py",
    "test_rtl_lint.py": "rtl/test_lint.py",
    "test_rtl_morph.py": "rtl/test_morph.py",
    "test_rtl_sim.py": "rtl/test_sim.py",
    "test_rtl_sloc.py": "rtl/test_sloc.py",
    "test_rtl_synth.py": "rtl/test_synth.py",
    "test_rtl_timing.py": "rtl/test_timing.py",
    "test_rtl_vcd.py": "rtl/test_vcd.py",
    # component
    "test_component_cli.py": "component/test_cli.py",
    "test_component_message.py": "component/test_message.py",
    "test_component_node.py": "component/test_node.py",
    "test_component_realros.py": "component/test_realros.py",
    "test_component_rtl.py": "component/test_rtl.py",
    "test_component_rtl_generic.py": "component/test_rtl_generic.py",
    "test_demo.py": "component/test_demo.py",                  # component/demo.py
    # widgets
    "test_widgets_bytes.py": "widgets/test_bytes.py",
    "test_widgets_export.py": "widgets/test_export.py",
    "test_widgets_images.py": "widgets/test_images.py",
    "test_widgets_live.py": "widgets/test_live.py",
    "test_widgets_sequence.py": "widgets/test_sequence.py",
    "test_widgets_statemachine.py": "widgets/test_statemachine.py",
    "test_widgets_static.py": "widgets/test_static.py",
    "test_widgets_waveform.py": "widgets/test_waveform.py",
    # checks
    "test_checks.py": "checks/test_checks.py",
    "test_checks_circuit.py": "checks/test_circuit.py",
    "test_checks_ownmsg.py": "checks/test_ownmsg.py",
    "test_checks_ros2.py": "checks/test_ros2.py",
    # cli
    "test_ros_node_signals.py": "cli/test_signals.py",         # cli/_signals.py, every command
    # flow: what spans the lab, and the repository's own checks
    "test_architecture_doc.py": "flow/test_architecture_doc.py",
    "test_browser_byteviewer.py": "flow/test_browser_byteviewer.py",
    "test_browser_notebooks.py": "flow/test_browser_notebooks.py",
    "test_browser_waveform.py": "flow/test_browser_waveform.py",
    "test_capture_scripts.py": "flow/test_capture_scripts.py",
    "test_course_hub.py": "flow/test_course_hub.py",
    "test_course_nbgrader.py": "flow/test_course_nbgrader.py",
    "test_data_map.py": "flow/test_data_map.py",
    "test_environment_hermetic.py": "flow/test_environment_hermetic.py",
    "test_interop_realros.py": "flow/test_interop_realros.py",
    "test_lab_student_view.py": "flow/test_lab_student_view.py",
    "test_layers.py": "flow/test_layers.py",
    "test_function_length.py": "flow/test_function_length.py",
    "test_rtps_disc_rom.py": "rtl/test_discrom.py",
    "test_rtl_disc_rom.py": "rtl/test_fabric_disc_rom.py",
    "test_rtl_rtps_rx.py": "rtl/test_fabric_rtps_rx.py",
    "test_rtl_rtps_cdr.py": "rtl/test_fabric_rtps_cdr.py",
    "test_notebook10_own_type.py": "flow/test_notebook10_own_type.py",
    "test_notebook10_shipped.py": "flow/test_notebook10_shipped.py",
    "test_notebooks_build.py": "flow/test_notebooks_build.py",
    "test_notebooks_claims.py": "flow/test_notebooks_claims.py",
    "test_notebooks_exec.py": "flow/test_notebooks_exec.py",
    "test_packaging.py": "flow/test_packaging.py",
    "test_readme.py": "flow/test_readme.py",
    "test_ros2_interop.py": "flow/test_ros2_interop.py",
    "test_ros2_realros2.py": "flow/test_ros2_realros2.py",
    "test_ros_package.py": "flow/test_ros_package.py",
    "test_stream_framing.py": "flow/test_stream_framing.py",   # HLS, Verilog and models agree
    "test_types.py": "flow/test_types.py",
}

#: Files of tests/ that stay where they are.
STAY = {"conftest.py"}

#: Literal edits, each applied where its old text is still there: (file after the move, old, new).
EDITS = [
    ("conftest.py",
     '"""Shared fixtures. Real-ROS helpers live in ``realros.py`` beside this file."""',
     '"""Shared fixtures. The helpers live in the package ``tests/support/`` (real ROS:\n'
     '``tests/support/realros.py``)."""'),
    ("conftest.py", "import sys\n", ""),
    ("conftest.py", "sys.path.insert(0, str(Path(__file__).resolve().parent))\n\n", ""),
    ("benchmarks/bench_ros2.py", "sys.path.insert(0, str(Path(__file__).resolve().parent.parent))",
     "sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the root: tests.support"),
    ("benchmarks/bench_rtps_attacks.py", "sys.path.insert(0, str(HERE.parent.parent))",
     "sys.path.insert(0, str(HERE.parents[2]))   # the root: tests.support"),
    ("benchmarks/bench_transport.py", 'sys.path.insert(0, str(ROOT / "tests"))',
     "sys.path.insert(0, str(ROOT))   # tests.support"),
]

#: Comments that said how a helper was reached (the package says it now).
STALE_COMMENTS = re.compile(r"[ \t]+# tests/ is on sys\.path \(conftest\.py\)$", re.M)

TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".sh", ".cfg", ".ini", ".yaml", ".yml",
                 ".ipynb", ".cpp", ".h", ".hpp", ".v", ".sv", ".j2", ".tcl", ".json", ""}

SUPPORT_INIT = '''"""Helpers the tests share (not tests): ``from tests.support.realros import require_ros``."""

from pathlib import Path

#: The repository's root, ``tests/`` and ``data/``: a test may reach files through these rather
#: than through how deep it sits.
REPO = Path(__file__).resolve().parents[2]
TESTS = REPO / "tests"
DATA = REPO / "data"
'''

LAYOUT_TEST = '''"""The tests are laid out like the library (ARCHITECTURE.md "Where the tests live"): a test
file sits in ``tests/<package>/`` for a package of ``rosfpga_lab/`` or in ``tests/flow/``;
helpers in ``tests/support/``; cocotb benches are ``tests/rtl/bench_<verilog module>.py``."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support import REPO, TESTS

PACKAGES = {p.parent.name for p in (REPO / "rosfpga_lab").glob("*/__init__.py")}
#: The folders of tests/ that are not a package's: what they hold.
OTHER = {"flow": "tests", "support": "helpers", "benchmarks": "benchmarks",
         "golden": "golden files", "ros_programs": "real ROS programs"}


def test_every_test_file_sits_in_a_package_folder_or_flow() -> None:
    misplaced = [str(p.relative_to(TESTS)) for p in TESTS.rglob("test_*.py")
                 if "__pycache__" not in p.parts
                 and (len(p.relative_to(TESTS).parts) != 2
                      or p.parent.name not in PACKAGES | {"flow"})]
    assert misplaced == [], "tests/<package>/test_<module>.py or tests/flow/ (tools/relayout_tests.py)"


def test_tests_holds_only_conftest_and_known_folders() -> None:
    assert sorted(p.name for p in TESTS.glob("*.py")) == ["__init__.py", "conftest.py"]
    folders = {p.name for p in TESTS.iterdir() if p.is_dir() and p.name != "__pycache__"
               and not p.name.startswith(".")}
    assert folders <= PACKAGES | set(OTHER), sorted(folders - PACKAGES - set(OTHER))


def test_tests_and_each_folder_of_tests_or_helpers_is_a_package() -> None:
    """Tests import each other and the helpers as ``tests.<folder>.<module>``."""
    folders = {p.parent for p in TESTS.rglob("test_*.py")} | {TESTS, TESTS / "support"}
    assert sorted(str(f.relative_to(TESTS)) for f in folders
                  if not (f / "__init__.py").exists()) == []


def test_rtl_python_files_are_tests_or_benches_named_after_their_module() -> None:
    verilog = "\\n".join(p.read_text(encoding="utf-8", errors="replace")
                        for base in (REPO / "rosfpga_lab", TESTS)
                        for p in base.rglob("*.v*") if p.suffix in (".v", ".sv", ".j2"))
    for path in (TESTS / "rtl").glob("*.py"):
        assert path.name.startswith(("test_", "bench_", "__init__")), path.name
        if path.name.startswith("bench_"):
            module = path.stem.removeprefix("bench_")
            assert re.search(rf"\\bmodule\\s+{module}\\b", verilog), f"{path.name}: no module {module}"
'''

ARCH_MARK = "## Where the tests live"
ARCH_SECTION = f"""{ARCH_MARK}

A test of `rosfpga_lab/<package>/<module>.py` is `tests/<package>/test_<module>.py` (as
`tests/msg/test_cdr.py`); what spans the lab (real ROS against the whole component, notebooks,
course, browser, packaging, these documents) is in `tests/flow/`; helpers are `tests/support/`;
cocotb benches are `tests/rtl/bench_<verilog module>.py`; `tests/benchmarks/` holds the
measurements. `tests/` and its folders are packages, so names repeat across folders and a test
imports another as `tests.hw.test_walker`. `tests/flow/test_layout_of_tests.py` holds this layout.

"""


def git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True,
                          text=True).stdout


def bare_name(name: str) -> re.Pattern[str]:
    return re.compile(rf"(?<![\w/.\-]){re.escape(name)}(?![\w])")


def old_path(rel: str) -> re.Pattern[str]:
    return re.compile(rf"(?<![\w/.\-])tests/{re.escape(rel)}(?![\w])")


def check_table() -> list[str]:
    """What stops the run: files the table does not place, rows that cannot be applied."""
    problems = []
    olds = set(MOVES)
    news = set(MOVES.values())
    if len(news) != len(MOVES):
        problems.append("two rows move to the same new path")
    for path in sorted([*TESTS.glob("*.py"), *(TESTS / "rtl").glob("*.py")]):
        rel = str(path.relative_to(TESTS))
        if (rel in olds or rel in news or rel in STAY or Path(rel).name == "__init__.py"
                or rel.startswith(("rtl/test_", "rtl/bench_"))):
            continue
        package = re.match(r"test_([a-z0-9]+)_(\w+\.py)$", rel)
        hint = (f'"{rel}": "{package[1]}/test_{package[2]}"' if package
                and (ROOT / "rosfpga_lab" / package[1] / "__init__.py").exists()
                else f'"{rel}": "rtl/bench_<the Verilog module it drives>.py"' if rel.startswith("rtl/")
                else f'"{rel}": "<package or flow>/test_<module>.py"')
        problems.append(f"not in MOVES: tests/{rel} (add a row to MOVES: {hint})")
    for old, new in MOVES.items():
        there_old, there_new = (TESTS / old).exists(), (TESTS / new).exists()
        if there_old and there_new:
            problems.append(f"both there: tests/{old} and tests/{new}")
        elif not there_old and not there_new:
            problems.append(f"neither there: tests/{old} nor tests/{new} (drop or fix the row)")
    return problems


def shift_parents(text: str) -> str:
    """``Path(__file__)[.resolve()].parent...`` names one folder more up (the file sits one deeper)."""
    def one(match: re.Match[str]) -> str:
        head, chain, index = match.group(1), match.group(2), match.group(3)
        depth = int(index) + 1 if index is not None else chain.count(".parent")
        return f"{head}.parents[{depth}]"
    return re.sub(r"(Path\(__file__\)(?:\.resolve\(\)|\.absolute\(\))?)"
                  r"((?:\.parent(?![\w\[]))+|\.parents\[(\d+)\])", one, text)


def rename_mentions(text: str, new_rel: str) -> str:
    """Bare names of old test files, in a file just moved to ``new_rel`` (one pass: a name it
    writes is never read again as an old one)."""
    here = Path(new_rel).parent
    olds = {old: Path(new) for old, new in MOVES.items() if "/" not in old and old.startswith("test_")}
    pattern = re.compile(r"(?<![\w/.\-])(" + "|".join(map(re.escape, olds)) + r")(?![\w])")
    return pattern.sub(lambda m: olds[m[1]].name if olds[m[1]].parent == here
                       else str(olds[m[1]]), text)


def rewrite_imports(text: str) -> str:
    """Helpers, other tests and conftest, imported by their names in the ``tests`` package."""
    names = "|".join(HELPERS)
    text = re.sub(rf"^(\s*)from ({names}) import ", r"\1from tests.support.\2 import ", text,
                  flags=re.M)
    text = re.sub(rf"^(\s*)import ({names})((?: as \w+)?)(?=[ \t]*(?:$|#))",
                  r"\1from tests.support import \2\3", text, flags=re.M)
    text = re.sub(r"^(\s*)from conftest import ", r"\1from tests.conftest import ", text, flags=re.M)
    tests = {Path(old).stem: Path(new).with_suffix("").as_posix().replace("/", ".")
             for old, new in MOVES.items() if "/" not in old and old.startswith("test_")}
    text = re.sub(r"^(\s*)from (test_\w+) import ",
                  lambda m: f"{m[1]}from tests.{tests[m[2]]} import " if m[2] in tests else m[0],
                  text, flags=re.M)
    return STALE_COMMENTS.sub("", text)


BENCHES = {Path(old).stem: Path(new).stem for old, new in MOVES.items() if old.startswith("rtl/")}


#: Mentions of test files that never were (old slips), put right with the rest.
NEVER_WERE = {"test_bag_realros.py": "msg/test_bag.py",              # rosfpga_lab/msg/bag.py
              "test_notebook_claims.py": "flow/test_notebooks_claims.py"}  # data/make_timing_report.py


def rewrite_paths(text: str) -> str:
    paths = {**MOVES, **NEVER_WERE}
    pattern = re.compile(r"(?<![\w/.\-])tests/(" + "|".join(map(re.escape, paths)) + r")(?![\w])")
    return pattern.sub(lambda m: f"tests/{paths[m[1]]}", text)


def rewrite_benches(text: str) -> str:
    for old, new in BENCHES.items():
        text = bare_name(old).sub(new, text)
    return text


def tracked_text_files() -> list[Path]:
    """Every tracked text file but the golden files (compared byte for byte) and data/'s
    captures and results (its scripts and README are in)."""
    files = []
    for rel in git("ls-files", "-z").split("\0"):
        path = ROOT / rel
        if not rel or rel.startswith("tests/golden/") or path.suffix not in TEXT_SUFFIXES:
            continue
        if rel.startswith("data/") and path.suffix not in (".py", ".md"):
            continue
        if path.is_file() and path.resolve() != SELF:
            files.append(path)
    return files


def write(path: Path, text: str, changed: list[str], dry: bool) -> None:
    if path.read_text(encoding="utf-8") != text:
        changed.append(str(path.relative_to(ROOT)))
        if not dry:
            path.write_text(text, encoding="utf-8")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if a run would")
    dry = parser.parse_args().check

    problems = check_table()
    if problems:
        print("relayout_tests: nothing changed:", *problems, sep="\n  ", file=sys.stderr)
        return 2

    changed: list[str] = []
    moved = [(old, new) for old, new in MOVES.items() if (TESTS / old).exists()]
    for old, new in moved:
        changed.append(f"git mv tests/{old} tests/{new}")
        if dry:
            continue
        (TESTS / new).parent.mkdir(parents=True, exist_ok=True)
        git("mv", f"tests/{old}", f"tests/{new}")
        path = TESTS / new
        text = path.read_text(encoding="utf-8")
        path.write_text(rename_mentions(shift_parents(text), new), encoding="utf-8")

    for file, old, new in EDITS:
        path = TESTS / file
        text = path.read_text(encoding="utf-8")
        if old in text:
            write(path, text.replace(old, new), changed, dry)

    for path in tracked_text_files():
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, FileNotFoundError):
            continue
        new = rewrite_benches(rewrite_paths(text))
        if path.suffix == ".py" and path.is_relative_to(TESTS):
            new = rewrite_imports(new)
        write(path, new, changed, dry)

    inits = {str(Path(new).parent / "__init__.py") for new in MOVES.values()} | {"__init__.py"}
    for rel, content in (("support/__init__.py", SUPPORT_INIT),
                         *((init, "") for init in sorted(inits - {"support/__init__.py"})),
                         ("flow/test_layout_of_tests.py", LAYOUT_TEST)):
        path = TESTS / rel
        if not path.exists():
            changed.append(f"create tests/{rel}")
            if not dry:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(content, encoding="utf-8")
                git("add", f"tests/{rel}")

    arch = ROOT / "ARCHITECTURE.md"
    text = arch.read_text(encoding="utf-8")
    if ARCH_MARK not in text:
        anchor = "## How to add"
        assert anchor in text, f"ARCHITECTURE.md: no {anchor!r} section to put the layout before"
        write(arch, text.replace(anchor, ARCH_SECTION + anchor, 1), changed, dry)

    print(*changed, sep="\n") if changed else print("relayout_tests: already laid out, nothing to do")
    return 1 if dry and changed else 0


if __name__ == "__main__":
    sys.exit(main())
