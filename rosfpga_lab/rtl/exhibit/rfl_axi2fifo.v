// rfl_axi2fifo -- AXI4-Stream video beats back to bytes: for every beat, the bytes of the lanes
// whose TKEEP bit is set, lane 0 first, one byte per clock onto the 8-bit stream.
`default_nettype none

module rfl_axi2fifo (
    input  wire        clk,
    input  wire        rst_n,
    input  wire [31:0] s_axis_tdata,
    input  wire [3:0]  s_axis_tkeep,
    input  wire        s_axis_tvalid,
    output wire        s_axis_tready,
    output wire [7:0]  m_tdata,
    output wire        m_tvalid,
    input  wire        m_tready
);
    reg [31:0] d;                               // the beat being unpacked
    reg [3:0]  left;                            // its lanes not yet sent

    wire [1:0] lane = left[0] ? 2'd0 : left[1] ? 2'd1 : left[2] ? 2'd2 : 2'd3;
    wire [3:0] rest = left & ~(4'b0001 << lane);

    assign m_tdata = d[8 * lane +: 8];
    assign m_tvalid = (left != 4'd0);
    assign s_axis_tready = (left == 4'd0) || (m_tready && rest == 4'd0);

    always @(posedge clk) begin
        if (!rst_n) begin
            d <= 32'd0;
            left <= 4'd0;
        end else if (s_axis_tvalid && s_axis_tready) begin
            d <= s_axis_tdata;
            left <= s_axis_tkeep;
        end else if (m_tvalid && m_tready) begin
            left <= rest;
        end
    end
endmodule

`default_nettype wire
