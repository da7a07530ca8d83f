// rfl_subscriber -- the subscriber circuit: reads one TCPROS frame of sensor_msgs/Image from an
// 8-bit valid/ready byte stream (the FIFO the hardwired TCP/IP stack fills), field by field in
// wire order, and checks every field as the generated HLS subscriber and the lab's Python
// interpreter do. An accepted frame's pixel bytes go out on m_* (to fifo2axi) and its
// carried-over fields (stamp, frame_id, is_bigendian) are held for the publisher (meta_valid
// until meta_release). A refused frame is skipped to its end, so the next one is read right.
// Each frame ends in a one-clock status_valid pulse with the status code (rfl_status.vh).
// The header fields are read one byte per clock; so are the pixel bytes, straight through.
// Timing (100 MHz on an ECP5, see 'rosfpga-lab rtl timing'): the checks that need the frame's
// end compare against `left`, the bytes of the frame still to come, kept as a down-counter, so
// no check adds three 32-bit numbers; a field's byte counter has the width of the longest
// string field; frame_id is read by the publisher from a RAM with a registered read port.
// For the Verilated simulation, where the pixel bytes are most clocks: the state machine tests
// S_DATA first, and the encoding compare is a function called in S_ENC, not a wire evaluated
// on every clock; the same logic after synthesis.
`default_nettype none

module rfl_subscriber #(
    parameter WIDTH = 640,
    parameter HEIGHT = 480,
    parameter BYTES = 4,                        // bytes per pixel
    parameter ENC_LEN = 5,                      // length of ENCODING
    parameter [8*32-1:0] ENCODING = "rgba8",    // right-aligned, as a Verilog string is
    parameter FRAME_ID_MAX = 256,               // longest header.frame_id kept
    parameter ENCODING_MAX = 32,                // longest encoding string accepted
    parameter MIN_BODY = 37,                    // bytes of an Image with empty strings, no pixels
    parameter MAX_FRAME = 67108864,             // largest frame length accepted
    parameter AFTER_FRAME_ID = 12,              // fixed-size bytes after header.frame_id
    parameter AFTER_ENCODING = 9,               // fixed-size bytes after encoding
    parameter FIDW = $clog2(FRAME_ID_MAX + 1),  // bits of a frame_id length
    parameter FIDA = (FRAME_ID_MAX > 1) ? $clog2(FRAME_ID_MAX) : 1  // bits of a frame_id address
) (
    input  wire            clk,
    input  wire            rst_n,
    input  wire [7:0]      s_tdata,
    input  wire            s_tvalid,
    output wire            s_tready,
    output wire [7:0]      m_tdata,
    output reg             m_tuser,             // the frame's first pixel byte (fifo2axi re-syncs)
    output wire            m_tvalid,
    input  wire            m_tready,
    output reg             meta_valid,
    input  wire            meta_release,
    output reg  [31:0]     meta_secs,
    output reg  [31:0]     meta_nsecs,
    output reg  [7:0]      meta_bigendian,
    output reg  [FIDW-1:0] meta_fid_len,
    input  wire [FIDA-1:0] fid_raddr,           // read port: fid_rdata is fid_mem[fid_raddr]
    output reg  [7:0]      fid_rdata,           //   one clock after fid_raddr
    output wire            frame_start,
    output reg             status_valid,
    output reg  [3:0]      status,
    output wire            idle                 // between frames
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (ENC_LEN < 1 || ENC_LEN > 32 || ENC_LEN > ENCODING_MAX)
            $fatal(1, "rfl_subscriber: ENC_LEN must be 1..32 and at most ENCODING_MAX");
        if (FRAME_ID_MAX < 1 || FRAME_ID_MAX >= 16777216 || ENCODING_MAX >= 16777216)
            $fatal(1, "rfl_subscriber: FRAME_ID_MAX must be 1..2**24-1 and ENCODING_MAX below 2**24");
        if (MIN_BODY >= 16777216 || MAX_FRAME < MIN_BODY)
            $fatal(1, "rfl_subscriber: MIN_BODY must be below 2**24 and at most MAX_FRAME");
    end
`else
    if (ENC_LEN < 1 || ENC_LEN > 32 || ENC_LEN > ENCODING_MAX) begin : g_bad_enc_len
        $error("rfl_subscriber: ENC_LEN must be 1..32 and at most ENCODING_MAX");
    end
    if (FRAME_ID_MAX < 1 || FRAME_ID_MAX >= 16777216 || ENCODING_MAX >= 16777216) begin : g_bad_str_max
        $error("rfl_subscriber: FRAME_ID_MAX must be 1..2**24-1 and ENCODING_MAX below 2**24");
    end
    if (MIN_BODY >= 16777216 || MAX_FRAME < MIN_BODY) begin : g_bad_body
        $error("rfl_subscriber: MIN_BODY must be below 2**24 and at most MAX_FRAME");
    end
`endif

`include "rfl_status.vh"
    localparam [31:0] STEP = WIDTH * BYTES;
    localparam [31:0] DATA_BYTES = WIDTH * HEIGHT * BYTES;
    localparam [31:0] MAX_FRAME_32 = MAX_FRAME;
    // `left` holds up to MAX_FRAME; a string field's counter up to its longest length
    localparam LW = $clog2(MAX_FRAME + 1);
    localparam STR_MAX = (FRAME_ID_MAX > ENCODING_MAX) ? FRAME_ID_MAX : ENCODING_MAX;
    localparam CW = $clog2(STR_MAX + 1);
    localparam [CW-1:0] U32_LAST = 3;
    localparam [LW-1:0] ONE = 1;
    localparam [31:0] DATA_LEFT_32 = DATA_BYTES + 1;
    localparam [LW-1:0] DATA_LEFT = DATA_LEFT_32[LW-1:0];  // `left` as the data length is taken
    // the string checks, at widths that hold the sums: fits when length + after < left
    localparam SUMW = ((FIDW > 6) ? FIDW : 6) + 2;
    localparam [SUMW-1:0] AFTER_FID_S = AFTER_FRAME_ID;
    localparam [SUMW-1:0] AFTER_ENC_S = AFTER_ENCODING;

    localparam [31:0] HEIGHT_32 = HEIGHT, WIDTH_32 = WIDTH, ENC_LEN_32 = ENC_LEN;

    localparam [3:0] S_FLEN = 4'd0, S_SEQ = 4'd1, S_SECS = 4'd2, S_NSECS = 4'd3,
                     S_FIDLEN = 4'd4, S_FID = 4'd5, S_HEIGHT = 4'd6, S_WIDTH = 4'd7,
                     S_ENCLEN = 4'd8, S_ENC = 4'd9, S_BIG = 4'd10, S_STEP = 4'd11,
                     S_DLEN = 4'd12, S_DATA = 4'd13, S_SKIP = 4'd14;

    reg [3:0]    state;
    reg          in_frame;                      // past the frame length field
    reg [LW-1:0] left;                          // bytes of the frame after those taken
    reg [CW-1:0] cnt;                           // bytes of the current field taken so far
    reg [23:0]   acc;                           // the bytes of a uint32 field so far
    reg [CW-1:0] flast;                         // last index of the current string field
    reg          same;                          // the encoding matches so far
    reg          one_left;                      // `left` is 1
    // distributed RAM: a block RAM's clock-to-output would start the publisher's output path
    (* ram_style = "distributed" *) reg [7:0] fid_mem [0:FRAME_ID_MAX-1];

    // A new frame waits until the publisher has taken the previous frame's fields.
    wire at_start = (state == S_FLEN) && (cnt == 0);
    wire stall = at_start && meta_valid;
    assign s_tready = (state == S_DATA) ? m_tready : !stall;
    assign m_tvalid = (state == S_DATA) && s_tvalid;
    assign m_tdata = s_tdata;
    wire take = s_tvalid && s_tready;
    assign frame_start = take && at_start;
    assign idle = at_start;

    always @(posedge clk) fid_rdata <= fid_mem[fid_raddr];

    wire [31:0] value = {s_tdata, acc};         // the uint32 completed by this byte
    wire        u32_done = (cnt == U32_LAST);
    wire        last_byte = in_frame && one_left;        // the frame's last byte is taken

    // Every check of a uint32 field is split: its low three bytes are compared as the third
    // byte is taken (into the registers pre_*), the fourth byte alone as it comes. The sums
    // with the bytes left use `left` after the third byte (left - 1 then).
    wire [23:0] low = value[31:8];              // the low three bytes, as the third comes
    wire [LW-1:0] left3 = left - ONE;           // `left` as the fourth byte comes
    wire [SUMW-1:0] low_s = low[SUMW-1:0];
    wire        left3_big = |(left3 >> SUMW);
    wire [SUMW-1:0] left3_s = left3[SUMW-1:0];
    reg pre_fid, pre_enc, pre_zero, pre_one, pre_short, pre_long, pre_enclen,
        pre_height, pre_width, pre_step, pre_dlen, pre_dleft;
    always @(posedge clk) begin
        if (take && cnt == U32_LAST - 1'b1) begin
            pre_fid <= (low <= FRAME_ID_MAX) && (left3_big || low_s + AFTER_FID_S < left3_s);
            pre_enc <= (low <= ENCODING_MAX) && (left3_big || low_s + AFTER_ENC_S < left3_s);
            pre_zero <= (low == 24'd0);
            pre_one <= (low == 24'd1);
            pre_short <= (low < MIN_BODY);
            pre_long <= (low > MAX_FRAME_32[23:0]);
            pre_enclen <= (low == ENC_LEN_32[23:0]);
            pre_height <= (low == HEIGHT_32[23:0]);
            pre_width <= (low == WIDTH_32[23:0]);
            pre_step <= (low == STEP[23:0]);
            pre_dlen <= (low == DATA_BYTES[23:0]);
            pre_dleft <= (left3 == DATA_LEFT);
        end
    end
    wire top0 = (s_tdata == 8'd0);
    wire fid_fits = top0 && pre_fid;            // FRAME_ID_MAX and ENCODING_MAX are < 2**24
    wire enc_fits = top0 && pre_enc;
    wire is_zero = top0 && pre_zero;
    wire too_long = (s_tdata > MAX_FRAME_32[31:24])
                    || (s_tdata == MAX_FRAME_32[31:24] && pre_long);
    wire too_short = top0 && pre_short;          // MIN_BODY < 2**24
    wire is_one = top0 && pre_one;
    wire height_ok = (s_tdata == HEIGHT_32[31:24]) && pre_height;
    wire width_ok = (s_tdata == WIDTH_32[31:24]) && pre_width;
    wire step_ok = (s_tdata == STEP[31:24]) && pre_step;
    wire dlen_ok = (s_tdata == DATA_BYTES[31:24]) && pre_dlen && pre_dleft;

    // the expected encoding byte at position n of the string
    function [7:0] enc_at(input [CW-1:0] n);
        integer b;
        begin
            enc_at = 8'd0;
            for (b = 0; b < ENC_LEN; b = b + 1)
                if (n == b[CW-1:0]) enc_at = ENCODING[8 * (ENC_LEN - 1 - b) +: 8];
        end
    endfunction
    // the encoding matches up to and with byte b at position n (a function, not a wire: the
    // simulation compares only in S_ENC)
    function enc_ok(input [7:0] b, input [CW-1:0] n);
        enc_ok = same && (b == enc_at(n));
    endfunction


    // Enter state `next` at the start of a field.
    task advance(input [3:0] next);
        begin
            state <= next;
            cnt <= {CW{1'b0}};
        end
    endtask

    // Refuse the frame with status `code`; skip what is left of it.
    task refuse(input [3:0] code);
        begin
            status_valid <= 1'b1;
            status <= code;
            cnt <= {CW{1'b0}};
            if (last_byte) begin
                state <= S_FLEN;
                in_frame <= 1'b0;
            end else begin
                state <= S_SKIP;
            end
        end
    endtask

    always @(posedge clk) begin
        if (take && state == S_FID) fid_mem[cnt[FIDA-1:0]] <= s_tdata;
        if (!rst_n) begin
            state <= S_FLEN;
            in_frame <= 1'b0;
            left <= {LW{1'b0}};
            cnt <= {CW{1'b0}};
            acc <= 24'd0;
            flast <= {CW{1'b0}};
            same <= 1'b0;
            one_left <= 1'b0;
            meta_valid <= 1'b0;
            meta_secs <= 32'd0;
            meta_nsecs <= 32'd0;
            meta_bigendian <= 8'd0;
            meta_fid_len <= {FIDW{1'b0}};
            status_valid <= 1'b0;
            status <= SUB_OK;
            m_tuser <= 1'b0;
        end else begin
            status_valid <= 1'b0;
            if (meta_release) meta_valid <= 1'b0;
            if (take) begin
                left <= left - ONE;
                one_left <= (left == 2);
                acc <= value[31:8];
                cnt <= cnt + 1'b1;
                // the pixel bytes (or the rest of a refused frame) first: most of the stream
                if (state == S_DATA || state == S_SKIP) begin
                    m_tuser <= 1'b0;                    // the first pixel byte is taken
                    if (last_byte) begin
                        advance(S_FLEN);
                        in_frame <= 1'b0;
                    end
                end else case (state)
                    S_FLEN: if (u32_done) begin
                        cnt <= {CW{1'b0}};
                        if (too_long) begin
                            // Not to be trusted for skipping: wait for the next frame length.
                            status_valid <= 1'b1;
                            status <= SUB_BAD_FRAME_LENGTH;
                        end else begin
                            left <= value[LW-1:0];
                            one_left <= is_one;
                            if (too_short) begin
                                // Too short for an Image, but framed: skip its bytes, as the
                                // HLS subscriber and the Python interpreter do.
                                status_valid <= 1'b1;
                                status <= SUB_BAD_FRAME_LENGTH;
                                if (!is_zero) begin
                                    state <= S_SKIP;
                                    in_frame <= 1'b1;
                                end
                            end else begin
                                in_frame <= 1'b1;
                                state <= S_SEQ;
                            end
                        end
                    end
                    S_SEQ: if (u32_done) advance(S_SECS);
                    S_SECS: if (u32_done) begin
                        meta_secs <= value;
                        advance(S_NSECS);
                    end
                    S_NSECS: if (u32_done) begin
                        meta_nsecs <= value;
                        advance(S_FIDLEN);
                    end
                    S_FIDLEN: if (u32_done) begin
                        if (!fid_fits) begin
                            refuse(SUB_BAD_FRAME_ID_LENGTH);
                        end else begin
                            meta_fid_len <= value[FIDW-1:0];
                            flast <= value[CW-1:0] - 1'b1;
                            advance(is_zero ? S_HEIGHT : S_FID);
                        end
                    end
                    S_FID: if (cnt == flast) advance(S_HEIGHT);
                    S_HEIGHT: if (u32_done) begin
                        if (!height_ok) refuse(SUB_BAD_HEIGHT);
                        else advance(S_WIDTH);
                    end
                    S_WIDTH: if (u32_done) begin
                        if (!width_ok) refuse(SUB_BAD_WIDTH);
                        else advance(S_ENCLEN);
                    end
                    S_ENCLEN: if (u32_done) begin
                        if (!enc_fits) begin
                            refuse(SUB_BAD_ENCODING_LENGTH);
                        end else if (is_zero) begin
                            refuse(SUB_BAD_ENCODING);   // an empty string matches no encoding
                        end else begin
                            flast <= value[CW-1:0] - 1'b1;
                            same <= top0 && pre_enclen;
                            advance(S_ENC);
                        end
                    end
                    S_ENC: begin
                        if (cnt == flast) begin
                            if (!enc_ok(s_tdata, cnt)) refuse(SUB_BAD_ENCODING);
                            else advance(S_BIG);
                        end
                        same <= enc_ok(s_tdata, cnt);
                    end
                    S_BIG: begin
                        meta_bigendian <= s_tdata;
                        advance(S_STEP);
                    end
                    S_STEP: if (u32_done) begin
                        if (!step_ok) refuse(SUB_BAD_STEP);
                        else advance(S_DLEN);
                    end
                    S_DLEN: if (u32_done) begin
                        if (!dlen_ok) begin
                            refuse(SUB_BAD_DATA_LENGTH);
                        end else begin
                            status_valid <= 1'b1;
                            status <= SUB_OK;
                            meta_valid <= 1'b1;
                            m_tuser <= 1'b1;
                            advance(S_DATA);
                        end
                    end
                    default: begin
                        advance(S_FLEN);
                        in_frame <= 1'b0;
                    end
                endcase
            end
        end
    end
endmodule

`default_nettype wire
