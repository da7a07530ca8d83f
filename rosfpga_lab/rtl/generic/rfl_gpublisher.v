// rfl_gpublisher -- the publisher circuit of any message: for every frame the subscriber has
// read (meta_valid), writes one TCPROS frame onto the 8-bit valid/ready output stream, one byte
// per clock: the frame length the subscriber added up, then every field in wire order as the
// program of rfl_layout.vh says (carried bytes from the carry memory, constants, its message
// number, zeros, or the application's bytes from s_*). For a frame refused after its stream
// went out (meta_drop) it reads the STREAM_DATA_BYTES bytes of the application's output and
// writes nothing. meta_release ends the frame. CDR: before each field the zeros that align it,
// counted from its own output position (P_PAD); a string's count includes its NUL (written
// after a constant; an empty string for a skipped one); OP_ENCAP writes its 4 constant bytes.
// No multiplier (100 MHz on an ECP5 with no DSP): an OP_VAR's bytes are its count shifted by
// lsize, and a body's last byte is found by a count down (left_b). With streaming early release
// (the subscriber's STREAM_EARLY) it starts a frame at the stream's count and writes the stream
// as the application's bytes come; a carried byte waits for carry_valid (the fields after the
// stream may not be in the carry memory yet).
`default_nettype none

module rfl_gpublisher #(
    parameter STREAM_DATA_BYTES = 4,            // bytes of the stream, for a dropped frame
    parameter [31:0] SEQ_START = 1              // the first message number (PUB_COUNT)
) (
    input  wire        clk,
    input  wire        rst_n,
    input  wire [7:0]  s_tdata,                 // the application's bytes
    input  wire        s_tvalid,
    output wire        s_tready,
    output reg  [7:0]  m_tdata,                 // the outgoing frame (combinational)
    output wire        m_tvalid,
    input  wire        m_tready,
    input  wire        meta_valid,
    output wire        meta_release,
    input  wire [31:0] meta_out_len,
    input  wire        meta_drop,
    output wire        carry_restart,           // read the carried bytes from the first
    output wire        carry_pop,               // carry_rdata taken: the next carried byte
    input  wire [7:0]  carry_rdata,             // the carried byte at hand (a register)
    input  wire        carry_valid,             // ... is there (the subscriber may still be
                                                // writing it: streaming early release)
    output wire        idle                     // no frame being written
);
`include "rfl_layout.vh"
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (STREAM_DATA_BYTES < 0)
            $fatal(1, "rfl_gpublisher: STREAM_DATA_BYTES must be at least 0");
    end
`else
    if (STREAM_DATA_BYTES < 0) begin : g_bad_stream
        $error("rfl_gpublisher: STREAM_DATA_BYTES must be at least 0");
    end
`endif

    localparam [3:0] P_IDLE = 4'd0, P_LEN = 4'd1, P_DECODE = 4'd2, P_COUNT = 4'd3,
                     P_COUNTED = 4'd4, P_BODY = 4'd5, P_DROP = 4'd6, P_DONE = 4'd7, P_PAD = 4'd8;

    reg [3:0]  state;
    reg [31:0] opos;                            // bytes of this frame written so far
    reg [2:0]  padn;                            // zeros to write (P_PAD; fewer than 8)
    reg [3:0]  pad_ret;                         // the state after them
    reg [15:0] pc;
    reg [31:0] cnt;                             // bytes of the current part written so far
    reg [31:0] n;                               // the count being written
    reg [34:0] left_b;                          // bytes of the current body still to write
    reg [31:0] seq;
    // elements left of each open loop, 32 bits each (a vector, not a memory: Verilator keeps
    // a memory's every write site, the reset's one per entry, as work on every clock)
    reg [32*LOOPS-1:0] left;
    // Flags kept with the registers they test, so that no decision that chooses the next
    // instruction compares 32 bits first (100 MHz on an ECP5): n is zero (OP_VAR: so is its
    // body, n << lsize), the body's last byte is next (left_b == 1), and each open loop's last
    // element. (P_LEN's and P_COUNT's cnt counts 0 to 3: its low bits tell its 4th byte.)
    reg        n_zero;
    reg        last_b;                          // left_b == 1
    reg [LOOPS-1:0] last_of;                    // left[d] == 1
    reg [DB-1:0] depth;
    // PUB_CONST's next byte in a body: its constant's address (kaddr + cnt) and the constant's
    // bytes left (klen - cnt, 0 once past), counted with cnt so that the output byte starts
    // from flip-flops, not from an adder and a 32-bit comparison (Fmax)
    reg [15:0] kp, kleft;

    // The current instruction, prog_word(pc): a memory of one word (a register on an FPGA),
    // written at one place, so that Verilator copies its 224 bits only on the clocks it loads
    // (a register the walk's block writes is copied in and out on every clock).
    reg [IW-1:0] w_q [0:0];
    wire [IW-1:0] w = w_q[0];
    // CDR's parts, constant for TCPROS (CDR = 0) so that synthesis removes their logic
    wire [3:0]  align = CDR ? w[221:218] : 4'd1;
    wire [3:0]  elem_align = CDR ? w[217:214] : 4'd1;
    wire        nul = CDR ? w[213] : 1'b0;
    wire [2:0]  op = w[204:202];
    wire [2:0]  pub = w[198:196];
    wire        variable = w[195];
    wire [31:0] size = w[176:145];
    wire [31:0] count = w[144:113];
    wire [15:0] kaddr = w[112:97];
    wire [15:0] klen = w[96:81];
    wire [15:0] jump = w[80:65];
    wire [1:0]  lsize = w[223:222];
    /* verilator lint_off UNUSEDSIGNAL */
    wire [93:0] unused_fields = {w[212:205], w[201:199], w[194:177], w[64:0]};  // the subscriber's
    /* verilator lint_on UNUSEDSIGNAL */

    // The count an OP_VAR or variable OP_LOOP writes, when not carried.
    wire [31:0] own_count = (pub == PUB_CONST) ? {16'd0, klen} + {31'd0, nul}  // strings: a byte each
                            : (pub == PUB_STREAM) ? count : {31'd0, nul};
    wire from_stream = (state == P_BODY) && (pub == PUB_STREAM);
    wire [7:0] len_byte = meta_out_len[8 * cnt[1:0] +: 8];
    // (a count not carried is n, loaded with own_count as P_COUNT starts: the byte comes from
    // flip-flops, not from own_count's adder)
    wire [7:0] cnt_byte = n[8 * cnt[1:0] +: 8];
    wire [7:0] seq_byte = seq[8 * cnt[1:0] +: 8];

    wire carried = (state == P_COUNT || state == P_BODY) && (pub == PUB_CARRY);
    // A carried byte comes from the subscriber's carry_rdata register (read ahead of the carry
    // memory's block RAM); every other byte is `other`.
    reg [7:0] other;
    always @* begin
        case (state)
            P_LEN: other = len_byte;
            P_COUNT: other = cnt_byte;
            P_BODY: case (pub)
                PUB_CONST:  // then a NUL (an if, not ?:, so that the ROM is looked up only here)
                    if (kleft != 16'd0) other = konst(kp);
                    else other = 8'd0;
                PUB_COUNT: other = (cnt < 32'd4) ? seq_byte : 8'd0;
                PUB_STREAM: other = s_tdata;
                default: other = 8'd0;
            endcase
            default: other = 8'd0;
        endcase
        m_tdata = carried ? carry_rdata : other;
    end

    assign m_tvalid = (state == P_LEN) || (state == P_PAD)
                      || ((state == P_COUNT || state == P_BODY)
                          && (from_stream ? s_tvalid : (!carried || carry_valid)));
    assign s_tready = (from_stream && m_tready) || (state == P_DROP);
    assign carry_restart = (state == P_IDLE) && meta_valid;
    assign meta_release = (state == P_DONE);
    assign idle = (state == P_IDLE);
    wire put = m_tvalid && m_tready;
    assign carry_pop = put && carried;
    // the count completed by this byte (a function: evaluated in P_COUNT only)
    function [31:0] n_next(input [7:0] byte_in);
        n_next = {byte_in, n[31:8]};
    endfunction
    // OP_VAR: count x size (a function, not a wire: a simulation evaluates it in P_COUNTED only)
    function [34:0] body_of(input [31:0] count_n);
        body_of = {3'd0, count_n} << lsize;
    endfunction

    // Write `p` alignment zeros (if any), then go to state `next`.
    task pad_then(input [31:0] p, input [3:0] next);
        begin
            cnt <= 32'd0;
            if (p != 32'd0) begin
                padn <= p[2:0];
                pad_ret <= next;
                state <= P_PAD;
            end else begin
                state <= next;
            end
        end
    endtask

    // Where the program goes on this clock: pc and w load as it says, at one place (the end of
    // the walk's block).
    localparam [1:0] G_STAY = 2'd0, G_FIRST = 2'd1, G_NEXT = 2'd2, G_JUMP = 2'd3;
    reg [1:0] step;
    always @* begin
        step = G_STAY;
        case (state)
            P_IDLE: if (meta_valid) step = G_FIRST;
            P_LEN: if (put && cnt[1:0] == 2'd3) step = G_FIRST;
            P_DECODE:
                if (op == OP_END) step = last_of[depth - 1'b1] ? G_NEXT : G_JUMP;
                else if ((op == OP_FIXED || op == OP_ENCAP) && size == 32'd0) step = G_NEXT;
            P_COUNTED:
                if (op == OP_LOOP && n_zero) step = G_JUMP;
                else if (op == OP_LOOP || n_zero) step = G_NEXT;
            P_BODY: if (put && last_b) step = G_NEXT;
            default: step = G_STAY;
        endcase
    end

    // Go on with the instruction `step` loads.
    task go;
        begin
            state <= P_DECODE;
            cnt <= 32'd0;
        end
    endtask

    always @(posedge clk) begin
        if (!rst_n) begin
            state <= P_IDLE;
            cnt <= 32'd0;
            n <= 32'd0;
            n_zero <= 1'b1;
            last_of <= {LOOPS{1'b0}};
            left_b <= 35'd0;
            last_b <= 1'b0;
            seq <= SEQ_START;
            opos <= 32'd0;
            padn <= 3'd0;
            pad_ret <= P_IDLE;
            depth <= {DB{1'b0}};
            left <= {(32 * LOOPS){1'b0}};
            kp <= 16'd0;
            kleft <= 16'd0;
        end else begin
            if (put) cnt <= cnt + 32'd1;
            if (state == P_BODY) begin  // (read, then written: a simulation copies neither)
                if (put) begin
                    if (kleft != 16'd0) kleft <= kleft - 16'd1;
                    kp <= kp + 16'd1;
                end
            end else begin  // (a body starts with cnt 0)
                kp <= kaddr;
                kleft <= klen;
            end
            if (put) opos <= opos + 32'd1;
            case (state)
                P_IDLE: if (meta_valid) begin
                    cnt <= 32'd0;
                    opos <= 32'd0;
                    depth <= {DB{1'b0}};
                    state <= meta_drop ? ((STREAM_DATA_BYTES == 0) ? P_DONE : P_DROP) : P_LEN;
                end
                P_DROP: if (s_tvalid) begin
                    cnt <= cnt + 32'd1;
                    if (cnt == STREAM_DATA_BYTES - 1) state <= P_DONE;
                end
                P_LEN: if (put && cnt[1:0] == 2'd3) go;
                P_DECODE: case (op)
                    OP_DONE: begin
                        seq <= seq + 32'd1;
                        state <= P_DONE;
                    end
                    OP_END: begin
                        if (!last_of[depth - 1'b1]) begin
                            left[{depth - 1'b1, 5'd0} +: 32] <= left[{depth - 1'b1, 5'd0} +: 32] - 32'd1;
                            last_of[depth - 1'b1] <= (left[{depth - 1'b1, 5'd0} +: 32] == 32'd2);
                        end else begin
                            depth <= depth - 1'b1;
                        end
                        go;
                    end
                    OP_FIXED, OP_ENCAP: begin
                        left_b <= {3'd0, size};
                        last_b <= (size == 32'd1);
                        if (size != 32'd0) pad_then(pad_at(opos, align), P_BODY);
                    end
                    default: begin  // OP_VAR, OP_LOOP
                        if (op == OP_LOOP && !variable) begin
                            n <= count;
                            n_zero <= (count == 32'd0);
                            state <= P_COUNTED;
                        end else begin
                            n <= own_count;
                            n_zero <= (own_count == 32'd0);
                            pad_then(pad_at(opos, align), P_COUNT);
                        end
                    end
                endcase
                P_COUNT: if (put) begin
                    if (pub == PUB_CARRY) begin
                        n <= n_next(carry_rdata);
                        n_zero <= (n_next(carry_rdata) == 32'd0);
                    end
                    if (cnt[1:0] == 2'd3) begin
                        state <= P_COUNTED;
                        cnt <= 32'd0;
                    end
                end
                P_COUNTED: begin
                    if (op == OP_LOOP) begin
                        if (!n_zero) begin
                            left[{depth, 5'd0} +: 32] <= n;
                            last_of[depth] <= (n == 32'd1);
                            depth <= depth + 1'b1;
                        end
                        go;
                    end else if (n_zero) begin  // body == 0
                        go;
                    end else begin
                        left_b <= body_of(n);
                        last_b <= (body_of(n) == 35'd1);
                        pad_then(pad_at(opos, elem_align), P_BODY);
                    end
                end
                P_PAD: if (put && cnt[2:0] + 3'd1 == padn) begin
                    state <= pad_ret;
                    cnt <= 32'd0;
                end
                P_BODY: if (put) begin
                    left_b <= left_b - 35'd1;
                    last_b <= (left_b == 35'd2);
                    if (last_b) go;
                end
                P_DONE: state <= P_IDLE;
                default: state <= P_IDLE;
            endcase
        end
        // (w follows pc: the word of the next pc, from a look-up by the current pc)
        if (!rst_n || step != G_STAY) begin
            w_q[0] <= (!rst_n || step == G_FIRST) ? prog_word(16'd0)
                    : (step == G_JUMP) ? prog_jump(pc) : prog_next(pc);
            pc <= (!rst_n || step == G_FIRST) ? 16'd0
                  : (step == G_JUMP) ? jump + 16'd1 : pc + 16'd1;
        end
    end
`ifdef FORMAL
    // the instruction register holds the word of pc (an invariant the proofs carry)
    always @(*) if (rst_n) assert(w == prog_word(pc));
    // ... and the flags their registers (invariants too)
    integer fd;
    always @(*) if (rst_n) begin
        assert(n_zero == (n == 32'd0));
        assert(last_b == (left_b == 35'd1));
        if (state == P_LEN || state == P_COUNT) assert(cnt < 32'd4);
        if ((state == P_COUNT || (state == P_PAD && pad_ret == P_COUNT)) && pub != PUB_CARRY)
            assert(n == own_count);
        if (state == P_BODY)
            assert(kp == kaddr + cnt[15:0]
                   && (kleft == 16'd0
                       || (cnt < {16'd0, klen} && kleft == klen - cnt[15:0])));
        for (fd = 0; fd < LOOPS; fd = fd + 1) assert(last_of[fd] == (left[32 * fd +: 32] == 32'd1));
    end
`endif
endmodule

`default_nettype wire
