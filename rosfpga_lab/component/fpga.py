"""The ROS-compliant FPGA component, emulated: a ROS node whose TCPROS data path is the circuit.

How this works (Figure 3 of the paper): the *software* side is an ordinary
:class:`rosfpga_lab.graph.Node`. It registers with the master (embedded or real) as
subscriber of the input topic and publisher of the output topic, answers the Slave API and
runs the TCPROS handshakes. The *hardware* side is the data path: every complete TCPROS frame
the subscriber reads (the raw bytes, never deserialized in software) goes through the
modelled circuit -- :class:`rosfpga_lab.hw.msgpipeline.MessagePipeline`, the walkers rendered
from the circuit record the generator renders too (:func:`rosfpga_lab.hls.circuit.circuit_of`
of the same node configuration; ``sensor_msgs/Image`` is one type among the others, its
``data`` filtered as a picture) -- and the frame the circuit's publisher writes is sent, as
bytes, to every subscriber.

Queues (drop policy, as roscpp's): frames wait in front of the circuit in the subscriber's
queue (``input_queue`` deep; when the circuit is busy and it is full, the oldest waiting frame
is dropped and counted) and behind it in one queue per downstream subscriber
(``output_queue``; a subscriber too slow for the rate loses the oldest frames, the others are
not held back). A frame the circuit refuses (wrong size, encoding, truncated) is counted under
its reason and logged; the pipeline has reset itself and the next good frame comes out right.
A monitor thread checks once a second that the master still knows the node (registering it
again after a master restart, keeping the established input connections:
:meth:`rosfpga_lab.graph.Node.register_again`) and logs what changed: drops by either queue, publishers and
subscribers coming and going.

Observe it live with :meth:`FpgaComponent.add_observer` (called with a :class:`FrameRecord`
for every frame, in the component's thread: keep it short) or :attr:`FpgaComponent.recent`
(the last few records).
"""

from __future__ import annotations

import collections
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rosfpga_lab.component import limits
from rosfpga_lab.component.errors import ComponentConfigError, ComponentError, ComponentShutDown
from rosfpga_lab.component.stats import ComponentStats, LatencyWindow, fps_meter, since_stamp
from rosfpga_lab.config import NodeConfig, load_config
from rosfpga_lab.config import master_uri as pick_master_uri
from rosfpga_lab.config.limits import IMAGE_TYPE
from rosfpga_lab.config.vocabulary import CDR_WIRE, MODELS, RTL_MODEL, TIMINGS
from rosfpga_lab.errors import LabError
from rosfpga_lab.graph import EmbeddedMaster, MessageInfo, Node, call
from rosfpga_lab.hls.circuit import Circuit, circuit_of
from rosfpga_lab.hls.program import Refused
from rosfpga_lab.hw.errors import FrameFieldError, PipelineError
from rosfpga_lab.hw.layoutsteps import StepKind
from rosfpga_lab.hw.msgpipeline import MessagePipeline, MessageResult

log = logging.getLogger("rosfpga_lab.component")



@dataclass(frozen=True)
class FrameRecord:
    """One frame through the component (what a live view shows).

    Attributes:
        index: frames seen by the circuit so far, counting from 0 (refused ones included).
        input_frame: the TCPROS frame received (4-byte length + message body).
        output_frame: the frame published (empty when refused).
        result: the model's :class:`~rosfpga_lab.hw.msgpipeline.MessageResult` (its
            ``input_image``/``output_image`` for Image); None when refused.
        error: the refusal reason (empty when the frame went through).
        publisher: callerid of the node that sent the frame.
        received: ``time.time()`` when the frame was complete on the input connection.
        published: ``time.time()`` when the output was handed to the publisher.
    """

    index: int
    input_frame: bytes
    output_frame: bytes
    result: MessageResult | None
    error: str
    publisher: str
    received: float
    published: float

    @property
    def ok(self) -> bool:
        """True when the circuit took the frame (False: refused, see :attr:`error`). With
        ``model="rtl"`` :attr:`result` is None either way: the Verilog, not a model, ran."""
        return not self.error

    @property
    def latency(self) -> float:
        """Seconds from receive-complete to publish."""
        return self.published - self.received

    @property
    def input_image(self) -> np.ndarray | None:
        return None if self.result is None else self.result.input_image

    @property
    def output_image(self) -> np.ndarray | None:
        return None if self.result is None else self.result.output_image


def master_answers(uri: str, timeout: float = 2.0) -> bool:
    """True when a ROS master (or any ROS XML-RPC server) answers ``getPid`` at ``uri``."""
    try:
        call(uri, "getPid", "/rosfpga_lab_probe", timeout=timeout)
        return True
    except LabError:
        return False


def _reason(exc: PipelineError) -> str:
    text = str(exc)
    if isinstance(exc, FrameFieldError):
        return f"{exc.field}: {text}"
    return text


def refusal_kind(exc: PipelineError) -> str:
    """What a refusal is counted under: ``"field: rule"`` for a bad field (the same for every
    value that broke the rule), else the stage and the error's class."""
    if isinstance(exc, FrameFieldError):
        return exc.kind
    return f"{exc.stage or 'pipeline'}: {type(exc).__name__}"


def _check_arguments(config: NodeConfig, model: str, timing: str, input_queue: int,
                     output_queue: int) -> None:
    """Refuse what the component cannot run, before anything is built.

    Raises:
        ComponentConfigError: ``image:`` with another type than Image (or an Image subscriber
            publishing another type), an unknown model or timing, ``--model rtl`` on a CDR
            configuration, a queue shorter than one.
    """
    if config.is_image != (config.subscriber.type == IMAGE_TYPE):
        raise ComponentConfigError(
            f"subscriber.type is {config.subscriber.type!r} but image: is given: image: is "
            f"for {IMAGE_TYPE} only")
    if config.is_image and config.publisher.type != IMAGE_TYPE:
        raise ComponentConfigError(
            f"publisher.type is {config.publisher.type!r}: the video path publishes "
            f"{IMAGE_TYPE} only")
    if model not in MODELS:
        raise ComponentConfigError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    if timing not in TIMINGS:
        raise ComponentConfigError(f"timing must be one of {', '.join(TIMINGS)}, got {timing!r}")
    if model == RTL_MODEL and config.wire == CDR_WIRE:
        raise ComponentConfigError(
            f"{config.path or 'the configuration'} has wire: cdr, whose circuit reads CDR "
            "samples (ROS 2); this ROS 1 node feeds its circuit TCPROS frames: for --model "
            "rtl run this one as a ROS 2 node (node CONFIG --ros2 --model rtl), or use a copy "
            "with wire: tcpros (or leave wire out)")
    if input_queue < 1 or output_queue < 1:
        raise ComponentConfigError("input_queue and output_queue must be at least 1")


class FpgaComponent:
    """The FPGA node: software registration and handshakes, the modelled circuit on the data path.

    Args:
        config: the node configuration (as :func:`rosfpga_lab.config.load_config` returns it).
        master_uri: the master to use instead of the configuration's ``node.master_uri``.
        master: an :class:`~rosfpga_lab.graph.EmbeddedMaster` to use (overrides both).
        model: ``"fast"`` (numpy), ``"reference"`` (one byte or beat at a time; small images)
            or ``"rtl"`` (the Verilog itself, in a long-lived simulator:
            :mod:`rosfpga_lab.rtl.server`: the generated top ``rosfpga-lab generate`` writes,
            for every type; TCPROS configurations only: ``wire: cdr`` is refused here and runs
            as a ROS 2 node, :class:`~rosfpga_lab.component.ros2.Ros2Component`).
        timing: ``"host"`` (publish as soon as the data path is done) or ``"fpga"`` (publish
            when the circuit's clocks for the frame at ``clock_mhz`` have passed since it
            arrived, or since the circuit became free -- the generated circuit's walk
            (:meth:`rosfpga_lab.hls.circuit.Circuit.frame_clocks`), or with ``"rtl"`` the
            simulated clocks; the input queue is then 1 deep, as the
            input FIFO and the socket hold one waiting frame: a newer frame replaces it and the
            older one is counted in :attr:`ComponentStats.dropped_input`).
        input_queue: frames waiting in front of the circuit (see module docstring).
        output_queue: frames waiting per downstream subscriber.
        history: records kept in :attr:`recent`.
        name: node name instead of the configuration's ``node.name``.
        host: address to bind and advertise instead of ``node.ip_address``.
        input_topic, output_topic: topic names instead of the configuration's (after a ROS
            remapping: :func:`rosfpga_lab.config.rosargs.component_names`).
        trace: a :class:`~rosfpga_lab.graph.Trace` to record the conversation into.
        watchdog: check the master once a second and register again after a restart (the
            monitor thread runs either way, logging drops and connections).

    Raises:
        ComponentConfigError: the configuration cannot be run (``op: custom``).

    Every type, ``sensor_msgs/Image`` included, runs the circuit rendered from its layout,
    :class:`~rosfpga_lab.hw.msgpipeline.MessagePipeline` (an Image's ``data`` through the 2-D
    application, ``header.seq`` numbered by the publisher).
    """

    def __init__(self, config: NodeConfig, *, master_uri: str | None = None,
                 master: EmbeddedMaster | None = None, model: str = "fast",
                 timing: str = "host", input_queue: int = limits.DEFAULT_INPUT_QUEUE,
                 output_queue: int = limits.DEFAULT_OUTPUT_QUEUE,
                 history: int = limits.DEFAULT_HISTORY, name: str | None = None,
                 host: str | None = None, trace: Any = None, watchdog: bool = True,
                 input_topic: str | None = None, output_topic: str | None = None) -> None:
        _check_arguments(config, model, timing, input_queue, output_queue)
        self._build_circuit(config, model)
        self.timing = timing
        self._clock_hz = config.clock_mhz * 1e6
        self._busy_until = 0.0      # time.time() when the circuit is free again (timing fpga)
        if timing == "fpga":   # what waits in front of the board: one frame (see above)
            input_queue = 1
        self.config = config
        self.model = model
        self.master = master
        # the Python API takes the file's master, not ROS_MASTER_URI (commands add the environment)
        self.master_uri = master.uri if master is not None else pick_master_uri(
            master_uri, config, environ={})
        self.name = name or config.node.global_name
        self.host = host or config.node.ip_address
        self.input_topic = input_topic or config.subscriber.topic
        self.output_topic = output_topic or config.publisher.topic
        self.input_queue, self.output_queue = input_queue, output_queue
        self.trace = trace
        self.watchdog = watchdog
        pixels = config.image.width * config.image.height if config.is_image else 0
        if model == "reference" and pixels > limits.REFERENCE_WARN_PIXELS:
            log.warning("reference model with %dx%d frames: expect seconds per frame; "
                        "use model='fast' for real-time rates", config.image.width,
                        config.image.height)
        self.recent: collections.deque[FrameRecord] = collections.deque(maxlen=max(1, history))
        self._observers: list[Callable[[FrameRecord], Any]] = []
        self._lock = threading.Lock()
        self._latency = LatencyWindow(limits.LATENCY_WINDOW)
        self._process = LatencyWindow(limits.LATENCY_WINDOW)
        self._since_stamp = LatencyWindow(limits.LATENCY_WINDOW)
        self._published_rate = fps_meter()
        self._counts = {"seen": 0, "processed": 0, "published": 0, "refused": 0,
                        "reregistered": 0, "observer_errors": 0}
        self._last_clocks = 0
        self._reasons: dict[str, int] = {}        # refusal kind -> count
        self._examples: dict[str, str] = {}       # refusal kind -> the first reason text seen
        self._high_water: dict[str, int] = {}
        self._last: MessageResult | None = None
        self._last_error = ""
        self._master_ok = True
        self._name_taken = False
        self._done = threading.Condition(self._lock)
        self._stop = threading.Event()
        self._watch: threading.Thread | None = None
        self.node: Node | None = None
        self._pub: Any = None
        self._sub: Any = None

    def _build_circuit(self, config: NodeConfig, model: str) -> None:
        """The circuit's models, from its record (:func:`~rosfpga_lab.hls.circuit.circuit_of`):
        the Python model (with ``model="rtl"`` the fast model still names the operation and
        sets its limits), the generated walk, whose clocks per frame are the timing (a
        configuration the generator refuses, e.g. another publisher type, keeps the model's
        stages' sum), and with ``model="rtl"`` the Verilog."""
        try:
            self.circuit: Circuit = circuit_of(config)
            self.registry = self.circuit.reg
            pmodel = "fast" if model == RTL_MODEL else model
            self.pipeline: MessagePipeline = self.circuit.model(pmodel)
        except LabError as exc:
            raise ComponentConfigError(f"cannot model this circuit: {exc}") from None
        self._timed = self._has_generated_walk()
        self._shape_clocks: dict[tuple[int, ...], int] = {}
        self._rtl: Any = None
        if model == RTL_MODEL:
            from rosfpga_lab.rtl.server import RtlServer

            log.info("building the Verilog of %s's circuit on Verilator (seconds the first "
                     "time, then cached) ...", config.subscriber.type)
            try:
                self._rtl = RtlServer(config)
            except LabError as exc:
                raise ComponentConfigError(f"cannot run the Verilog (--model rtl): {exc}") from None

    def _has_generated_walk(self) -> bool:
        """Whether the generator renders this configuration (its walk then times the frames)."""
        try:
            return self.circuit.program is not None
        except LabError:
            return False

    @classmethod
    def from_config(cls, config: str | Path | NodeConfig, master_uri: str | None = None,
                    model: str = "fast", **kwargs: Any) -> FpgaComponent:
        """Build the component from a node configuration file (or a loaded one).

        Args:
            config: path of the YAML file the generator reads, or a :class:`NodeConfig`.
            master_uri, model, kwargs: as for :class:`FpgaComponent`.

        Raises:
            ConfigError: the file is not a valid node configuration.
            ComponentConfigError: it cannot be run as a component.
        """
        if not isinstance(config, NodeConfig):
            config = load_config(config)
        return cls(config, master_uri=master_uri, model=model, **kwargs)

    # ------------------------------------------------------------------ life cycle
    @property
    def running(self) -> bool:
        return self.node is not None and not self.node.is_shutdown

    def start(self) -> FpgaComponent:
        """Register with the master, subscribe to the input, advertise the output.

        Raises:
            GraphError: the master cannot be reached or refused (nothing is left running).
            ComponentShutDown: a remote ``shutdown`` came while it was registering.
        """
        if self.node is not None:
            raise ComponentError(f"component {self.name} was already started")
        kw: dict[str, Any] = {"master": self.master} if self.master is not None else {
            "master_uri": self.master_uri}
        if self.trace is not None:
            kw["trace"] = self.trace
        node = Node(self.name, host=self.host, xmlrpc_port=self.config.node.xmlrpc_port,
                    tcpros_port=self.config.node.tcpros_port, registry=self.registry, **kw)
        node.watch_master = False   # check_master below watches (and reports) for the component
        try:
            self._pub = node.advertise(self.output_topic, self.config.publisher.type,
                                       queue_size=self.output_queue)
            self._sub = node.subscribe(self.input_topic, self.config.subscriber.type, self._on_frame,
                                       raw=True, queue_size=self.input_queue, tcp_nodelay=True)
        except BaseException:
            remote = node.is_shutdown and node.shutdown_reason   # shut down while starting
            node.shutdown()
            node.wait_for_shutdown(limits.SHUTDOWN_WAIT)   # a remote one unregisters in a thread
            if remote:
                raise ComponentShutDown(f"{self.name} was shut down from outside while it started "
                                        f"({remote})", remote) from None
            raise
        self.node = node
        self._stop.clear()
        self._watch = threading.Thread(target=self._watch_loop, daemon=True,
                                       name=f"rosfpga-component-monitor-{self.name}")
        self._watch.start()
        log.info("%s: %s -> %s circuit (%s model) -> %s; master %s", self.name, self.input_topic,
                 self.pipeline.op, self.model, self.output_topic, self.master_uri)
        return self

    def stop(self) -> None:
        """Unregister, close every connection, join every thread (idempotent)."""
        self._stop.set()
        if self._watch is not None and self._watch is not threading.current_thread():
            self._watch.join(5.0)
        if self.node is not None:
            self.node.shutdown("component stopped")
        if self._rtl is not None:
            self._rtl.close()

    def __enter__(self) -> FpgaComponent:
        if self.node is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def __repr__(self) -> str:
        state = "running" if self.running else "stopped"
        return (f"<FpgaComponent {self.name} {self.input_topic} -> {self.pipeline.op} -> "
                f"{self.output_topic} {state}>")

    # ------------------------------------------------------------------ observers
    def add_observer(self, callback: Callable[[FrameRecord], Any]) -> None:
        """Call ``callback(record)`` after every frame (in the component's thread; keep it short)."""
        with self._lock:
            self._observers.append(callback)

    def remove_observer(self, callback: Callable[[FrameRecord], Any]) -> None:
        """Stop calling ``callback``."""
        with self._lock:
            if callback in self._observers:
                self._observers.remove(callback)

    # ------------------------------------------------------------------ the data path
    def _clocks(self, frame: bytes, result: MessageResult) -> int:
        """The circuit's clocks for ``frame``: the generated walk's, first byte in to last byte
        out (:meth:`~rosfpga_lab.hls.circuit.Circuit.frame_clocks`, equal to the RTL's clock
        for clock); without a generated walk the model's stages' sum.

        The walk takes a byte per clock and a fixed number of clocks per decision, so a frame's
        clocks follow from its shape (the counts of its strings and arrays: where each field
        lies), never from its values: they are computed once per shape (a 640x480 frame's walk
        takes milliseconds in Python; the board's frame time is what ``--timing fpga`` waits).
        """
        if not self._timed:
            return result.total_cycles
        shape = (len(frame), *(t.value for t in result.extracted.tokens
                               if self.pipeline.layout.steps[t.step].kind is StepKind.LENGTH))
        clocks = self._shape_clocks.get(shape)
        if clocks is not None:
            return clocks
        try:
            clocks = self.circuit.frame_clocks(frame).total
        except Refused:     # the walk and the model disagree: keep the model's stages' sum
            return result.total_cycles
        if len(self._shape_clocks) >= limits.MAX_TIMED_SHAPES:
            self._shape_clocks.clear()
        self._shape_clocks[shape] = clocks
        return clocks

    def _hold(self, info: MessageInfo, clocks: int) -> None:
        """Timing ``fpga``: wait until ``clocks`` at the circuit's clock have passed since the
        frame arrived (or since the circuit became free)."""
        if clocks:
            self._last_clocks = clocks
        if self.timing != "fpga":
            return
        with self._lock:   # one circuit, whichever connection the frame came on
            done = max(info.received, self._busy_until) + clocks / self._clock_hz
            self._busy_until = done
        left = done - time.time()
        if left > 0:
            time.sleep(left)

    def _on_frame(self, body: bytes | memoryview, info: MessageInfo) -> None:
        frame = len(body).to_bytes(4, "little") + body
        if self._rtl is not None:
            self._on_frame_rtl(frame, info)
            return
        t0 = time.perf_counter()
        try:
            result = self.pipeline.process(frame)
        except PipelineError as exc:
            self._hold(info, 0)
            self._refuse(exc, frame, info)
            return
        t1 = time.perf_counter()
        self._hold(info, self._clocks(frame, result))
        self._pub.publish_body(memoryview(result.output_frame)[4:])
        now = time.time()
        for problem in result.status:
            log.warning("%s: frame from %s passed with a problem: %s", self.name, info.publisher,
                        problem)
        self._latency.add(now - info.received)
        self._process.add(t1 - t0)
        stamp = result.stamp
        from_stamp = since_stamp(now, *stamp) if stamp is not None else None
        if from_stamp is not None:  # a wall-clock stamp (a camera's)
            self._since_stamp.add(from_stamp)
        with self._lock:
            index = self._counts["seen"]
            self._counts["seen"] += 1
            self._counts["processed"] += 1
            self._counts["published"] += 1
            self._published_rate.tick()
            self._last = result
            for fifo, level in result.fifo_high_water.items():
                self._high_water[fifo] = max(level, self._high_water.get(fifo, 0))
            self._done.notify_all()
        self._observe(FrameRecord(index, frame, result.output_frame, result, "", info.publisher,
                                  info.received, now))

    def _on_frame_rtl(self, frame: bytes, info: MessageInfo) -> None:
        """The simulated Verilog on the data path: its bytes are published, its status codes
        are the refusal reasons."""
        t0 = time.perf_counter()
        got = self._rtl.process(frame)
        t1 = time.perf_counter()
        refused = [code for _, code in got.status if code]
        if refused or not got.output:
            self._hold(info, got.clocks)
            code = refused[0] if refused else -1
            if code >= 0:
                name, field = got.name(code)
                self._count_refusal(f"circuit status {code} ({name}): bad {field}",
                                    f"circuit status {code}: {name}", frame, info)
            else:
                self._count_refusal("the circuit sent nothing (the frame was cut short)",
                                    "circuit: no output", frame, info)
            return
        self._hold(info, got.span)
        self._pub.publish_body(memoryview(got.output)[4:])
        now = time.time()
        self._latency.add(now - info.received)
        self._process.add(t1 - t0)
        with self._lock:
            index = self._counts["seen"]
            self._counts["seen"] += 1
            self._counts["processed"] += 1
            self._counts["published"] += 1
            self._published_rate.tick()
            self._done.notify_all()
        self._observe(FrameRecord(index, frame, got.output, None, "", info.publisher,
                                  info.received, now))

    def _refuse(self, exc: PipelineError, frame: bytes, info: MessageInfo) -> None:
        self._count_refusal(_reason(exc), refusal_kind(exc), frame, info)

    def _count_refusal(self, reason: str, kind: str, frame: bytes, info: MessageInfo) -> None:
        with self._lock:
            self._counts["seen"] += 1
            self._counts["refused"] += 1
            if kind not in self._reasons and len(self._reasons) >= limits.MAX_REFUSAL_KINDS:
                kind = "other"
            n = self._reasons[kind] = self._reasons.get(kind, 0) + 1
            self._examples.setdefault(kind, reason)
            self._last_error = f"refused a frame from {info.publisher}: {reason}"
            index = self._counts["seen"] - 1
            self._done.notify_all()
        if n <= limits.LOG_FIRST or n % limits.LOG_EVERY == 0:
            log.warning("%s: refused frame #%d from %s (%d so far of this kind: %s): %s",
                        self.name, info.index, info.publisher, n, kind, reason)
        self._observe(FrameRecord(index, frame, b"", None, reason, info.publisher, info.received,
                                  time.time()))

    def _observe(self, record: FrameRecord) -> None:
        self.recent.append(record)
        with self._lock:
            observers = list(self._observers)
        for callback in observers:
            try:
                callback(record)
            except Exception as exc:  # an observer must never stop the data path
                with self._lock:
                    self._counts["observer_errors"] += 1
                log.warning("%s: observer %r raised %s: %s", self.name, callback,
                            type(exc).__name__, exc)

    # ------------------------------------------------------------------ master watchdog
    def _watch_loop(self) -> None:
        before = self.stats
        while not self._stop.wait(limits.WATCHDOG_PERIOD):
            node = self.node
            if node is None or node.is_shutdown:
                return
            if self.watchdog:
                try:
                    self.check_master()
                except LabError as exc:
                    if self._master_ok:
                        log.warning("%s: master %s unreachable: %s (will keep trying)", self.name,
                                    self.master_uri, exc)
                    self._master_ok = False
            now = self.stats
            self._log_changes(before, now)
            before = now

    def _log_changes(self, old: ComponentStats, new: ComponentStats) -> None:
        if new.dropped_input > old.dropped_input:
            log.warning("%s: dropped %d input frame(s): input queue full (%d deep), the circuit "
                        "was busy; the oldest waiting frame goes", self.name,
                        new.dropped_input - old.dropped_input, self.input_queue)
        for peer, n in new.dropped_output_by_peer.items():
            if n > old.dropped_output_by_peer.get(peer, 0):
                log.warning("%s: dropped %d output frame(s) for subscriber %s: its queue (%d "
                            "deep) is full, it is too slow for the rate", self.name,
                            n - old.dropped_output_by_peer.get(peer, 0), peer, self.output_queue)
        fresh = [e for e in new.connection_errors if e not in old.connection_errors]
        for problem in fresh[-3:]:
            log.warning("%s: input connection problem: %s", self.name, problem)
        if new.publishers != old.publishers:
            log.info("%s: %d publisher(s) of %s connected (was %d)", self.name, new.publishers,
                     self.input_topic, old.publishers)
        if new.subscribers != old.subscribers:
            log.info("%s: %d subscriber(s) of %s connected (was %d)", self.name, new.subscribers,
                     self.output_topic, old.subscribers)

    def check_master(self) -> bool:
        """Ask the master whether it knows this node; register again if it does not.

        Returns:
            True when the node had to register again (the master restarted).

        Raises:
            GraphError: the master cannot be reached.
        """
        node = self.node
        if node is None:
            raise ComponentError("component not started")
        reply = call(self.master_uri, "lookupNode", self.name, self.name, timeout=2.0)
        self._master_ok = True
        if isinstance(reply, list) and len(reply) == 3 and reply[0] == 1:
            if reply[2] != node.uri and not self._name_taken:
                # Another node took the name: ROS's rule is that the newer one wins (the master
                # shuts the older down), so never register again over it.
                self._name_taken = True
                log.error("%s: another node (%s) registered under this name; not registering "
                          "again", self.name, reply[2])
            return False
        node.register_again()   # established input links stay up (the camera keeps streaming)
        with self._lock:
            self._counts["reregistered"] += 1
        log.warning("%s: the master %s did not know this node (restarted?); registered again",
                    self.name, self.master_uri)
        return True

    # ------------------------------------------------------------------ figures
    @property
    def stats(self) -> ComponentStats:
        """A snapshot of the counters (see :class:`ComponentStats`)."""
        sub_stats = self._sub.stats if self._sub is not None else None
        pub_stats = self._pub.stats if self._pub is not None else None
        by_peer: dict[str, int] = {}
        if pub_stats is not None:
            for link in pub_stats.links:
                if link.drops:
                    by_peer[link.peer] = by_peer.get(link.peer, 0) + link.drops
        with self._lock:
            c = dict(self._counts)
            fps = self._published_rate.rate()
            last = self._last
            return ComponentStats(
                received=sub_stats.frames if sub_stats else 0,
                processed=c["processed"], published=c["published"], refused=c["refused"],
                refused_reasons=dict(self._reasons), refused_examples=dict(self._examples),
                dropped_input=sub_stats.drops if sub_stats else 0,
                dropped_output=sum(by_peer.values()), dropped_output_by_peer=by_peer,
                subscribers=pub_stats.connections if pub_stats else 0,
                publishers=sub_stats.connections if sub_stats else 0,
                latency=self._latency.summary(), process_time=self._process.summary(),
                since_stamp=self._since_stamp.summary(),
                circuit_time_s=(self._last_clocks / self._clock_hz if self._last_clocks
                                else float("nan")),
                timing=self.timing, model=self.model,
                cycles=dict(last.cycles) if last is not None else {},
                fifo_high_water=dict(self._high_water), fps=fps,
                master_reregistrations=c["reregistered"], master_ok=self._master_ok,
                observer_errors=c["observer_errors"], last_error=self._last_error,
                connection_errors=list(sub_stats.errors) if sub_stats else [])

    def latency_samples(self) -> list[float]:
        """The kept receive-to-publish latencies (seconds), oldest first."""
        return self._latency.samples()

    def wait_for_subscribers(self, n: int = 1, timeout: float = 10.0) -> bool:
        """Wait until ``n`` subscribers are connected to the output; False on time-out."""
        return self._pub is not None and self._pub.wait_for_subscribers(n, timeout)

    def wait_for_publishers(self, n: int = 1, timeout: float = 10.0) -> bool:
        """Wait until ``n`` publishers of the input are connected; False on time-out."""
        return self._sub is not None and self._sub.wait_for_connection(n, timeout)

    def wait_for(self, frames: int, timeout: float = 10.0) -> bool:
        """Wait until the circuit has handled ``frames`` frames (published + refused).

        Returns:
            False on time-out.
        """
        deadline = time.monotonic() + timeout
        with self._done:
            while self._counts["seen"] < frames:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._done.wait(left)
        return True
