// The node in the fabric from RTPS to RTPS (tests/rtl/test_fabric_rtps_loop.py, under cocotb):
// RTPS datagrams in (one UDP payload per packet) -> rfl_rtps_rx -> rfl_rtps_to_cdr -> rfl_node
// (a generated wire: cdr project's rfl_gtop with its configuration's parameters) -> rfl_rtps_tx
// (the participant's parameters, rtl.discrom.tx_parameters) -> RTPS datagrams out, with the
// subscriber's status pulses and the transmit path's counters.
`timescale 1ns/1ps
`default_nettype none

module rtps_loop_top #(
    parameter MAX_BYTES = 2048,
    parameter [95:0] GUID_PREFIX = 96'd1,
    parameter [31:0] WRITER_ID = 32'h00000102,
    parameter [31:0] READER_ID = 32'd0,
    parameter FRAG_BYTES = 1344,
    parameter MAX_DATAGRAM = 1472,
    parameter INFO_TS = 1
) (
    input  wire         clk,
    input  wire         rst_n,
    input  wire [95:0]  cfg_prefix,
    input  wire [31:0]  cfg_reader,
    input  wire [31:0]  cfg_writer,
    input  wire [63:0]  cfg_time,
    input  wire [7:0]   s_axis_tdata,
    input  wire         s_axis_tvalid,
    output wire         s_axis_tready,
    input  wire         s_axis_tlast,
    output wire [7:0]   m_axis_tdata,
    output wire         m_axis_tvalid,
    input  wire         m_axis_tready,
    output wire         m_axis_tlast,
    output wire         status_valid,
    output wire [7:0]   status,
    output wire [31:0]  cnt_samples,
    output wire [31:0]  cnt_datagrams,
    output wire [31:0]  cnt_dropped
);
    wire [7:0] rx_tdata, rec_tdata, pub_tdata;
    wire rx_tvalid, rx_tready, rx_tlast, rx_tuser, rec_tvalid, rec_tready;
    wire pub_tvalid, pub_tready;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [127:0] guid;
    wire [63:0] seq, ts, tx_seq;
    wire ts_valid, frame_start, busy;
    wire [31:0] cnt_packets, cnt_bad_header, cnt_malformed, cnt_rx_samples, cnt_rx_dropped;
    wire [31:0] cnt_seam_samples, cnt_seam_dropped, cnt_too_long;
    wire [7:0] framing;
    /* verilator lint_on UNUSEDSIGNAL */
    rfl_rtps_rx u_rx (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(cfg_prefix), .cfg_reader(cfg_reader),
        .cfg_writer(cfg_writer), .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast),
        .m_axis_tdata(rx_tdata), .m_axis_tvalid(rx_tvalid), .m_axis_tready(rx_tready),
        .m_axis_tlast(rx_tlast), .m_axis_tuser(rx_tuser), .m_sample_guid(guid),
        .m_sample_seq(seq), .m_sample_ts(ts), .m_sample_ts_valid(ts_valid),
        .cnt_packets(cnt_packets), .cnt_bad_header(cnt_bad_header),
        .cnt_malformed(cnt_malformed), .cnt_samples(cnt_rx_samples),
        .cnt_dropped(cnt_rx_dropped));
    rfl_rtps_to_cdr #(.MAX_BYTES(MAX_BYTES)) u_seam (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(rx_tdata), .s_axis_tvalid(rx_tvalid), .s_axis_tready(rx_tready),
        .s_axis_tlast(rx_tlast), .s_axis_tuser(rx_tuser),
        .m_tdata(rec_tdata), .m_tvalid(rec_tvalid), .m_tready(rec_tready),
        .cnt_samples(cnt_seam_samples), .cnt_dropped(cnt_seam_dropped),
        .cnt_too_long(cnt_too_long));
    rfl_node u_node (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rec_tdata), .s_tvalid(rec_tvalid), .s_tready(rec_tready),
        .m_tdata(pub_tdata), .m_tvalid(pub_tvalid), .m_tready(pub_tready),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .busy(busy),
        .framing(framing));
    rfl_rtps_tx #(.GUID_PREFIX(GUID_PREFIX), .WRITER_ID(WRITER_ID), .READER_ID(READER_ID),
                  .FRAG_BYTES(FRAG_BYTES), .MAX_DATAGRAM(MAX_DATAGRAM), .INFO_TS(INFO_TS)) u_tx (
        .clk(clk), .rst_n(rst_n), .cfg_time(cfg_time),
        .s_tdata(pub_tdata), .s_tvalid(pub_tvalid), .s_tready(pub_tready),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast), .m_seq(tx_seq),
        .cnt_samples(cnt_samples), .cnt_datagrams(cnt_datagrams), .cnt_dropped(cnt_dropped));
endmodule
`default_nettype wire
