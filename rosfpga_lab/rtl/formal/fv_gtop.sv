// fv_gtop -- rfl_gtop, tiny (the walk of rosfpga_lab.rtl.proofs.formal_program, 1-byte
// elements, arrays of 2, dilate over 3, FIFOs 2 and 4 deep), fed any bytes by the stream rules:
// its 8-bit output keeps the rules, every status is a code of the table, and it is busy while
// output is pending. The walk hands a frame over at its stream's count (EARLY); FV_WHOLE: the
// same walk without an exact fit, a frame handed over once read (formal_program(early=False)).
module fv_gtop (input clk, input rst_n, input [7:0] s_tdata, input s_tvalid, input m_tready);
    wire s_tready, m_tvalid, frame_start, status_valid, busy;
    wire [7:0] m_tdata, status;
`ifdef FV_WHOLE
    localparam EARLY = 0;
`else
    localparam EARLY = 1;
`endif
    rfl_gtop #(.EBYTES(1), .LENGTH(2), .KSIZE(3), .OP(0), .KIND(0), .CARRY_BYTES(6), .CW(3),
               .MIN_BODY(11), .MAX_FRAME(13), .RX_DEPTH(2), .TX_DEPTH(2), .AXIS_DEPTH(2),
               .OUT_DEPTH(4), .SEQ_START(1), .EARLY(EARLY)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready), .frame_start(frame_start),
        .status_valid(status_valid), .status(status), .busy(busy));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)
    always @(posedge clk) if (!fv_init && rst_n) begin
        if (m_tvalid) assert(busy);                        // output pending counts as in flight
        if (status_valid) assert(status <= 8'd4);          // a code of the table
    end
endmodule
