"""The fabric node's counters, all of them (one owner of their names and their order), and
the counter readout's datagrams.

``rfl_fabric_top`` brings out the UDP port's ``cnt_rx_*``, the answers' ``cnt_answers`` and
``cnt_no_credit``, the SPDP learner's ``cnt_peer_*``; the RTPS stages' counters (``rfl_rtps_rx``,
the seam ``rfl_rtps_to_cdr``, ``rfl_rtps_tx``, ``rfl_rtps_ctrl``) stay inside
``rfl_fabric_node``, which hands them to the top packed (its ``cnt_stages``); the counter
readout ``rfl_counter_readout`` counts its own. :data:`FABRIC_COUNTERS` lists them all in the
order the readout sends them; :func:`verilog_include` renders ``fabric/rfl_fabric_counters.vh``
(the packing both modules use, the readout's magic word; a test holds the checked-in file equal
to it). Simulations also read the node's wires through the hierarchy: cocotb by the node's wire
names (tests/rtl/bench_rfl_fabric_top_wire.py), the fast model (``rtl.fabricsim``) from a
Verilator configuration that keeps those wires public (:func:`verilator_config`) and a header
listing them for its C++ main (:func:`cxx_header`).

Each counter has a key (the reports' and tests' name, ``rtps_repeated``), the stage and its
output port as rtl/fabric/vendor/README.md ("What the node refuses") names them
(``rfl_rtps_rx``'s ``cnt_repeated``), the wire it is connected to in its scope
(``cnt_rx_repeated`` in the node) and its scope (``top``: ``rfl_fabric_top``'s port; ``node``;
``readout``).

The readout (no bus needed on a board): a UDP datagram of exactly :func:`answer_bytes` bytes to
the counters port (:func:`rosfpga_lab.rtl.discrom.counters_port`), :data:`MAGIC` big endian then
zeros (:func:`request`), is answered by one datagram of as many bytes to its sender's address and
port: :data:`MAGIC`, the count of counters, then each counter's value (32 bits, big endian, this
order). So the circuit never sends more bytes on that port than it is sent; anything else is
dropped (``counters_malformed``), and a request within the readout's gap after the last one
answered (``COUNTERS_GAP`` clocks, :func:`counters_gap`) is dropped too (``counters_limited``).
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass

from rosfpga_lab.graph.udpports import ask
from rosfpga_lab.rtl.errors import RtlError

__all__ = ["ANSWERS_PER_SECOND", "CountersError", "FABRIC_COUNTERS", "INCLUDE_FILE", "MAGIC",
           "NODE_COUNTERS", "NODE_INSTANCE", "NODE_MODULE", "READOUT_MODULE", "StageCounter",
           "answer_bytes", "counters_gap", "cxx_header", "node_wires", "parse_answer",
           "read_counters", "request", "stage_lines", "verilator_config", "verilog_include"]

#: The node's module and its instance in ``rfl_fabric_top``.
NODE_MODULE, NODE_INSTANCE = "rfl_fabric_node", "u_node"
#: The readout's module.
READOUT_MODULE = "rfl_counter_readout"
#: The rendered include (in rtl/fabric/).
INCLUDE_FILE = "rfl_fabric_counters.vh"
#: The readout's first word, requests' and answers': "RFC" and the format's version, 1.
MAGIC = int.from_bytes(b"RFC\x01", "big")
#: Answers a second at most (the readout's gap is a second's clocks over this).
ANSWERS_PER_SECOND = 1000


class CountersError(RtlError):
    """No answer from the counter readout, or one that is not its answer."""


@dataclass(frozen=True)
class StageCounter:
    """One counter: its key, the stage, the stage's port, the wire in its scope, the scope."""

    key: str
    stage: str
    port: str
    wire: str
    scope: str = "node"


def _c(key: str, stage: str, port: str, wire: str | None = None,
       scope: str = "node") -> StageCounter:
    return StageCounter(key, stage, port, wire or port, scope)


def _t(key: str, stage: str, port: str | None = None) -> StageCounter:
    """A port of rfl_fabric_top named ``cnt_<key>`` (the stage's port, default the same)."""
    return StageCounter(key, stage, port or f"cnt_{key}", f"cnt_{key}", "top")


#: Every counter, in the order the readout sends them: the top's ports, the RTPS stages' inside
#: the node (in the order the fast model reports them), the readout's own (its ports' order).
FABRIC_COUNTERS: tuple[StageCounter, ...] = (
    _t("samples", "rfl_rtps_tx"),
    _t("answers", "rfl_rtps_disc_answer"),
    _t("no_credit", "rfl_rtps_disc_answer"),
    _t("rx_packets", "rfl_udp_port"),
    _t("rx_error", "rfl_udp_port"),
    _t("rx_length", "rfl_udp_port"),
    _t("rx_overflow", "rfl_udp_port"),
    _t("tx_packets", "rfl_udp_port"),
    _t("tx_overflow", "rfl_udp_port"),
    _t("rx_port", "rfl_fabric_top"),
    _t("rx_header", "rfl_udp_port"),
    _t("rx_other", "rfl_udp_port"),
    _t("peer_learned", "rfl_spdp_peer", "cnt_learned"),
    _t("peer_refused", "rfl_spdp_peer", "cnt_refused"),
    _t("peer_other", "rfl_spdp_peer", "cnt_other"),
    _c("rtps_packets", "rfl_rtps_rx", "cnt_packets"),
    _c("rtps_bad_header", "rfl_rtps_rx", "cnt_bad_header"),
    _c("rtps_malformed", "rfl_rtps_rx", "cnt_malformed"),
    _c("rtps_samples", "rfl_rtps_rx", "cnt_samples", "cnt_rx_samples"),
    _c("rtps_dropped", "rfl_rtps_rx", "cnt_dropped", "cnt_rx_dropped"),
    _c("rtps_repeated", "rfl_rtps_rx", "cnt_repeated", "cnt_rx_repeated"),
    _c("seam_samples", "rfl_rtps_to_cdr", "cnt_samples", "cnt_seam_samples"),
    _c("seam_dropped", "rfl_rtps_to_cdr", "cnt_dropped", "cnt_seam_dropped"),
    _c("seam_too_long", "rfl_rtps_to_cdr", "cnt_too_long"),
    _c("tx_datagrams", "rfl_rtps_tx", "cnt_datagrams"),
    _c("tx_dropped", "rfl_rtps_tx", "cnt_dropped"),
    _c("ctrl_requests", "rfl_rtps_ctrl", "cnt_requests"),
    _c("ctrl_busy", "rfl_rtps_ctrl", "cnt_busy"),
    _c("ctrl_malformed", "rfl_rtps_ctrl", "cnt_malformed", "cnt_ctrl_malformed"),
    _c("ctrl_bad_header", "rfl_rtps_ctrl", "cnt_bad_header", "cnt_ctrl_bad_header"),
    _c("counters_answered", READOUT_MODULE, "cnt_answered", scope="readout"),
    _c("counters_malformed", READOUT_MODULE, "cnt_malformed", scope="readout"),
    _c("counters_limited", READOUT_MODULE, "cnt_limited", scope="readout"),
)
#: The RTPS stages' counters inside the node.
NODE_COUNTERS: tuple[StageCounter, ...] = tuple(c for c in FABRIC_COUNTERS if c.scope == "node")


def _scoped(scope: str) -> tuple[StageCounter, ...]:
    return tuple(c for c in FABRIC_COUNTERS if c.scope == scope)


def answer_bytes() -> int:
    """The bytes of a request and of its answer: the magic word, the count, the counters."""
    return 8 + 4 * len(FABRIC_COUNTERS)


def counters_gap(period: int) -> int:
    """The readout's gap in clocks (``COUNTERS_GAP``) for a second of ``period`` clocks (the
    node's SPDP period): at most :data:`ANSWERS_PER_SECOND` answers a second, never less than an
    answer's bytes."""
    return max(period // ANSWERS_PER_SECOND, answer_bytes())


def request() -> bytes:
    """A request for the counters."""
    return MAGIC.to_bytes(4, "big").ljust(answer_bytes(), b"\0")


def parse_answer(data: bytes) -> dict[str, int]:
    """The counters an answer holds, by key.

    Raises:
        CountersError: not the readout's answer (length, magic word, count).
    """
    if len(data) != answer_bytes():
        raise CountersError(f"an answer of {len(data)} bytes: the readout sends "
                            f"{answer_bytes()} ({len(FABRIC_COUNTERS)} counters)")
    magic, count = struct.unpack_from(">II", data)
    if magic != MAGIC:
        raise CountersError(f"an answer starting 0x{magic:08x}: the readout's starts "
                            f"0x{MAGIC:08x} (another format version, or not the readout)")
    if count != len(FABRIC_COUNTERS):
        raise CountersError(f"an answer of {count} counters: this lab knows "
                            f"{len(FABRIC_COUNTERS)} (a bitstream of another version)")
    values = struct.unpack_from(f">{count}I", data, 8)
    return {c.key: v for c, v in zip(FABRIC_COUNTERS, values)}


def read_counters(host: str, port: int, timeout: float = 1.0) -> dict[str, int]:
    """Ask the counter readout at ``host``:``port`` (a board, or ``fabric sim``) for the counters.

    Raises:
        CountersError: no answer within ``timeout`` seconds, or not the readout's.
        GraphError: the request could not be sent.
    """
    data = ask(host, port, request(), timeout)
    if data is None:
        raise CountersError(f"no answer from {host}:{port} within {timeout:g} s: is the board "
                            "up / fabric sim running? (a request within a millisecond of "
                            "another one's answer is dropped: ask again)")
    return parse_answer(data)


def _packed(counters: tuple[StageCounter, ...]) -> str:
    """A concatenation putting the i-th counter in bits [32*i +: 32]."""
    return "{" + ", ".join(c.wire for c in reversed(counters)) + "}"


def verilog_include() -> str:
    """``fabric/rfl_fabric_counters.vh``: the counters' count, the node's stage counters packed
    (``RFL_NODE_COUNTER_BUS`` in rfl_fabric_node's scope), all but the readout's packed in the
    top's scope (``RFL_TOP_COUNTER_BUS``, the node's as its ``cnt_stages``), the readout's own
    count and the magic word."""
    top, node, own = _scoped("top"), _scoped("node"), _scoped("readout")
    if FABRIC_COUNTERS != (*top, *node, *own):
        raise RtlError("FABRIC_COUNTERS: the top's first, then the node's, the readout's last")
    wrap = lambda text: " \\\n    ".join(_lines(text))  # noqa: E731
    return ("// rfl_fabric_counters.vh -- generated by rosfpga_lab.rtl.fabriccounters (do not edit:\n"
            "// a test holds it equal): the counters the readout sends, counter i in bits\n"
            "// [32*i +: 32] of a bus; the readout's own last.\n"
            "`ifndef RFL_FABRIC_COUNTERS_VH\n`define RFL_FABRIC_COUNTERS_VH\n"
            f"`define RFL_NODE_COUNTER_COUNT {len(node)}\n"
            f"`define RFL_TOP_COUNTER_COUNT {len(top) + len(node)}\n"
            f"`define RFL_READOUT_COUNTER_COUNT {len(own)}\n"
            f"`define RFL_COUNTERS_MAGIC 32'h{MAGIC:08x}\n"
            f"`define RFL_NODE_COUNTER_BUS \\\n    {wrap(_packed(node))}\n"
            "`define RFL_TOP_COUNTER_BUS \\\n    "
            f"{wrap('{cnt_stages, ' + _packed(top)[1:])}\n"
            "`endif\n")


def _lines(text: str, width: int = 90) -> list[str]:
    out, line = [], ""
    for word in text.split(" "):
        if line and len(line) + 1 + len(word) > width:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return [*out, line]


def node_wires() -> dict[str, str]:
    """Key -> the node's wire (what a simulator reads under the node's instance)."""
    return {c.key: c.wire for c in NODE_COUNTERS}


def verilator_config() -> str:
    """A Verilator configuration file (``.vlt``) that keeps the node's counter wires readable
    from C++ (``public_flat_rd``: nothing else of the model changes)."""
    lines = ["`verilator_config"]
    lines += [f'public_flat_rd -module "{NODE_MODULE}" -var "{c.wire}"' for c in NODE_COUNTERS]
    return "\n".join(lines) + "\n"


def cxx_header(top: str) -> str:
    """A C++ header for a model of ``top`` (its instance of the node is :data:`NODE_INSTANCE`):
    ``RFL_NODE_COUNTERS(X)`` expands ``X(member)`` for each counter in :data:`NODE_COUNTERS`'
    order, ``member`` the wire's flattened name in the model's root (Verilator's
    ``--public-flat`` naming)."""
    items = " \\\n    ".join(f"X({top}__DOT__{NODE_INSTANCE}__DOT__{c.wire})"
                             for c in NODE_COUNTERS)
    return ("// Generated by rosfpga_lab.rtl.fabriccounters: the RTPS stages' counters.\n"
            f"#define RFL_NODE_COUNTER_COUNT {len(NODE_COUNTERS)}\n"
            f"#define RFL_NODE_COUNTERS(X) \\\n    {items}\n")


def stage_lines(values: Mapping[str, int]) -> list[str]:
    """One line a stage, its counters by their port names: ``rfl_rtps_rx: cnt_packets 3, ...``
    (the counters ``values`` has)."""
    stages: dict[str, list[str]] = {}
    for c in NODE_COUNTERS:
        if c.key in values:
            stages.setdefault(c.stage, []).append(f"{c.port} {values[c.key]}")
    return [f"{stage}: " + ", ".join(parts) for stage, parts in stages.items()]
