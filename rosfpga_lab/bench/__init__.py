"""Benchmarks behind ``rosfpga-lab bench``: figures printed side by side, not timed tests.

``run_bench()`` returns a :class:`BenchReport`; ``print(report.table())`` prints it. Modules:
``pipeline`` (the fast circuit model against ``cv2.dilate``), ``path`` (publisher -> middle ->
subscriber, with the FPGA component, roscpp's ``topic_tools relay`` and a rospy relay as
middles), ``runner`` (the whole run), ``ros_programs`` (real ROS programs, run by the system
Python when real ROS 1 is installed).

Recorded once on this project's machine (2 cores of an AMD EPYC, Python 3.11, idle; every
middle its own process between the same lab publisher and subscriber; sustained = median of 3
interleaved rounds, frames/s; about 30 s). These figures move with the machine's load: rerun
``rosfpga-lab bench`` rather than quote them. The pipeline model alone: 2,827 frames/s against
8,791 for ``cv2.dilate`` alone (3.1x, goal: within 8x), its output equal to OpenCV's.

=============================  =======  =======  ========  =====  =======  ========  =======
middle                         1 in     2 in     CPU per   at     latency  added     outputs
                               flight   flight   frame     30/s   median   median    correct
=============================  =======  =======  ========  =====  =======  ========  =======
direct (no middle)             2097     2555     -         90/90  0.7 ms   baseline  260/260
FPGA component (dilate)        655      815      1.05 ms   90/90  2.0 ms   +1.3 ms   259/259
roscpp ``topic_tools relay``   427      640      1.65 ms   90/90  2.4 ms   +1.7 ms   260/260
rospy relay (``AnyMsg``)       449      545      1.76 ms   90/90  2.6 ms   +1.9 ms   261/261
=============================  =======  =======  ========  =====  =======  ========  =======

The component, computing the dilation, beats roscpp's relay, which only copies (it receives each
frame straight into its buffer and never deserializes it in software); with other programs busy
on the same cores earlier runs put the two about level. In the real FPGA the byte-wide walkers
(one byte per clock in, then out) would cap the component below gigabit Ethernet (the generated
circuit's clocks, ``hls.circuit.Circuit.frame_clocks``; the demo's "modelled circuit" line). Other scripts (figures printed, never asserted):
``python -m rosfpga_lab.msg.bench``, ``python -m rosfpga_lab.widgets.bench`` and
``tests/benchmarks/bench_*.py``, each saying what it measures in its docstring.
"""

from rosfpga_lab.bench.path import PathFigures, find_relay, measure
from rosfpga_lab.bench.pipeline import PipelineFigures, bench_pipeline
from rosfpga_lab.bench.runner import MIDDLES, BenchReport, machine_description, run_bench

__all__ = ["MIDDLES", "BenchReport", "PathFigures", "PipelineFigures", "bench_pipeline",
           "find_relay", "machine_description", "measure", "run_bench"]
