"""What the notebooks' texts claim, held against the code and the README (no kernel needed).

The claims that need a run (Table 1's ratio, the wire time, the fault gallery) are checked on
the executed notebooks in ``test_notebooks_exec.py``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rosfpga_lab.checks import nbbuild

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = ROOT / "notebooks" / "solutions"
NOTEBOOKS = sorted(SOLUTIONS.glob(nbbuild.NOTEBOOK_GLOB))


def cells(name: str) -> list[dict]:
    return json.loads((SOLUTIONS / name).read_text(encoding="utf-8"))["cells"]


def markdown(name: str) -> str:
    return "\n".join("".join(c["source"]) for c in cells(name) if c["cell_type"] == "markdown")


def test_table_1_ratio_is_computed_not_written() -> None:
    text = markdown("06_design_flow.ipynb")
    assert "order of magnitude" not in text            # 860 / 163 is 5.3x, the paper's own 6.8x
    assert not re.search(r"\d(\.\d)?\s*x\b|\d+ times", text), "a ratio written into the text"
    code = "\n".join("".join(c["source"]) for c in cells("06_design_flow.ipynb") if c["cell_type"] == "code")
    assert "hls.PAPER_TABLE1" in code
    # like for like (06 printed the paper's Verilog over the lab's C++, 08 the lab's over the lab's)
    assert "paper_verilog / table.total" not in code
    assert "verilog.total / table.total" in code and "paper_verilog / paper_hls" in code
    rtl_code = "\n".join("".join(c["source"]) for c in cells("08_rtl.ipynb") if c["cell_type"] == "code")
    assert "conventional.total / cpp.total" in rtl_code   # the hand-written exhibit over the generated C++
    assert "paper_verilog / paper_cpp" in rtl_code


def test_workshop_notebook_names_the_packages_the_readme_installs() -> None:
    text = markdown("07_workshop_demo.ipynb")
    assert "ros-*" not in text
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    apt = re.search(r"sudo apt-get install (python3-rospy[^`]*?)```", readme, re.S)[1]
    named = set(re.findall(r"`(python3-[a-z-]+|lib[a-z-]+)`", text))
    assert named and named <= set(apt.replace("\\", " ").split()), named


def test_network_time_says_what_it_counts() -> None:
    text = markdown("05_application.ipynb")
    assert "9.8 ms" in text and "10.4 ms on the wire" in text and "hw.wire_bytes" in text


def test_difference_views_are_named_for_what_they_compare() -> None:
    text = markdown("00_overview.ipynb")
    assert "*output vs reference*" in text and "*input vs output*" in text
    from rosfpga_lab.component import demo
    assert "output - input" in Path(demo.__file__).read_text()   # demo.png's third panel


def test_course_map_and_readme_list_notebooks_08_and_09() -> None:
    course = markdown("00_overview.ipynb")
    assert "| 8 The circuit in RTL |" in course and "| 9 ROS 2 on the wire |" in course
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "| `08_rtl` |" in readme and "| `09_ros2_wire` |" in readme


@pytest.mark.parametrize("name", ["00_overview.ipynb", "04_fifo_to_axi_stream.ipynb",
                                  "05_application.ipynb", "06_design_flow.ipynb"])
def test_notebooks_that_speak_of_cycles_point_to_notebook_08(name: str) -> None:
    text = markdown(name)
    assert "Notebook 08" in text or "notebook 08" in text
    assert "cycle" in text or "clock" in text


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_clicking_is_only_mentioned_where_something_is_clickable(path: Path) -> None:
    """A page exported without a kernel drops ``rfl-live-only`` spans; nothing else asks to click."""
    from rosfpga_lab.widgets.export import drop_live_only

    text = drop_live_only(markdown(path.name))
    assert not re.search(r"\b(click|hover)", text, re.I), re.search(r".{0,60}\b(click|hover).{0,60}", text, re.I)[0]


def _numbers(phrase: str) -> set[int]:
    """``"1 to 6, 8 and 9"`` -> {1, ..., 6, 8, 9}."""
    out: set[int] = set()
    for part in re.split(r",\s*|\s+and\s+", phrase.strip()):
        lo, _, hi = part.partition(" to ")
        out |= set(range(int(lo), int(hi or lo) + 1))
    return out


def test_one_place_says_which_notebooks_have_exercises() -> None:
    """It was told three ways (00: "1 to 6", README: "1 to 6, 8 and 9", notebooks/README:
    "1 to 6"). notebooks/README.md says it, from the notebooks' own exercise cells; the others
    point there."""
    with_exercises = {int(p.name[:2]) for p in NOTEBOOKS
                      if any(nbbuild.is_exercise_cell(c) for c in nbbuild.load(p)["cells"])}
    owner = (ROOT / "notebooks" / "README.md").read_text(encoding="utf-8")
    said = re.findall(r"Notebooks ([\d ,toand]+?) end with exercises", owner)
    assert len(said) == 1 and _numbers(said[0]) == with_exercises, (said, with_exercises)
    for text in ((ROOT / "README.md").read_text(encoding="utf-8"), markdown("00_overview.ipynb")):
        assert not re.search(r"Notebooks [\d ,toand]+ end with exercises", text)
        assert "end with them" in text


def test_stats_report_says_which_time_is_which() -> None:
    """00 printed "circuit model alone: median 1.1 ms" (the Python model's wall time) and
    "modelled circuit time 12.31 ms" (the circuit at 100 MHz) beside an end-to-end latency of
    2.7 ms, with nothing saying which time is which."""
    from rosfpga_lab.component.stats import ComponentStats, LatencySummary

    stats = ComponentStats(latency=LatencySummary(3, 2.7e-3, 2.7e-3, 2.9e-3),
                           process_time=LatencySummary(3, 1.1e-3, 1.1e-3, 1.2e-3),
                           circuit_time_s=12.31e-3, cycles={"interpreter": 1_228_846})
    report = stats.report()
    assert "wall time" in report and "Python circuit model's own run" in report
    assert "real circuit would need 12.31 ms per frame" in report and "not measured" in report
    prose = " ".join(markdown("00_overview.ipynb").split())
    assert "wall time" in prose and "not measured" in prose


def test_stats_report_shows_a_short_circuit_time_in_microseconds() -> None:
    """10 printed "the real circuit would need 0.00 ms per frame" for a 2.55 us frame."""
    from rosfpga_lab.component.stats import ComponentStats, LatencySummary

    stats = ComponentStats(latency=LatencySummary(3, 2.7e-3, 2.7e-3, 2.9e-3),
                           process_time=LatencySummary(3, 1.1e-3, 1.1e-3, 1.2e-3),
                           circuit_time_s=255 / 100e6, cycles={"subscriber": 100})
    report = stats.report()
    assert "real circuit would need 2.55 \u00b5s per frame" in report
    assert "0.00 ms" not in report
    short = ComponentStats(circuit_time_s=4e-8, cycles={"subscriber": 4}).report()
    assert "real circuit would need 40 ns per frame" in short


def test_workshop_notebook_says_when_the_stop_button_is_there_and_explains_resets() -> None:
    """07 promised a Stop button that Run All never shows (the last cell closes the view), and
    left real rospy's 'Connection reset by peer' line unexplained."""
    text = " ".join(markdown("07_workshop_demo.ipynb").split())
    assert "after *Run All* the cameras have already stopped" in text
    assert "*Connection reset by peer*" in text and "not a damaged frame" in text
    code = "\n".join("".join(c["source"]) for c in cells("07_workshop_demo.ipynb") if c["cell_type"] == "code")
    assert "live.close()" in code        # what the prose says the last cell does


def test_the_shipped_timing_report_meets_the_clock_and_notebook_08_says_how_to_make_one() -> None:
    """Issue 21 item 4: the place-and-route report shipped in data/ (made by
    data/make_timing_report.py) is what `rosfpga-lab rtl timing` prints and meets its clock.
    Notebook 08 (issue 28: it steps through the generated circuit only) shows it: it is the
    generated top's (its critical path runs through rfl_gsubscriber's registers, which the
    exhibit's subscriber does not have), and the notebook says how to place and route the
    generated project and what a critical path is."""
    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl.timing import (
        SHIPPED_CONFIG, SHIPPED_REPORT, format_timing, report_from_dict, shipped_report,
    )

    data = json.loads((ROOT / "data" / SHIPPED_REPORT).read_text(encoding="utf-8"))
    report = report_from_dict(data)
    config = load_config(ROOT / "data" / SHIPPED_CONFIG)
    # the clock is met, at the configuration's clock, and the stored verdict agrees
    assert report.clock_mhz == config.clock_mhz == 100
    assert report.fmax_mhz >= report.clock_mhz and report.met and data["met"] is True
    assert report.utilization["TRELLIS_COMB"][0] > 0 and report.path
    # the text beside it is what `rosfpga-lab rtl timing` prints for it
    text = (ROOT / "data" / SHIPPED_REPORT).with_suffix(".txt").read_text(encoding="utf-8")
    assert text.rstrip("\n") == format_timing(report, title=f"Timing of data/{SHIPPED_CONFIG}")
    assert ": met (" in text
    assert shipped_report() == report
    assert (ROOT / "data" / "make_timing_report.py").is_file()
    # what the notebook says
    text08 = markdown("08_rtl.ipynb")
    code08 = "\n".join("".join(c["source"]) for c in cells("08_rtl.ipynb")
                       if c["cell_type"] == "code")
    assert "rosfpga-lab rtl timing CONFIG" in text08 and "place_and_route_dir" in code08
    assert "shipped_report()" in code08 and "format_timing(shipped" in code08
    # the report is of the generated top: each instance its critical path crosses is one
    # rfl_gtop.v declares (u_top is the generated wrapper's instance of it), and one of them is
    # not the exhibit's rfl_top.v
    gtop = (ROOT / "rosfpga_lab" / "rtl" / "generic" / "rfl_gtop.v").read_text()
    exhibit = (ROOT / "rosfpga_lab" / "rtl" / "exhibit" / "rfl_top.v").read_text()
    blocks = {n for path in re.findall(r"u_top\.([\w.]+)", text)
              for n in path.split(".")[:-1] if n.startswith(("u_", "g_"))}
    assert blocks and all(re.search(rf"\b{n}\b", gtop) for n in blocks), blocks
    # a block the exhibit lacks, or a walker's register the exhibit's module of that name lacks
    gen = ROOT / "rosfpga_lab" / "rtl" / "generic"
    hand = ROOT / "rosfpga_lab" / "rtl" / "exhibit"
    modules = {"u_subscriber": ("rfl_gsubscriber.v", "rfl_subscriber.v"),
               "u_publisher": ("rfl_gpublisher.v", "rfl_publisher.v")}
    own = [(n, r) for n, r in re.findall(r"u_top\.(u_subscriber|u_publisher)\.(\w+)", text)
           if re.search(rf"\b{r}\b", (gen / modules[n][0]).read_text())
           and not re.search(rf"\b{r}\b", (hand / modules[n][1]).read_text())]
    assert own or any(not re.search(rf"\b{n}\b", exhibit) for n in blocks), blocks
    # and the notebook says where this path lies (the circuits rfl_gtop names so)
    words = {"u_subscriber": "walker", "u_publisher": "walker", "u_app": "dilate",
             "u_axis_in_fifo": "FIFO before the dilate"}
    assert any(n in words for n in blocks), blocks
    assert all(words[n] in " ".join(text08.split()) for n in blocks if n in words), blocks
    assert "Most of\nits delay is routing" in text08
    assert "valid/ready handshake" in text08


def test_the_fabric_notebook_says_what_ran_and_how_big_its_dump_is() -> None:
    """Notebook 12's opening: simulated, no board, the dump's script and test named, its size
    and the datagrams as the shipped files have them."""
    from rosfpga_lab.rtl.fabricdemo import DUMP_NAME, demo_datagrams

    text = markdown("12_fabric_sample.ipynb")
    assert "No board" in text and "Verilator simulated" in text
    assert f"data/{DUMP_NAME}" in text and "data/make_fabric_dump.py" in text
    assert "tests/rtl/test_fabric_demo.py" in text
    said = re.search(r"about (\d+) KB", text)
    size = (ROOT / "data" / DUMP_NAME).stat().st_size / 1000
    assert said and abs(int(said[1]) - size) <= 0.1 * size, (said, size)
    assert len(demo_datagrams()) == 2 and "**two DATA_FRAG datagrams**" in text
