"""Hand-built walks (:class:`rosfpga_lab.hls.program.Program`) for tests of the generic renderers,
and a numpy oracle of the 1-D applications written independently of the circuit."""

from __future__ import annotations

import functools
import subprocess
from pathlib import Path

import numpy as np

from rosfpga_lab.hls.generic import GenericSpec
from rosfpga_lab.hls.program import Instr, Op, Program, Pub, Sub
from tests.support.rtltools import require_iverilog, require_verilator

STATUSES = (("SUB_OK", "frame accepted"), ("SUB_BAD_FRAME_LENGTH", "frame length"),
            ("SUB_BAD_A", "a"), ("SUB_BAD_B", "b"), ("SUB_BAD_C", "c"), ("SUB_BAD_D", "d"),
            ("SUB_BAD_E", "e"), ("SUB_BAD_F", "f"))


def scan_program(length: int = 16) -> Program:
    """A LaserScan-like walk: header, 7 float32, ranges streamed (float32), intensities carried."""
    fx = [Instr(Op.FIXED, Sub.CARRY, Pub.CARRY, 4, name=n, type="float32")
          for n in ("angle_min", "angle_max", "angle_increment", "time_increment", "scan_time",
                    "range_min", "range_max")]
    instrs = [
        Instr(Op.FIXED, Sub.SKIP, Pub.COUNT, 4, name="header.seq", type="uint32"),
        Instr(Op.FIXED, Sub.CARRY, Pub.CARRY, 8, name="header.stamp", type="time"),
        Instr(Op.VAR, Sub.CARRY, Pub.CARRY, 1, 32, status=2, name="header.frame_id", type="string"),
        *fx,
        Instr(Op.VAR, Sub.STREAM, Pub.STREAM, 4, length, status=3, name="ranges", type="float32[]"),
        Instr(Op.VAR, Sub.CARRY, Pub.CARRY, 4, 8, status=4, name="intensities", type="float32[]"),
        Instr(Op.DONE, status=5),
    ]
    return Program.build(instrs, statuses=STATUSES[:6], min_body=52, max_frame=1 << 20,
                         seq_start=1, stream_bytes=4, stream_length=length,
                         carry_bytes=8 + 4 + 32 + 28 + 4 + 32, type_in="sensor_msgs/LaserScan",
                         type_out="sensor_msgs/LaserScan")


def nested_program(length: int = 5) -> Program:
    """A custom walk with checks, constants, zeros, loops nested two deep and a stream in the middle."""
    instrs = [
        Instr(Op.FIXED, Sub.CHECK, Pub.CONST, 2, status=2, const=b"\x07\x00", name="version", type="uint16"),
        Instr(Op.VAR, Sub.CHECK, Pub.CONST, 1, 8, status=3, status2=6, const=b"abc", name="kind", type="string"),
        Instr(Op.LOOP, Sub.CARRY, Pub.CARRY, 0, 3, variable=True, status=4, name="points", type="Point[]"),
        Instr(Op.FIXED, Sub.CARRY, Pub.CARRY, 8, name="points.x", type="float64"),
        Instr(Op.VAR, Sub.CARRY, Pub.CARRY, 1, 6, status=5, name="points.label", type="string"),
        Instr(Op.LOOP, Sub.CARRY, Pub.CARRY, 0, 2, name="points.pair", type="Tag[2]"),
        Instr(Op.FIXED, Sub.SKIP, Pub.ZERO, 1, name="points.pair.flag", type="bool"),
        Instr(Op.VAR, Sub.CARRY, Pub.CARRY, 2, 3, status=6, name="points.pair.codes", type="int16[]"),
        Instr(Op.END, name="points.pair"),
        Instr(Op.END, name="points"),
        Instr(Op.VAR, Sub.STREAM, Pub.STREAM, 2, length, status=7, name="values", type="int16[]"),
        Instr(Op.LOOP, Sub.SKIP, Pub.ZERO, 0, 2, variable=True, status=4, name="extras", type="Tag[]"),
        Instr(Op.FIXED, Sub.SKIP, Pub.ZERO, 1, name="extras.flag", type="bool"),
        Instr(Op.END, name="extras"),
        Instr(Op.FIXED, Sub.SKIP, Pub.COUNT, 4, name="counter", type="uint32"),
        Instr(Op.DONE, status=1),
    ]
    return Program.build(instrs, statuses=STATUSES, min_body=2 + 4 + 4 + 4 + 4 + 4, max_frame=1 << 20,
                         seq_start=1, stream_bytes=2, stream_length=length, carry_bytes=4 + 3 * (8 + 4 + 6 + 2 * (4 + 6)),
                         type_in="lab_msgs/Nested", type_out="lab_msgs/Nested")


def spec_for(prog: Program, op: str = "dilate", ksize: int = 3, kind: str = "float",
             stream: str = "ranges") -> GenericSpec:
    hdr = {"callerid": "/fpga", "md5sum": "0" * 32, "type": prog.type_in, "topic": "/in",
           "message_definition": "x", "tcp_nodelay": "1"}
    return GenericSpec(program=prog, node_name="/fpga", sub_topic="/in", pub_topic="/out",
                       master_uri="http://127.0.0.1:11311", ip_address="127.0.0.1",
                       input_depth=2048, output_depth=2048, axis_depth=16, part="xc7z020clg400-1",
                       clock_mhz=100.0, op=op, ksize=ksize, kind=kind, stream_name=stream,
                       stream_type="?", subscriber_header=hdr, publisher_header=hdr)


def window_oracle(data: bytes, dtype: str, ksize: int, op: str) -> bytes:
    """numpy's maximum/minimum folded over the in-array part of each window, oldest first."""
    x = np.frombuffer(data, dtype=np.dtype(dtype))
    if op == "passthrough":
        return data
    half = ksize // 2
    pick = np.maximum if op == "dilate" else np.minimum
    out = np.empty_like(x)
    with np.errstate(invalid="ignore"):
        for i in range(len(x)):
            out[i] = functools.reduce(pick, x[max(0, i - half):i + half + 1])
    return out.tobytes()


def assert_rtl_lint_clean(rtl: Path) -> None:
    """iverilog -Wall and Verilator -Wall find nothing in a generated project's ``rtl`` folder
    (top ``rfl_node``; the lab's rfl_fifo.v is another file's business). Verilator missing: skip."""
    sources = sorted(p.name for p in rtl.glob("*.v") if p.name != "rfl_tb.v")
    iverilog = require_iverilog()
    # never "-o /dev/null": iverilog makes its output executable, and as root that chmod turned
    # /dev/null into 0755 for the whole machine (apt and the course's students could not write it)
    proc = subprocess.run([iverilog, "-Wall", "-g2005", "-I.", "-s", "rfl_node", "-o", "lint.vvp",
                           *sources], cwd=rtl, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr
    verilator = require_verilator()
    proc = subprocess.run([verilator, "--lint-only", "-Wall", "-Wno-fatal", "-I.", "--top-module",
                           "rfl_node", *sources], cwd=rtl, capture_output=True, text=True,
                          timeout=120)
    ours = [line for line in proc.stderr.splitlines()
            if line.startswith("%Warning") and "rfl_fifo.v" not in line]
    assert proc.returncode == 0 and not ours, proc.stderr
