"""Build and run a generated project's C-simulation testbench with g++ (no Xilinx tools).

How this works: :func:`build_csim` runs the generated Makefile's ``csim_testbench`` target
(``g++ -std=c++14 -Wall -Werror -O2`` against ``hls_include/``), or the same g++ command when
``make`` is missing. :func:`run_csim` writes the frames to a file, runs the testbench and reads
back what it wrote: the output bytes, the AXI4-Stream beats on both sides of the application
(as :class:`rosfpga_lab.hw.Beats`, so they compare directly with the Python models'), the
subscriber's status per frame and the two connection headers.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rosfpga_lab.hls.errors import CsimError
from rosfpga_lab.hls.limits import BUILD_TIMEOUT, RUN_TIMEOUT
from rosfpga_lab.hw import Beats

#: The flags and sources of the generated Makefile (also used directly when make is missing).
CXXFLAGS = ("-std=c++14", "-Wall", "-Werror", "-O2")
SOURCES = ("subscriber.cpp", "publisher.cpp", "stream_filter.cpp", "ros_fpga_node.cpp",
           "connection_headers.cpp", "csim_testbench.cpp")
BINARY = "csim_testbench"
#: The lab's g++ stand-ins for Xilinx's headers (``include/``), copied to a project's
#: ``hls_include/`` (both flavours).
INCLUDE_DIR = Path(__file__).resolve().parent / "include"
HLS_HEADERS = ("ap_int.h", "ap_axi_sdata.h", "hls_stream.h")
#: The test frames a generated project ships and what the Python models publish for them.
TB_INPUT = "tb_input.bin"
TB_EXPECTED = "tb_expected.bin"


@dataclass(frozen=True)
class CsimResult:
    """What one run of the testbench produced.

    Attributes:
        output: the bytes the publisher wrote (TCPROS frames).
        input_beats: the beats fifo2axi produced (into the application), all frames.
        output_beats: the beats the application produced, all frames.
        status: ``(byte offset, subscriber status)`` per input frame, e.g. ``(0, "SUB_OK")``.
        subscriber_header, publisher_header: the connection-header bytes.
        log: the testbench's standard output and error.
    """

    output: bytes
    input_beats: Beats
    output_beats: Beats
    status: tuple[tuple[int, str], ...]
    subscriber_header: bytes
    publisher_header: bytes
    log: str


def build_csim(project_dir: str | Path, *, cxx: str = "g++") -> Path:
    """Compile the testbench of a generated project.

    Args:
        project_dir: a directory written by :func:`rosfpga_lab.hls.generate`.
        cxx: the C++ compiler.

    Returns:
        The path of the testbench executable.

    Raises:
        CsimError: no compiler, or the build failed (the compiler's messages are quoted).
    """
    project = Path(project_dir)
    if shutil.which(cxx) is None:
        raise CsimError(f"no C++ compiler {cxx!r} on this machine (apt-get install g++)")
    if shutil.which("make"):
        cmd = ["make", "-s", f"CXX={cxx}", BINARY]
    else:
        cmd = [cxx, *CXXFLAGS, "-Ihls_include", "-I.", "-o", BINARY, *SOURCES]
    try:
        proc = subprocess.run(cmd, cwd=project, capture_output=True, text=True,
                              timeout=BUILD_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise CsimError(f"building the testbench took longer than {BUILD_TIMEOUT:g} s") from None
    if proc.returncode != 0:
        raise CsimError(f"building the testbench in {project} failed ({' '.join(cmd)}):\n"
                        f"{proc.stdout}{proc.stderr}")
    return project / BINARY


def read_beats(path: Path) -> Beats:
    """Beats from a text file of ``tdata tkeep tuser tlast`` lines in hexadecimal (what the
    C-simulation testbench and the RTL testbench write)."""
    text = path.read_text()
    if not text.strip():
        return Beats.empty()
    rows = np.array([[int(v, 16) for v in line.split()] for line in text.splitlines()],
                    dtype=np.uint64)
    return Beats(rows[:, 0].astype(np.uint32), rows[:, 1].astype(np.uint8),
                 rows[:, 2].astype(bool), rows[:, 3].astype(bool))


def run_csim(project_dir: str | Path, frames: bytes, *, binary: str | Path | None = None,
             work_dir: str | Path | None = None) -> CsimResult:
    """Run the testbench on TCPROS frames (building it first when needed).

    Args:
        project_dir: a generated project.
        frames: one or more TCPROS frames (4-byte length + serialized message each).
        binary: the testbench executable (default: build it with :func:`build_csim`).
        work_dir: where the input and outputs go (default: a temporary directory).

    Returns:
        The testbench's outputs.

    Raises:
        CsimError: the build failed, or the testbench failed or did not finish in time.
    """
    exe = Path(binary) if binary else build_csim(project_dir)
    with tempfile.TemporaryDirectory(prefix="rosfpga-csim-") as tmp:
        work = Path(work_dir) if work_dir else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        (work / "input.bin").write_bytes(frames)
        try:
            proc = subprocess.run([str(exe.resolve()), str(work / "input.bin"), str(work)],
                                  capture_output=True, text=True, timeout=RUN_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise CsimError(f"the C simulation ran longer than {RUN_TIMEOUT:g} s") from None
        log = proc.stdout + proc.stderr
        if proc.returncode != 0:
            raise CsimError(f"the C simulation failed (exit {proc.returncode}):\n{log}")
        status = []
        for line in (work / "status.txt").read_text().splitlines():
            offset, name = line.split()
            status.append((int(offset), name))
        return CsimResult(
            output=(work / "output.bin").read_bytes(),
            input_beats=read_beats(work / "input_beats.txt"),
            output_beats=read_beats(work / "output_beats.txt"),
            status=tuple(status),
            subscriber_header=(work / "subscriber_header.bin").read_bytes(),
            publisher_header=(work / "publisher_header.bin").read_bytes(),
            log=log,
        )
