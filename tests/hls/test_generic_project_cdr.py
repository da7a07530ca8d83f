"""Generated projects that read and write CDR (``wire: cdr``, ROS 2's samples): C simulation
(g++) and RTL simulation (Icarus Verilog, random input gaps and output backpressure) equal the
lab's CDR models (``hw.cdrwalker`` + ``hw.morph1d``) byte for byte, on samples that real Cyclone
DDS serialized (PyPI ``cyclonedds``, the IDL types of tests/support/cdrtypes.py).

Expected output comes from the models and, for the accepted samples, is held against an
independent oracle too: Cyclone DDS's own serialization of the value with the stream replaced by
a numpy sliding max/min (tests/support/generictools.py). Refused samples (a bad encapsulation header, a
string without its NUL, a failed check, a wrong stream length, a string of length 0, a string
over its maximum) each come before a good one, which must come out right. One generated project
per example for the whole module (the Makefile's builds are reused).
"""

from __future__ import annotations

import re
import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.generictools import assert_rtl_lint_clean, window_oracle
from tests.support.realros import require_cxx
from tests.support.rtltools import require_iverilog
from tests.support.wiretools import require_cyclonedds
from rosfpga_lab.config import load_config
from rosfpga_lab.hls.vectors import model_output_cdr
from rosfpga_lab.hls.compiler import program_from_cdr
from rosfpga_lab.hls.program import run_program
from rosfpga_lab.hw.cdrlayout import CdrLayout, cdr_layout_from_config, derive_cdr_layout
from rosfpga_lab.hw.cdrwalker import extract_cdr_fast
from rosfpga_lab.hw.errors import FrameFieldError, FrameLengthError
from rosfpga_lab.hw.layout import Action, StepKind
from rosfpga_lab.msg.cdr import serialize_cdr
from rosfpga_lab.msg.ros2 import ros2_registry
from rosfpga_lab.msg.strategies import message
from rosfpga_lab.rtl.generic import simulate_project
from tests.hw.test_walker import definitions  # the models' strategy over message definitions

DATA = Path(__file__).resolve().parents[2] / "data"
SAMPLES = "fpga_samples_dilate_cdr.yaml"
SCAN = "fpga_laserscan_min_cdr.yaml"


def make(project: Path, *args: str) -> str:
    proc = subprocess.run(["make", "-s", *args], cwd=project, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


@pytest.fixture(scope="module")
def projects(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Both shipped CDR examples through ``rosfpga-lab generate`` (as a student types it)."""
    out = {}
    for name in (SAMPLES, SCAN):
        where = tmp_path_factory.mktemp("cdr") / "project"
        proc = subprocess.run([sys.executable, "-m", "rosfpga_lab", "generate", str(DATA / name),
                               "-o", str(where), "-q"], capture_output=True, text=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stderr
        out[name] = where
    return out


def cdr_of(name: str) -> CdrLayout:
    return cdr_layout_from_config(load_config(DATA / name))


def record(payload: bytes) -> bytes:
    """The circuit's input record: the sample length the RTPS reader writes, then the payload."""
    return struct.pack("<I", len(payload)) + payload


def pad_tail(payload: bytes, pad: int) -> bytes:
    """The payload padded as Cyclone's core pads it on the wire (options' low bits = pad)."""
    return payload[:2] + struct.pack(">H", pad) + payload[4:] + bytes(pad)


def pad_to_4(payload: bytes, options: int = 0, fill: bytes | None = None) -> bytes:
    """The payload as Cyclone DDS's core sends it: padded to a multiple of 4 (counted from the
    encapsulation header) with ``fill`` (default zeros), the options saying ``options``."""
    n = -len(payload) % 4
    fill = bytes(n) if fill is None else fill
    assert len(fill) == n
    return payload[:2] + struct.pack(">H", options) + payload[4:] + fill


def statuses_of(cdr: CdrLayout, records: list[bytes]) -> list[str]:
    """The status name the circuit must report per record: the field the models refused it at."""
    by_label = {label: name for name, label in cdr.layout.statuses}
    names = []
    for rec in records:
        try:
            extract_cdr_fast(cdr, rec)
        except FrameFieldError as exc:
            label = "sample length" if exc.field == "frame length" else \
                re.sub(r"\[\d+\]", "[]", exc.field)
            # a sample that ends inside a field the circuit checks nothing of: its length's status
            names.append(by_label.get(label, "SUB_BAD_FRAME_LENGTH")
                         if isinstance(exc, FrameLengthError) else by_label[label])
            continue
        names.append("SUB_OK")
    return names


def both_simulations(project: Path, records: list[bytes]) -> tuple[tuple[bytes, list[str]], ...]:
    frames = b"".join(records)
    return (simulate_project(project, frames, target="csim", out="c_out"),
            simulate_project(project, frames, target="rtlsim", simulator="iverilog", gap=250,
                             bp=350, seed=3, out="r_out"))


def check_against_models(name: str, project: Path, records: list[bytes], oracle: bytes) -> None:
    cdr = cdr_of(name)
    app = load_config(DATA / name).application
    expected, why = model_output_cdr(cdr, app.op, app.ksize, records)
    assert expected == oracle  # the models agree with Cyclone DDS's own bytes
    want = statuses_of(cdr, records)
    assert [w == "" for w in why] == [s == "SUB_OK" for s in want]
    csim, rtl = both_simulations(project, records)
    assert csim == (expected, want)
    assert rtl == (expected, want)
    # and the program's Python executor, the walkers' specification
    dtype = np.dtype(cdr.layout.stream.dtype)
    out, codes = run_program(program_from_cdr(cdr), records,
                             lambda b: window_oracle(b, dtype.str, app.ksize, app.op))
    names = [n for n, _label in cdr.layout.statuses]
    assert (out, [names[c] for c in codes]) == (expected, want)


def cyclone() -> Any:
    require_cyclonedds()
    from tests.support import cdrtypes

    return cdrtypes


@pytest.mark.parametrize("name", [SAMPLES, SCAN])
def test_shipped_cdr_example_generates_and_simulates_exactly(name: str,
                                                             projects: dict[str, Path]) -> None:
    """``make csim`` and ``make rtlsim`` pass on the records the project ships (a good sample, a
    big-endian one refused by its header, a good one with end padding); ``sloc`` counts it."""
    out = projects[name]
    expected = check_shipped_records(out)
    assert expected[4:8] == b"\x00\x01\x00\x00"
    assert "rfl_window1d.v" in sloc_table(out)


def check_shipped_records(out: Path) -> bytes:
    """``make csim`` and ``make rtlsim`` (gaps, backpressure) of a generated CDR project pass on
    the records it ships (good, big-endian refused, good with end padding); the expected output."""
    require_cxx()
    require_iverilog()
    assert "PASS: output equals tb_expected.bin" in make(out, "csim")
    assert (out / "csim_out/status.txt").read_text().split()[1::2] == \
        ["SUB_OK", "SUB_BAD_ENCAPSULATION", "SUB_OK"]
    assert "PASS: output equals tb_expected.bin" in make(out, "rtlsim", "SIM=iverilog", "GAP=300",
                                                         "BP=400")
    expected = (out / "tb_expected.bin").read_bytes()
    assert len(expected) > 0 and expected == (out / "rtlsim_out/output.bin").read_bytes()
    return expected


def sloc_table(out: Path) -> str:
    """What ``rosfpga-lab sloc`` prints for a generated project (it must succeed)."""
    table = subprocess.run([sys.executable, "-m", "rosfpga_lab", "sloc", str(out)],
                           capture_output=True, text=True, timeout=60)
    assert table.returncode == 0, table.stderr
    return table.stdout


def test_cyclone_dds_samples_through_the_generated_circuit(projects: dict[str, Path]) -> None:
    """lab_msgs/Samples as Cyclone DDS serialized them: strings whose lengths move the alignment
    of everything after them, 0..4 history elements, end padding; each refusal then a good one."""
    require_cxx()
    require_iverilog()
    T = cyclone()
    rng = np.random.default_rng(20)

    def sample(values: np.ndarray, label: str = "hi", names: tuple[str, ...] = ("imu",),
               frame_id: str = "array", mode: int = 2, history: int = 2) -> bytes:
        calib = T.Calibration_(names[0], [0.25, -1.5, 3.0], mode)
        hist = [T.Calibration_(names[k % len(names)] * k, [1.0, 2.0, float(k)], k)
                for k in range(history)]
        return T.Samples_(T.Header_(T.Time_(-7, 999_999_999), frame_id), calib, label,
                          [-1, 2, -3, 32767], [int(v) for v in values], T.Duration_(3, 1000),
                          hist, bool(history % 2)).serialize()

    goods, oracle = [], b""
    shapes = [dict(), dict(label="", names=("",), frame_id=""), dict(label="x", frame_id="ab",
              history=4, names=("seven!!", "q")), dict(label="y" * 32, history=0),
              dict(frame_id="f" * 13, history=3, names=("", "zz")), dict(history=1)]
    for kw in shapes:
        x = rng.integers(-2**31, 2**31, 64, dtype=np.int32)
        goods.append(record(sample(x, **kw)))
        dilated = np.frombuffer(window_oracle(x.tobytes(), "<i4", 3, "dilate"), "<i4")
        oracle += record(sample(dilated, **kw))
    base = goods[0][4:]
    frame_id_nul = 4 + 8 + 4 + len("array")      # header, stamp, length, "array": its NUL
    x = rng.integers(-2**31, 2**31, 64, dtype=np.int32)
    bad = [
        record(b"\x00\x00" + base[2:]),                                     # CDR big-endian
        record(base[:frame_id_nul] + b"!" + base[frame_id_nul + 1:]),       # no NUL
        record(sample(x, mode=3)),                                          # calibration.mode
        record(sample(x[:63])),                                             # stream length
        record(base[:12] + struct.pack("<I", 0) + base[16:]),               # frame_id length 0
        record(sample(x, label="z" * 33)),                                  # label over 32
    ]
    records = []
    for k, b in enumerate(bad):
        records += [goods[k], b]
    # the last good one as the wire carries it: padded to a multiple of 4, options saying so
    tail = (-len(goods[5][4:])) % 4 or 4
    records.append(record(pad_tail(goods[5][4:], tail)))
    oracle += oracle[-len(goods[5]):]  # the same sample comes out, unpadded
    want_refused = ["SUB_BAD_ENCAPSULATION", "SUB_BAD_HEADER_FRAME_ID_NUL",
                    "SUB_BAD_CALIBRATION_MODE", "SUB_BAD_SAMPLES_LENGTH",
                    "SUB_BAD_HEADER_FRAME_ID_LENGTH", "SUB_BAD_LABEL_LENGTH"]
    assert statuses_of(cdr_of(SAMPLES), records)[1::2][:6] == want_refused
    check_against_models(SAMPLES, projects[SAMPLES], records, oracle)


def test_cyclone_dds_laser_scans_through_the_generated_circuit(projects: dict[str, Path]) -> None:
    """sensor_msgs/LaserScan as Cyclone DDS serialized it: a float32 minimum over 5 beams with
    NaN, infinities and signed zeros; intensities 0..360; a range_max over its bound refused."""
    require_cxx()
    require_iverilog()
    T = cyclone()
    rng = np.random.default_rng(21)
    specials = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1.0, 2.5], np.float32)

    def scan(ranges: np.ndarray, intensities: int, frame_id: str, range_max: float = 30.0) -> bytes:
        header = T.Header_(T.Time_(12, 34), frame_id)
        return T.LaserScan_(header, -1.5, 1.5, 0.01, 0.0, 0.1, 0.05, range_max,
                            [float(r) for r in ranges],
                            [float(k) for k in range(intensities)]).serialize()

    records, oracle = [], b""
    for k, (n_int, fid) in enumerate([(0, "laser"), (360, ""), (7, "l" * 64)]):
        ranges = (rng.choice(specials, 360) if k != 1
                  else rng.standard_normal(360).astype(np.float32))
        records.append(record(scan(ranges, n_int, fid)))
        eroded = np.frombuffer(window_oracle(ranges.tobytes(), "<f4", 5, "erode"), "<f4")
        oracle += record(scan(eroded, n_int, fid))
        bad = [scan(ranges, 1, "laser", range_max=1000.5), scan(ranges[:359], 0, "x"),
               b"\x00\x01\x00\x00" + scan(ranges, 0, "x")[4:-1]][k]  # the last: cut short
        records.append(record(bad))
    assert statuses_of(cdr_of(SCAN), records)[1::2][:2] == ["SUB_BAD_RANGE_MAX",
                                                            "SUB_BAD_RANGES_LENGTH"]
    records.append(records[0])
    oracle += oracle[:len(records[0])]
    check_against_models(SCAN, projects[SCAN], records, oracle)


def test_unannounced_end_padding_through_the_generated_circuit(projects: dict[str, Path]) -> None:
    """Issue 20: Cyclone DDS pads lab_msgs/Samples to a multiple of 4 with options 00 00 (or
    options announcing fewer): 2 and 3 bytes are taken, zero or not (padding's value is never
    looked at: CDR leaves it undefined), bytes beyond the multiple or short of it are refused
    with SUB_BAD_FRAME_LENGTH; each refusal then a good sample, which comes out right. C
    simulation, RTL simulation (gaps, backpressure) and the executor equal the models."""
    require_cxx()
    require_iverilog()
    T = cyclone()
    rng = np.random.default_rng(22)

    def sample(values: np.ndarray, history: int) -> bytes:
        calib = T.Calibration_("imu", [0.25, -1.5, 3.0], 2)
        hist = [T.Calibration_("a" * k, [1.0, 2.0, 3.0], k) for k in range(history)]
        return T.Samples_(T.Header_(T.Time_(5, 6), "array"), calib, "hi", [1, 2, 3, 4],
                          [int(v) for v in values], T.Duration_(3, 1000), hist,
                          True).serialize()

    by_fill: dict[int, tuple[bytes, bytes]] = {}
    for history in (1, 0):   # they leave 2 and 3 bytes to pad
        x = rng.integers(-2**31, 2**31, 64, dtype=np.int32)
        payload = sample(x, history)
        dilated = np.frombuffer(window_oracle(x.tobytes(), "<i4", 3, "dilate"), "<i4")
        by_fill[-len(payload) % 4] = (payload, record(sample(dilated, history)))
    (p2, out2), (p3, out3) = by_fill[2], by_fill[3]
    cases = [  # (record, what the circuit publishes for it: b"" when refused)
        (record(pad_to_4(p2)), out2),                           # options 00 00, 2 zeros
        (record(pad_to_4(p3)), out3),                           # options 00 00, 3 zeros
        (record(pad_to_4(p2, options=1)), out2),                # options announce 1 of 2
        (record(pad_to_4(p3, options=2)), out3),                # options announce 2 of 3
        (record(pad_to_4(p3, fill=b"\x00\x07\x00")), out3),    # non-zero mid-padding
        (record(pad_to_4(p2)), out2),
        (record(pad_to_4(p2, options=1, fill=b"\x00\x80")), out2),  # non-zero last byte
        (record(pad_to_4(p3)), out3),
        (record(pad_to_4(p3, fill=b"\x09\x00\x00")), out3),    # non-zero first byte
        (record(pad_to_4(p2)), out2),
        (record(pad_to_4(p2) + bytes(4)), b""),                # beyond the multiple of 4
        (record(pad_to_4(p3)), out3),
        (record(p3 + bytes(2)), b""),                          # short of it
        (record(pad_to_4(p2)), out2),
    ]
    records = [r for r, _out in cases]
    oracle = b"".join(out for _r, out in cases)
    assert statuses_of(cdr_of(SAMPLES), records) == [
        "SUB_OK", "SUB_OK", "SUB_OK", "SUB_OK", "SUB_OK", "SUB_OK", "SUB_OK", "SUB_OK",
        "SUB_OK", "SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_OK", "SUB_BAD_FRAME_LENGTH", "SUB_OK"]
    check_against_models(SAMPLES, projects[SAMPLES], records, oracle)


@pytest.mark.parametrize("name", [SAMPLES, SCAN])
def test_generated_cdr_verilog_is_lint_clean(name: str, projects: dict[str, Path]) -> None:
    """Verilator -Wall and iverilog -Wall find nothing in the walkers with CDR's parts and the
    generated walk (the lab's rfl_fifo.v is another file's business)."""
    rtl = projects[name] / "rtl"
    walk = (rtl / "rfl_layout.vh").read_text()
    assert "OP_ENCAP" in walk and "NUL counted and checked" in walk and "align 4" in walk
    assert_rtl_lint_clean(rtl)


def test_wire_key_is_checked_and_defaults_to_tcpros() -> None:
    from rosfpga_lab.config import ConfigError, parse_config
    from rosfpga_lab.config.vocabulary import WIRES

    text = (DATA / "fpga_laserscan_min.yaml").read_text()
    assert parse_config(text).wire == "tcpros" and "cdr" in WIRES
    assert parse_config(text + "wire: cdr\n").wire == "cdr"
    with pytest.raises(ConfigError) as exc:
        parse_config(text + "wire: dds\n")
    assert "wire must be one of tcpros, cdr" in str(exc.value)


def _random_case(data: st.DataObject) -> tuple[CdrLayout, list[bytes], str]:
    """A random message definition (the models' strategy), small maxima, two samples serialized
    by the msg layer's CDR codec (held equal to Cyclone's bytes in hw/test_cdr.py) with end
    padding of 0..3 bytes announced, or Cyclone's unannounced padding to 4 (zeros, or with a
    non-zero byte), a damaged copy of the first, and an application."""
    reg, type_name, stream = data.draw(definitions())
    r2 = ros2_registry(reg)
    values = [data.draw(message(r2, type_name)) for _ in range(2)]
    n = max(1, len(values[0][stream]))
    values = [v for v in values if len(v[stream]) == n] or values[:1]
    cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n)
    small = {s.path: 3 for s in cdr.base.steps[1:] if s.kind is StepKind.LENGTH
             and s.action is not Action.STREAM and not s.label.endswith("[] length")}
    cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=n, limits_=small)

    def wire(payload: bytes) -> bytes:
        """Padded as announced (0..3), or to 4 unannounced (options fewer), maybe not zero."""
        fill = -len(payload) % 4
        how = data.draw(st.sampled_from(["announced", "unannounced", "not zero"]))
        if how == "announced" or fill == 0:
            return pad_tail(payload, data.draw(st.integers(0, 3)))
        pad = bytearray(fill)
        if how == "not zero":
            pad[data.draw(st.integers(0, fill - 1))] = data.draw(st.integers(1, 255))
        return pad_to_4(payload, data.draw(st.integers(0, fill - 1)), bytes(pad))

    records = [record(wire(serialize_cdr(r2, type_name, v))) for v in values]
    damaged = bytearray(records[0])
    at = data.draw(st.integers(4, len(damaged) - 1))
    damaged[at] ^= data.draw(st.integers(1, 255))
    records += [bytes(damaged), records[-1]]
    return cdr, records, data.draw(st.sampled_from(["dilate", "erode", "passthrough"]))


QUIET = [HealthCheck.too_slow, HealthCheck.function_scoped_fixture]


@settings(max_examples=100, deadline=None, suppress_health_check=QUIET)
@given(data=st.data())
def test_the_program_executor_equals_the_cdr_models_on_random_definitions(
        data: st.DataObject) -> None:
    """The walkers' specification (hls.program.run_program) publishes and refuses exactly as
    hw.cdrwalker does, status for status, on random types and damaged samples."""
    cdr, records, op = _random_case(data)
    expected, _why = model_output_cdr(cdr, op, 3, records)
    dtype = np.dtype(cdr.layout.stream.dtype)
    out, codes = run_program(program_from_cdr(cdr), records,
                             lambda b: window_oracle(b, dtype.str, 3, op))
    names = [n for n, _label in cdr.layout.statuses]
    assert (out, [names[c] for c in codes]) == (expected, statuses_of(cdr, records))


@settings(max_examples=2, deadline=None, derandomize=True, suppress_health_check=QUIET)
@given(data=st.data())
def test_random_definitions_simulate_as_the_cdr_models(data: st.DataObject,
                                                       tmp_path_factory: pytest.TempPathFactory
                                                       ) -> None:
    require_cxx()
    require_iverilog()
    from rosfpga_lab.hls.generic import spec_from_layout
    from rosfpga_lab.rtl.generic import project_files

    cdr, records, op = _random_case(data)
    expected, _why = model_output_cdr(cdr, op, 3, records)
    spec = spec_from_layout(cdr.layout, cdr.registry, op=op, ksize=3,
                            program=program_from_cdr(cdr), wire="cdr")
    where = tmp_path_factory.mktemp("random_cdr")
    for name, blob in project_files(spec).items():
        (where / name).parent.mkdir(parents=True, exist_ok=True)
        (where / name).write_bytes(blob)
    want = statuses_of(cdr, records)
    csim, rtl = both_simulations(where, records)
    assert csim == (expected, want)
    assert rtl == (expected, want)


def test_a_tcpros_frame_cut_short_in_a_count_is_refused_by_that_count_in_verilog_too(
        tmp_path: Path) -> None:
    """Regression (the Verilog walker said SUB_BAD_FRAME_LENGTH where the C++ and the models name
    the count): a LaserScan frame whose length ends inside ``intensities``' count."""
    require_cxx()
    require_iverilog()
    from rosfpga_lab.hls.vectors import model_output, sample_tokens
    from rosfpga_lab.hls.generic import spec_from_config
    from rosfpga_lab.hw.layout import layout_from_config, marshal
    from rosfpga_lab.rtl.generic import project_files

    config = load_config(DATA / "fpga_laserscan_min.yaml")
    layout = layout_from_config(config)
    toks = []
    for t in sample_tokens(layout, np.random.default_rng(1)):
        label = layout.steps[t.step].label
        toks.append(t._replace(value=0) if label == "intensities length" else
                    t._replace(value=np.zeros(0, np.float32)) if label == "intensities" else t)
    good = marshal(layout, toks)
    body = good[4:-2]
    frames = [struct.pack("<I", len(body)) + body, good]
    expected, why = model_output(layout, "erode", 5, frames)
    assert "'intensities length'" in why[0] and why[1] == ""
    for name, blob in project_files(spec_from_config(config)).items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(blob)
    want = ["SUB_BAD_INTENSITIES_LENGTH", "SUB_OK"]
    assert both_simulations(tmp_path, frames) == ((expected, want), (expected, want))


def test_a_bool_is_carried_as_its_byte_by_the_models_as_by_the_walkers() -> None:
    """A bool's byte goes through as received (0x02 stays 0x02), in the models as in the walkers'
    program (and so the RTL): a damaged copy's bool once came out 0x01 from the models only
    (Hypothesis found it: h_msgs/T0, a carried bool after the stream, XORed with 2)."""
    from rosfpga_lab.msg.registry import MsgRegistry

    reg = MsgRegistry()
    reg.add("h_msgs/T1", "char[2] f0\nbool f1\n")
    reg.add("h_msgs/T0", "h_msgs/T1 f0\nint8[] stream\nbool f1\n")
    cdr = derive_cdr_layout(reg, "h_msgs/T0", stream="stream", stream_length=3)
    # length 16, CDR_LE, f0.f0 = 00 00, f0.f1 = 01, stream [0, 0, 0] aligned to 4, f1 = 0x02
    record = bytes.fromhex("10000000" "00010000" "0000" "01" "00" "03000000" "000000" "02")
    expected, why = model_output_cdr(cdr, "passthrough", 3, [record])
    assert why == [""] and expected == record
    out, codes = run_program(program_from_cdr(cdr), [record],
                             lambda b: window_oracle(b, "|i1", 3, "passthrough"))
    assert (out, codes) == (expected, [0])
