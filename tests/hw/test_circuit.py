"""hw.circuit: a configuration's layouts derived once per configuration object, and the field its
publisher numbers."""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.hw.circuit import NUMBERED_FIELD, ConfigCache, circuit_layouts, numbered_field
from rosfpga_lab.hw.layout import layout_from_config

DATA = Path(__file__).resolve().parents[2] / "data"


def test_layouts_are_derived_once_per_configuration_object() -> None:
    config = load_config(DATA / "fpga_laserscan_min.yaml")
    first = circuit_layouts(config)
    assert circuit_layouts(config) is first
    assert first.layout == layout_from_config(config) and first.out_layout is None
    assert first.cdr is first.cdr                       # derived on first use, then kept
    assert first.cdr.layout.type_name == "sensor_msgs/LaserScan"
    again = load_config(DATA / "fpga_laserscan_min.yaml")   # loaded again: a .msg may have changed
    assert circuit_layouts(again) is not first
    # a caller's own registry: derived from it, not kept
    assert circuit_layouts(config, config.registry()) is not first


def test_only_a_tcpros_image_numbers_its_header_seq() -> None:
    image = load_config(DATA / "fpga_dilate_rgba8.yaml")
    assert numbered_field(image) == NUMBERED_FIELD == "header.seq"
    assert circuit_layouts(image).numbered == "header.seq"
    assert circuit_layouts(image).video is not None
    for name in ("fpga_laserscan_min.yaml", "fpga_samples_dilate.yaml"):
        assert numbered_field(load_config(DATA / name)) is None


def test_the_cache_keeps_the_newest_and_builds_again_after_an_error() -> None:
    cache: ConfigCache[int] = ConfigCache(kept=2)
    configs = [load_config(DATA / "fpga_samples_dilate.yaml") for _ in range(3)]
    built: list[int] = []

    def build(k: int) -> int:
        built.append(k)
        return k

    assert [cache.get(c, lambda k=k: build(k)) for k, c in enumerate(configs)] == [0, 1, 2]
    assert cache.get(configs[2], lambda: build(9)) == 2 and built == [0, 1, 2]
    assert cache.get(configs[0], lambda: build(7)) == 7      # the oldest went
    assert built == [0, 1, 2, 7]
