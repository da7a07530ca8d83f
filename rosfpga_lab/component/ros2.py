"""The FPGA component as a ROS 2 node: RTPS in software, the CDR circuit on the data path.

How this works: a :class:`~rosfpga_lab.graph.ros2.Ros2Node` discovers and matches the peers
in software (SPDP/SEDP, as the ROS 1 side does XML-RPC); every sample that arrives on the
input topic is a CDR payload, which goes through the CDR circuit model
(:class:`~rosfpga_lab.hw.CdrPipeline`: CDR subscriber from the layout -> application -> CDR
publisher, the bytes never deserialized in software) and out through the RTPS writer on the
output topic. Any type the layout accepts works, ``sensor_msgs/Image`` included. With
``model="rtl"`` the Verilog itself is on the data path instead: the configuration's generated
CDR top in one long-lived simulator (:class:`~rosfpga_lab.rtl.server.RtlServer`), fed each
sample as the record the RTPS reader's software writes into the circuit's byte FIFO (the
4-byte sample length, then the payload); its output record loses its length on the way to the
RTPS writer, and a sample it refuses is counted under the status name of its walk. With
``timing="fpga"`` each output leaves when the circuit's clocks for the sample at ``clock_mhz``
have passed since it arrived (or since the circuit became free): the simulated span with
``"rtl"``, else the generated walk's clocks (:func:`rosfpga_lab.hls.program.frame_clocks`,
equal to the RTL's).

The camera and the viewer on ROS 2 (:class:`Ros2ImagePublisher`, :func:`subscribe_ros1_bodies`)
are software peers, not the circuit: they convert between the ROS 1 image bodies the lab's
camera and viewer use and CDR (:func:`ros1_frame_to_cdr`, :func:`cdr_to_ros1_frame`), as a
ROS 2 camera driver serializes its images in software.
"""

from __future__ import annotations

import logging
import struct
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rosfpga_lab.component.errors import ComponentConfigError
from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.config.vocabulary import CDR_WIRE, MODELS, RTL_MODEL, TIMINGS
from rosfpga_lab.errors import LabError
from rosfpga_lab.graph import MessageInfo
from rosfpga_lab.graph.ros2 import Ros2Node, Ros2Publisher
from rosfpga_lab.hw import CdrPipeline, PipelineError
from rosfpga_lab.msg import default_registry, deserialize, deserialize_cdr, serialize, serialize_cdr
from rosfpga_lab.msg import to_ros2_value
from rosfpga_lab.rtps.participant import Qos, Sample
from rosfpga_lab.rtps.rosnode import split_node_name

log = logging.getLogger(__name__)
IMAGE = "sensor_msgs/Image"


def cdr_to_ros1_frame(payload: bytes, seq: int = 0) -> bytes:
    """A ROS 2 Image (CDR payload) as a TCPROS frame (length + body): the viewer's conversion."""
    v = deserialize_cdr(None, IMAGE, payload)
    stamp = v["header"]["stamp"]
    if stamp["sec"] < 0:
        raise PipelineError(f"header.stamp.sec is {stamp['sec']}: ROS 1 time has no negative "
                            f"seconds")
    v["header"] = {"seq": seq & 0xFFFFFFFF, "stamp": (stamp["sec"], stamp["nanosec"]),
                   "frame_id": v["header"]["frame_id"]}
    body = serialize(default_registry(), IMAGE, v)
    return len(body).to_bytes(4, "little") + body


def ros1_frame_to_cdr(frame: bytes) -> bytes:
    """A ROS 1 Image frame (length + body) as a ROS 2 CDR payload: the camera's conversion."""
    v = deserialize(default_registry(), IMAGE, frame[4:])
    return serialize_cdr(None, IMAGE, to_ros2_value(default_registry(), IMAGE, v))


class Ros2ImagePublisher:
    """A ROS 2 image publisher that takes ROS 1 bodies, as the graph's publisher does
    (``publish_body``, ``get_num_connections``): what lets the camera publish on ROS 2."""

    def __init__(self, node: Ros2Node, topic: str, qos: Qos = Qos()) -> None:
        self.pub = node.create_publisher(topic, IMAGE, qos)

    def publish_body(self, body: bytes | memoryview) -> None:
        self.pub.publish(ros1_frame_to_cdr(len(body).to_bytes(4, "little") + bytes(body)))

    def get_num_connections(self) -> int:
        return self.pub.matched()


def subscribe_ros1_bodies(node: Ros2Node, topic: str,
                          callback: Callable[[bytes, MessageInfo], None], qos: Qos = Qos()) -> None:
    """Subscribe to a ROS 2 image topic; ``callback`` gets each sample as a ROS 1 body and a
    :class:`~rosfpga_lab.graph.MessageInfo` (publisher: the writer's GUID), as a raw ROS 1
    subscriber's callback does (what lets the viewer read ROS 2)."""
    def on_sample(payload: bytes, sample: Sample) -> None:
        body = cdr_to_ros1_frame(payload, sample.seq)[4:]
        callback(body, MessageInfo(topic, sample.writer_guid.hex(), 0, sample.seq, len(body),
                                   time.time()))

    node.create_subscriber(topic, IMAGE, on_sample, qos)


def _record(payload: bytes) -> bytes:
    """What the RTPS reader's software writes into the circuit's byte FIFO for a sample: its
    4-byte length, then the payload."""
    return struct.pack("<I", len(payload)) + bytes(payload)


class Ros2Component:
    """The FPGA component on ROS 2: ``config``'s topics, DDS domain ``domain``.

    Samples are processed on the node's receive thread, one at a time (the circuit is one
    stream); KEEP_LAST ``qos.depth`` bounds what waits in the reader meanwhile (with
    ``timing="fpga"`` too: what comes while the circuit is busy waits there).

    Args:
        config: the node configuration (any type; read in its ROS 2 form).
        domain: the DDS domain.
        model: ``"fast"``, ``"reference"`` or ``"rtl"`` (the generated CDR top on Verilator's
            fast harness, see the module docstring).
        timing: ``"host"`` (publish as soon as the data path is done) or ``"fpga"`` (hold each
            output for the circuit's clocks at ``clock_mhz``).
        qos_in, qos_out: the input reader's and the output writer's QoS.
        name: the node's name instead of the configuration's.

    Raises:
        ComponentConfigError: an unknown model or timing, no model of the circuit (``op:
            custom``), or with ``"rtl"`` no Verilator or no generated circuit.
    """

    def __init__(self, config: NodeConfig | str | Path, *, domain: int = 0, model: str = "fast",
                 qos_in: Qos = Qos(), qos_out: Qos = Qos(), name: str | None = None,
                 timing: str = TIMINGS[0]) -> None:
        if not isinstance(config, NodeConfig):
            config = load_config(config)
        if model not in MODELS or timing not in TIMINGS:
            raise ComponentConfigError(f"model must be one of {', '.join(MODELS)} and timing one "
                                       f"of {', '.join(TIMINGS)}, got {model!r} and {timing!r}")
        # the Verilog first: its refusals (op: custom, no Verilator) name --model rtl
        self._rtl: Any = self._start_rtl(config) if model == RTL_MODEL else None
        try:   # with "rtl" the fast model still names the operation and refuses what it cannot
            self.pipeline = CdrPipeline(config, "fast" if model == RTL_MODEL else model)
        except LabError as exc:
            if self._rtl is not None:
                self._rtl.close()
            raise ComponentConfigError(f"cannot model this circuit: {exc}") from None
        self.model, self.timing = model, timing
        self._program: Any = self._walk(config) if timing == "fpga" and self._rtl is None else None
        self._clock_hz = config.clock_mhz * 1e6
        self._busy_until = 0.0      # time.time() when the circuit is free again (timing fpga)
        #: The circuit's clocks per published sample, beside :attr:`latencies` (0 unless the
        #: model is ``"rtl"`` or the timing ``"fpga"``).
        self.clocks: list[int] = []
        self.config, self.domain, self.qos_in, self.qos_out = config, domain, qos_in, qos_out
        self.namespace, self.name = split_node_name(name or config.node.global_name)
        self.input_topic, self.output_topic = config.subscriber.topic, config.publisher.topic
        self.counts = {"seen": 0, "published": 0, "refused": 0}
        self.latencies: list[float] = []
        self._cond = threading.Condition()
        self.node: Ros2Node | None = None
        self._pub: Ros2Publisher | None = None

    @staticmethod
    def _start_rtl(config: NodeConfig) -> Any:
        """The generated CDR top in its long-lived simulator (seconds to build the first time);
        a configuration without ``wire: cdr`` is read as the ROS 2 node reads it, on CDR."""
        import dataclasses

        from rosfpga_lab.rtl.server import RtlServer

        config = dataclasses.replace(config, wire=CDR_WIRE)
        log.info("building the Verilog of %s's CDR circuit on Verilator (seconds the first "
                 "time, then cached) ...", config.subscriber.type)
        try:
            return RtlServer(config)
        except LabError as exc:
            raise ComponentConfigError(f"cannot run the Verilog (--model rtl): {exc}") from None

    @staticmethod
    def _walk(config: NodeConfig) -> Any:
        """The generated CDR walk whose clocks are the timing of the Python models."""
        import dataclasses

        from rosfpga_lab.hls.generic import spec_from_config

        try:
            return spec_from_config(dataclasses.replace(config, wire=CDR_WIRE)).program
        except LabError as exc:
            raise ComponentConfigError(f"timing fpga needs the generated circuit: {exc}") from None

    def start(self) -> Ros2Component:
        self.node = Ros2Node(self.name, self.domain, namespace=self.namespace)
        reg = self.config.registry()
        self._pub = self.node.create_publisher(self.output_topic, self.config.publisher.type,
                                               self.qos_out, reg)
        self.node.create_subscriber(self.input_topic, self.config.subscriber.type,
                                    self._on_sample, self.qos_in, reg)
        log.info("%s: ROS 2 node in DDS domain %d (participant index %d): %s -> %s -> %s",
                 self.name, self.domain, self.node.index, self.input_topic, self.pipeline.op,
                 self.output_topic)
        return self

    def _on_sample(self, payload: bytes, sample: Sample) -> None:
        t0, arrived = time.perf_counter(), time.time()
        with self._cond:
            self.counts["seen"] += 1
        try:
            out, clocks = self._process_timed(payload)
        except LabError as exc:
            with self._cond:
                self.counts["refused"] += 1
                n = self.counts["refused"]
                self._cond.notify_all()
            if n <= 3:
                log.warning("%s: refused sample %d from %s: %s", self.name, sample.seq,
                            sample.writer_guid.hex(), exc)
            return
        self._hold(arrived, clocks)
        assert self._pub is not None
        self._pub.publish(out)
        with self._cond:
            self.counts["published"] += 1
            if len(self.latencies) < 10000:
                self.latencies.append(time.perf_counter() - t0)
                self.clocks.append(clocks)
            self._cond.notify_all()

    def _process(self, payload: bytes) -> bytes:
        """The sample through the CDR circuit (whose subscriber takes the zero bytes Cyclone DDS
        pads an XCDR1 payload with to a multiple of 4, announced or not)."""
        return self._process_timed(payload)[0]

    def _process_timed(self, payload: bytes) -> tuple[bytes, int]:
        """The output payload and the circuit's clocks for it (0 when nobody asked for them).

        Raises:
            LabError: the circuit refused the sample (the models' ``FrameFieldError``, the
                RTL's status as an ``RtlError``), or the simulator failed.
        """
        if self._rtl is None:
            out = self.pipeline.process(payload)
            if self._program is None:
                return out, 0
            from rosfpga_lab.hls.program import Refused, frame_clocks

            try:
                return out, frame_clocks(self._program, _record(payload)).total
            except Refused:     # the walk and the model disagree: the model's II=1 clocks
                return out, sum(self.pipeline.run(payload).cycles.values())
        from rosfpga_lab.rtl.errors import RtlError

        got = self._rtl.process(_record(payload))
        refused = [code for _, code in got.status if code]
        if refused:
            name, field = got.name(refused[0])
            raise RtlError(f"circuit status {refused[0]} ({name}): bad {field}")
        if len(got.output) < 4:
            raise RtlError("the circuit sent nothing for the sample")
        return got.output[4:], got.span

    def _hold(self, arrived: float, clocks: int) -> None:
        """Timing ``fpga``: wait until ``clocks`` at the circuit's clock have passed since the
        sample arrived (or since the circuit became free)."""
        if self.timing != "fpga":
            return
        done = max(arrived, self._busy_until) + clocks / self._clock_hz
        self._busy_until = done
        left = done - time.time()
        if left > 0:
            time.sleep(left)

    def wait_for_peers(self, timeout: float = 10.0) -> bool:
        """Until the input has a matched writer and the output a matched reader."""
        assert self.node is not None and self._pub is not None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            subs = self.node._subs.values()
            if self._pub.matched() and all(s.matched() for s in subs):
                return True
            time.sleep(0.01)
        return False

    def wait_for(self, frames: int, timeout: float = 10.0) -> bool:
        """Until ``frames`` samples were published or refused."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self.counts["published"] + self.counts["refused"] < frames:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def notes(self) -> list[str]:
        return self.node.notes() if self.node else []

    def stop(self) -> None:
        if self.node is not None:
            self.node.close()
            self.node = None
        if self._rtl is not None:
            self._rtl.close()

    def __enter__(self) -> Ros2Component:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
