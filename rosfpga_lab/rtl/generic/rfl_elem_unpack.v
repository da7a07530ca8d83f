// rfl_elem_unpack -- AXI4-Stream beats of one element each back to bytes: byte 0 (TDATA bits
// 7..0) first, one byte per clock onto the 8-bit valid/ready stream (little-endian, as on the
// wire). TKEEP, TUSER and TLAST are not needed: every beat carries EBYTES bytes.
module rfl_elem_unpack #(
    parameter EBYTES = 4                        // bytes per element: 1, 2, 4 or 8
) (
    input                     clk,
    input                     rst_n,
    input  [8*EBYTES-1:0]     s_axis_tdata,
    input                     s_axis_tvalid,
    output                    s_axis_tready,
    output [7:0]              m_tdata,
    output                    m_tvalid,
    input                     m_tready
);
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
