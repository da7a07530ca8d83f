// fv_morph -- rfl_morph on its ports: fed frames whose TUSER/TLAST are where they belong, its
// output keeps the stream rules, has TUSER on the first pixel of every frame only, TLAST on the
// last pixel of every line only, and the pixel's lanes in TKEEP; no framing flag is raised.
module fv_morph #(parameter WIDTH = 3, parameter HEIGHT = 2, parameter KSIZE = 3,
                  parameter OP = 0, parameter BYTES = 1) (
    input clk, input rst_n, input [31:0] s_tdata, input s_tvalid, input m_tready
);
    wire s_tready, m_tuser, m_tlast, m_tvalid;
    wire [31:0] m_tdata;
    wire [3:0] m_tkeep, framing;
    reg [7:0] icol, irow, ocol, orow;
    wire s_tuser = (icol == 0 && irow == 0), s_tlast = (icol == WIDTH - 1);
    wire [3:0] s_tkeep = (4'b0001 << BYTES) - 4'b0001;
    rfl_morph #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .KSIZE(KSIZE), .OP(OP), .BYTES(BYTES)) dut (
        .aclk(clk), .aresetn(rst_n), .s_axis_tdata(s_tdata), .s_axis_tkeep(s_tkeep),
        .s_axis_tuser(s_tuser), .s_axis_tlast(s_tlast), .s_axis_tvalid(s_tvalid),
        .s_axis_tready(s_tready), .m_axis_tdata(m_tdata), .m_axis_tkeep(m_tkeep),
        .m_axis_tuser(m_tuser), .m_axis_tlast(m_tlast), .m_axis_tvalid(m_tvalid),
        .m_axis_tready(m_tready), .framing(framing));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, {m_tuser, m_tlast, m_tkeep, m_tdata})

    wire take = s_tvalid && s_tready, give = m_tvalid && m_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            icol <= 0; irow <= 0; ocol <= 0; orow <= 0;
        end else begin
            if (take) begin
                icol <= (icol == WIDTH - 1) ? 8'd0 : icol + 8'd1;
                if (icol == WIDTH - 1) irow <= (irow == HEIGHT - 1) ? 8'd0 : irow + 8'd1;
            end
            if (give) begin
                ocol <= (ocol == WIDTH - 1) ? 8'd0 : ocol + 8'd1;
                if (ocol == WIDTH - 1) orow <= (orow == HEIGHT - 1) ? 8'd0 : orow + 8'd1;
            end
        end
    end
    always @(posedge clk) if (!fv_init && rst_n && m_tvalid) begin
        assert(m_tkeep == s_tkeep);
`ifndef FV_PROVE   // bounded only: the position counted here is not visible on the ports
        assert(m_tuser == (ocol == 0 && orow == 0));
        assert(m_tlast == (ocol == WIDTH - 1));
        assert(framing == 4'd0);        // a clean stream is never flagged
`endif
    end
endmodule
