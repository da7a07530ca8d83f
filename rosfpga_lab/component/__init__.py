"""The ROS-compliant FPGA component as a running node, with a camera, a viewer and a demo.

Quick use::

    from rosfpga_lab.component import FpgaComponent
    fpga = FpgaComponent.from_config("data/fpga_dilate_rgba8.yaml").start()  # master from the file
    ...                                   # frames on /image_raw come out dilated on /image_dilated
    print(fpga.stats.report())            # frames in/out/dropped/refused, latency, cycles, FIFOs
    fpga.add_observer(lambda rec: ...)    # every FrameRecord (input, output, result, latency)
    fpga.stop()

    from rosfpga_lab.component import run_demo
    result = run_demo(frames=60)          # master + camera + component + bit-exact checker
    print("\\n".join(result.lines()))

    with DemoRig(source="synthetic") as rig:   # the same, non-blocking (notebooks)
        rig.component.add_observer(lambda rec: ...)   # e.g. a live view
        rig.start_camera()
        ...

The component is an ordinary ROS 1 node whose data path is the modelled circuit, started from
the YAML file ``rosfpga-lab generate`` reads: it pushes every received TCPROS frame (the raw
bytes, never deserialized in software) through the circuit model and publishes the frame the
circuit's message generator writes. Frames wait in front of the circuit in one queue and behind
it in one queue per subscriber (sizes in module ``limits``; ``--input-queue``,
``--output-queue``); when one is full the oldest frame is dropped, counted and logged. A frame of
the wrong size or encoding is refused with its reason (field and byte offset), counted by kind
and logged, and the next good frame comes out right. The component survives its input
publisher dying and coming back, a master restart (it registers again and keeps its
established input connections, as roscpp does) and a subscriber too slow for the rate (only
that subscriber loses frames). Commands: ``rosfpga-lab demo`` (``--view`` for a live page on
127.0.0.1), ``node CONFIG``, ``camera``, ``view`` (ARCHITECTURE.md's command table); the
measured figures are printed by ``rosfpga-lab demo`` and ``rosfpga-lab bench`` (:mod:`rosfpga_lab.bench`).

Modules: ``fpga`` (:class:`FpgaComponent`, :class:`FrameRecord`), ``stats``
(:class:`ComponentStats`), ``sources`` (pictures: synthetic, grace_hopper, files), ``camera``
(:class:`Camera`, :class:`Viewer`), ``checker`` (:class:`Checker`, OpenCV as the oracle),
``demo`` (:func:`run_demo`, :func:`run_demo_ros2`), ``ros2`` (:class:`Ros2Component`: the node on
ROS 2, and the camera's and viewer's ROS 2 adapters), ``limits``, ``errors``.
"""

from rosfpga_lab.component.camera import Camera, SentFrame, ViewedFrame, Viewer, stamp_of
from rosfpga_lab.component.checker import CheckReport, Checker, expected_output
from rosfpga_lab.component.demo import (
    DemoResult, DemoRig, Ros2DemoResult, default_config, run_demo, run_demo_ros2, write_figure,
)
from rosfpga_lab.component.errors import (ComponentConfigError, ComponentError, ComponentShutDown,
                                          SourceError)
from rosfpga_lab.component.fpga import FpgaComponent, FrameRecord, master_answers
from rosfpga_lab.component.msgchecker import MessageChecker
from rosfpga_lab.component.sources import SOURCES, ImageSource, open_source, to_rgb
from rosfpga_lab.component.stats import ComponentStats, LatencySummary, LatencyWindow

__all__ = [
    "MessageChecker",
    "SOURCES", "Camera", "CheckReport", "Checker", "ComponentConfigError", "ComponentError",
    "ComponentShutDown",
    "ComponentStats", "DemoResult", "DemoRig", "FpgaComponent", "FrameRecord", "ImageSource",
    "LatencySummary", "LatencyWindow", "Ros2DemoResult", "SentFrame", "SourceError", "ViewedFrame",
    "Viewer", "default_config", "expected_output", "master_answers", "open_source", "run_demo",
    "run_demo_ros2", "stamp_of", "to_rgb", "write_figure",
]
