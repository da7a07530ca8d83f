// rfl_publisher -- the publisher circuit: writes one TCPROS frame of sensor_msgs/Image onto the
// 8-bit valid/ready output stream for every frame the subscriber accepted, one byte per clock:
// the frame length first (computed from sizes the circuit knows), then every field in wire
// order: header.seq (counting from SEQ_START, as a rospy publisher does), the stamp and
// frame_id carried over from the subscriber, the image's fixed fields, and the pixel bytes
// from axi2fifo last, passed straight through. Timing: each field's last byte index is set as
// the field starts (no subtraction on the way to the handshake), the byte counter has the
// width of the longest field, and frame_id comes from the subscriber's RAM one clock after its
// address (fid_raddr is the byte the next clock shows). For the Verilated simulation, where
// the pixel bytes are most clocks: the output multiplexer tests F_DATA first, and what only a
// header field or a field's end needs (its uint32 value, the next field) are functions called
// there, not wires evaluated on every clock; the same logic after synthesis.
`default_nettype none

module rfl_publisher #(
    parameter WIDTH = 640,
    parameter HEIGHT = 480,
    parameter BYTES = 4,
    parameter ENC_LEN = 5,
    parameter [8*32-1:0] ENCODING = "rgba8",
    parameter FRAME_ID_MAX = 256,
    parameter MIN_BODY = 37,
    parameter [31:0] SEQ_START = 1,
    parameter FIDW = $clog2(FRAME_ID_MAX + 1),
    parameter FIDA = (FRAME_ID_MAX > 1) ? $clog2(FRAME_ID_MAX) : 1
) (
    input  wire            clk,
    input  wire            rst_n,
    input  wire [7:0]      s_tdata,             // pixel bytes from axi2fifo
    input  wire            s_tvalid,
    output wire            s_tready,
    output reg  [7:0]      m_tdata,             // the outgoing frame (combinational)
    output wire            m_tvalid,
    input  wire            m_tready,
    input  wire            meta_valid,
    output wire            meta_release,
    input  wire [31:0]     meta_secs,
    input  wire [31:0]     meta_nsecs,
    input  wire [7:0]      meta_bigendian,
    input  wire [FIDW-1:0] meta_fid_len,
    output wire [FIDA-1:0] fid_raddr,
    input  wire [7:0]      fid_rdata,
    output wire            frame_done,
    output wire            idle                 // no frame being written
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (ENC_LEN < 1 || ENC_LEN > 32) $fatal(1, "rfl_publisher: ENC_LEN must be 1..32");
        if (FRAME_ID_MAX < 1) $fatal(1, "rfl_publisher: FRAME_ID_MAX must be at least 1");
    end
`else
    if (ENC_LEN < 1 || ENC_LEN > 32) begin : g_bad_enc_len
        $error("rfl_publisher: ENC_LEN must be 1..32");
    end
    if (FRAME_ID_MAX < 1) begin : g_bad_fid_max
        $error("rfl_publisher: FRAME_ID_MAX must be at least 1");
    end
`endif

    localparam [31:0] STEP = WIDTH * BYTES;
    localparam [31:0] DATA_BYTES = WIDTH * HEIGHT * BYTES;
    localparam [31:0] BODY = MIN_BODY + ENC_LEN + DATA_BYTES;  // all but frame_id
    // the byte counter holds the last index of the longest field
    localparam LONGEST = (DATA_BYTES > FRAME_ID_MAX) ? DATA_BYTES : FRAME_ID_MAX;
    localparam IW = $clog2(LONGEST + 1);
    localparam [31:0] DATA_LAST_32 = DATA_BYTES - 1, ENC_LAST_32 = ENC_LEN - 1;
    localparam [IW-1:0] DATA_LAST = DATA_LAST_32[IW-1:0];
    localparam [IW-1:0] ENC_LAST = ENC_LAST_32[IW-1:0];
    localparam [IW-1:0] U32_LAST = 3;
    localparam [FIDA-1:0] FID_ONE = 1;

    localparam [3:0] F_IDLE = 4'd0, F_LEN = 4'd1, F_SEQ = 4'd2, F_SECS = 4'd3, F_NSECS = 4'd4,
                     F_FIDLEN = 4'd5, F_FID = 4'd6, F_HEIGHT = 4'd7, F_WIDTH = 4'd8,
                     F_ENCLEN = 4'd9, F_ENC = 4'd10, F_BIG = 4'd11, F_STEP = 4'd12,
                     F_DLEN = 4'd13, F_DATA = 4'd14;

    reg [3:0]    f;                             // the field being written
    reg [IW-1:0] i;                             // its byte being written
    reg [IW-1:0] ilast;                         // its last byte's index
    reg          in_fid;                        // f is F_FID
    reg [FIDA-1:0] fa, fa1;                     // frame_id byte shown, and the next one
    reg [31:0]   seq;

    wire [31:0] fid_len = {{(32-FIDW){1'b0}}, meta_fid_len};
    wire [IW-1:0] fid_last = fid_len[IW-1:0] - 1'b1;

    // the encoding's byte at position n
    function [7:0] enc_at(input [IW-1:0] n);
        integer b;
        begin
            enc_at = 8'd0;
            for (b = 0; b < ENC_LEN; b = b + 1)
                if (n == b[IW-1:0]) enc_at = ENCODING[8 * (ENC_LEN - 1 - b) +: 8];
        end
    endfunction

    // the field after field `g` (a function, not a wire: the simulation computes it only as a
    // field ends)
    function [3:0] next_of(input [3:0] g);
        begin
            if (g == F_FIDLEN) next_of = (fid_len == 0) ? F_HEIGHT : F_FID;
            else if (g == F_DATA) next_of = F_IDLE;
            else next_of = g + 4'd1;
        end
    endfunction

    // the last byte index of field `g`
    function [IW-1:0] last_of(input [3:0] g);
        begin
            case (g)
                F_FID:   last_of = fid_last;
                F_ENC:   last_of = ENC_LAST;
                F_BIG:   last_of = {IW{1'b0}};
                F_DATA:  last_of = DATA_LAST;
                default: last_of = U32_LAST;
            endcase
        end
    endfunction

    // the value of the uint32 field `g`
    function [31:0] word_of(input [3:0] g);
        begin
            case (g)
                F_LEN:    word_of = BODY + fid_len;
                F_SEQ:    word_of = seq;
                F_SECS:   word_of = meta_secs;
                F_NSECS:  word_of = meta_nsecs;
                F_FIDLEN: word_of = fid_len;
                F_HEIGHT: word_of = HEIGHT;
                F_WIDTH:  word_of = WIDTH;
                F_ENCLEN: word_of = ENC_LEN;
                F_STEP:   word_of = STEP;
                F_DLEN:   word_of = DATA_BYTES;
                default:  word_of = 32'd0;
            endcase
        end
    endfunction

    // byte n (little-endian) of the word w
    function [7:0] byte_of(input [31:0] w, input [1:0] n);
        byte_of = w[8 * n +: 8];
    endfunction

    // the pixel bytes first: the simulation then looks at no header field most of the frame
    always @* begin
        if (f == F_DATA) begin
            m_tdata = s_tdata;
        end else begin
            case (f)
                F_FID:   m_tdata = fid_rdata;
                F_ENC:   m_tdata = enc_at(i);
                F_BIG:   m_tdata = meta_bigendian;
                default: m_tdata = byte_of(word_of(f), i[1:0]);
            endcase
        end
    end

    assign m_tvalid = (f == F_DATA) ? s_tvalid : (f != F_IDLE);
    assign s_tready = (f == F_DATA) && m_tready;
    wire put = m_tvalid && m_tready;
    wire field_done = put && (i == ilast);
    wire [IW-1:0] i_next = i + 1'b1;
    // in F_FID m_tvalid is 1, so a byte goes when m_tready is 1: one LUT from registers
    assign fid_raddr = (in_fid && m_tready) ? fa1 : fa;
    assign meta_release = field_done && (f == F_BIG);  // the last field taken from the subscriber
    assign frame_done = field_done && (f == F_DATA);
    assign idle = (f == F_IDLE);

    always @(posedge clk) begin
        if (!rst_n) begin
            f <= F_IDLE;
            i <= {IW{1'b0}};
            ilast <= U32_LAST;
            in_fid <= 1'b0;
            fa <= {FIDA{1'b0}};
            fa1 <= FID_ONE;
            seq <= SEQ_START;
        end else if (put) begin                 // a byte goes (never in F_IDLE)
            if (in_fid) begin
                fa <= fa1;
                fa1 <= fa1 + 1'b1;
            end
            if (field_done) begin
                if (f == F_DATA) seq <= seq + 32'd1;
                in_fid <= (next_of(f) == F_FID);
                ilast <= last_of(next_of(f));
                f <= next_of(f);
            end
            i <= field_done ? {IW{1'b0}} : i_next;
        end else if (f == F_IDLE && meta_valid) begin
            f <= F_LEN;
            fa <= {FIDA{1'b0}};
            fa1 <= FID_ONE;
            ilast <= U32_LAST;
        end
    end
endmodule

`default_nettype wire
