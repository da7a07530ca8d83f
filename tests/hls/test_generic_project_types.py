"""Every primitive type at its full range, in every field position, through ``rosfpga-lab
generate``'s flow on both wires: the generated project's own test frames pass ``make csim`` and
``make rtlsim``, and frames holding each type's extremes come out exact.

Issue 28, item 8: ``generate`` crashed (``ValueError: high is out of bounds for int64``) for a
``uint64`` field outside the stream, because its test frames were drawn with numpy's int64
bounds; no test had a ``uint64`` scalar there. Here every type of the ``.msg`` language is a
top-level scalar, a fixed array, a variable array, a field of a nested message, of a fixed and a
variable array of messages, a checked field (equal to an extreme, inside a full range, inside a
range one short of the extremes at both ends) and the streamed array (each numeric type once,
``[]`` and ``[8]`` in turn). Values (independent of the lab's generator): each integer type's
minimum, maximum, zero and their neighbours; floats' infinities, largest finite values, NaN,
-0.0 and the smallest subnormal; strings empty and at their maximum (UTF-8 beyond ASCII); time
and duration at both ends of their two parts; arrays empty and full. Expected output comes from
the msg layer (``serialize``, ``serialize_cdr``) of the same value with the stream replaced by a
numpy sliding max/min (tests/support/generictools.py), and is held equal to the Python models' too.
"""

from __future__ import annotations

import concurrent.futures
import math
import os
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings

from tests.support.generictools import window_oracle
from tests.support.realros import require_cxx
from tests.support.rtltools import require_iverilog
from rosfpga_lab.config import NodeConfig, parse_config
from rosfpga_lab.hls.vectors import model_output, model_output_cdr, sample_frames_generic, sample_records_cdr
from rosfpga_lab.hw.cdrlayout import cdr_layout_from_config, derive_cdr_layout
from rosfpga_lab.hw.layout import Action, StepKind, derive_layout, layout_from_config
from rosfpga_lab.msg import MsgRegistry, Time, Duration, deserialize, serialize
from rosfpga_lab.msg.builtins import FLOAT_TYPES, SCALARS, integer_bounds
from rosfpga_lab.msg.cdr import deserialize_cdr, serialize_cdr
from rosfpga_lab.msg.ros2 import ros2_registry
from rosfpga_lab.rtl.generic import simulate_project
from rosfpga_lab.rtl.project import generate_project
from tests.hw.test_walker import NUMERIC, PRIMS, definitions

PKG = "t_msgs"
#: Bytes of every string and elements of every variable array other than the stream.
LIMIT = 3
LENGTH = 8
F32 = np.finfo(np.float32)
F64 = np.finfo(np.float64)
#: The values each type takes in turn (minimum and maximum first).
SPECIALS: dict[str, list[Any]] = {
    "bool": [False, True],
    "float32": [-math.inf, math.inf, -float(F32.max), float(F32.max), math.nan, -0.0,
                float(F32.smallest_subnormal), 0.0],
    "float64": [-math.inf, math.inf, -float(F64.max), float(F64.max), math.nan, -0.0,
                float(F64.smallest_subnormal), 0.0],
    "string": ["", "é!", "a"],          # "é!" is 3 bytes in UTF-8: the maximum
    "time": [Time(0, 0), Time(2**32 - 1, 2**32 - 1), Time(1, 999_999_999)],
    "duration": [Duration(-2**31, -2**31), Duration(2**31 - 1, 2**31 - 1), Duration(0, 0)],
}
for _t in NUMERIC:
    if _t not in FLOAT_TYPES:
        _lo, _hi = integer_bounds(_t)
        SPECIALS[_t] = [_lo, _hi, 0, _lo + 1, _hi - 1, 1 if _lo == 0 else -1]
CHECKABLE = [t for t in PRIMS if t not in ("time", "duration")]


def texts(stream: str, fixed_stream: bool) -> dict[str, str]:
    """``.msg`` texts: ``Scalars`` (one field per type), ``Arrays`` (a fixed and a variable array
    per type) and ``All``, which holds them in every position and streams ``stream``."""
    scalars = "".join(f"{t} f_{t}\n" for t in PRIMS)
    arrays = "".join(f"{t}[2] fixed_{t}\n{t}[] var_{t}\n" for t in PRIMS)
    top = [f"{t} top_{t}" for t in PRIMS] + [
        "Scalars nested", "Arrays arrays", "Scalars[2] nested_fixed", "Scalars[] nested_var",
        "Arrays[] arrays_var", "Scalars eq", "Scalars rng", "Scalars cut"]
    top.insert(len(PRIMS) + 2, f"{stream}[{LENGTH if fixed_stream else ''}] stream")
    return {"Scalars": scalars, "Arrays": arrays, "All": "\n".join(top) + "\n"}


def bounds(t: str) -> tuple[Any, Any]:
    return (-math.inf, math.inf) if t in FLOAT_TYPES else integer_bounds(t)


def config_text(stream: str, fixed_stream: bool, wire: str, op: str, limits: dict[str, int]
                ) -> str:
    """The node configuration: the stream, small maxima, and the checks of ``eq`` (each type's
    maximum, minimum for signed types, -0.0 for float64), ``rng`` (the full range, infinities
    included) and ``cut`` (one short of both ends; floats: the largest finite values)."""
    checks: dict[str, Any] = {}
    for t in CHECKABLE:
        if t == "string":
            checks["eq.f_string"] = "é!"
            continue
        if t == "bool":
            checks["eq.f_bool"] = True
            continue
        lo, hi = bounds(t)
        if t in FLOAT_TYPES:
            finite = float((F32 if t == "float32" else F64).max)
            checks[f"eq.f_{t}"] = -finite if t == "float32" else -0.0
            checks[f"rng.f_{t}"] = {"min": lo, "max": hi}
            checks[f"cut.f_{t}"] = {"min": -finite, "max": finite}
        else:
            checks[f"eq.f_{t}"] = lo if lo < 0 else hi
            checks[f"rng.f_{t}"] = {"min": lo, "max": hi}
            checks[f"cut.f_{t}"] = {"min": lo + 1, "max": hi - 1}
    conf = {
        "node": {"name": "/fpga_types"},
        "subscriber": {"topic": "/all", "type": f"{PKG}/All"},
        "publisher": {"topic": "/all_out"},
        "msg_path": ["msg"],
        "stream": {"field": "stream", "length": LENGTH},
        "checks": checks, "limits": limits,
        "fifo": {"input_depth": 256, "output_depth": 256, "axis_depth": 4},
        "application": {"op": op, "ksize": 3}, "wire": wire,
    }
    return yaml.safe_dump(conf, allow_unicode=True, sort_keys=False)


def small_limits(reg: MsgRegistry, type_name: str) -> dict[str, int]:
    """``limits:`` keys of every string and variable array but the stream, each :data:`LIMIT`."""
    layout = derive_layout(reg, type_name, stream="stream", stream_length=LENGTH)
    return {s.path + ("[]" if s.label.endswith("[] length") else ""): LIMIT
            for s in layout.steps[1:] if s.kind is StepKind.LENGTH and s.action is not Action.STREAM}


def write_config(where: Path, stream: str, fixed_stream: bool, wire: str, op: str) -> NodeConfig:
    msgdir = where / "msg" / PKG / "msg"
    msgdir.mkdir(parents=True)
    reg = MsgRegistry.with_defaults()
    for name, text in texts(stream, fixed_stream).items():
        (msgdir / f"{name}.msg").write_text(text, encoding="utf-8")
        reg.add(f"{PKG}/{name}", text)
    text = config_text(stream, fixed_stream, wire, op, small_limits(reg, f"{PKG}/All"))
    (where / "types.yaml").write_text(text, encoding="utf-8")
    return parse_config(text, source=str(where / "types.yaml"), base_dir=where)


# -- values: the k-th frame gives field j the (j + k)-th special of its type ---------------------

def value(reg: MsgRegistry, type_name: str, k: int, *, empty: bool = False) -> dict[str, Any]:
    """A value of ``type_name`` whose fields cycle through their types' specials with ``k``;
    variable arrays hold 0..LIMIT elements (none: ``empty``). ``eq``/``rng``/``cut`` get values
    their checks take."""
    out: dict[str, Any] = {}
    for j, f in enumerate(reg.get(type_name).fields):
        base = f.base_type
        n = 2 if f.array_length == 2 else 0 if empty else (j + k) % (LIMIT + 1)

        def one(e: int, base: str = base) -> Any:
            if base in SPECIALS:
                vals = SPECIALS[base]
                return vals[(j + k + e) % len(vals)]
            return value(reg, base, k + e, empty=empty)

        if f.name == "stream":
            vals = SPECIALS[base]
            out[f.name] = [vals[(k + e) % len(vals)] for e in range(LENGTH)]
        elif f.is_array:
            out[f.name] = [one(e) for e in range(n)]
        else:
            out[f.name] = one(0)
    if type_name.endswith("/All"):
        for name, pick in (("eq", _eq), ("rng", _rng), ("cut", _cut)):
            out[name] = {**out[name], **{f"f_{t}": pick(t, k) for t in CHECKABLE}}
    return out


def _eq(t: str, k: int) -> Any:
    if t in ("string", "bool"):
        return "é!" if t == "string" else True
    lo, hi = bounds(t)
    if t == "float32":
        return -float(F32.max)
    if t == "float64":
        return [-0.0, 0.0][k % 2]   # equality of floats is by value: both zeros pass
    return lo if lo < 0 else hi


def _rng(t: str, k: int) -> Any:
    if t in ("string", "bool"):
        return SPECIALS[t][k % len(SPECIALS[t])]
    vals = [v for v in SPECIALS[t] if not (isinstance(v, float) and math.isnan(v))]
    return vals[k % len(vals)]


def _cut(t: str, k: int) -> Any:
    if t in ("string", "bool"):
        return SPECIALS[t][k % len(SPECIALS[t])]
    lo, hi = bounds(t)
    if t in FLOAT_TYPES:
        finite = float((F32 if t == "float32" else F64).max)
        return [-finite, finite, 0.0, -0.0][k % 4]
    return [lo + 1, hi - 1, 0 if lo < 0 else 1][k % 3]


def refusals() -> list[tuple[str, str, Any]]:
    """(field of ``eq``/``cut``, value, status) of each refused frame: one past each end."""
    out = []
    for t in CHECKABLE:
        if t == "string":
            out.append(("eq", "f_string", "é?"))
        elif t == "bool":
            out.append(("eq", "f_bool", False))
        elif t in FLOAT_TYPES:
            out.append(("eq", f"f_{t}", -math.inf if t == "float32" else
                        float((F64.smallest_subnormal))))
            out += [("cut", f"f_{t}", v) for v in (-math.inf, math.inf, math.nan)]
        else:
            lo, hi = bounds(t)
            out.append(("eq", f"f_{t}", lo + 1 if lo < 0 else hi - 1))
            out += [("cut", f"f_{t}", v) for v in (lo, hi)]
    return out


class Wire:
    """How one wire serializes a value of ``t_msgs/All`` into the circuit's input record."""

    def __init__(self, config: NodeConfig) -> None:
        self.config = config
        self.reg = config.registry()
        self.cdr = config.wire == "cdr"
        self.vreg = ros2_registry(self.reg) if self.cdr else self.reg
        self.type = f"{PKG}/All"

    def value(self, k: int, empty: bool = False) -> dict[str, Any]:
        return value(self.vreg, self.type, k, empty=empty)

    def record(self, v: dict[str, Any]) -> bytes:
        body = (serialize_cdr(self.vreg, self.type, v) if self.cdr
                else serialize(self.vreg, self.type, v))
        return struct.pack("<I", len(body)) + body

    def models(self, records: list[bytes]) -> tuple[bytes, list[str]]:
        app = self.config.application
        if self.cdr:
            return model_output_cdr(cdr_layout_from_config(self.config), app.op, app.ksize,
                                    records)
        return model_output(layout_from_config(self.config), app.op, app.ksize, records)


def expected_of(wire: Wire, v: dict[str, Any], stream_type: str) -> bytes:
    """The oracle: the same value, its stream replaced by numpy's sliding max/min over 3."""
    dtype = SCALARS[stream_type].dtype
    data = np.asarray(v["stream"], dtype).tobytes()
    out = np.frombuffer(window_oracle(data, dtype.str, 3, wire.config.application.op), dtype)
    return wire.record({**v, "stream": out})


def generate_and_simulate(where: Path, stream: str, fixed_stream: bool, wire_name: str,
                          op: str, refuse: bool) -> None:
    """Generate the project (as ``rosfpga-lab generate`` does), run its own test frames, then
    frames of every extreme (and, ``refuse``, each check failing at an extreme, each followed by
    a good frame): the C and RTL simulations publish the oracle's bytes with the right status."""
    config = write_config(where, stream, fixed_stream, wire_name, op)
    project = where / "project"
    generate_project(config, project)
    for target in ("csim", "rtlsim"):  # the frames the project ships, checked by the Makefile
        got, statuses = simulate_project(project, (project / "tb_input.bin").read_bytes(),
                                         target=target, simulator="iverilog", out=f"tb_{target}")
        assert got == (project / "tb_expected.bin").read_bytes() and got, (target, statuses)
    wire = Wire(config)
    goods = [wire.value(k) for k in range(LENGTH)]
    records = [wire.record(v) for v in goods]
    oracle = b"".join(expected_of(wire, v, stream) for v in goods)
    want = ["SUB_OK"] * len(goods)
    if refuse:  # (no variable array filled: short frames, a quicker simulation)
        for i, (msg, name, bad) in enumerate(refusals()):
            v = wire.value(i, empty=True)
            records += [wire.record({**v, msg: {**v[msg], name: bad}}), wire.record(v)]
            oracle += expected_of(wire, v, stream)
            want += [f"SUB_BAD_{msg.upper()}_{name.upper()}", "SUB_OK"]
    models, why = wire.models(records)
    assert models == oracle, [w for w in why if w]
    frames = b"".join(records)
    csim = simulate_project(project, frames, target="csim", out="c_out")
    rtl = simulate_project(project, frames, target="rtlsim", simulator="iverilog", gap=200,
                           bp=300, seed=5, out="r_out")
    assert csim == (oracle, want)
    assert rtl == (oracle, want)


WIRES = ("tcpros", "cdr")


@pytest.mark.slow
@pytest.mark.parametrize("wire", WIRES)
def test_every_type_in_every_position_at_its_extremes(wire: str, tmp_path: Path) -> None:
    """A uint64 stream (the defect's type) with every type in every other position, each check
    failing one past its extremes (each refusal then a good frame)."""
    require_cxx()
    require_iverilog()
    generate_and_simulate(tmp_path, "uint64", False, wire, "dilate", refuse=True)


#: The streamed type, a fixed-length stream, the wire and the operation of each project.
STREAMED = [("int8", False, "tcpros", "dilate"), ("uint8", True, "cdr", "erode"),
            ("char", False, "cdr", "dilate"), ("byte", True, "tcpros", "erode"),
            ("int16", False, "cdr", "erode"), ("uint16", True, "tcpros", "dilate"),
            ("int32", True, "tcpros", "erode"), ("uint32", False, "cdr", "dilate"),
            ("float32", True, "cdr", "dilate"), ("int64", False, "cdr", "erode"),
            ("float64", False, "tcpros", "erode")]


@pytest.mark.slow
def test_every_numeric_type_streamed_at_its_extremes(tmp_path: Path) -> None:
    """Each numeric type streamed beside every type in every other position: ``[]`` and ``[8]``,
    dilate and erode, TCPROS and CDR in turn (each element size and kind on both wires; uint64
    is the test above's, on both). One project per type (about 3 s of g++ and Icarus Verilog each), built in
    parallel, one per core."""
    require_cxx()
    require_iverilog()
    cases = {t: (fixed, wire, op) for t, fixed, wire, op in STREAMED}
    assert sorted(cases) == sorted(t for t in NUMERIC if t != "uint64")
    # each element size, and each kind (unsigned, signed, float), on both wires
    for group in ({np.dtype(SCALARS[t].dtype).itemsize for t in NUMERIC},
                  {np.dtype(SCALARS[t].dtype).kind for t in NUMERIC}):
        for g in group:
            on = {w for t, (_f, w, _o) in cases.items() if g in (np.dtype(SCALARS[t].dtype).itemsize,
                                                              np.dtype(SCALARS[t].dtype).kind)}
            assert on | ({"tcpros", "cdr"} if g in (8, "u") else set()) == set(WIRES), g
    with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        futures = {t: pool.submit(generate_and_simulate, tmp_path / t, t, fixed, wire, op,
                                  refuse=False) for t, (fixed, wire, op) in cases.items()}
        for t, fut in futures.items():
            try:
                fut.result()
            except AssertionError as exc:
                raise AssertionError(f"stream of {t} ({cases[t]}): {exc}") from exc


# -- the test frames `generate` draws, for random definitions (no simulation: fast) -------------

@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(definitions())
def test_the_generators_test_frames_are_drawn_for_any_definition(defn: Any) -> None:
    """What ``generate`` ships as ``tb_input.bin`` (sample_frames_generic, sample_records_cdr)
    exists for every random definition (every type in every position: the int64 bounds of
    the old draw crashed on a uint64 outside the stream), and its good frames are values of the
    type: the msg layer reads them back, the stream at the circuit's length."""
    reg, type_name, stream = defn
    small = {s.path + ("[]" if s.label.endswith("[] length") else ""): 2
             for s in derive_layout(reg, type_name, stream=stream, stream_length=3).steps[1:]
             if s.kind is StepKind.LENGTH and s.action is not Action.STREAM}
    layout = derive_layout(reg, type_name, stream=stream, stream_length=3, limits_=small)
    frames, expected = sample_frames_generic(layout, "dilate", 3)
    good, at = [], 0
    while at < len(frames):
        size = 4 + struct.unpack_from("<I", frames, at)[0]
        good.append(frames[at:at + size])
        at += size
    assert len(good) == 3 and expected
    for frame in (good[0], good[2]):
        assert len(deserialize(reg, type_name, frame[4:])[stream]) == 3
    cdr = derive_cdr_layout(reg, type_name, stream=stream, stream_length=3, limits_=small)
    records, expected = sample_records_cdr(cdr, "erode", 3)
    first = records[:4 + struct.unpack_from("<I", records)[0]]
    assert expected and len(deserialize_cdr(ros2_registry(reg), type_name, first[4:])[stream]) == 3
