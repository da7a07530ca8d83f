// rfl_top -- the whole data path of the ROS-compliant FPGA component, as the paper's
// conventional design:
//
//   s_* (8-bit, from TCP/IP) -> [rx FIFO] -> subscriber -> fifo2axi -> [axis FIFO] -> rfl_morph
//     -> [axis FIFO] -> axi2fifo -> publisher -> [slice] -> [tx FIFO] -> m_* (8-bit, to TCP/IP)
//
// The subscriber holds the carried-over fields (stamp, frame_id) of an accepted frame until
// the publisher has written them. OP: 0 dilate, 1 erode, 2 passthrough.
`default_nettype none

module rfl_top #(
    parameter WIDTH = 640,
    parameter HEIGHT = 480,
    parameter BYTES = 4,
    parameter ENC_LEN = 5,
    parameter [8*32-1:0] ENCODING = "rgba8",
    parameter OP = 0,
    parameter KSIZE = 3,
    parameter FRAME_ID_MAX = 256,
    parameter ENCODING_MAX = 32,
    parameter MIN_BODY = 37,
    parameter MAX_FRAME = 67108864,
    parameter AFTER_FRAME_ID = 12,
    parameter AFTER_ENCODING = 9,
    parameter RX_DEPTH = 2048,
    parameter TX_DEPTH = 2048,
    parameter AXIS_DEPTH = 16,
    parameter [31:0] SEQ_START = 1
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
    output wire [3:0] status,
    output wire       busy,                     // something is in flight
    // framing flags since reset (hw.framing.FRAMING_FLAGS order): fifo2axi's in 7..4,
    // the application's in 3..0
    output wire [7:0] framing
);
    localparam FIDW = $clog2(FRAME_ID_MAX + 1);
    localparam FIDA = (FRAME_ID_MAX > 1) ? $clog2(FRAME_ID_MAX) : 1;

    // rx FIFO -> subscriber
    wire [7:0] rx_tdata;
    wire rx_tvalid, rx_tready;
    wire [$clog2(RX_DEPTH + 1)-1:0] rx_level;
    // OUTREG: the subscriber reads a register, not the block RAM's output (timing)
    rfl_fifo #(.WIDTH(8), .DEPTH(RX_DEPTH), .OUTREG(RX_DEPTH > 2 ? 1 : 0)) u_rx_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(rx_tdata), .m_tvalid(rx_tvalid), .m_tready(rx_tready), .level(rx_level));

    // subscriber -> fifo2axi (pixel bytes), subscriber <-> publisher (carried-over fields)
    wire [7:0] pix_in_tdata;
    wire pix_in_tvalid, pix_in_tready, pix_in_tuser;
    wire meta_valid, meta_release, sub_idle, pub_idle;
    wire [31:0] meta_secs, meta_nsecs;
    wire [7:0] meta_bigendian, fid_rdata;
    wire [FIDW-1:0] meta_fid_len;
    wire [FIDA-1:0] fid_raddr;
    rfl_subscriber #(
        .WIDTH(WIDTH), .HEIGHT(HEIGHT), .BYTES(BYTES), .ENC_LEN(ENC_LEN), .ENCODING(ENCODING),
        .FRAME_ID_MAX(FRAME_ID_MAX), .ENCODING_MAX(ENCODING_MAX), .MIN_BODY(MIN_BODY),
        .MAX_FRAME(MAX_FRAME), .AFTER_FRAME_ID(AFTER_FRAME_ID), .AFTER_ENCODING(AFTER_ENCODING)
    ) u_subscriber (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rx_tdata), .s_tvalid(rx_tvalid), .s_tready(rx_tready),
        .m_tdata(pix_in_tdata), .m_tuser(pix_in_tuser), .m_tvalid(pix_in_tvalid),
        .m_tready(pix_in_tready), .meta_valid(meta_valid), .meta_release(meta_release), .meta_secs(meta_secs),
        .meta_nsecs(meta_nsecs), .meta_bigendian(meta_bigendian), .meta_fid_len(meta_fid_len),
        .fid_raddr(fid_raddr), .fid_rdata(fid_rdata),
        .frame_start(frame_start), .status_valid(status_valid), .status(status),
        .idle(sub_idle));

    // fifo2axi -> axis FIFO
    wire [31:0] axis_in_tdata;
    wire [3:0] axis_in_tkeep;
    wire axis_in_tuser, axis_in_tlast, axis_in_tvalid, axis_in_tready;
    rfl_fifo2axi #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .BYTES(BYTES)) u_fifo2axi (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pix_in_tdata), .s_tuser(pix_in_tuser), .s_tvalid(pix_in_tvalid),
        .s_tready(pix_in_tready), .framing(framing[7:4]),
        .m_axis_tdata(axis_in_tdata), .m_axis_tkeep(axis_in_tkeep), .m_axis_tuser(axis_in_tuser),
        .m_axis_tlast(axis_in_tlast), .m_axis_tvalid(axis_in_tvalid),
        .m_axis_tready(axis_in_tready));

    // axis FIFO -> application
    wire [31:0] app_in_tdata;
    wire [3:0] app_in_tkeep;
    wire app_in_tuser, app_in_tlast, app_in_tvalid, app_in_tready;
    wire [$clog2(AXIS_DEPTH + 1)-1:0] axis_in_level, axis_out_level;
    rfl_fifo #(.WIDTH(38), .DEPTH(AXIS_DEPTH)) u_axis_in_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({axis_in_tlast, axis_in_tuser, axis_in_tkeep, axis_in_tdata}),
        .s_tvalid(axis_in_tvalid), .s_tready(axis_in_tready),
        .m_tdata({app_in_tlast, app_in_tuser, app_in_tkeep, app_in_tdata}),
        .m_tvalid(app_in_tvalid), .m_tready(app_in_tready), .level(axis_in_level));

    // application -> axis FIFO
    wire [31:0] app_out_tdata;
    wire [3:0] app_out_tkeep;
    wire app_out_tuser, app_out_tlast, app_out_tvalid, app_out_tready;
    rfl_morph #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .KSIZE(KSIZE), .OP(OP), .BYTES(BYTES)) u_app (
        .aclk(clk), .aresetn(rst_n),
        .s_axis_tdata(app_in_tdata), .s_axis_tkeep(app_in_tkeep), .s_axis_tuser(app_in_tuser),
        .s_axis_tlast(app_in_tlast), .s_axis_tvalid(app_in_tvalid), .s_axis_tready(app_in_tready),
        .m_axis_tdata(app_out_tdata), .m_axis_tkeep(app_out_tkeep), .m_axis_tuser(app_out_tuser),
        .m_axis_tlast(app_out_tlast), .m_axis_tvalid(app_out_tvalid),
        .m_axis_tready(app_out_tready), .framing(framing[3:0]));

    wire [31:0] axis_out_tdata;
    wire [3:0] axis_out_tkeep;
    wire axis_out_tuser, axis_out_tlast, axis_out_tvalid, axis_out_tready;
    rfl_fifo #(.WIDTH(38), .DEPTH(AXIS_DEPTH)) u_axis_out_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({app_out_tlast, app_out_tuser, app_out_tkeep, app_out_tdata}),
        .s_tvalid(app_out_tvalid), .s_tready(app_out_tready),
        .m_tdata({axis_out_tlast, axis_out_tuser, axis_out_tkeep, axis_out_tdata}),
        .m_tvalid(axis_out_tvalid), .m_tready(axis_out_tready), .level(axis_out_level));

    // axi2fifo -> publisher
    wire [7:0] pix_out_tdata;
    wire pix_out_tvalid, pix_out_tready;
    rfl_axi2fifo u_axi2fifo (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(axis_out_tdata), .s_axis_tkeep(axis_out_tkeep),
        .s_axis_tvalid(axis_out_tvalid), .s_axis_tready(axis_out_tready),
        .m_tdata(pix_out_tdata), .m_tvalid(pix_out_tvalid), .m_tready(pix_out_tready));

    // publisher -> register slice -> tx FIFO
    wire [7:0] pub_tdata, tx_tdata;
    wire pub_tvalid, pub_tready, tx_tvalid, tx_tready, frame_done;
    wire [$clog2(TX_DEPTH + 1)-1:0] tx_level;
    rfl_publisher #(
        .WIDTH(WIDTH), .HEIGHT(HEIGHT), .BYTES(BYTES), .ENC_LEN(ENC_LEN), .ENCODING(ENCODING),
        .FRAME_ID_MAX(FRAME_ID_MAX), .MIN_BODY(MIN_BODY), .SEQ_START(SEQ_START)
    ) u_publisher (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pix_out_tdata), .s_tvalid(pix_out_tvalid), .s_tready(pix_out_tready),
        .m_tdata(pub_tdata), .m_tvalid(pub_tvalid), .m_tready(pub_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_secs(meta_secs),
        .meta_nsecs(meta_nsecs), .meta_bigendian(meta_bigendian), .meta_fid_len(meta_fid_len),
        .fid_raddr(fid_raddr), .fid_rdata(fid_rdata), .frame_done(frame_done), .idle(pub_idle));

    // the publisher's output multiplexer and the tx FIFO's fullness meet in registers (timing)
    rfl_slice #(.WIDTH(8)) u_tx_slice (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(pub_tdata), .s_tvalid(pub_tvalid), .s_tready(pub_tready),
        .m_tdata(tx_tdata), .m_tvalid(tx_tvalid), .m_tready(tx_tready));

    rfl_fifo #(.WIDTH(8), .DEPTH(TX_DEPTH)) u_tx_fifo (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(tx_tdata), .s_tvalid(tx_tvalid), .s_tready(tx_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready), .level(tx_level));

    // The publisher is busy from an accepted frame until its last byte, so an accepted frame
    // (and every pixel of it inside the application) counts as in flight.
    assign busy = rx_tvalid || meta_valid || pix_in_tvalid || axis_in_tvalid || app_in_tvalid
                  || app_out_tvalid || axis_out_tvalid || pix_out_tvalid || pub_tvalid || tx_tvalid
                  || m_tvalid || !sub_idle || !pub_idle;

    // FIFO levels and the publisher's frame_done are for testbenches and waveforms; axi2fifo
    // sends bytes, not beats, so TUSER/TLAST end at its input
    wire unused_ok = &{1'b0, rx_level, axis_in_level, axis_out_level, tx_level, frame_done,
                       axis_out_tuser, axis_out_tlast};
endmodule

`default_nettype wire
