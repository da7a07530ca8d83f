// fv_rtps_ctrl -- rfl_rtps_ctrl (two slots: a writer holding sequence numbers 1..2, answers 0..2;
// a built-in reader, answer 3) on its ports, for ANY input bytes and datagram ends and any
// configuration prefix: the request stream keeps the stream rules (a request offered stays
// offered, unchanged, until taken), a request names an answer of the table (0..3), and the
// watcher is always ready (it never holds back the datagram stream it watches).
module fv_rtps_ctrl (
    input clk, input rst_n, input [95:0] cfg_prefix, input [7:0] s_axis_tdata,
    input s_axis_tvalid, input s_axis_tlast, input m_axis_tready
);
    wire s_axis_tready, m_axis_tvalid, rx_byte;
    wire [167:0] m_axis_tdata;
    wire [3:0] cnt_requests, cnt_busy, cnt_malformed, cnt_bad_header;
    rfl_rtps_ctrl #(.SLOTS(2), .SLOT_IDS(64'h000003C7_000003C2), .SLOT_MSGS(16'h0300),
                    .SLOT_LASTS(16'h0002), .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(cfg_prefix), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .s_axis_tlast(s_axis_tlast), .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .rx_byte(rx_byte), .cnt_requests(cnt_requests),
        .cnt_busy(cnt_busy), .cnt_malformed(cnt_malformed),
        .cnt_bad_header(cnt_bad_header));
`include "fv_env.vh"
    `FV_SINK(m_axis_tvalid, m_axis_tready, m_axis_tdata)
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(s_axis_tready);
        assert(rx_byte == s_axis_tvalid);
        if (m_axis_tvalid) assert(m_axis_tdata[7:0] <= 8'd3);
    end
endmodule
