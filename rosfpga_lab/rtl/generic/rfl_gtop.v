// rfl_gtop -- the whole data path of a generated component for any message type:
//
//   s_* (8-bit, from TCP/IP) -> [rx FIFO] -> [slice] -> rfl_gsubscriber -> [slice]
//     -> rfl_elem_pack -> [axis FIFO]
//     -> rfl_window1d -> [axis FIFO, OUT_DEPTH] -> rfl_elem_unpack -> rfl_gpublisher
//     -> [register slice] -> [tx FIFO] -> m_* (8-bit, to TCP/IP)
//
// VIDEO = 1: the streamed array is HEIGHT lines of WIDTH pixels of EBYTES bytes; the packer ends
// every line with TLAST and the application is the video project's 2-D rfl_morph (32-bit TDATA,
// unused lanes zero) instead of rfl_window1d.
//
// The publisher starts a frame once the subscriber has read all of it (the frame length comes
// first and depends on every field), so the FIFO after the application holds a whole stream:
// OUT_DEPTH >= LENGTH + 2 (checked). EARLY = 1 (streaming early release, the walk's
// STREAM_EARLY, from Program.stream_early: nothing after the stream's count can refuse the
// frame): the subscriber hands the frame over at the count, the publisher writes it while the
// stream flows, and OUT_DEPTH needs only 2. The carry memory lives in the subscriber; the publisher
// reads it in order (the subscriber reads it ahead into registers). The subscriber holds two
// frames' records (and carry banks), so it reads frame n+1 while the publisher writes frame n:
// back to back a frame costs the slower walker, not both. Frame n+1's stream queues behind
// frame n's in the FIFOs: with OUT_DEPTH = LENGTH + 2 it flows once the publisher reads frame
// n's stream (the AXIS FIFO, the application's registers and 2 beats take the rest), so the
// overlap is whole when the publisher reaches its stream no later than the subscriber does;
// with EARLY the FIFOs hold a few beats and frame n+1's stream follows frame n's through the
// application.
// The FIFOs that feed logic (rx, axis in, axis out) register their RAM's output once more
// (rfl_fifo's OUTREG, when at least 3 deep): what reads them does not start from a block RAM's
// slow clock-to-output (100 MHz timing on an ECP5); same entries, two more clocks of latency.
`default_nettype none

module rfl_gtop #(
    parameter EBYTES = 4,                       // bytes per streamed element
    parameter LENGTH = 16,                      // elements of the streamed array
    parameter KSIZE = 3,
    parameter OP = 0,                           // 0 dilate, 1 erode, 2 passthrough
    parameter KIND = 0,                         // 0 unsigned, 1 signed, 2 float
    parameter CARRY_BYTES = 64,
    parameter CW = 6,
    parameter MIN_BODY = 0,
    parameter MAX_FRAME = 67108864,
    parameter RX_DEPTH = 2048,
    parameter TX_DEPTH = 2048,
    parameter AXIS_DEPTH = 16,
    parameter OUT_DEPTH = 18,
    parameter [31:0] SEQ_START = 1,
    parameter EARLY = -1,                       // streaming early release: the walk's STREAM_EARLY
                                                // (1 or 0; -1: the subscriber takes the walk's)
    parameter VIDEO = 0,                        // 1: frame the stream as video (rfl_morph)
    parameter WIDTH = LENGTH,                   // VIDEO: pixels per line
    /* verilator lint_off UNUSEDPARAM */
    parameter HEIGHT = 1                        // VIDEO: lines (unused without VIDEO)
    /* verilator lint_on UNUSEDPARAM */
) (
    input  wire       clk,
    input  wire       rst_n,
    input  wire [7:0] s_tdata,
    input  wire       s_tvalid,
    output wire       s_tready,
    output wire [7:0] m_tdata,
    output wire       m_tvalid,
    input  wire       m_tready,
    output wire       frame_start,              // the subscriber took a frame's first byte
    output wire       status_valid,             // the subscriber decided on a frame
    output wire [7:0] status,
    output wire       busy                      // something is in flight
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (VIDEO ? (EBYTES < 1 || EBYTES > 4) : !(EBYTES == 1 || EBYTES == 2 || EBYTES == 4
                                                  || EBYTES == 8))
            $fatal(1, "rfl_gtop: EBYTES must be 1, 2, 4 or 8 (VIDEO: 1..4)");
        if (LENGTH < 1) $fatal(1, "rfl_gtop: LENGTH must be at least 1");
        if (OUT_DEPTH < (EARLY == 1 ? 2 : LENGTH + 2))
            $fatal(1, "rfl_gtop: OUT_DEPTH must be at least LENGTH + 2 (a whole stream; EARLY: 2)");
    end
`else
    if (VIDEO ? (EBYTES < 1 || EBYTES > 4) : !(EBYTES == 1 || EBYTES == 2 || EBYTES == 4
                                              || EBYTES == 8)) begin : g_bad_ebytes
        $error("rfl_gtop: EBYTES must be 1, 2, 4 or 8 (VIDEO: 1..4)");
    end
    if (LENGTH < 1) begin : g_bad_length
        $error("rfl_gtop: LENGTH must be at least 1");
    end
    if (OUT_DEPTH < (EARLY == 1 ? 2 : LENGTH + 2)) begin : g_bad_out_depth
        $error("rfl_gtop: OUT_DEPTH must be at least LENGTH + 2 (a whole stream; EARLY: 2)");
    end
`endif

    localparam EW = 8 * EBYTES;
    localparam BW = EW + EBYTES + 2;            // a beat in the FIFOs: tlast, tuser, tkeep, tdata

    // rx FIFO -> subscriber
    wire [7:0] rx_tdata;
    wire rx_tvalid, rx_tready;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [$clog2(RX_DEPTH + 1)-1:0] rx_level;
    wire [$clog2(TX_DEPTH + 1)-1:0] tx_level;
    wire [$clog2(AXIS_DEPTH + 1)-1:0] axis_in_level;
    wire [$clog2(OUT_DEPTH + 1)-1:0] axis_out_level;
    wire [EBYTES-1:0] axis_out_tkeep;
    wire axis_out_tuser, axis_out_tlast;
    /* verilator lint_on UNUSEDSIGNAL */
    wire [7:0] rxf_tdata;
    wire rxf_tvalid, rxf_tready;
    rfl_fifo #(.WIDTH(8), .DEPTH(RX_DEPTH), .OUTREG(RX_DEPTH > 2 ? 1 : 0)) u_rx_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(rxf_tdata), .m_tvalid(rxf_tvalid), .m_tready(rxf_tready), .level(rx_level));
    // a register slice: the subscriber's ready (which every one of its registers' enables
    // follows) reaches the rx FIFO's read side through a flip-flop (100 MHz timing on an ECP5)
    rfl_slice #(.WIDTH(8)) u_rx_slice (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rxf_tdata), .s_tvalid(rxf_tvalid), .s_tready(rxf_tready),
        .m_tdata(rx_tdata), .m_tvalid(rx_tvalid), .m_tready(rx_tready));

    // subscriber -> element packer (streamed bytes), subscriber <-> publisher (meta, carry)
    wire [7:0] pix_in_tdata, carry_rdata;
    wire pix_in_tvalid, pix_in_tready;
    wire meta_valid, meta_release, meta_drop, sub_idle, pub_idle, carry_restart, carry_pop;
    wire carry_valid;
    wire [31:0] meta_out_len;
    rfl_gsubscriber #(.CARRY_BYTES(CARRY_BYTES), .CW(CW), .MIN_BODY(MIN_BODY),
                      .MAX_FRAME(MAX_FRAME), .EARLY(EARLY)) u_subscriber (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rx_tdata), .s_tvalid(rx_tvalid), .s_tready(rx_tready),
        .m_tdata(pix_in_tdata), .m_tvalid(pix_in_tvalid), .m_tready(pix_in_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_out_len(meta_out_len),
        .meta_drop(meta_drop), .carry_restart(carry_restart), .carry_pop(carry_pop),
        .carry_rdata(carry_rdata), .carry_valid(carry_valid), .frame_start(frame_start),
        .status_valid(status_valid),
        .status(status), .idle(sub_idle));

    // element packer -> axis FIFO -> application
    wire [EW-1:0] axis_in_tdata, app_in_tdata, app_out_tdata, axis_out_tdata;
    wire [EBYTES-1:0] axis_in_tkeep, app_in_tkeep, app_out_tkeep;
    wire axis_in_tuser, axis_in_tlast, axis_in_tvalid, axis_in_tready;
    wire app_in_tuser, app_in_tlast, app_in_tvalid, app_in_tready;
    wire app_out_tuser, app_out_tlast, app_out_tvalid, app_out_tready;
    wire axis_out_tvalid, axis_out_tready;
    // a register slice: the packer's ready (from the axis FIFO's level) reaches the
    // subscriber through a flip-flop, not on to the rx side (100 MHz timing on an ECP5)
    wire [7:0] pk_tdata;
    wire pk_tvalid, pk_tready;
    rfl_slice #(.WIDTH(8)) u_pack_slice (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pix_in_tdata), .s_tvalid(pix_in_tvalid), .s_tready(pix_in_tready),
        .m_tdata(pk_tdata), .m_tvalid(pk_tvalid), .m_tready(pk_tready));
    rfl_elem_pack #(.EBYTES(EBYTES), .LENGTH(LENGTH), .LINE(VIDEO ? WIDTH : LENGTH)) u_fifo2axi (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pk_tdata), .s_tvalid(pk_tvalid), .s_tready(pk_tready),
        .m_axis_tdata(axis_in_tdata), .m_axis_tkeep(axis_in_tkeep), .m_axis_tuser(axis_in_tuser),
        .m_axis_tlast(axis_in_tlast), .m_axis_tvalid(axis_in_tvalid),
        .m_axis_tready(axis_in_tready));
    rfl_fifo #(.WIDTH(BW), .DEPTH(AXIS_DEPTH), .OUTREG(AXIS_DEPTH > 2 ? 1 : 0)) u_axis_in_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({axis_in_tlast, axis_in_tuser, axis_in_tkeep, axis_in_tdata}),
        .s_tvalid(axis_in_tvalid), .s_tready(axis_in_tready),
        .m_tdata({app_in_tlast, app_in_tuser, app_in_tkeep, app_in_tdata}),
        .m_tvalid(app_in_tvalid), .m_tready(app_in_tready), .level(axis_in_level));
    generate
        if (VIDEO) begin : g_video
            // the video application: one pixel per 32-bit beat, lanes above EBYTES zero
            wire [31:0] v_in_tdata, v_out_tdata;
            wire [3:0] v_in_tkeep, v_out_tkeep;
            /* verilator lint_off UNUSEDSIGNAL */
            wire [3:0] v_framing;               // framing flags: the packer frames every array
            wire [31:0] v_out_all = v_out_tdata;
            wire [3:0] v_keep_all = v_out_tkeep;
            /* verilator lint_on UNUSEDSIGNAL */
            if (EW < 32) begin : g_pad
                assign v_in_tdata = {{(32 - EW){1'b0}}, app_in_tdata};
                assign v_in_tkeep = {{(4 - EBYTES){1'b0}}, app_in_tkeep};
            end else begin : g_full
                assign v_in_tdata = app_in_tdata;
                assign v_in_tkeep = app_in_tkeep;
            end
            rfl_morph #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .KSIZE(KSIZE), .OP(OP), .BYTES(EBYTES)) u_app (
                .aclk(clk), .aresetn(rst_n),
                .s_axis_tdata(v_in_tdata), .s_axis_tkeep(v_in_tkeep), .s_axis_tuser(app_in_tuser),
                .s_axis_tlast(app_in_tlast), .s_axis_tvalid(app_in_tvalid),
                .s_axis_tready(app_in_tready),
                .m_axis_tdata(v_out_tdata), .m_axis_tkeep(v_out_tkeep), .m_axis_tuser(app_out_tuser),
                .m_axis_tlast(app_out_tlast), .m_axis_tvalid(app_out_tvalid),
                .m_axis_tready(app_out_tready), .framing(v_framing));
            assign app_out_tdata = v_out_all[EW-1:0];
            assign app_out_tkeep = v_keep_all[EBYTES-1:0];
        end else begin : g_window
            /* verilator lint_off UNUSEDSIGNAL */
            wire [EBYTES-1:0] unused_keep = app_in_tkeep;
            /* verilator lint_on UNUSEDSIGNAL */
            rfl_window1d #(.EBYTES(EBYTES), .KSIZE(KSIZE), .OP(OP), .KIND(KIND)) u_app (
                .aclk(clk), .aresetn(rst_n),
                .s_axis_tdata(app_in_tdata), .s_axis_tuser(app_in_tuser), .s_axis_tlast(app_in_tlast),
                .s_axis_tvalid(app_in_tvalid), .s_axis_tready(app_in_tready),
                .m_axis_tdata(app_out_tdata), .m_axis_tkeep(app_out_tkeep), .m_axis_tuser(app_out_tuser),
                .m_axis_tlast(app_out_tlast), .m_axis_tvalid(app_out_tvalid),
                .m_axis_tready(app_out_tready));
        end
    endgenerate

    // application -> axis FIFO (a whole stream; EARLY: a few beats) -> element unpacker -> publisher
    rfl_fifo #(.WIDTH(BW), .DEPTH(OUT_DEPTH), .OUTREG(OUT_DEPTH > 2 ? 1 : 0)) u_axis_out_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({app_out_tlast, app_out_tuser, app_out_tkeep, app_out_tdata}),
        .s_tvalid(app_out_tvalid), .s_tready(app_out_tready),
        .m_tdata({axis_out_tlast, axis_out_tuser, axis_out_tkeep, axis_out_tdata}),
        .m_tvalid(axis_out_tvalid), .m_tready(axis_out_tready), .level(axis_out_level));

    wire [7:0] pix_out_tdata;
    wire pix_out_tvalid, pix_out_tready;
    rfl_elem_unpack #(.EBYTES(EBYTES)) u_axi2fifo (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(axis_out_tdata), .s_axis_tvalid(axis_out_tvalid),
        .s_axis_tready(axis_out_tready),
        .m_tdata(pix_out_tdata), .m_tvalid(pix_out_tvalid), .m_tready(pix_out_tready));

    wire [7:0] pub_tdata, tx_tdata;
    wire pub_tvalid, pub_tready, tx_tvalid, tx_tready;
    rfl_gpublisher #(.STREAM_DATA_BYTES(LENGTH * EBYTES), .SEQ_START(SEQ_START)) u_publisher (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pix_out_tdata), .s_tvalid(pix_out_tvalid), .s_tready(pix_out_tready),
        .m_tdata(pub_tdata), .m_tvalid(pub_tvalid), .m_tready(pub_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_out_len(meta_out_len),
        .meta_drop(meta_drop), .carry_restart(carry_restart), .carry_pop(carry_pop),
        .carry_rdata(carry_rdata), .carry_valid(carry_valid), .idle(pub_idle));

    // a register slice: the publisher's bytes (a carried one straight from the carry memory's
    // block RAM) reach a flip-flop before the tx FIFO's RAM (100 MHz timing on an ECP5)
    rfl_slice #(.WIDTH(8)) u_tx_slice (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pub_tdata), .s_tvalid(pub_tvalid), .s_tready(pub_tready),
        .m_tdata(tx_tdata), .m_tvalid(tx_tvalid), .m_tready(tx_tready));

    rfl_fifo #(.WIDTH(8), .DEPTH(TX_DEPTH)) u_tx_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(tx_tdata), .s_tvalid(tx_tvalid), .s_tready(tx_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready), .level(tx_level));

    assign busy = rxf_tvalid || rx_tvalid || meta_valid || pix_in_tvalid || pk_tvalid
                  || axis_in_tvalid || app_in_tvalid
                  || app_out_tvalid || axis_out_tvalid || pix_out_tvalid || pub_tvalid || tx_tvalid
                  || m_tvalid || !sub_idle || !pub_idle;
endmodule

`default_nettype wire
