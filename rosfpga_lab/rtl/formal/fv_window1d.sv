// fv_window1d -- rfl_window1d on its ports (1-byte unsigned elements, arrays of 3, dilate over
// 3), fed arrays by the stream rules (TUSER on each array's first element, TLAST on its last):
// its beat stream keeps the rules, TKEEP is the element's lanes, it takes nothing more than it
// gives out plus the window, TUSER/TLAST come out on an array's first/last element only, and
// each element out is the maximum of its in-array neighbours (the reference computed here).
module fv_window1d #(parameter LENGTH = 3) (
    input clk, input rst_n, input [7:0] s_tdata, input s_tuser, input s_tlast, input s_tvalid,
    input m_axis_tready
);
    wire s_tready, m_tuser, m_tlast, m_tvalid;
    wire [7:0] m_tdata;
    wire m_tkeep;
    rfl_window1d #(.EBYTES(1), .KSIZE(3), .OP(0), .KIND(0)) dut (
        .aclk(clk), .aresetn(rst_n), .s_axis_tdata(s_tdata), .s_axis_tuser(s_tuser),
        .s_axis_tlast(s_tlast), .s_axis_tvalid(s_tvalid), .s_axis_tready(s_tready),
        .m_axis_tdata(m_tdata), .m_axis_tkeep(m_tkeep), .m_axis_tuser(m_tuser),
        .m_axis_tlast(m_tlast), .m_axis_tvalid(m_tvalid), .m_axis_tready(m_axis_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, {s_tuser, s_tlast, s_tdata})
    `FV_SINK(m_tvalid, m_axis_tready, {m_tuser, m_tlast, m_tkeep, m_tdata})

    // the element positions in and out, and the array coming in
    reg [7:0] in_idx, out_idx;
    reg [7:0] mem [0:LENGTH-1];
    wire take = s_tvalid && s_tready, give = m_tvalid && m_axis_tready;
    integer i;
    always @(posedge clk) begin
        if (!rst_n) begin
            in_idx <= 0; out_idx <= 0;
            for (i = 0; i < LENGTH; i = i + 1) mem[i] <= 0;
        end else begin
            if (take) begin
                mem[in_idx] <= s_tdata;
                in_idx <= (in_idx == LENGTH - 1) ? 8'd0 : in_idx + 8'd1;
            end
            if (give) out_idx <= (out_idx == LENGTH - 1) ? 8'd0 : out_idx + 8'd1;
        end
    end
    // the input arrays are well formed
    always @(*) if (rst_n && s_tvalid) assume(s_tuser == (in_idx == 0) && s_tlast == (in_idx == LENGTH - 1));

    // the reference: the maximum over the in-array neighbours of element `at`
    function [7:0] max2(input [7:0] a, input [7:0] b);
        max2 = a > b ? a : b;
    endfunction
    function [7:0] expect_at(input [7:0] at);
        begin
            expect_at = mem[at];
            if (at > 0) expect_at = max2(expect_at, mem[at - 1]);
            if (at < LENGTH - 1) expect_at = max2(expect_at, mem[at + 1]);
        end
    endfunction

    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(in_idx < LENGTH && out_idx < LENGTH);
        assert(m_tkeep == 1'b1);
`ifndef FV_PROVE   // bounded only: the positions counted here are not visible on the ports
        if (m_tvalid) begin
            assert(m_tuser == (out_idx == 0));          // TUSER: an array's first element only
            assert(m_tlast == (out_idx == LENGTH - 1)); // TLAST: an array's last element only
        end
        // a new beat is the maximum over its element's in-array window
        if (m_tvalid && !$past(m_tvalid && !m_axis_tready)) assert(m_tdata == expect_at(out_idx));
`endif
    end
endmodule
