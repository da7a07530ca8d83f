"""The exhibit's parameters: the hand-written Image circuit's (``rfl_top``), read from a node
configuration. Only the exhibit's own test (``tests/rtl/test_exhibit.py``) and benchmark use this
module; no tool of the library imports it (that test holds it so).

How this works: :func:`rtl_params` reads a :class:`NodeConfig` (image, application, FIFO depths,
``frame_id_max``; pixel formats from :data:`rosfpga_lab.hw.encodings.PIXEL_FORMATS`, frame
limits from :mod:`rosfpga_lab.hw.limits`), adds the exhibit's own facts about the Image frame it
hard-codes (:data:`MIN_BODY_BYTES`, :data:`AFTER_FRAME_ID`, :data:`AFTER_ENCODING`,
:data:`SUBSCRIBER_STATUSES`: the museum piece keeps them itself, the live lab derives every
type's from its layout) and returns a frozen :class:`RtlParams`.
:func:`node_wrapper` renders ``rfl_node.v``, the top level with those parameters, and
:func:`status_header` the include of the subscriber's status codes. An :class:`RtlParams` is a design
:func:`rosfpga_lab.rtl.sim.build` takes (:class:`rosfpga_lab.rtl.sim.OwnSources`): its
:meth:`RtlParams.rtl_files` are the exhibit's Verilog, the lab's shared modules
(``rfl_fifo``, ``rfl_slice``, ``rfl_morph``) and the lab's testbench.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from rosfpga_lab.config import CUSTOM, MODEL_OPS, PASSTHROUGH, NodeConfig, load_config
from rosfpga_lab.config.vocabulary import CDR_WIRE, canonical_op, model_ksize
from rosfpga_lab.hw import limits as hw_limits
from rosfpga_lab.hw.encodings import PIXEL_FORMATS
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.proofs import Proof
from rosfpga_lab.rtl.tools import NODE_FILE, TB_DIR, TB_TOP, VERILOG_DIR

__all__ = ["EXHIBIT_DIR", "OP_CODES", "RtlParams", "load_config", "node_wrapper", "rtl_params",
           "status_header"]

#: The exhibit's folder: its Verilog, status include and property wrappers.
EXHIBIT_DIR = Path(__file__).resolve().parent

#: ``rfl_morph``'s OP parameter per operation (the names of :data:`~rosfpga_lab.config.MODEL_OPS`;
#: the codes are the Verilog's).
OP_CODES = {"dilate": 0, "erode": 1, PASSTHROUGH: 2}
assert set(OP_CODES) == set(MODEL_OPS), "every operation the models run has an RTL code"
#: Longest encoding string the RTL's ENCODING parameter holds (bytes).
ENCODING_PARAM_BYTES = 32
#: The status include's file name (beside the Verilog sources).
STATUS_HEADER = "rfl_status.vh"
#: ``rfl_subscriber``'s status codes, in code order: ``SUB_OK`` (0), then one per field it
#: checks, with the field's label (the exhibit's own table: ``rfl_status.vh`` is generated from
#: it; the generated circuit numbers its statuses from its layout instead).
SUBSCRIBER_STATUSES: tuple[tuple[str, str], ...] = (
    ("SUB_OK", "frame accepted"), ("SUB_BAD_FRAME_LENGTH", "frame length"),
    ("SUB_BAD_FRAME_ID_LENGTH", "header.frame_id length"), ("SUB_BAD_HEIGHT", "height"),
    ("SUB_BAD_WIDTH", "width"), ("SUB_BAD_ENCODING_LENGTH", "encoding length"),
    ("SUB_BAD_ENCODING", "encoding"), ("SUB_BAD_STEP", "step"),
    ("SUB_BAD_DATA_LENGTH", "data length"))
#: Bytes of an Image body with empty strings and no pixels (``rfl_subscriber``'s MIN_BODY):
#: seq, stamp (2), frame_id length, height, width, encoding length, is_bigendian (1 byte),
#: step, data length.
MIN_BODY_BYTES = 4 + 4 + 4 + 4 + 4 + 4 + 4 + 1 + 4 + 4
#: Bytes of the fixed fields between ``header.frame_id`` and the next string (height, width,
#: encoding length): the subscriber checks they fit in the frame before reading on.
AFTER_FRAME_ID = 4 + 4 + 4
#: Bytes of the fixed fields between ``encoding`` and ``data`` (is_bigendian, step, data length).
AFTER_ENCODING = 1 + 4 + 4
#: The number the publisher writes into the first frame's ``header.seq`` (then 2, 3 ...), as
#: the generated publisher numbers it.
SEQ_START = 1


@dataclass(frozen=True)
class RtlParams:
    """Parameters of ``rfl_top`` for one node configuration (names as in the Verilog)."""

    WIDTH: int
    HEIGHT: int
    BYTES: int
    ENCODING: str
    OP: int
    KSIZE: int
    FRAME_ID_MAX: int
    ENCODING_MAX: int
    MIN_BODY: int
    MAX_FRAME: int
    AFTER_FRAME_ID: int
    AFTER_ENCODING: int
    RX_DEPTH: int
    TX_DEPTH: int
    AXIS_DEPTH: int
    SEQ_START: int

    @property
    def op_name(self) -> str:
        """The application's operation as the Python models name it."""
        return {v: k for k, v in OP_CODES.items()}[self.OP]

    @property
    def data_bytes(self) -> int:
        """Pixel bytes of one frame."""
        return self.WIDTH * self.HEIGHT * self.BYTES

    @property
    def statuses(self) -> tuple[tuple[str, str], ...]:
        """``(name, field)`` per status code of ``rfl_subscriber``, code 0 (accepted) first."""
        return tuple(SUBSCRIBER_STATUSES)

    def rtl_files(self, note: str = "") -> dict[str, bytes]:
        """``{file name: bytes}`` the testbench runs: the exhibit's Verilog and status include,
        the lab's shared modules (``verilog/``), the testbench and ``rfl_node.v``."""
        files = {p.name: p.read_bytes()
                 for p in [*sorted(VERILOG_DIR.glob("*.v")), *sorted(EXHIBIT_DIR.glob("rfl_*")),
                           TB_DIR / f"{TB_TOP}.v"]}
        files[NODE_FILE] = node_wrapper(self, note).encode("utf-8")
        return files


def rtl_params(config: NodeConfig) -> RtlParams:
    """The RTL parameters of ``config``.

    Raises:
        RtlError: ``op: custom`` (the RTL has no user application), a FIFO shallower than 2, or
            ``wire: cdr`` (these parameters are the TCPROS Image circuit's).
    """
    if config.wire == CDR_WIRE:
        raise RtlError("wire: cdr: the lab's Image circuit (rtl sim, cycles, synth, timing, "
                       "--model rtl) reads TCPROS frames; the CDR circuit's Verilog is a generated "
                       "project's: rosfpga-lab generate CONFIG -o DIR, then make -C DIR rtlsim "
                       "(or synth)")
    if config.application.op == CUSTOM:
        raise RtlError("a custom application has no RTL: the lab's Verilog holds dilate, erode "
                       "and passthrough only")
    for name, depth in (("input_depth", config.fifo.input_depth),
                        ("output_depth", config.fifo.output_depth),
                        ("axis_depth", config.fifo.axis_depth)):
        if depth < 2:
            raise RtlError(f"fifo.{name} is {depth}; the RTL FIFOs need a depth of at least 2")
    image, app = config.image, config.application
    op = canonical_op(app.op)
    return RtlParams(
        WIDTH=image.width, HEIGHT=image.height,
        BYTES=PIXEL_FORMATS[image.encoding].bytes_per_pixel, ENCODING=image.encoding,
        OP=OP_CODES[op], KSIZE=model_ksize(op, app.ksize)[0],
        FRAME_ID_MAX=config.frame_id_max, ENCODING_MAX=hw_limits.MAX_ENCODING_BYTES,
        MIN_BODY=MIN_BODY_BYTES, MAX_FRAME=hw_limits.MAX_FRAME_BYTES,
        AFTER_FRAME_ID=AFTER_FRAME_ID, AFTER_ENCODING=AFTER_ENCODING,
        RX_DEPTH=config.fifo.input_depth, TX_DEPTH=config.fifo.output_depth,
        AXIS_DEPTH=config.fifo.axis_depth, SEQ_START=SEQ_START,
    )


#: The exhibit's formal checks (wrappers ``fv_<name>.sv`` here; run by
#: :func:`rosfpga_lab.rtl.proofs.prove` from ``tests/rtl/test_exhibit.py``, not by ``rtl prove``).
EXHIBIT_PROOFS: tuple[Proof, ...] = (
    Proof("fifo2axi", ("rfl_fifo2axi.v",), "prove", 10,
          "rfl_fifo2axi (3x2, 2 bytes/pixel): output stream rules; all reachable states",
          ("FV_PROVE",), home=EXHIBIT_DIR),
    Proof("fifo2axi", ("rfl_fifo2axi.v",), "bmc", 20,
          "rfl_fifo2axi (3x2, 2 bytes/pixel): TUSER on a frame's first pixel only, TLAST on a "
          "line's last pixel only, TKEEP, each beat = the bytes taken; 20 clocks",
          home=EXHIBIT_DIR),
    Proof("axi2fifo", ("rfl_axi2fifo.v",), "prove", 8,
          "rfl_axi2fifo: output stream rules; all reachable states", ("FV_PROVE",),
          home=EXHIBIT_DIR),
    Proof("axi2fifo", ("rfl_axi2fifo.v",), "bmc", 12,
          "rfl_axi2fifo: one byte per kept lane in lane order, no beat overwritten; 12 clocks",
          home=EXHIBIT_DIR),
    Proof("subscriber", ("rfl_subscriber.v",), "prove", 8,
          "rfl_subscriber (any input bytes): pixel stream rules, status codes of the table; "
          "all reachable states", home=EXHIBIT_DIR),
    # bounded: the publisher's place in the frame is not visible on its ports (the whole
    # rfl_top below closes by induction instead); the wrapper reads frame_id from a RAM of any
    # fixed contents with a clock, as rfl_top does
    Proof("publisher", ("rfl_publisher.v",), "bmc", 32,
          "rfl_publisher (2x1 mono8): output stream rules, releases only fields it holds; 32 "
          "clocks (through the header and frame_id)", home=EXHIBIT_DIR),
    Proof("top", tuple(sorted(p.name for p in [*VERILOG_DIR.glob("*.v"),
                                               *EXHIBIT_DIR.glob("*.v")])), "prove", 8,
          "rfl_top (2x1 mono8, FIFOs 4 deep, any input bytes): output stream rules, busy while "
          "output is pending; all reachable states", home=EXHIBIT_DIR),
)


def _value(name: str, value: object) -> str:
    if name == "ENCODING":
        return f'"{value}"'
    return str(value)


def node_wrapper(params: RtlParams, note: str = "") -> str:
    """``rfl_node.v``: ``rfl_top`` with the configuration's parameters, same ports.

    Args:
        params: the parameters.
        note: a comment line naming where they came from.
    """
    assert len(params.ENCODING) <= ENCODING_PARAM_BYTES
    lines = [f"// rfl_node -- rfl_top with the parameters of one node configuration.",
             f"// {note}" if note else "// Generated by rosfpga-lab (do not edit: regenerate).",
             "`default_nettype none",
             "",
             "module rfl_node (",
             "    input wire clk, input wire rst_n,",
             "    input wire [7:0] s_tdata, input wire s_tvalid, output wire s_tready,",
             "    output wire [7:0] m_tdata, output wire m_tvalid, input wire m_tready,",
             "    output wire frame_start, output wire status_valid, output wire [7:0] status,",
             "    output wire busy, output wire [7:0] framing);",
             "    // the status codes fit 4 bits; the port is 8 wide as the generated top's, so",
             "    // that one testbench and one harness take either",
             "    assign status[7:4] = 4'd0;",
             "    rfl_top #("]
    names = [f.name for f in fields(params)]
    params_text = [f"        .{n}({_value(n, getattr(params, n))})" for n in names]
    params_text.insert(names.index("ENCODING") + 1,
                       f"        .ENC_LEN({len(params.ENCODING)})")
    lines.append(",\n".join(params_text))
    lines += ["    ) u_top (",
              "        .clk(clk), .rst_n(rst_n),",
              "        .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),",
              "        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),",
              "        .frame_start(frame_start), .status_valid(status_valid), .status(status[3:0]),",
              "        .busy(busy), .framing(framing));",
              "endmodule", "", "`default_nettype wire", ""]
    return "\n".join(lines)


def status_header() -> str:
    """``rfl_status.vh``: the subscriber's status codes as Verilog localparams."""
    lines = ["// rfl_status.vh -- the subscriber's status codes (0: accepted, else the refused field).",
             "// Generated from rosfpga_lab.rtl.exhibit.params.SUBSCRIBER_STATUSES by",
             "// rosfpga_lab.rtl.exhibit.params.status_header(); a test keeps this file equal",
             "// to it."]
    for code, (name, label) in enumerate(SUBSCRIBER_STATUSES):
        lines.append(f"localparam [3:0] {name} = 4'd{code};  // {label}")
    return "\n".join(lines) + "\n"


def load_params(path: str | Path) -> RtlParams:
    """Read a node configuration file and return its RTL parameters."""
    return rtl_params(load_config(path))
