"""rosidl's IDL of the types the CDR tests send, as PyPI cyclonedds' IDL dataclasses.

Written by hand from the ``.msg`` files (independently of the lab's registry), as rosidl and
rmw_cyclonedds_cpp name them. No ``from __future__ import annotations`` here: cyclonedds
resolves the annotations of module-level classes. Import only after ``require_cyclonedds()``.
"""

from dataclasses import dataclass

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Duration_(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_
    frame_id: str


@dataclass
class Image_(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header_
    height: t.uint32
    width: t.uint32
    encoding: str
    is_bigendian: t.uint8
    step: t.uint32
    data: t.sequence[t.uint8]


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
