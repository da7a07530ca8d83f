// rfl_fifo -- a synchronous first-word-fall-through FIFO of DEPTH entries, valid/ready on both
// sides. The entries live in a RAM with a registered read (block or distributed RAM after
// synthesis) and in the output register that m_tdata shows: DEPTH-1 in the RAM and a word
// written into an empty FIFO appears at the output two clocks later. With OUTREG = 1 the RAM's
// read register is followed by one more register in the fabric, so that what reads m_tdata
// does not start from a block RAM's slow clock-to-output (100 MHz timing on an ECP5): DEPTH-2
// entries in the RAM, and three clocks from an empty FIFO's input to its output.
// For the Verilated simulation (four of these FIFOs move a byte or a beat on almost every clock):
// the RAM is declared with 2**AW words (the same RAM after synthesis; the pointers wrap before
// the words past the last entry) so that no address needs a range check, and the RAM, the
// pointers and the level counter are written in one block, each register once, so that the
// model keeps no copy of their old values.
`default_nettype none

module rfl_fifo #(
    parameter WIDTH = 8,
    parameter DEPTH = 16,                       // entries, at least 2 (3 with OUTREG): checked
    parameter OUTREG = 0,                       // 1: register the RAM's output once more
    parameter LEVEL_BITS = $clog2(DEPTH + 1)
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [WIDTH-1:0]      s_tdata,
    input  wire                  s_tvalid,
    output wire                  s_tready,
    output wire [WIDTH-1:0]      m_tdata,
    output wire                  m_tvalid,
    input  wire                  m_tready,
    output wire [LEVEL_BITS-1:0] level
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (WIDTH < 1) $fatal(1, "rfl_fifo: WIDTH must be at least 1");
        if (OUTREG != 0 && OUTREG != 1) $fatal(1, "rfl_fifo: OUTREG must be 0 or 1");
        if (DEPTH < 2 + OUTREG) $fatal(1, "rfl_fifo: DEPTH must be at least 2 (3 with OUTREG = 1)");
    end
`else
    if (WIDTH < 1) begin : g_bad_width
        $error("rfl_fifo: WIDTH must be at least 1");
    end
    if (OUTREG != 0 && OUTREG != 1) begin : g_bad_outreg
        $error("rfl_fifo: OUTREG must be 0 or 1");
    end
    if (DEPTH < 2 + OUTREG) begin : g_bad_depth
        $error("rfl_fifo: DEPTH must be at least 2 (3 with OUTREG = 1)");
    end
`endif

    localparam MEMD = DEPTH - 1 - OUTREG;       // entries in the RAM
    localparam AW = (MEMD > 1) ? $clog2(MEMD) : 1;
    localparam [31:0] LAST_32 = MEMD - 1;
    localparam [AW-1:0] LAST = LAST_32[AW-1:0];  // the RAM's last address
    localparam [31:0] MEMD_32 = MEMD;
    localparam [LEVEL_BITS-1:0] FULL = MEMD_32[LEVEL_BITS-1:0];

    reg [WIDTH-1:0] mem [0:(1 << AW)-1];        // MEMD entries used
    reg [AW-1:0] wptr, rptr;
    reg [LEVEL_BITS-1:0] cnt;                   // entries in the RAM
    reg [WIDTH-1:0] q;                          // the RAM's read register
    reg qvalid;
    wire [WIDTH-1:0] dout;
    wire dvalid;

    wire wr = s_tvalid && s_tready;
    wire pop = dvalid && m_tready;
    wire load;                                  // RAM -> q

    assign s_tready = (cnt != FULL);
    assign m_tdata = dout;
    assign m_tvalid = dvalid;

    generate
        if (OUTREG != 0) begin : outreg
            reg [WIDTH-1:0] r;
            reg rvalid;
            wire move = qvalid && (!rvalid || pop);   // q -> r
            assign load = (cnt != 0) && (!qvalid || move);
            assign dout = r;
            assign dvalid = rvalid;
            assign level = cnt + {{(LEVEL_BITS-1){1'b0}}, qvalid}
                           + {{(LEVEL_BITS-1){1'b0}}, rvalid};
            always @(posedge clk) begin
                if (move) r <= q;
                if (!rst_n) rvalid <= 1'b0;
                else if (move) rvalid <= 1'b1;
                else if (pop) rvalid <= 1'b0;
            end
            always @(posedge clk) begin
                if (!rst_n) qvalid <= 1'b0;
                else if (load) qvalid <= 1'b1;
                else if (move) qvalid <= 1'b0;
            end
        end else begin : direct
            assign load = (cnt != 0) && (!qvalid || pop);
            assign dout = q;
            assign dvalid = qvalid;
            assign level = cnt + {{(LEVEL_BITS-1){1'b0}}, qvalid};
            always @(posedge clk) begin
                if (!rst_n) qvalid <= 1'b0;
                else if (load) qvalid <= 1'b1;
                else if (pop) qvalid <= 1'b0;
            end
        end
    endgenerate

    always @(posedge clk) begin
        if (wr) mem[wptr] <= s_tdata;
        if (load) q <= mem[rptr];
        if (!rst_n) begin
            wptr <= 0;
            rptr <= 0;
            cnt <= 0;
        end else begin
            if (wr) wptr <= (wptr == LAST) ? {AW{1'b0}} : wptr + 1'b1;
            if (load) rptr <= (rptr == LAST) ? {AW{1'b0}} : rptr + 1'b1;
            if (wr != load) cnt <= wr ? cnt + 1'b1 : cnt - 1'b1;
        end
    end
endmodule

`default_nettype wire
