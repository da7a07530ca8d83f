// The receive path of the node in the fabric (tests/rtl/test_fabric_rtps_cdr.py, under cocotb): RTPS
// datagrams in (one UDP payload per packet) -> rfl_rtps_rx -> rfl_rtps_to_cdr -> rfl_node (a
// generated wire: cdr project's rfl_gtop with its configuration's parameters) -> the published
// records out, with the subscriber's status pulses and both stages' counters.
`timescale 1ns/1ps
`default_nettype none

module rtps_cdr_top #(
    parameter MAX_BYTES = 2048
) (
    input  wire         clk,
    input  wire         rst_n,
    input  wire [95:0]  cfg_prefix,
    input  wire [31:0]  cfg_reader,
    input  wire [31:0]  cfg_writer,
    input  wire [7:0]   s_axis_tdata,
    input  wire         s_axis_tvalid,
    output wire         s_axis_tready,
    input  wire         s_axis_tlast,
    output wire [7:0]   m_tdata,
    output wire         m_tvalid,
    input  wire         m_tready,
    output wire         status_valid,
    output wire [7:0]   status,
    output wire [31:0]  cnt_rx_samples,
    output wire [31:0]  cnt_rx_dropped,
    output wire [31:0]  cnt_samples,
    output wire [31:0]  cnt_dropped,
    output wire [31:0]  cnt_too_long
);
    wire [7:0] rx_tdata, rec_tdata;
    wire rx_tvalid, rx_tready, rx_tlast, rx_tuser, rec_tvalid, rec_tready;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [127:0] guid;
    wire [63:0] seq, ts;
    wire ts_valid, frame_start, busy;
    wire [31:0] cnt_packets, cnt_bad_header, cnt_malformed, cnt_rx_repeated;
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
        .cnt_dropped(cnt_rx_dropped), .cnt_repeated(cnt_rx_repeated));
    rfl_rtps_to_cdr #(.MAX_BYTES(MAX_BYTES)) u_seam (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(rx_tdata), .s_axis_tvalid(rx_tvalid), .s_axis_tready(rx_tready),
        .s_axis_tlast(rx_tlast), .s_axis_tuser(rx_tuser),
        .m_tdata(rec_tdata), .m_tvalid(rec_tvalid), .m_tready(rec_tready),
        .cnt_samples(cnt_samples), .cnt_dropped(cnt_dropped), .cnt_too_long(cnt_too_long));
    rfl_node u_node (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rec_tdata), .s_tvalid(rec_tvalid), .s_tready(rec_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .busy(busy),
        .framing(framing));
endmodule
`default_nettype wire
