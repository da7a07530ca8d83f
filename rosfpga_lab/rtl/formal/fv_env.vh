// fv_env.vh -- the formal environment every property wrapper includes: reset held in the first
// clock only, and the stream macros.
//   `FV_SOURCE(valid, ready, data): the environment offers a stream by the rules (a valid beat
//       stays valid, its data unchanged, until taken).
//   `FV_SINK(valid, ready, data): the design under proof offers its stream by the same rules.
reg fv_init = 1'b1;
always @(posedge clk) fv_init <= 1'b0;
always @(*) assume(rst_n == !fv_init);
`define FV_SOURCE(v, r, d) \
    always @(posedge clk) if (!fv_init && $past(rst_n) && $past(v && !r)) \
        assume(v && d == $past(d));
`define FV_SINK(v, r, d) \
    always @(posedge clk) if (!fv_init && rst_n && $past(rst_n) && $past(v && !r)) begin \
        assert(v); \
        assert(d == $past(d)); \
    end
