// rfl_fifo2axi -- the paper's Figure 7: pixel bytes from the 8-bit stream become AXI4-Stream
// video beats, one pixel per beat. Byte i of a pixel goes to TDATA bits 8i+7..8i, unused lanes
// are zero and null (TKEEP low), TUSER marks the first pixel of a frame and TLAST the last pixel
// of every line. One byte is taken per clock: a beat of BYTES bytes takes BYTES clocks.
//
// Start of frame: s_tuser marks the first pixel byte of every frame (the subscriber sets it).
// As the video IP after it (rfl_morph, hw.framing), every frame started comes out whole,
// WIDTH x HEIGHT beats: bytes before a marked byte are dropped (sof_missing); a marked byte
// inside a frame ends it, the rest of the frame (the current pixel's missing bytes included)
// going out as zero bytes, and starts the next (sof_early). framing holds the flags since
// reset in hw.framing.FRAMING_FLAGS order (bit 0 sof_early, 3 sof_missing; a byte stream has
// no lines, so bits 1 and 2 stay 0).
`default_nettype none

module rfl_fifo2axi #(
    parameter WIDTH = 640,
    parameter HEIGHT = 480,
    parameter BYTES = 4                         // bytes per pixel: 1..4
) (
    input  wire        clk,
    input  wire        rst_n,
    input  wire [7:0]  s_tdata,
    input  wire        s_tuser,                 // the frame's first pixel byte
    input  wire        s_tvalid,
    output wire        s_tready,
    output reg  [31:0] m_axis_tdata,
    output wire [3:0]  m_axis_tkeep,
    output reg         m_axis_tuser,
    output reg         m_axis_tlast,
    output reg         m_axis_tvalid,
    input  wire        m_axis_tready,
    output wire [3:0]  framing
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (BYTES < 1 || BYTES > 4)
            $fatal(1, "rfl_fifo2axi: BYTES must be 1..4 (one pixel per 32-bit beat)");
        if (WIDTH < 1 || WIDTH > 65536 || HEIGHT < 1 || HEIGHT > 65536)
            $fatal(1, "rfl_fifo2axi: WIDTH and HEIGHT must be 1..65536 (16-bit counters)");
    end
`else
    if (BYTES < 1 || BYTES > 4) begin : g_bad_bytes
        $error("rfl_fifo2axi: BYTES must be 1..4 (one pixel per 32-bit beat)");
    end
    if (WIDTH < 1 || WIDTH > 65536 || HEIGHT < 1 || HEIGHT > 65536) begin : g_bad_size
        $error("rfl_fifo2axi: WIDTH and HEIGHT must be 1..65536 (16-bit counters)");
    end
`endif

    localparam [31:0] K_LAST_32 = BYTES - 1;
    localparam [1:0] K_LAST = K_LAST_32[1:0];
    localparam [31:0] X_LAST_32 = WIDTH - 1, Y_LAST_32 = HEIGHT - 1;
    localparam [15:0] X_LAST = X_LAST_32[15:0], Y_LAST = Y_LAST_32[15:0];
    reg [23:0] acc;                             // the pixel's bytes so far, shifted in from the top
    reg [1:0]  k;                               // the lane the next byte goes to
    reg [15:0] x, y;                            // the pixel the next beat carries
    reg        run;                             // inside a frame (else waiting for a marked byte)
    reg        padf;                            // the rest of the frame is zero bytes
    reg        sof_early, sof_missing;

    wire out_free = !m_axis_tvalid || m_axis_tready;
    wire last_byte = (k == K_LAST);
    wire slot = !last_byte || out_free;         // a byte can go into the pixel this clock
    wire start = s_tvalid && s_tuser;
    wire pad = run && (padf || start);          // this clock's byte is a zero, none taken
    wire step = slot && (pad || (s_tvalid && (run || s_tuser)));
    // the byte that goes into the pixel: a zero while padding (a function, not a wire: the
    // simulation evaluates it only as a byte goes in)
    function [7:0] byte_in(input zero, input [7:0] b);
        byte_in = zero ? 8'd0 : b;
    endfunction
    wire frame_end = last_byte && (x == X_LAST) && (y == Y_LAST);

    assign s_tready = run ? (slot && !padf && !s_tuser) : (!s_tuser || slot);
    assign m_axis_tkeep = (4'b0001 << BYTES) - 4'b0001;
    assign framing = {sof_missing, 2'b00, sof_early};

    always @(posedge clk) begin
        if (!rst_n) begin
            acc <= 24'd0;
            k <= 2'd0;
            x <= 16'd0;
            y <= 16'd0;
            run <= 1'b0;
            padf <= 1'b0;
            sof_early <= 1'b0;
            sof_missing <= 1'b0;
            m_axis_tdata <= 32'd0;
            m_axis_tuser <= 1'b0;
            m_axis_tlast <= 1'b0;
            m_axis_tvalid <= 1'b0;
        end else begin
            if (m_axis_tvalid && m_axis_tready) m_axis_tvalid <= 1'b0;
            if (!run && s_tvalid && !s_tuser) sof_missing <= 1'b1;   // dropped
            if (step && pad && !padf) begin
                padf <= 1'b1;
                sof_early <= 1'b1;
            end
            if (step) begin
                run <= 1'b1;
                if (last_byte) begin
                    m_axis_tdata <= {byte_in(pad, s_tdata), acc} >> (8 * (4 - BYTES));
                    m_axis_tuser <= (x == 0) && (y == 0);
                    m_axis_tlast <= (x == X_LAST);
                    m_axis_tvalid <= 1'b1;
                    if (x == X_LAST) y <= (y == Y_LAST) ? 16'd0 : y + 16'd1;
                    x <= (x == X_LAST) ? 16'd0 : x + 16'd1;
                end else begin
                    acc <= {byte_in(pad, s_tdata), acc[23:8]};
                end
                k <= last_byte ? 2'd0 : k + 2'd1;
                if (frame_end) begin
                    run <= 1'b0;
                    padf <= 1'b0;
                end
            end
        end
    end
endmodule

`default_nettype wire
