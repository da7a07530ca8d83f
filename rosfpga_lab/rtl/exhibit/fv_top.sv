// fv_top -- rfl_top, tiny, fed any bytes by the stream rules: its 8-bit output keeps the rules.
module fv_top (input clk, input rst_n, input [7:0] s_tdata, input s_tvalid, input m_tready);
    wire s_tready, m_tvalid, frame_start, status_valid, busy;
    wire [7:0] m_tdata;
    wire [3:0] status;
    wire [7:0] framing;
    rfl_top #(.WIDTH(2), .HEIGHT(1), .BYTES(1), .ENC_LEN(5), .ENCODING("mono8"), .OP(0),
              .KSIZE(3), .FRAME_ID_MAX(4), .MAX_FRAME(64), .RX_DEPTH(4), .TX_DEPTH(4),
              .AXIS_DEPTH(4)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready), .frame_start(frame_start),
        .status_valid(status_valid), .status(status), .busy(busy), .framing(framing));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)
    always @(posedge clk) if (!fv_init && rst_n) begin
        if (m_tvalid) assert(busy);                        // output pending counts as in flight
    end
endmodule
