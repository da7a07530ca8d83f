// rfl_elem_unpack -- AXI4-Stream beats of one element each back to bytes: byte 0 (TDATA bits
// 7..0) first, one byte per clock onto the 8-bit valid/ready stream (little-endian, as on the
// wire). TKEEP, TUSER and TLAST are not needed: every beat carries EBYTES bytes.
`default_nettype none

module rfl_elem_unpack #(
    parameter EBYTES = 4                        // bytes per element (beat): 1..8
) (
    input  wire                clk,
    input  wire                rst_n,
    input  wire [8*EBYTES-1:0] s_axis_tdata,
    input  wire                s_axis_tvalid,
    output wire                s_axis_tready,
    output wire [7:0]          m_tdata,
    output wire                m_tvalid,
    input  wire                m_tready
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (EBYTES < 1 || EBYTES > 8) $fatal(1, "rfl_elem_unpack: EBYTES must be 1..8");
    end
`else
    if (EBYTES < 1 || EBYTES > 8) begin : g_bad_ebytes
        $error("rfl_elem_unpack: EBYTES must be 1..8");
    end
`endif

    localparam EW = 8 * EBYTES;
    localparam [3:0] NBYTES = EBYTES[3:0];
    reg [EW-1:0] d;                             // the element being sent, next byte in d[7:0]
    reg [3:0]    left;                          // its bytes not yet sent

    wire last = (left == 4'd1);

    assign m_tdata = d[7:0];
    assign m_tvalid = (left != 4'd0);
    assign s_axis_tready = (left == 4'd0) || (m_tready && last);

    always @(posedge clk) begin
        if (!rst_n) begin
            d <= {EW{1'b0}};
            left <= 4'd0;
        end else if (s_axis_tvalid && s_axis_tready) begin
            d <= s_axis_tdata;
            left <= NBYTES;
        end else if (m_tvalid && m_tready) begin
            d <= d >> 8;
            left <= left - 4'd1;
        end
    end
endmodule

`default_nettype wire
