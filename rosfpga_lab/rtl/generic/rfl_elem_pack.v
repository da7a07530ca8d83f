// rfl_elem_pack -- the streamed array's bytes (8-bit valid/ready, little-endian, as on the
// wire) become AXI4-Stream beats of one element each: element byte i in TDATA bits 8i+7..8i,
// TUSER on the array's first element, TLAST on its last (LENGTH elements per array) or, for
// video, on the last of every line of LINE elements (pixels). One byte is taken per clock, so a
// beat of EBYTES bytes takes EBYTES clocks.
`default_nettype none

module rfl_elem_pack #(
    parameter EBYTES = 4,                       // bytes per element (beat): 1..8
    parameter LENGTH = 256,                     // elements per array (at least 1)
    parameter LINE = LENGTH                     // elements per line (TLAST): divides LENGTH
) (
    input  wire                clk,
    input  wire                rst_n,
    input  wire [7:0]          s_tdata,
    input  wire                s_tvalid,
    output wire                s_tready,
    output reg  [8*EBYTES-1:0] m_axis_tdata,
    output wire [EBYTES-1:0]   m_axis_tkeep,
    output reg                 m_axis_tuser,
    output reg                 m_axis_tlast,
    output reg                 m_axis_tvalid,
    input  wire                m_axis_tready
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (EBYTES < 1 || EBYTES > 8) $fatal(1, "rfl_elem_pack: EBYTES must be 1..8");
        if (LENGTH < 1) $fatal(1, "rfl_elem_pack: LENGTH must be at least 1");
        if (LINE < 1 || LENGTH % LINE != 0)
            $fatal(1, "rfl_elem_pack: LINE must be at least 1 and divide LENGTH");
    end
`else
    if (EBYTES < 1 || EBYTES > 8) begin : g_bad_ebytes
        $error("rfl_elem_pack: EBYTES must be 1..8");
    end
    if (LENGTH < 1) begin : g_bad_length
        $error("rfl_elem_pack: LENGTH must be at least 1");
    end
    if (LINE < 1 || LENGTH % LINE != 0) begin : g_bad_line
        $error("rfl_elem_pack: LINE must be at least 1 and divide LENGTH");
    end
`endif

    localparam EW = 8 * EBYTES;
    localparam NB = EBYTES - 1;
    localparam [3:0] LAST_LANE = NB[3:0];
    localparam LN = LENGTH - 1;
    localparam [31:0] LAST_N = LN[31:0];
    reg [EW-1:0] acc;                           // the element's bytes so far
    reg [3:0]    k;                             // the byte lane the next byte goes to
    reg [31:0]   n;                             // the element the next beat carries

    wire out_free = !m_axis_tvalid || m_axis_tready;
    wire last_byte = (k == LAST_LANE);
    wire take = s_tvalid && s_tready;
    wire [EW-1:0] byte_in = {{(EW-8){1'b0}}, s_tdata};
    wire line_end;                              // the next beat ends a line

    generate
        if (LINE == LENGTH) begin : g_one_line
            assign line_end = (n == LAST_N);
        end else begin : g_lines
            localparam LC = LINE - 1;
            localparam [31:0] LAST_C = LC[31:0];
            reg [31:0] c;                       // the next beat's element within its line
            always @(posedge clk) begin
                if (!rst_n) c <= 32'd0;
                else if (take && last_byte) c <= (c == LAST_C || n == LAST_N) ? 32'd0 : c + 32'd1;
            end
            assign line_end = (c == LAST_C);
        end
    endgenerate

    assign s_tready = !last_byte || out_free;
    assign m_axis_tkeep = {EBYTES{1'b1}};

    always @(posedge clk) begin
        if (!rst_n) begin
            acc <= {EW{1'b0}};
            k <= 4'd0;
            n <= 32'd0;
            m_axis_tdata <= {EW{1'b0}};
            m_axis_tuser <= 1'b0;
            m_axis_tlast <= 1'b0;
            m_axis_tvalid <= 1'b0;
        end else begin
            if (m_axis_tvalid && m_axis_tready) m_axis_tvalid <= 1'b0;
            if (take) begin
                if (last_byte) begin
                    m_axis_tdata <= acc | (byte_in << (8 * LAST_LANE));
                    m_axis_tuser <= (n == 32'd0);
                    m_axis_tlast <= line_end;
                    m_axis_tvalid <= 1'b1;
                    acc <= {EW{1'b0}};
                    k <= 4'd0;
                    n <= (n == LAST_N) ? 32'd0 : n + 32'd1;
                end else begin
                    acc <= acc | (byte_in << (8 * k));
                    k <= k + 4'd1;
                end
            end
        end
    end
endmodule

`default_nettype wire
