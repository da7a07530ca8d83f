// fv_udp_store -- rfl_udp_store (rtl/fabric) with a 16-byte ring and a queue of 2 packets, under
// any input packets (any bytes, TLAST, TUSER, sideband) by the stream rules. Bounded (bmc): the
// output keeps the stream rules (a beat, its TLAST, its packet's meta and length held until
// taken); a packet's done_* pulses come only with its TLAST beat; WAIT = 0 (FV_WAIT unset)
// never holds its input back.
module fv_udp_store (
    input clk, input rst_n, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tlast, input s_axis_tuser, input [1:0] s_meta, input m_axis_tready
);
`ifdef FV_WAIT
    localparam WAIT = 1;
`else
    localparam WAIT = 0;
`endif
    wire s_axis_tready, m_axis_tvalid, m_axis_tlast, done_keep, done_drop, done_user;
    wire [7:0] m_axis_tdata;
    wire [1:0] m_meta;
    wire [15:0] m_len;
    rfl_udp_store #(.ADDR_BITS(4), .QUEUE_BITS(1), .META_W(2), .WAIT(WAIT)) dut (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast),
        .s_axis_tuser(s_axis_tuser), .s_meta(s_meta), .m_axis_tdata(m_axis_tdata),
        .m_axis_tvalid(m_axis_tvalid), .m_axis_tready(m_axis_tready),
        .m_axis_tlast(m_axis_tlast), .m_meta(m_meta), .m_len(m_len), .done_keep(done_keep),
        .done_drop(done_drop), .done_user(done_user));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_axis_tuser, s_meta})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_meta, m_len})
    wire fin = s_axis_tvalid && s_axis_tready && s_axis_tlast;
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(!(done_keep || done_drop) || fin);
        assert(!(done_keep && done_drop));
        assert(!done_user || done_drop);
        if (WAIT == 0) assert(s_axis_tready);
        if (m_axis_tvalid) assert(m_len != 16'd0 && m_len <= 16'd16);
    end
endmodule
