// rfl_gpublisher -- the publisher circuit of any message: for every frame the subscriber has
// read (meta_valid), writes one TCPROS frame onto the 8-bit valid/ready output stream, one byte
// per clock: the frame length the subscriber added up, then every field in wire order as the
// program of rfl_layout.vh says (carried bytes from the carry memory, constants, its message
// number, zeros, or the application's bytes from s_*). For a frame refused after its stream
// went out (meta_drop) it reads the STREAM_DATA_BYTES bytes of the application's output and
// writes nothing. meta_release ends the frame.
module rfl_gpublisher #(
    parameter CW = 6,                           // carry memory address bits
    parameter STREAM_DATA_BYTES = 4,            // bytes of the stream, for a dropped frame
    parameter [31:0] SEQ_START = 1              // the first message number (PUB_COUNT)
) (
    input              clk,
    input              rst_n,
    input      [7:0]   s_tdata,                 // the application's bytes
    input              s_tvalid,
    output             s_tready,
    output reg [7:0]   m_tdata,                 // the outgoing frame (combinational)
    output             m_tvalid,
    input              m_tready,
    input              meta_valid,
    output             meta_release,
    input      [31:0]  meta_out_len,
    input              meta_drop,
    output     [CW-1:0] carry_raddr,
    input      [7:0]   carry_rdata,
    output             idle                     // no frame being written
);
`include "rfl_layout.vh"
    localparam [2:0] P_IDLE = 3'd0, P_LEN = 3'd1, P_DECODE = 3'd2, P_COUNT = 3'd3,
                     P_COUNTED = 3'd4, P_BODY = 3'd5, P_DROP = 3'd6, P_DONE = 3'd7;

    reg [2:0]  state;
    reg [15:0] pc;
    reg [31:0] cnt;                             // bytes of the current part written so far
    reg [31:0] n;                               // the count being written
    reg [63:0] need;                            // bytes of the current body
    reg [31:0] seq;
    reg [CW-1:0] raddr;
    reg [31:0] left [0:LOOPS-1];
    reg [DB-1:0] depth;

    wire [IW-1:0] w = prog_word(pc);
    wire [2:0]  op = w[204:202];
    wire [2:0]  pub = w[198:196];
    wire        variable = w[195];
    wire [31:0] size = w[176:145];
    wire [31:0] count = w[144:113];
    wire [15:0] kaddr = w[112:97];
    wire [15:0] klen = w[96:81];
    wire [15:0] jump = w[80:65];
    /* verilator lint_off UNUSEDSIGNAL */
    wire [85:0] unused_fields = {w[201:199], w[194:177], w[64:0]};  // the subscriber's part
    /* verilator lint_on UNUSEDSIGNAL */

    // The count an OP_VAR or variable OP_LOOP writes, when not carried.
    wire [31:0] own_count = (pub == PUB_CONST) ? {16'd0, klen}  // strings: one byte per element
                            : (pub == PUB_STREAM) ? count : 32'd0;
    wire from_stream = (state == P_BODY) && (pub == PUB_STREAM);
    wire [7:0] len_byte = meta_out_len[8 * cnt[1:0] +: 8];
    wire [7:0] cnt_byte = own_count[8 * cnt[1:0] +: 8];
    wire [7:0] seq_byte = seq[8 * cnt[1:0] +: 8];

    always @* begin
        case (state)
            P_LEN: m_tdata = len_byte;
            P_COUNT: m_tdata = (pub == PUB_CARRY) ? carry_rdata : cnt_byte;
            P_BODY: case (pub)
                PUB_CARRY: m_tdata = carry_rdata;
                PUB_CONST: m_tdata = konst(kaddr + cnt[15:0]);
                PUB_COUNT: m_tdata = (cnt < 32'd4) ? seq_byte : 8'd0;
                PUB_STREAM: m_tdata = s_tdata;
                default: m_tdata = 8'd0;
            endcase
            default: m_tdata = 8'd0;
        endcase
    end

    assign m_tvalid = (state == P_LEN) || (state == P_COUNT) || (state == P_BODY && (!from_stream || s_tvalid));
    assign s_tready = (from_stream && m_tready) || (state == P_DROP);
    assign carry_raddr = raddr;
    assign meta_release = (state == P_DONE);
    assign idle = (state == P_IDLE);
    wire put = m_tvalid && m_tready;
    wire carried = (state == P_COUNT || state == P_BODY) && (pub == PUB_CARRY);
    wire [31:0] n_next = {carry_rdata, n[31:8]};

    task go(input [15:0] next);
        begin
            pc <= next;
            state <= P_DECODE;
            cnt <= 32'd0;
        end
    endtask

    integer d;
    always @(posedge clk) begin
        if (!rst_n) begin
            state <= P_IDLE;
            pc <= 16'd0;
            cnt <= 32'd0;
            n <= 32'd0;
            need <= 64'd0;
            seq <= SEQ_START;
            raddr <= {CW{1'b0}};
            depth <= {DB{1'b0}};
            for (d = 0; d < LOOPS; d = d + 1) left[d] <= 32'd0;
        end else begin
            if (put) cnt <= cnt + 32'd1;
            if (put && carried) raddr <= raddr + 1'b1;
            case (state)
                P_IDLE: if (meta_valid) begin
                    cnt <= 32'd0;
                    raddr <= {CW{1'b0}};
                    depth <= {DB{1'b0}};
                    pc <= 16'd0;
                    state <= meta_drop ? ((STREAM_DATA_BYTES == 0) ? P_DONE : P_DROP) : P_LEN;
                end
                P_DROP: if (s_tvalid) begin
                    cnt <= cnt + 32'd1;
                    if (cnt == STREAM_DATA_BYTES - 1) state <= P_DONE;
                end
                P_LEN: if (put && cnt == 32'd3) go(16'd0);
                P_DECODE: case (op)
                    OP_DONE: begin
                        seq <= seq + 32'd1;
                        state <= P_DONE;
                    end
                    OP_END: begin
                        if (left[depth - 1'b1] != 32'd1) begin
                            left[depth - 1'b1] <= left[depth - 1'b1] - 32'd1;
                            go(jump + 16'd1);
                        end else begin
                            depth <= depth - 1'b1;
                            go(pc + 16'd1);
                        end
                    end
                    OP_FIXED: begin
                        need <= {32'd0, size};
                        state <= (size == 32'd0) ? P_DECODE : P_BODY;
                        if (size == 32'd0) pc <= pc + 16'd1;
                    end
                    default: begin  // OP_VAR, OP_LOOP
                        if (op == OP_LOOP && !variable) begin
                            n <= count;
                            state <= P_COUNTED;
                        end else begin
                            n <= own_count;
                            state <= P_COUNT;
                        end
                    end
                endcase
                P_COUNT: if (put) begin
                    if (pub == PUB_CARRY) n <= n_next;
                    if (cnt == 32'd3) begin
                        state <= P_COUNTED;
                        cnt <= 32'd0;
                    end
                end
                P_COUNTED: begin
                    if (op == OP_LOOP) begin
                        if (n == 32'd0) go(jump + 16'd1);
                        else begin
                            left[depth] <= n;
                            depth <= depth + 1'b1;
                            go(pc + 16'd1);
                        end
                    end else if ({32'd0, n} * {32'd0, size} == 64'd0) begin
                        go(pc + 16'd1);
                    end else begin
                        need <= {32'd0, n} * {32'd0, size};
                        state <= P_BODY;
                    end
                end
                P_BODY: if (put && {32'd0, cnt} + 64'd1 == need) go(pc + 16'd1);
                P_DONE: state <= P_IDLE;
                default: state <= P_IDLE;
            endcase
        end
    end
endmodule
