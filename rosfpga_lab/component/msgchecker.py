"""Check a component of any message type: every output must be the oracle's answer to an input.

How this works: :class:`MessageChecker` subscribes to the component's input *and* output
topics. For every input it computes, with the ``msg`` layer's deserializer and numpy alone (not
the lab's circuit models), the message the circuit must publish: the input with the streamed
array replaced by its sliding maximum (``dilate``) or minimum (``erode``) over ``ksize``
elements, folded left to right with ``np.maximum``/``np.minimum`` over the in-array part of
the window (or unchanged for ``passthrough``), and every skipped field at its default. Each
output body must equal one of the expected bodies (bit for bit); inputs the circuit refuses
simply never match (the component counts them). Expected bodies are kept for the last
``limits.CHECKER_PENDING`` inputs.
"""

from __future__ import annotations

import functools
import threading
import time
from typing import Any

import numpy as np

from rosfpga_lab.component import limits
from rosfpga_lab.component.errors import ComponentError
from rosfpga_lab.config import PASSTHROUGH, NodeConfig, canonical_op
from rosfpga_lab.graph import EmbeddedMaster, MessageInfo, Node
from rosfpga_lab.msg import default_value, deserialize, serialize


def expected_stream(values: np.ndarray, op: str, ksize: int) -> np.ndarray:
    """The oracle's application: numpy's fold over each in-array window, one output at a time."""
    op = canonical_op(op)
    if op == PASSTHROUGH:
        return values
    fold = {"dilate": np.maximum, "erode": np.minimum}.get(op)
    if fold is None:
        raise ComponentError(f"no oracle for op {op!r}")
    r = ksize // 2
    n = len(values)
    return np.array([functools.reduce(fold, values[max(0, i - r):min(n, i + r + 1)])
                     for i in range(n)], values.dtype).reshape(n)


def _set(message: dict[str, Any], path: str, value: Any) -> None:
    *parents, last = path.split(".")
    for name in parents:
        message = message[name]
    message[last] = value


def _get(message: dict[str, Any], path: str) -> Any:
    for name in path.split("."):
        message = message[name]
    return message


class MessageChecker:
    """Checks a running component of a non-Image configuration (see module docstring).

    Args:
        config: the component's configuration (same input and output type).
        name, master, master_uri, host: as for :class:`rosfpga_lab.graph.Node`.

    Attributes:
        inputs, outputs, bit_exact: counts so far; ``mismatches``: the first few problems.
    """

    def __init__(self, config: NodeConfig, *, name: str = "/msg_checker",
                 master: EmbeddedMaster | None = None, master_uri: str | None = None,
                 host: str | None = None) -> None:
        if config.subscriber.type != config.publisher.type or config.stream is None:
            raise ComponentError("the checker needs the same input and output type")
        self.config = config
        self.registry = config.registry()
        self.type_name = config.subscriber.type
        self.inputs = self.outputs = self.bit_exact = 0
        self.mismatches: list[str] = []
        self._expected: dict[bytes, int] = {}
        self._cond = threading.Condition()
        self.node = Node(name, master_uri, host, master=master, registry=self.registry)
        try:
            self.node.subscribe(config.subscriber.topic, self.type_name, self._on_input,
                                raw=True, queue_size=0)
            self.node.subscribe(config.publisher.topic, self.type_name, self._on_output,
                                raw=True, queue_size=0)
        except BaseException:
            self.node.shutdown()
            raise

    def expected_body(self, body: bytes) -> bytes:
        """The body the circuit must publish for input ``body``."""
        assert self.config.stream is not None
        msg = deserialize(self.registry, self.type_name, body)
        field = self.config.stream.field
        app = self.config.application
        _set(msg, field, expected_stream(np.asarray(_get(msg, field)), app.op, app.ksize))
        for path in self.config.skip:
            *parents, last = path.split(".")
            spec = self.registry.check(self.type_name)
            for name in parents:
                spec = self.registry.check(next(f for f in spec.fields if f.name == name).base_type)
            f = next(f for f in spec.fields if f.name == last)
            _set(msg, path, default_value(self.registry, f))
        return serialize(self.registry, self.type_name, msg)

    def _on_input(self, body: bytes | memoryview, info: MessageInfo) -> None:
        try:
            want = self.expected_body(bytes(body))
        except Exception as exc:  # a body the msg layer refuses: the circuit refuses it too
            want = b""
            self._note(f"input #{info.index} from {info.publisher}: {exc}")
        with self._cond:
            self.inputs += 1
            if want:
                self._expected[want] = info.index
                while len(self._expected) > limits.CHECKER_PENDING:
                    del self._expected[next(iter(self._expected))]
            self._cond.notify_all()

    def _on_output(self, body: bytes | memoryview, info: MessageInfo) -> None:
        data = bytes(body)
        deadline = time.monotonic() + 2.0  # the input may reach us a moment after the output
        with self._cond:
            while data not in self._expected and time.monotonic() < deadline:
                self._cond.wait(0.05)
            self.outputs += 1
            if self._expected.pop(data, None) is not None:
                self.bit_exact += 1
            else:
                self._note(f"output #{info.index} ({len(data)} bytes) is the expected output of "
                           "no input seen")
            self._cond.notify_all()

    def _note(self, text: str) -> None:
        if len(self.mismatches) < 50:
            self.mismatches.append(text)

    def wait_for(self, outputs: int, timeout: float) -> bool:
        """Wait until ``outputs`` outputs were checked; False on time-out."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self.outputs < outputs:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def stop(self) -> None:
        """Unsubscribe and shut the node down."""
        self.node.shutdown()
