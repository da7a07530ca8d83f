// fv_slice -- rfl_slice on its ports: the output keeps the stream rules; the slice holds at
// most two words (beats in minus beats out is 0, 1 or 2), offers one whenever it holds one,
// is ready whenever it holds fewer than two (full throughput), and the n-th word out is the
// n-th word in (none lost, duplicated or reordered).
module fv_slice #(parameter WIDTH = 4) (
    input clk, input rst_n, input [WIDTH-1:0] s_tdata, input s_tvalid, input m_tready
);
    wire s_tready, m_tvalid;
    wire [WIDTH-1:0] m_tdata;
    rfl_slice #(.WIDTH(WIDTH)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)

    // scoreboard: words in and out, and the data of the word numbered `pick`
    (* anyconst *) reg [5:0] pick;
    (* anyconst *) reg [WIDTH-1:0] pick_data;
    reg [5:0] n_in, n_out;
    wire wr = s_tvalid && s_tready, rd = m_tvalid && m_tready;
    wire [5:0] held = n_in - n_out;
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
        assert(held <= 2);                   // no overflow: never a third word
        assert(m_tvalid == (held != 0));     // a word held is offered, none invented
        assert(s_tready == (held < 2));      // ready while there is room
`ifndef FV_PROVE   // bounded only: the skid register is not visible on the ports
        if (rd && n_out == pick) assert(m_tdata == pick_data);   // order and data kept
`endif
    end
endmodule
