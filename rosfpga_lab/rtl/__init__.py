"""The circuit as a circuit: Verilog RTL of the data path, its simulation and synthesis.

Every configuration, ``sensor_msgs/Image`` on TCPROS included, simulates, counts, synthesizes,
times, proves and serves the generated top of :mod:`rosfpga_lab.rtl.generic` (walkers stepping
through a generated program, one instruction per field of the message):
``build(design_from_config(config))``, with Icarus Verilog or Verilator through the file-based
testbench ``tb/rfl_tb.v`` (the lab's shared modules ``rfl_fifo``, ``rfl_slice`` and the video
application ``rfl_morph`` are in ``verilog/``). The hand-written Image circuit (``exhibit/``:
``rfl_subscriber``, ``rfl_fifo2axi``, ``rfl_axi2fifo``, ``rfl_publisher``, ``rfl_top``) is kept as
the paper's conventional design of Table 1, beside the generated one; nothing here imports it
(``exhibit/README.md``; ``tests/rtl/test_exhibit.py`` holds it equal to the generated Image
circuit)::

    from rosfpga_lab.config import load_config
    from rosfpga_lab.rtl import build, run
    from rosfpga_lab.rtl.sim import design_from_config
    sim = build(design_from_config(load_config("data/fpga_dilate_rgba8.yaml")))
    result = run(sim, frames, gap=100, bp=500)   # result.output: the frames sent

:mod:`rosfpga_lab.rtl.vcd` reads waveform dumps into per-clock arrays,
:mod:`rosfpga_lab.rtl.synth` synthesizes the modules with Yosys,
:mod:`rosfpga_lab.rtl.timing` places and routes them with nextpnr-ecp5 (Fmax against the clock) and
:mod:`rosfpga_lab.rtl.sloc` counts the lines of a generated project's and of the exhibit's for the
paper's Table 1.

The ROS 2 node in the fabric (issue #31) announces itself from a ROM built at build time:
:mod:`rosfpga_lab.rtl.discrom` renders the software participant's SPDP, SEDP and
``ros_discovery_info`` datagrams for a ``wire: cdr`` configuration, ``fabric/rfl_rtps_disc_rom.v``
streams them out (proof ``rtps_disc_rom``; ``rosfpga-lab generate CONFIG -o DIR --target fabric``).
Its built-in writers are reliable: ``fabric/rfl_rtps_ctrl.v`` watches the received datagrams for
ACKNACKs to them and HEARTBEATs to its SEDP readers, ``fabric/rfl_rtps_disc_answer.v`` sends the
answers discrom renders (resent DATA, HEARTBEATs, ACKNACKs) within a byte credit (proofs
``rtps_ctrl``, ``rtps_disc_answer``); :mod:`rosfpga_lab.rtl.discanswer` models both.

From the shell (ARCHITECTURE.md's command table; each sub-command's ``--help``)::

    rosfpga-lab generate data/fpga_erode_mono8.yaml -o build/erode   # the RTL goes to build/erode/rtl/
    make -C build/erode rtlsim        # "rtlsim: PASS: output equals tb_expected.bin"
    make -C build/erode rtlsim INPUT=frames.bin EXPECTED=expected.bin OUT=out GAP=200 BP=500 VCD=1
    make -C build/erode lint          # Verilator --lint-only -Wall on rtl/ (0 warnings)
    rosfpga-lab rtl sim CONFIG --bp 500 --vcd wave.vcd      # against the Python models
    rosfpga-lab rtl cycles CONFIG     # the cycle model against the RTL (module ``cycles``)
    rosfpga-lab rtl prove|synth|timing CONFIG
    rosfpga-lab node CONFIG --model rtl --timing fpga       # the live node runs the Verilog
    rosfpga-lab node CDR_CONFIG --ros2 --model rtl          # the ROS 2 node, the CDR top
    rosfpga-lab rtl demo [CONFIG]     # notebook 08's run, each frame beside the models (``demo``)

Simulation (module ``sim``): the testbench streams frames with random input gaps (``GAP``) and
output backpressure (``BP``, per mille of clocks) and writes ``output.bin``, ``status.txt`` and
``stats.txt``; with Verilator and a C++ compiler the fast harness ``harness/`` runs instead,
clock for clock the same (built by ``rosfpga_lab/hls/rtlbuild.py``); Icarus Verilog is the slow fallback;
``SIM=`` picks one and builds are cached (module ``sim``). Speeds are measured, never asserted:
``tests/benchmarks/bench_rtl.py``. Without a simulator the RTL tests skip; with
``ROSFPGA_REQUIRE_RTL=1`` (CI) they fail. The walk's cycle model (``hls.program.frame_clocks``) is held to the RTL (module ``cycles``).
The live node on the RTL (``--model rtl``, ``FpgaComponent(config, model="rtl")``, on ROS 2
``Ros2Component(config, model="rtl")``): one long-lived simulator, module ``server``; ``--timing fpga`` holds each output until the circuit's
clocks have passed at ``clock_mhz``. Formal proofs of the stream handshakes (``formal/``, run by
module ``proofs`` with SymbiYosys; which check, mode and claim: ``rosfpga-lab rtl prove``, limits
in module ``limits``). The application ``rfl_morph.v``'s clocks and latency are its header
comment's; synthesis (``synth``: Yosys, the part's family, hierarchy kept, latches refused),
place and route (``timing``: nextpnr-ecp5) and Table 1's counting rule (``sloc.COUNTED``) are
their modules' docstrings.

The network side of a ROS 2 node in the fabric (issue #31) starts in ``fabric/``:
``rfl_rtps_rx`` walks RTPS datagrams (one UDP payload per AXI4-Stream packet) and streams one
writer's DATA / DATA_FRAG samples out (its header comment is the design note; proof
``rtps_rx``; tested against :func:`rosfpga_lab.rtps.parse_message` in
``tests/rtl/test_fabric_rtps_rx.py``). The receiving stages (``rfl_rtps_rx``, ``rfl_rtps_ctrl``,
``rfl_spdp_peer``) share one walk of the RTPS header and submessages, ``rfl_rtps_walk``: per byte
its place (header, submessage header, body and its position, the submessage's last byte, a bad
header) beside each stage's own field logic (proofs ``rtps_walk``; each stage's file list:
``proofs.RTPS_RX``, ``RTPS_CTRL``, ``SPDP_PEER``). ``rfl_rtps_to_cdr`` turns its sample packets
into the records a generated ``wire: cdr`` circuit's subscriber reads (the length, then the
payload), forwarding a sample only once it ended good, through a ring that fills while it sends (proof
``rtps_to_cdr``; alone in ``tests/rtl/test_fabric_seam.py``; datagrams through both into a
generated top in ``tests/rtl/test_fabric_rtps_cdr.py``). ``rfl_rtps_tx`` is the way back: the
generated publisher's records become the data writer's RTPS datagrams (DATA, or DATA_FRAGs
streamed without a sample buffer, and a HEARTBEAT), its GUID prefix and writer id
:func:`rosfpga_lab.rtl.discrom.tx_parameters` of the participant the discovery ROM announces
(proof ``rtps_tx``; byte for byte against the lab's RTPS builders in
``tests/rtl/test_fabric_rtps_tx.py``, RTPS in to RTPS out through a generated top in
``tests/rtl/test_fabric_rtps_loop.py``, where Cyclone DDS takes what it sends). Under them, the
MAC / ARP / IPv4 / UDP stage is LiteEth's core, vendored as generated Verilog in ``fabric/vendor/`` (its README says
which version, why LiteEth, and what ``tools/liteeth/gen_liteeth.py`` sets and fixes);
``rfl_udp_port`` (with ``rfl_udp_store``, store and forward) joins its raw UDP port to the lab's
streams, one payload per packet, and drops and counts what LiteEth flags late (proofs
``udp_store``, ``udp_port``; a GMII peer in ``tests/rtl/test_fabric_udp.py``; place and route in
``tests/benchmarks/bench_udp_timing.py``).
"""

from rosfpga_lab.rtl.errors import RtlError, SimulatorMissingError
from rosfpga_lab.config.vocabulary import SIMULATORS
from rosfpga_lab.rtl.sim import (
    STREAMS, Design, OwnSources, RtlBuild, RtlResult, StreamTiming, build, design_from_config,
    find_simulator, run, simulator_missing_reason, verilog_sources, write_sources,
)

__all__ = [
    "SIMULATORS", "STREAMS", "Design", "OwnSources", "RtlBuild", "RtlError", "RtlResult",
    "SimulatorMissingError", "StreamTiming", "build", "design_from_config", "find_simulator",
    "run", "simulator_missing_reason", "verilog_sources", "write_sources",
]
