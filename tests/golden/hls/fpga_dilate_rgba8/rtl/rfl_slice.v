// rfl_slice -- a register slice (skid buffer) on a valid/ready stream: every output and
// s_tready come straight from flip-flops, so neither the data nor the ready path runs through
// it combinationally (100 MHz timing), at full throughput. Two registers: the output, and a
// skid register that takes the word arriving while the output is stalled. A word appears at
// the output one clock after it was taken.
`default_nettype none

module rfl_slice #(
    parameter WIDTH = 8
) (
    input  wire             clk,
    input  wire             rst_n,
    input  wire [WIDTH-1:0] s_tdata,
    input  wire             s_tvalid,
    output reg              s_tready,
    output reg  [WIDTH-1:0] m_tdata,
    output reg              m_tvalid,
    input  wire             m_tready
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (WIDTH < 1) $fatal(1, "rfl_slice: WIDTH must be at least 1");
    end
`else
    if (WIDTH < 1) begin : g_bad_width
        $error("rfl_slice: WIDTH must be at least 1");
    end
`endif

    reg [WIDTH-1:0] skid;

    wire take = s_tvalid && s_tready;
    wire give = m_tvalid && m_tready;

    always @(posedge clk) begin
        if (!rst_n) begin
            s_tready <= 1'b1;
            m_tvalid <= 1'b0;
        end else if (s_tready) begin            // skid empty
            if (take && m_tvalid && !give) begin
                skid <= s_tdata;                // output stalled: keep the word aside
                s_tready <= 1'b0;
            end else if (take || give) begin
                m_tdata <= s_tdata;
                m_tvalid <= take;
            end
        end else if (give) begin                // skid full: it moves to the output
            m_tdata <= skid;
            s_tready <= 1'b1;
        end
    end
endmodule

`default_nettype wire
