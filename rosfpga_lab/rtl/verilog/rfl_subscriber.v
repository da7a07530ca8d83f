// rfl_subscriber -- the subscriber circuit: reads one TCPROS frame of sensor_msgs/Image from an
// 8-bit valid/ready byte stream (the FIFO the hardwired TCP/IP stack fills), field by field in
// wire order, and checks every field as the generated HLS subscriber and the lab's Python
// interpreter do. An accepted frame's pixel bytes go out on m_* (to fifo2axi) and its
// carried-over fields (stamp, frame_id, is_bigendian) are held for the publisher (meta_valid
// until meta_release). A refused frame is skipped to its end, so the next one is read right.
// Each frame ends in a one-clock status_valid pulse with the status code (rfl_status.vh).
// The header fields are read one byte per clock; so are the pixel bytes, straight through.
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
    parameter FIDW = $clog2(FRAME_ID_MAX + 1)
) (
    input                 clk,
    input                 rst_n,
    input      [7:0]      s_tdata,
    input                 s_tvalid,
    output                s_tready,
    output     [7:0]      m_tdata,
    output                m_tvalid,
    input                 m_tready,
    output reg            meta_valid,
    input                 meta_release,
    output reg [31:0]     meta_secs,
    output reg [31:0]     meta_nsecs,
    output reg [7:0]      meta_bigendian,
    output reg [FIDW-1:0] meta_fid_len,
    input      [FIDW-1:0] fid_raddr,
    output     [7:0]      fid_rdata,
    output                frame_start,
    output reg            status_valid,
    output reg [3:0]      status,
    output                idle                  // between frames
);
`include "rfl_status.vh"
    localparam [31:0] STEP = WIDTH * BYTES;
    localparam [31:0] DATA_BYTES = WIDTH * HEIGHT * BYTES;

    localparam [3:0] S_FLEN = 4'd0, S_SEQ = 4'd1, S_SECS = 4'd2, S_NSECS = 4'd3,
                     S_FIDLEN = 4'd4, S_FID = 4'd5, S_HEIGHT = 4'd6, S_WIDTH = 4'd7,
                     S_ENCLEN = 4'd8, S_ENC = 4'd9, S_BIG = 4'd10, S_STEP = 4'd11,
                     S_DLEN = 4'd12, S_DATA = 4'd13, S_SKIP = 4'd14;

    reg [3:0]  state;
    reg [31:0] pos;                             // bytes of this frame taken so far
    reg [31:0] endp;                            // 4 + frame length
    reg [31:0] cnt;                             // bytes of the current field taken so far
    reg [31:0] acc;                             // a uint32 field, shifted in little-endian
    reg [31:0] flen;                            // length of the current string field
    reg        same;                            // the encoding matches so far
    reg [7:0]  fid_mem [0:FRAME_ID_MAX-1];

    // A new frame waits until the publisher has taken the previous frame's fields.
    wire stall = (state == S_FLEN) && (cnt == 0) && meta_valid;
    assign s_tready = (state == S_DATA) ? m_tready : !stall;
    assign m_tvalid = (state == S_DATA) && s_tvalid;
    assign m_tdata = s_tdata;
    wire take = s_tvalid && s_tready;
    assign frame_start = take && (state == S_FLEN) && (cnt == 0);
    assign fid_rdata = fid_mem[fid_raddr];
    assign idle = (state == S_FLEN) && (cnt == 0);

    wire [31:0] value = {s_tdata, acc[31:8]};   // the uint32 completed by this byte
    wire        u32_done = (cnt == 32'd3);
    wire [32:0] pos_next = {1'b0, pos} + 33'd1; // pos after this byte
    wire [31:0] enc_index = ENC_LEN - 1 - cnt;
    wire [8*32-1:0] enc_shifted = ENCODING >> (8 * enc_index);
    wire [7:0]  enc_byte = enc_shifted[7:0];
    wire        enc_ok = same && (cnt < ENC_LEN) && (s_tdata == enc_byte);

    always @(posedge clk) begin
        if (take && state == S_FID) fid_mem[cnt[FIDW-1:0]] <= s_tdata;
    end

    // Enter state `next` at the start of a field.
    task advance(input [3:0] next);
        begin
            state <= next;
            cnt <= 32'd0;
        end
    endtask

    // Refuse the frame with status `code`; skip what is left of it.
    task refuse(input [3:0] code);
        begin
            status_valid <= 1'b1;
            status <= code;
            cnt <= 32'd0;
            if (pos_next == {1'b0, endp}) begin
                state <= S_FLEN;
                pos <= 32'd0;
            end else begin
                state <= S_SKIP;
            end
        end
    endtask

    always @(posedge clk) begin
        if (!rst_n) begin
            state <= S_FLEN;
            pos <= 32'd0;
            endp <= 32'd0;
            cnt <= 32'd0;
            acc <= 32'd0;
            flen <= 32'd0;
            same <= 1'b0;
            meta_valid <= 1'b0;
            meta_secs <= 32'd0;
            meta_nsecs <= 32'd0;
            meta_bigendian <= 8'd0;
            meta_fid_len <= {FIDW{1'b0}};
            status_valid <= 1'b0;
            status <= SUB_OK;
        end else begin
            status_valid <= 1'b0;
            if (meta_release) meta_valid <= 1'b0;
            if (take) begin
                pos <= pos_next[31:0];
                acc <= value;
                cnt <= cnt + 32'd1;
                case (state)
                    S_FLEN: if (u32_done) begin
                        if (value > MAX_FRAME) begin
                            // Not to be trusted for skipping: wait for the next frame length.
                            status_valid <= 1'b1;
                            status <= SUB_BAD_FRAME_LENGTH;
                            cnt <= 32'd0;
                            pos <= 32'd0;
                        end else if (value < MIN_BODY) begin
                            // Too short for an Image, but framed: skip its bytes, as the HLS
                            // testbench and the Python interpreter do.
                            status_valid <= 1'b1;
                            status <= SUB_BAD_FRAME_LENGTH;
                            cnt <= 32'd0;
                            endp <= value + 32'd4;
                            if (value == 0) pos <= 32'd0;
                            else state <= S_SKIP;
                        end else begin
                            endp <= value + 32'd4;
                            advance(S_SEQ);
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
                        if (value > FRAME_ID_MAX
                                || pos_next + value + AFTER_FRAME_ID > {1'b0, endp}) begin
                            refuse(SUB_BAD_FRAME_ID_LENGTH);
                        end else begin
                            meta_fid_len <= value[FIDW-1:0];
                            flen <= value;
                            advance(value == 0 ? S_HEIGHT : S_FID);
                        end
                    end
                    S_FID: if (cnt == flen - 1) advance(S_HEIGHT);
                    S_HEIGHT: if (u32_done) begin
                        if (value != HEIGHT) refuse(SUB_BAD_HEIGHT);
                        else advance(S_WIDTH);
                    end
                    S_WIDTH: if (u32_done) begin
                        if (value != WIDTH) refuse(SUB_BAD_WIDTH);
                        else advance(S_ENCLEN);
                    end
                    S_ENCLEN: if (u32_done) begin
                        if (value > ENCODING_MAX
                                || pos_next + value + AFTER_ENCODING > {1'b0, endp}) begin
                            refuse(SUB_BAD_ENCODING_LENGTH);
                        end else if (value == 0) begin
                            refuse(SUB_BAD_ENCODING);   // an empty string matches no encoding
                        end else begin
                            flen <= value;
                            same <= (value == ENC_LEN);
                            advance(S_ENC);
                        end
                    end
                    S_ENC: begin
                        same <= enc_ok;
                        if (cnt == flen - 1) begin
                            if (!enc_ok) refuse(SUB_BAD_ENCODING);
                            else advance(S_BIG);
                        end
                    end
                    S_BIG: begin
                        meta_bigendian <= s_tdata;
                        advance(S_STEP);
                    end
                    S_STEP: if (u32_done) begin
                        if (value != STEP) refuse(SUB_BAD_STEP);
                        else advance(S_DLEN);
                    end
                    S_DLEN: if (u32_done) begin
                        if (value != DATA_BYTES || pos_next + value != {1'b0, endp}) begin
                            refuse(SUB_BAD_DATA_LENGTH);
                        end else begin
                            status_valid <= 1'b1;
                            status <= SUB_OK;
                            meta_valid <= 1'b1;
                            advance(S_DATA);
                        end
                    end
                    S_DATA: if (cnt == DATA_BYTES - 1) begin
                        advance(S_FLEN);
                        pos <= 32'd0;
                    end
                    S_SKIP: if (pos_next == {1'b0, endp}) begin
                        advance(S_FLEN);
                        pos <= 32'd0;
                    end
                    default: advance(S_FLEN);
                endcase
            end
        end
    end
endmodule
