"""rosidl's IDL of the types the CDR tests send, as PyPI cyclonedds' IDL dataclasses.

Written by hand from the ``.msg`` files (independently of the lab's registry), as rosidl and
rmw_cyclonedds_cpp name them; Time_, Header_ and Image_ come from the shipped capture script's
own IDL (one owner: tests/support/ros2tools.py imports them from here). No ``from __future__ import annotations`` here: cyclonedds
resolves the annotations of module-level classes. Import only after ``require_cyclonedds()``.
"""

import importlib.util
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct


# Time_, Header_ and Image_ are the shipped capture script's (data/capture_rtps_image.py, which
# must stay runnable on its own and hands them to its Cyclone DDS processes as source text).
def _capture_types() -> dict[str, Any]:
    path = Path(__file__).resolve().parents[2] / "data" / "capture_rtps_image.py"
    spec = importlib.util.spec_from_file_location("capture_rtps_image", path)
    assert spec is not None and spec.loader is not None
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    names: dict[str, Any] = {"__name__": __name__}
    exec(script.TYPES, names)
    return names


_CAPTURE = _capture_types()
Time_ = _CAPTURE["Time_"]
Header_ = _CAPTURE["Header_"]
Image_ = _CAPTURE["Image_"]


@dataclass
class Duration_(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Calibration_(IdlStruct, typename="lab_msgs::msg::dds_::Calibration_"):
    sensor_name: str
    offset: t.array[t.float64, 3]
    mode: t.uint8


@dataclass
class Samples_(IdlStruct, typename="lab_msgs::msg::dds_::Samples_"):
    header: Header_
    calibration: Calibration_
    label: str
    thresholds: t.array[t.int16, 4]
    samples: t.sequence[t.int32]
    period: Duration_
    history: t.sequence[Calibration_]
    valid: bool


@dataclass
class LaserScan_(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header_
    angle_min: t.float32
    angle_max: t.float32
    angle_increment: t.float32
    time_increment: t.float32
    scan_time: t.float32
    range_min: t.float32
    range_max: t.float32
    ranges: t.sequence[t.float32]
    intensities: t.sequence[t.float32]
