// A COPY OF rfl_fifo WITH A PLANTED BUG, for tests/rtl/test_formal.py: the proof must fail.
// rfl_fifo -- a synchronous first-word-fall-through FIFO of DEPTH entries, valid/ready on both
// sides. DEPTH-1 entries live in a RAM with a registered read (block or distributed RAM after
// synthesis); the last one is the output register that m_tdata shows. A word written into an
// empty FIFO appears at the output two clocks later.
module rfl_fifo #(
    parameter WIDTH = 8,
    parameter DEPTH = 16,                       // entries, at least 2
    parameter LEVEL_BITS = $clog2(DEPTH + 1)
) (
    input                       clk,
    input                       rst_n,
    input      [WIDTH-1:0]      s_tdata,
    input                       s_tvalid,
    output                      s_tready,
    output     [WIDTH-1:0]      m_tdata,
    output                      m_tvalid,
    input                       m_tready,
    output     [LEVEL_BITS-1:0] level
);
    localparam MEMD = DEPTH - 1;
    localparam AW = (MEMD > 1) ? $clog2(MEMD) : 1;
    localparam [AW-1:0] LAST = MEMD - 1;        // the RAM's last address

    reg [WIDTH-1:0] mem [0:MEMD-1];
    reg [AW-1:0] wptr, rptr;
    reg [LEVEL_BITS-1:0] cnt;                   // entries in the RAM
    reg [WIDTH-1:0] dout;
    reg dvalid;

    wire wr = s_tvalid && s_tready;
    wire pop = dvalid && m_tready;
    wire load = (cnt != 0) && (!dvalid || pop);

    assign s_tready = (cnt != MEMD);
    assign m_tdata = dout;
    assign m_tvalid = dvalid;
    assign level = cnt + {{(LEVEL_BITS-1){1'b0}}, dvalid};

    always @(posedge clk) begin
        if (wr) mem[wptr] <= s_tdata;
        if (load) dout <= mem[rptr];
    end

    always @(posedge clk) begin
        if (!rst_n) begin
            wptr <= 0;
            rptr <= 0;
            cnt <= 0;
            dvalid <= 1'b0;
        end else begin
            if (wr) wptr <= (wptr == LAST) ? {AW{1'b0}} : wptr + 1'b1;
            if (load) rptr <= (rptr == LAST) ? {AW{1'b0}} : rptr + 1'b1;
            if (wr && !load && cnt != 0) cnt <= cnt + 1'b1;   // PLANTED BUG: a word written
                                                // into an empty RAM is never counted, so lost
            else if (load && !wr) cnt <= cnt - 1'b1;
            if (load) dvalid <= 1'b1;
            else if (pop) dvalid <= 1'b0;
        end
    end
endmodule
