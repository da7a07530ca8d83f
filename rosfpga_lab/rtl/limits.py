"""Limits and defaults of the rtl layer, in one place."""

from __future__ import annotations

#: Seconds allowed for one build and for one run.
BUILD_TIMEOUT = 600.0
RUN_TIMEOUT = 900.0

#: Seconds allowed for one synthesis.
SYNTH_TIMEOUT = 1800.0

#: Clocks without a handshake on any stream that end a run: the input ended inside a frame (or
#: the circuit hangs). Even at 990 per mille gaps and backpressure, a stream moves every ~100
#: clocks on average; 20,000 idle clocks in a row would happen with a chance below 1e-40.
IDLE_LIMIT = 20_000
#: Per mille: the largest input gap / backpressure share (1000 would never move).
MAX_PER_MILLE = 990
#: Bytes of input above which ``rtl sim`` picks Verilator when none is named (its fast
#: simulation repays its slow compilation).
VERILATOR_FROM_BYTES = 200_000

#: Largest header (everything before ``$enddefinitions``) read.
VCD_MAX_HEADER_BYTES = 16 << 20
#: Widest signal kept (bits).
VCD_MAX_SIGNAL_BITS = 1 << 16

#: Seconds allowed for one formal check (SymbiYosys): the generated subscriber's depth-50 bounded
#: check, the longest, takes some 425 s on an idle core with smtbmc and Yices since the subscriber
#: keeps two frame records (82 s with one), and a loaded machine makes it half as long again (at
#: a load of 18 on two cores it reached this limit at its 41st clock of 50). Where ``yosys-abc``
#: is found it runs on ABC's bmc3 (``proofs.bmc_engine``): 129 s of CPU (871 s wall) at a load
#: of 16, where smtbmc took 490 s of CPU (2,071 s wall; the limit is per run of one check).
FORMAL_TIMEOUT = 1200.0

#: Largest request to the long-lived simulator of ``--model rtl`` (bytes).
MAX_SERVE_FRAME = 64 << 20

#: Seconds allowed for one place and route (nextpnr).
PNR_TIMEOUT = 1800.0
#: The open FPGA ``rtl timing`` places and routes for: nextpnr-ecp5's device and package
#: (a Lattice ECP5 LFE5U-25F in a 256-ball BGA: 24k LUTs, 56 block RAMs, 197 I/Os).
ECP5_DEVICE = "25k"
ECP5_PACKAGE = "CABGA256"
#: Seconds between progress lines while Yosys or nextpnr runs (``rtl timing``).
PROGRESS_SECONDS = 30.0
#: Seconds allowed for a tool to say its version (a WebAssembly build compiles on first run).
VERSION_TIMEOUT = 120.0
#: Longest critical path kept in a timing report (steps).
MAX_PATH_STEPS = 400

#: Largest memory (bits: the FIFOs and the carry memory) of a generated top that
#: ``rtl prove CONFIG`` takes on: the proof maps every memory to flip-flops. Measured: the
#: shipped generic examples (50-60 kbit) took 19-33 s on a shared machine; a 640x480 rgba8
#: stream's FIFO (11.7 Mbit) stopped PyPI's Yosys (WebAssembly) after 90 s.
FORMAL_MAX_MEMORY_BITS = 256 * 1024

#: Largest discovery ROM image (``rtl.discrom``): its message table holds 16-bit offsets.
MAX_DISC_ROM_BYTES = 1 << 16

#: Largest UDP payload the fabric's transmit path (``fabric/rfl_rtps_tx.v``) sends: an Ethernet
#: frame's 1500-byte MTU less the IPv4 (20) and UDP (8) headers, so no datagram is IP-fragmented
#: (a MAC without IP fragmentation sends it as one frame). The fragment size is the software
#: participant's (``rtps.limits.FRAGMENT_BYTES``), whose DATA_FRAG datagram fits in it.
FABRIC_MAX_DATAGRAM = 1500 - 20 - 8
#: The fabric participant's answers (``rtl.discrom``, ``fabric/rfl_rtps_disc_answer.v``): the
#: credit of bytes at reset and at most, and the credit earned per byte received. The bytes it
#: answers never exceed ANSWER_BURST + ANSWER_RATE x the bytes received. Measured need: a
#: Cyclone DDS peer's discovery asks ~1.2 kB of answers (both SEDP writers' DATA and
#: HEARTBEATs) against its ~0.3 kB of ACKNACKs and HEARTBEATs; the burst covers two peers
#: arriving at once.
ANSWER_BURST = 4096
ANSWER_RATE = 4
#: The sequence numbers a writer slot resends (the watcher's bitmap window: 1 .. this) and the
#: slots it compares in parallel.
MAX_ANSWER_SEQ = 8
MAX_ANSWER_SLOTS = 8

#: Clocks the fabric demo (notebook 12's run, ``rtl.fabricdemo``) waits for its frames out
#: after the peer's last frame in, before it gives up.
FABRIC_DEMO_MAX_CLOCKS = 40_000

#: The largest record the fabric simulation's program takes on its stdin (an Ethernet frame, its
#: configuration; harness/rfl_fabric_sim.cpp's MAX_RECORD).
FABRIC_SIM_MAX_RECORD = 1 << 16
