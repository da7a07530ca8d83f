// fv_rtps_tx -- rfl_rtps_tx (rtl/fabric) with 4-byte fragments, samples of at most 16 bytes and
// INFO_TS on its ports: any records (any lengths, any bytes) under the stream rules, any time.
// Always (prove): the output keeps the stream rules (a valid beat, its byte and TLAST held until
// taken), and the framing the module's FORMAL block asserts with its invariants: every datagram
// opens with "R" and ends with TLAST within MAX_DATAGRAM bytes (here the smallest legal, 104:
// header 20, INFO_TS 12, DATA_FRAG 36, a 4-byte fragment, HEARTBEAT 32). Bounded (bmc, not
// FV_PROVE): the first datagram starts with the RTPS header's first 8 bytes: "RTPS", version 2.3,
// vendor 0, whatever the input and backpressure (the GUID prefix after them: the cocotb tests).
module fv_rtps_tx (
    input clk, input rst_n, input [63:0] cfg_time, input [7:0] s_tdata, input s_tvalid,
    input m_axis_tready
);
    localparam [95:0] PREFIX = 96'h010f_0102_0304_0506_0708_090a;
    wire s_tready, m_axis_tvalid, m_axis_tlast;
    wire [7:0] m_axis_tdata;
    wire [63:0] m_seq;
    wire [3:0] cnt_samples, cnt_datagrams, cnt_dropped;
    rfl_rtps_tx #(.GUID_PREFIX(PREFIX), .WRITER_ID(32'h00000102), .FRAG_BYTES(4),
                  .MAX_DATAGRAM(104), .MAX_SAMPLE(16), .INFO_TS(1), .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_time(cfg_time), .s_tdata(s_tdata),
        .s_tvalid(s_tvalid), .s_tready(s_tready), .m_axis_tdata(m_axis_tdata),
        .m_axis_tvalid(m_axis_tvalid), .m_axis_tready(m_axis_tready),
        .m_axis_tlast(m_axis_tlast), .m_seq(m_seq), .cnt_samples(cnt_samples),
        .cnt_datagrams(cnt_datagrams), .cnt_dropped(cnt_dropped));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast})

`ifndef FV_PROVE
    // the first datagram's first 8 bytes: the RTPS header's magic, version and vendor
    localparam [63:0] HEADER = {32'h52545053, 8'd2, 8'd3, 16'd0};
    reg [7:0] n_out;
    wire take_out = m_axis_tvalid && m_axis_tready;
    always @(posedge clk) begin
        if (!rst_n) n_out <= 8'd0;
        else if (take_out) begin
            if (n_out < 8'd8) begin
                assert(m_axis_tdata == HEADER[63 - 8 * n_out -: 8]);
                assert(!m_axis_tlast);
            end
            if (n_out != 8'd255) n_out <= n_out + 8'd1;
        end
    end
`endif
endmodule
