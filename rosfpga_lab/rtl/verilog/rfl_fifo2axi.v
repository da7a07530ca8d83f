// rfl_fifo2axi -- the paper's Figure 7: pixel bytes from the 8-bit stream become AXI4-Stream
// video beats, one pixel per beat. Byte i of a pixel goes to TDATA bits 8i+7..8i, unused lanes
// are zero and null (TKEEP low), TUSER marks the first pixel of a frame and TLAST the last pixel
// of every line. One byte is taken per clock: a beat of BYTES bytes takes BYTES clocks.
module rfl_fifo2axi #(
    parameter WIDTH = 640,
    parameter HEIGHT = 480,
    parameter BYTES = 4                         // bytes per pixel: 1..4
) (
    input             clk,
    input             rst_n,
    input      [7:0]  s_tdata,
    input             s_tvalid,
    output            s_tready,
    output reg [31:0] m_axis_tdata,
    output     [3:0]  m_axis_tkeep,
    output reg        m_axis_tuser,
    output reg        m_axis_tlast,
    output reg        m_axis_tvalid,
    input             m_axis_tready
);
    localparam [31:0] K_LAST_32 = BYTES - 1;
    localparam [1:0] K_LAST = K_LAST_32[1:0];
    reg [23:0] acc;                             // the pixel's bytes so far, shifted in from the top
    reg [1:0]  k;                               // the lane the next byte goes to
    reg [15:0] x, y;                            // the pixel the next beat carries

    wire out_free = !m_axis_tvalid || m_axis_tready;
    wire last_byte = (k == K_LAST);
    wire take = s_tvalid && s_tready;

    assign s_tready = !last_byte || out_free;
    assign m_axis_tkeep = (4'b0001 << BYTES) - 4'b0001;

    always @(posedge clk) begin
        if (!rst_n) begin
            acc <= 24'd0;
            k <= 2'd0;
            x <= 16'd0;
            y <= 16'd0;
            m_axis_tdata <= 32'd0;
            m_axis_tuser <= 1'b0;
            m_axis_tlast <= 1'b0;
            m_axis_tvalid <= 1'b0;
        end else begin
            if (m_axis_tvalid && m_axis_tready) m_axis_tvalid <= 1'b0;
            if (take) begin
                if (last_byte) begin
                    m_axis_tdata <= {s_tdata, acc} >> (8 * (4 - BYTES));
                    m_axis_tuser <= (x == 0) && (y == 0);
                    m_axis_tlast <= (x == WIDTH - 1);
                    m_axis_tvalid <= 1'b1;
                    k <= 2'd0;
                    if (x == WIDTH - 1) begin
                        x <= 16'd0;
                        y <= (y == HEIGHT - 1) ? 16'd0 : y + 16'd1;
                    end else begin
                        x <= x + 16'd1;
                    end
                end else begin
                    acc <= {s_tdata, acc[23:8]};
                    k <= k + 2'd1;
                end
            end
        end
    end
endmodule
