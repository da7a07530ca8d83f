"""The message model against real ROS 1 Noetic (Debian's genmsg and genpy), in CI.

Skipped with a reason without ROS; a failure under CI (ROSFPGA_REQUIRE_ROS=1). Every check runs
the system Python once per test and compares in bulk:

* every message type of Debian's std_msgs, sensor_msgs and geometry_msgs: the lab's md5 and
  full text against genpy's ``_md5sum`` and ``_full_text`` (a) with genpy's own commented texts
  loaded and (b) with the lab's shipped definitions (the same commented texts); fields and constants;
* the tricky definitions of test_parse.py against genmsg itself;
* serialized bytes against genpy on hypothesis-generated values of every type, both ways, and a
  640x480 rgba8 sensor_msgs/Image.
"""

from __future__ import annotations

import base64
import functools
import json
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from tests.support.realros import ROS_PROGRAMS, require_ros, run_ros_python
from rosfpga_lab.msg import (
    MsgRegistry, default_registry, deserialize, new_message, serialize,
)
from rosfpga_lab.msg.builtins import SCALARS
from rosfpga_lab.msg.strategies import message, normalize
from tests.msg.test_parse import BAD, TRICKY

pytestmark = pytest.mark.ros
REG = default_registry()
PACKAGES = ("std_msgs", "sensor_msgs", "geometry_msgs", "rosgraph_msgs", "roscpp")


def run_helper(name: str, argv: list[str] | None = None, stdin: Any = None) -> Any:
    path = ROS_PROGRAMS / name
    code = (f"import runpy, sys; sys.argv = [{str(path)!r}] + {argv or []!r}; "
            f"runpy.run_path({str(path)!r}, run_name='__main__')")
    data = None if stdin is None else json.dumps(stdin).encode()
    proc = run_ros_python(code, input=data, timeout=120)
    return json.loads(proc.stdout)


@functools.cache
def genpy_types() -> tuple[dict, ...]:
    return tuple(run_helper("genpy_dump.py", list(PACKAGES)))


@pytest.fixture(scope="module")
def genpy() -> dict[str, dict]:
    require_ros()
    return {t["type"]: t for t in genpy_types()}


def test_shipped_types_are_exactly_debians(genpy: dict[str, dict]) -> None:
    assert sorted(genpy) == REG.types()


def test_genpy_commented_texts_reproduce_full_text_and_md5(genpy: dict[str, dict]) -> None:
    bad = []
    for name, info in genpy.items():
        reg = MsgRegistry()
        reg.add_full_text(name, info["full_text"])
        if (reg.full_text(name), reg.md5(name)) != (info["full_text"], info["md5"]):
            bad.append(name)
    assert not bad, f"(a) differs from genpy for {bad}"


def test_shipped_definitions_match_genpy(genpy: dict[str, dict]) -> None:
    md5_bad, text_bad, field_bad, const_bad = [], [], [], []
    for name, info in genpy.items():
        spec = REG.get(name)
        if REG.md5(name) != info["md5"]:
            md5_bad.append(name)
        if REG.full_text(name) != info["full_text"]:  # byte for byte, comments included
            text_bad.append(name)
        if (spec.field_names, spec.field_types) != (info["slots"], info["slot_types"]):
            field_bad.append(name)
        if {c.name: c.value for c in spec.constants} != info["constants"]:
            const_bad.append(name)
    assert not md5_bad, f"md5 differs: {md5_bad}"
    assert not text_bad, f"full text differs: {text_bad}"
    assert not field_bad, f"fields differ: {field_bad}"
    assert not const_bad, f"constants differ: {const_bad}"


def test_tricky_definitions_against_genmsg(real_ros: None) -> None:
    result = run_helper("genpy_genmsg_md5.py", stdin={**TRICKY, **{k: v[0] for k, v in BAD.items()}})
    reg = MsgRegistry()
    for name, text in TRICKY.items():
        reg.add(name, text)
    for name in TRICKY:
        assert result[name] == {"md5": reg.md5(name), "full_text": reg.full_text(name)}, name
    for name in BAD:
        assert "error" in result[name], f"genmsg accepted {name}"


def to_json(type_name: str, value: Any) -> dict:
    spec = REG.get(type_name)
    out = {}
    for f in spec.fields:
        v = value[f.name]
        if f.is_array and f.base_type in ("uint8", "char"):
            raw = bytes(v) if isinstance(v, (bytes, bytearray, memoryview)) \
                else np.asarray(v, np.uint8).tobytes()
            out[f.name] = {"b64": base64.b64encode(raw).decode()}
        elif f.is_array:
            out[f.name] = [_json_elem(f.base_type, x) for x in v]
        else:
            out[f.name] = _json_elem(f.base_type, v)
    return out


def _json_elem(base: str, v: Any) -> Any:
    if base in ("time", "duration"):
        return [int(v[0]), int(v[1])]
    if base in SCALARS:
        return v.item() if isinstance(v, np.generic) else v
    if base == "string":
        return v
    return to_json(base, v)


def compare_with_genpy(items: list[tuple[str, Any]]) -> None:
    ours = [serialize(REG, t, v) for t, v in items]
    batch = [{"type": t, "value": to_json(t, v), "ours": base64.b64encode(b).decode()}
             for (t, v), b in zip(items, ours)]
    results = run_helper("genpy_serialize.py", stdin=batch)
    for (type_name, value), body, res in zip(items, ours, results):
        theirs = base64.b64decode(res["genpy"])
        assert body == theirs, f"{type_name}: lab and genpy bytes differ for {value!r}"
        assert base64.b64decode(res["reserialized"]) == body, type_name
        out = deserialize(REG, type_name, theirs)
        assert normalize(REG, type_name, out) == normalize(REG, type_name, value)


@pytest.mark.slow
@pytest.mark.parametrize("package", PACKAGES)
@settings(max_examples=4, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.large_base_example])
@given(data=st.data())
def test_bytes_match_genpy_for_every_type(package: str, data: st.DataObject) -> None:
    require_ros()
    # genpy canonicalizes time/duration when decoding, so the values drawn here are canonical
    # (test_msg_codec/test_msg_rosbags cover every 32-bit pattern).
    items = [(t, data.draw(message(REG, t, canonical_time=True), label=t))
             for t in REG.types(package) for _ in range(2)]
    compare_with_genpy(items)  # one system-Python run per example, no shrinking (slow)


def test_image_640x480_rgba8_matches_genpy(real_ros: None) -> None:
    pixels = np.random.default_rng(3).integers(0, 256, 640 * 480 * 4, dtype=np.uint8)
    value = new_message(REG, "sensor_msgs/Image",
                        header={"seq": 42, "stamp": (1700000000, 123456789), "frame_id": "camera"},
                        height=480, width=640, encoding="rgba8", step=2560, data=pixels)
    compare_with_genpy([("sensor_msgs/Image", value)])
