// fv_axi2fifo -- rfl_axi2fifo on its ports: both streams keep the rules, and every beat
// becomes its kept lanes' bytes, lane 0 first, none lost or repeated (the beat taken last is
// compared byte by byte with what comes out).
module fv_axi2fifo (
    input clk, input rst_n, input [31:0] s_tdata, input [3:0] s_tkeep, input s_tvalid,
    input m_tready
);
    wire s_tready, m_tvalid;
    wire [7:0] m_tdata;
    rfl_axi2fifo dut (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(s_tdata), .s_axis_tkeep(s_tkeep),
        .s_axis_tvalid(s_tvalid), .s_axis_tready(s_tready), .m_tdata(m_tdata),
        .m_tvalid(m_tvalid), .m_tready(m_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, {s_tkeep, s_tdata})
    `FV_SINK(m_tvalid, m_tready, m_tdata)

    // the beat last taken and the lanes of it still to come out
    reg [31:0] d;
    reg [3:0] left;
    wire [1:0] lane = left[0] ? 2'd0 : left[1] ? 2'd1 : left[2] ? 2'd2 : 2'd3;
    always @(posedge clk) begin
        if (!rst_n) begin
            d <= 0; left <= 0;
        end else if (s_tvalid && s_tready) begin
            d <= s_tdata; left <= s_tkeep;
        end else if (m_tvalid && m_tready) begin
            left <= left & ~(4'b0001 << lane);
        end
    end
    always @(posedge clk) if (!fv_init && rst_n) begin
`ifndef FV_PROVE   // bounded only: the lanes left are not visible on the ports
        assert(m_tvalid == (left != 0));                 // a byte for every kept lane, no more
        if (m_tvalid) assert(m_tdata == d[8 * lane +: 8]);
        if (s_tvalid && s_tready) assert(left == 0 || (m_tvalid && m_tready
                                         && (left & (left - 4'd1)) == 0));  // no beat overwritten
`endif
    end
endmodule
