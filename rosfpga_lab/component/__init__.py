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
