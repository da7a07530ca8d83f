// fv_frame_arbiter -- rfl_frame_arbiter (rtl/fabric: rfl_fabric_node's output) on its ports,
// 4-bit data, 2-bit TDEST, 3-bit TUSER, three sources offering any datagrams under the stream
// rules (each field held until taken). Always (prove): the output keeps the stream rules (TDATA,
// TLAST, TDEST and TUSER held, valid not dropped, until taken); one source at a time is ready,
// and only while the output is; a beat taken from a source is the beat taken out (its valid and
// every field: nothing lost, duplicated or altered); and what the module's FORMAL block asserts
// on its ports with its invariants: once a datagram's first beat is taken, the output is its
// source alone until its TLAST is taken (no datagram interleaved), and a source offering a
// datagram waits behind at most two others (round robin).
module fv_frame_arbiter (
    input clk, input rst_n, input [11:0] s_axis_tdata, input [2:0] s_axis_tvalid,
    input [2:0] s_axis_tlast, input [5:0] s_axis_tdest, input [8:0] s_axis_tuser,
    input m_axis_tready
);
    wire [2:0] s_axis_tready;
    wire [3:0] m_axis_tdata;
    wire m_axis_tvalid, m_axis_tlast;
    wire [1:0] m_axis_tdest;
    wire [2:0] m_axis_tuser;
    rfl_frame_arbiter #(.DATA_BITS(4), .DEST_BITS(2), .USER_BITS(3)) dut (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast),
        .s_axis_tdest(s_axis_tdest), .s_axis_tuser(s_axis_tuser), .m_axis_tdata(m_axis_tdata),
        .m_axis_tvalid(m_axis_tvalid), .m_axis_tready(m_axis_tready),
        .m_axis_tlast(m_axis_tlast), .m_axis_tdest(m_axis_tdest), .m_axis_tuser(m_axis_tuser));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid[0], s_axis_tready[0], {s_axis_tdata[3:0], s_axis_tlast[0],
               s_axis_tdest[1:0], s_axis_tuser[2:0]})
    `FV_SOURCE(s_axis_tvalid[1], s_axis_tready[1], {s_axis_tdata[7:4], s_axis_tlast[1],
               s_axis_tdest[3:2], s_axis_tuser[5:3]})
    `FV_SOURCE(s_axis_tvalid[2], s_axis_tready[2], {s_axis_tdata[11:8], s_axis_tlast[2],
               s_axis_tdest[5:4], s_axis_tuser[8:6]})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_axis_tdest,
             m_axis_tuser})

    wire [2:0] take = s_axis_tvalid & s_axis_tready;
    always @(*) if (!fv_init && rst_n) begin
        assert(s_axis_tready == 3'd0 || s_axis_tready == 3'd1 || s_axis_tready == 3'd2 ||
               s_axis_tready == 3'd4);
        if (s_axis_tready != 3'd0) assert(m_axis_tready);
        assert((take != 3'd0) == (m_axis_tvalid && m_axis_tready));
    end
    genvar i;
    generate for (i = 0; i < 3; i = i + 1) begin : g_pass
        always @(*) if (!fv_init && rst_n && s_axis_tready[i]) begin
            assert(m_axis_tvalid == s_axis_tvalid[i]);
            assert(m_axis_tdata == s_axis_tdata[4 * i +: 4]);
            assert(m_axis_tlast == s_axis_tlast[i]);
            assert(m_axis_tdest == s_axis_tdest[2 * i +: 2]);
            assert(m_axis_tuser == s_axis_tuser[3 * i +: 3]);
        end
    end endgenerate
endmodule
