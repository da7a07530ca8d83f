"""Benchmarks behind ``rosfpga-lab bench``: figures printed side by side, not timed tests.

``run_bench()`` returns a :class:`BenchReport`; ``print(report.table())`` prints it. Modules:
``pipeline`` (the fast circuit model against ``cv2.dilate``), ``path`` (publisher -> middle ->
subscriber, with the FPGA component, roscpp's ``topic_tools relay`` and a rospy relay as
middles), ``runner`` (the whole run), ``ros_programs`` (real ROS programs, run by the system
Python when real ROS 1 is installed).
"""

from rosfpga_lab.bench.path import PathFigures, find_relay, measure
from rosfpga_lab.bench.pipeline import PipelineFigures, bench_pipeline
from rosfpga_lab.bench.runner import MIDDLES, BenchReport, machine_description, run_bench

__all__ = ["MIDDLES", "BenchReport", "PathFigures", "PipelineFigures", "bench_pipeline",
           "find_relay", "machine_description", "measure", "run_bench"]
