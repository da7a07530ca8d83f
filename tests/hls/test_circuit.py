"""hls.circuit: the circuit record, once per configuration, holding what every renderer takes."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rosfpga_lab.config import load_config
from rosfpga_lab.hls.circuit import circuit_of
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.generic import spec_from_config, stream_path
from rosfpga_lab.hls.program import frame_clocks, stream_clocks
from rosfpga_lab.hls.vectors import sample_frames

DATA = Path(__file__).resolve().parents[2] / "data"


@pytest.mark.parametrize("name", ["fpga_erode_mono8.yaml", "fpga_samples_dilate.yaml",
                                  "fpga_laserscan_min_cdr.yaml"])
def test_one_record_per_configuration_holds_the_spec_program_and_models(name: str) -> None:
    config = load_config(DATA / name)
    circuit = circuit_of(config)
    assert circuit_of(config) is circuit and circuit.config is config
    assert circuit.spec is circuit.spec and circuit.program is circuit.spec.program
    assert circuit.spec == spec_from_config(config)
    frames, expected = sample_frames(config)
    first = frames[:4 + struct.unpack_from("<I", frames)[0]]
    spec = spec_from_config(config)
    assert circuit.frame_clocks(first) == frame_clocks(spec.program, first,
                                                       latency=stream_path(spec))
    # back to back, with the stream's path too (notebook 05's frame rate): the first frame's
    # clocks are its clocks alone
    ends = circuit.stream_clocks([first] * 3)
    assert ends == stream_clocks(spec.program, [first] * 3, latency=stream_path(spec))
    assert ends[0] == circuit.frame_clocks(first).total
    if config.wire == "cdr":
        out = circuit.cdr_model().run_record(first).output_record
    else:
        out = circuit.model().process(first).output_frame
    assert expected.startswith(out)


def test_each_model_counts_its_own_frames() -> None:
    config = load_config(DATA / "fpga_erode_mono8.yaml")
    frame = sample_frames(config)[0]
    a, b = circuit_of(config).model(), circuit_of(config).model()
    a.process(frame)
    assert (a.next_seq, b.next_seq) == (2, 1)


def test_a_record_without_a_generated_circuit_still_models_it(tmp_path: Path) -> None:
    """A publisher of another type has no generated circuit (its spec is refused on first
    use), but the record's model runs it."""
    from tests.hw.test_walker import conversion_config

    config = conversion_config(tmp_path)
    circuit = circuit_of(config)
    with pytest.raises(GenerateError, match="differs from subscriber.type"):
        circuit.spec
    assert circuit.layouts.out_layout is not None
    assert circuit.model().out_layout is circuit.layouts.out_layout
