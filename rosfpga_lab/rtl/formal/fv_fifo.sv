// fv_fifo -- properties of rfl_fifo on its ports only: both sides keep the stream rules, no
// beat is lost, duplicated or reordered (the data of an arbitrary n-th beat in comes out as the
// n-th beat out), no overflow or underflow (level counts beats in minus beats out, never above
// DEPTH), and the input is ready whenever there is room.
module fv_fifo #(parameter WIDTH = 4, parameter DEPTH = 4) (
    input clk, input rst_n,
    input [WIDTH-1:0] s_tdata, input s_tvalid, input m_tready
);
    localparam LB = $clog2(DEPTH + 1);
    wire s_tready, m_tvalid;
    wire [WIDTH-1:0] m_tdata;
    wire [LB-1:0] level;
    rfl_fifo #(.WIDTH(WIDTH), .DEPTH(DEPTH)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready), .level(level));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)

    // scoreboard: beats in and out, and the data of the beat numbered `pick`
    (* anyconst *) reg [5:0] pick;
    (* anyconst *) reg [WIDTH-1:0] pick_data;
    reg [5:0] n_in, n_out;
    wire wr = s_tvalid && s_tready, rd = m_tvalid && m_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            n_in <= 0;
            n_out <= 0;
        end else begin
            n_in <= n_in + wr;
            n_out <= n_out + rd;
        end
    end
    always @(*) if (rst_n && wr && n_in == pick) assume(s_tdata == pick_data);
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(level == n_in - n_out);            // nothing lost, nothing duplicated
        assert(level <= DEPTH);                   // no overflow
        if (m_tvalid) assert(level != 0);         // no underflow
        if (level < DEPTH - 1) assert(s_tready);  // room means ready
`ifndef FV_PROVE   // bounded only: the stored words are not visible on the ports, so induction
                   // cannot relate them to the picked beat
        if (rd && n_out == pick) assert(m_tdata == pick_data);   // order and data kept
`endif
    end
endmodule
