// fv_rtps_rx -- rfl_rtps_rx (rtl/fabric) on its ports: any input bytes under the stream rules,
// any configuration; the output keeps the stream rules (a valid beat, its byte, TLAST, TUSER
// and the sample's sideband held until taken), TUSER only on a TLAST beat, and the input is
// taken only when the output register is free or leaving (never more than a beat pending).
module fv_rtps_rx (
    input clk, input rst_n, input [95:0] cfg_prefix, input [31:0] cfg_reader,
    input [31:0] cfg_writer, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tlast, input m_axis_tready
);
    wire s_axis_tready, m_axis_tvalid, m_axis_tlast, m_axis_tuser, m_sample_ts_valid;
    wire [7:0] m_axis_tdata;
    wire [127:0] m_sample_guid;
    wire [63:0] m_sample_seq, m_sample_ts;
    wire [3:0] cnt_packets, cnt_bad_header, cnt_malformed, cnt_samples, cnt_dropped;
    wire [3:0] cnt_repeated;
    rfl_rtps_rx #(.COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(cfg_prefix), .cfg_reader(cfg_reader),
        .cfg_writer(cfg_writer), .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast),
        .m_axis_tuser(m_axis_tuser), .m_sample_guid(m_sample_guid),
        .m_sample_seq(m_sample_seq), .m_sample_ts(m_sample_ts),
        .m_sample_ts_valid(m_sample_ts_valid), .cnt_packets(cnt_packets),
        .cnt_bad_header(cnt_bad_header), .cnt_malformed(cnt_malformed),
        .cnt_samples(cnt_samples), .cnt_dropped(cnt_dropped), .cnt_repeated(cnt_repeated));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_axis_tuser,
             m_sample_guid, m_sample_seq, m_sample_ts, m_sample_ts_valid})
    always @(posedge clk) if (!fv_init && rst_n) begin
        if (m_axis_tvalid && m_axis_tuser) assert(m_axis_tlast);   // a drop ends a packet
        if (s_axis_tready) assert(!m_axis_tvalid || m_axis_tready);
    end
endmodule
