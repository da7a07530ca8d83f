"""The Verilog on a live data path: one long-lived simulator process fed whole frames.

How this works: :class:`RtlServer` builds (or takes from the cache) the fast harness of
:mod:`rosfpga_lab.rtl.sim` for a node configuration -- the generated top of every type,
``sensor_msgs/Image`` included, the same ``rtl/`` ``rosfpga-lab generate`` writes and its
``make rtlsim`` runs (:func:`rosfpga_lab.rtl.sim.design_from_config`) -- and starts it once in
serve mode (``rfl_fast --serve``). Each :meth:`RtlServer.process` call writes one request
(``RFLQ``, the length, the TCPROS frame) to its standard input and reads the reply (``RFLR``:
flags, clocks, span, the statuses the subscriber decided and the bytes the circuit sent). The
circuit keeps its state between frames, as the board does (the publisher's sequence number
counts on).

On ``wire: cdr`` the same server runs the generated CDR top, and a request is one or more
records as the RTPS reader's software writes them into the circuit's byte FIFO (the 4-byte
sample length, then the CDR payload); the reply's bytes are the publisher's records (length,
payload): what the ROS 2 node runs with ``--model rtl``
(:class:`rosfpga_lab.component.ros2.Ros2Component`).
"""

from __future__ import annotations

import struct
import subprocess
import threading
from dataclasses import dataclass, field
from typing import IO

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.errors import RtlError, SimulatorMissingError
from rosfpga_lab.rtl.limits import IDLE_LIMIT, MAX_SERVE_FRAME
from rosfpga_lab.rtl.sim import RtlBuild, build, design_from_config, simulator_missing_reason

_REPLY = struct.Struct("<4sIQQII")


@dataclass(frozen=True)
class RtlFrame:
    """What the circuit did with one request.

    Attributes:
        output: the bytes it sent (a TCPROS frame, or nothing when it refused the frame).
        status: ``(offset in the request, code)`` per frame the subscriber decided on.
        clocks: clocks simulated for the request (until the circuit was idle again).
        span: clocks from the first byte into the subscriber to the last byte out (0 without
            output): the frame's time on the board at ``clock_mhz``.
        cut_short: the request ended inside a frame (the circuit waits for the rest).
        table: ``(name, field)`` per status code of this circuit (:attr:`RtlBuild.statuses`).
    """

    output: bytes
    status: tuple[tuple[int, int], ...]
    clocks: int
    span: int
    cut_short: bool
    table: tuple[tuple[str, str], ...] = field(default=(), compare=False, repr=False)

    @property
    def refused(self) -> tuple[tuple[int, str, str], ...]:
        """``(code, name, field)`` per refused frame (status not 0)."""
        return tuple((code, *self.name(code)) for _, code in self.status if code)

    def name(self, code: int) -> tuple[str, str]:
        """``(name, field)`` of a status code (a code outside the table is named as such)."""
        return self.table[code] if 0 <= code < len(self.table) else (f"status {code}", "?")


def _read_exact(stream: IO[bytes], n: int) -> bytes:
    data = bytearray()
    while len(data) < n:
        chunk = stream.read(n - len(data))
        if not chunk:
            raise RtlError("the RTL simulator ended unexpectedly")
        data += chunk
    return bytes(data)


class RtlServer:
    """A long-lived simulation of the node's circuit (see the module docstring).

    Args:
        config: the node configuration (``op: custom`` has no RTL).
        cache: reuse a cached build of the same sources (compiling takes seconds).

    Raises:
        SimulatorMissingError: no Verilator or no C++ compiler (the fast harness needs both).
        RtlError: the configuration has no RTL (:func:`design_from_config`), or the build failed.
    """

    def __init__(self, config: NodeConfig, *, cache: bool = True) -> None:
        design = design_from_config(config)
        reason = simulator_missing_reason("verilator")
        if reason:
            raise SimulatorMissingError(
                f"--model rtl runs the Verilog on Verilator's fast harness: {reason}")
        self.build: RtlBuild = build(design, simulator="verilator", harness=True, cache=cache)
        self._lock = threading.Lock()
        self._proc: subprocess.Popen[bytes] | None = subprocess.Popen(
            [*self.build.command, "--serve", f"+idle_limit={IDLE_LIMIT}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)

    def process(self, frames: bytes) -> RtlFrame:
        """Feed ``frames`` (one or more TCPROS frames, or CDR records on ``wire: cdr``) to the
        circuit and run until it is idle.

        Raises:
            RtlError: the simulator is closed, stalled or ended.
        """
        if not 0 < len(frames) <= MAX_SERVE_FRAME:
            raise RtlError(f"a request is 1..{MAX_SERVE_FRAME} bytes, got {len(frames)}")
        with self._lock:
            proc = self._proc
            if proc is None or proc.stdin is None or proc.stdout is None:
                raise RtlError("the RTL simulator was closed")
            try:
                proc.stdin.write(b"RFLQ" + struct.pack("<I", len(frames)) + frames)
                proc.stdin.flush()
                magic, flags, clocks, span, n_status, n_out = _REPLY.unpack(
                    _read_exact(proc.stdout, _REPLY.size))
                if magic != b"RFLR":
                    raise RtlError("the RTL simulator answered out of step")
                raw = _read_exact(proc.stdout, 8 * n_status)
                output = _read_exact(proc.stdout, n_out)
            except (OSError, ValueError) as exc:
                raise RtlError(f"the RTL simulator ended unexpectedly: {exc}") from None
        if flags & 2:
            self.close()
            raise RtlError("the RTL simulation stalled: no handshake for "
                           f"{IDLE_LIMIT} clocks with input left")
        status = tuple(struct.unpack_from("<II", raw, 8 * i) for i in range(n_status))
        return RtlFrame(output, status, clocks, span, bool(flags & 1), self.build.statuses)

    def close(self) -> None:
        """End the simulator process (idempotent)."""
        with self._lock:
            proc, self._proc = self._proc, None
        if proc is None:
            return
        try:
            if proc.stdin is not None:
                proc.stdin.write(b"RFLQ\0\0\0\0")
                proc.stdin.close()
            proc.wait(5)
        except (OSError, subprocess.TimeoutExpired):
            proc.kill()
            proc.wait(5)
        if proc.stdout is not None:
            proc.stdout.close()

    def __enter__(self) -> RtlServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
