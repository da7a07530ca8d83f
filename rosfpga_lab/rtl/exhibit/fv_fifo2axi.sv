// fv_fifo2axi -- rfl_fifo2axi on its ports: the beat stream keeps the rules, TUSER is set on
// the first pixel of every frame only and TLAST on the last pixel of every line only, TKEEP is
// the pixel's lanes, and a beat carries the BYTES bytes taken since the last one, lane 0 first.
// The proof takes any start-of-frame markers; the bounded check marks each frame's first byte
// (a clean stream) and asserts that no framing flag is raised.
module fv_fifo2axi #(parameter WIDTH = 3, parameter HEIGHT = 2, parameter BYTES = 2) (
    input clk, input rst_n, input [7:0] s_tdata, input s_tuser, input s_tvalid,
    input m_axis_tready
);
    wire s_tready, m_tuser, m_tlast, m_tvalid;
    wire [31:0] m_tdata;
    wire [3:0] m_tkeep, framing;
    rfl_fifo2axi #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .BYTES(BYTES)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tuser(s_tuser), .s_tvalid(s_tvalid),
        .s_tready(s_tready), .framing(framing),
        .m_axis_tdata(m_tdata), .m_axis_tkeep(m_tkeep), .m_axis_tuser(m_tuser),
        .m_axis_tlast(m_tlast), .m_axis_tvalid(m_tvalid), .m_axis_tready(m_axis_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, {s_tuser, s_tdata})
    `FV_SINK(m_tvalid, m_axis_tready, {m_tuser, m_tlast, m_tkeep, m_tdata})

    // beats out: position in the frame; bytes in: the pixel being assembled
    reg [7:0] col, row;
    reg [1:0] lane;
    reg [31:0] pixel;
    reg [15:0] nin;                               // bytes taken in this frame
    wire take = s_tvalid && s_tready, give = m_tvalid && m_axis_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            col <= 0; row <= 0; lane <= 0; pixel <= 0; nin <= 0;
        end else begin
            if (take) begin
                nin <= (nin == WIDTH * HEIGHT * BYTES - 1) ? 16'd0 : nin + 16'd1;
                lane <= (lane == BYTES - 1) ? 2'd0 : lane + 2'd1;
                pixel <= (lane == 0 ? 32'd0 : pixel) | ({24'd0, s_tdata} << (8 * lane));
            end
            if (give) begin
                col <= (col == WIDTH - 1) ? 8'd0 : col + 8'd1;
                if (col == WIDTH - 1) row <= (row == HEIGHT - 1) ? 8'd0 : row + 8'd1;
            end
        end
    end
`ifndef FV_PROVE
    always @(*) if (s_tvalid) assume(s_tuser == (nin == 0));   // a clean stream
`endif
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(col < WIDTH && row < HEIGHT);
`ifndef FV_PROVE   // bounded only: the position counted here is not visible on the ports
        assert(framing == 4'd0);                  // a clean stream is never flagged
        if (m_tvalid) begin
            assert(m_tuser == (col == 0 && row == 0));   // TUSER: first pixel of a frame only
            assert(m_tlast == (col == WIDTH - 1));        // TLAST: last pixel of a line only
            assert(m_tkeep == (4'b0001 << BYTES) - 4'b0001);
        end
        // a beat appears only after the last byte of its pixel, with exactly those bytes
        if (m_tvalid && !$past(m_tvalid && !m_axis_tready)) begin
            assert(lane == 0);
            assert(m_tdata == pixel);
        end
`endif
    end
endmodule
