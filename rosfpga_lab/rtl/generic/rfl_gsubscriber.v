// rfl_gsubscriber -- the subscriber circuit of any message: reads one TCPROS frame from an 8-bit
// valid/ready byte stream, one byte per clock, stepping through the program of rfl_layout.vh
// (one instruction per field, in wire order). Each field's bytes are skipped, carried (written
// into the carry memory, in order, lengths included, for the publisher), checked (against the
// program's constants or bounds) or streamed (out on m_*, to the element packer). It adds up
// the length of the message the publisher will write (out_len). When it has read a whole frame
// (or refused one after its stream went out) it hands the frame's record (out_len, drop, its
// carry bank) to the publisher: meta_* show the oldest record, meta_valid until the publisher's
// meta_release. It holds RECORDS (2) records, each with a bank of the carry memory of its own,
// so it reads frame n+1 while the publisher writes frame n; a new frame waits only while both
// are held. A refused frame is skipped to its end (no record unless its stream went out). Each
// frame ends in a one-clock status_valid pulse with the status code (0: accepted).
// CDR samples (a sample length, then the payload): OP_ENCAP checks the encapsulation header and
// takes the payload's end padding from its options (skipped after the last field); before each
// field the bytes that align it are skipped (S_PAD); a string's count includes its NUL, which
// must be 0; out_len includes the padding the publisher will write. After the last field, the
// bytes the options do not announce that pad the payload to a multiple of END_ALIGN (Cyclone DDS
// pads so with options 00 00) are taken (S_TAIL); no padding byte is looked at (CDR leaves its
// value undefined).
// No multiplier (100 MHz on an ECP5 with no DSP): an OP_VAR's bytes are its count shifted by
// lsize; an OP_LOOP's fewest bytes (count x elem_min) are added up in S_LEAST, one bit of
// elem_min per clock, before S_COUNTED checks them. The bytes left for the fields (room: CDR
// less the end padding) and in the frame (left_f) are registers kept with pos, and a body's
// last byte is found by a count down (left_b), so that no clock subtracts and compares in a row.
// Streaming early release (STREAM_EARLY, from Program.stream_early; EARLY must equal it): when
// nothing after the stream's count can refuse the frame (TCPROS: its count fills the frame
// exactly with fixed fields that are skipped or carried; CDR: the stream is the last field and
// its elements end the payload, or leave only the unannounced end padding, checked at the count
// as c_early_bad), the frame is handed over (its record, out_len + EARLY_ADD) at the count's
// decision, so the publisher writes it while the stream flows; the frame's end then hands
// nothing over. The publisher may read the frame's carry bank while the fields after the stream
// are written into it: a byte is read only once written (craddr < the bank's count), and
// carry_valid says the carried byte at hand is there.
`default_nettype none

module rfl_gsubscriber #(
    parameter CARRY_BYTES = 64,                 // the carry memory of one frame (at least 1)
    parameter CW = 6,                           // its address bits
    parameter MIN_BODY = 0,                     // shortest frame length accepted
    parameter MAX_FRAME = 67108864,             // longest frame length accepted
    parameter EARLY = -1                        // streaming early release: the walk's STREAM_EARLY
                                                // (-1: take it; else it must be the walk's)
) (
    input  wire        clk,
    input  wire        rst_n,
    input  wire [7:0]  s_tdata,
    input  wire        s_tvalid,
    output wire        s_tready,
    output wire [7:0]  m_tdata,                 // streamed bytes
    output wire        m_tvalid,
    input  wire        m_tready,
    output reg         meta_valid,
    input  wire        meta_release,
    output reg  [31:0] meta_out_len,            // the publisher's frame length
    output reg         meta_drop,               // refused after its stream: drop the stream
    input  wire        carry_restart,           // the publisher reads them from the first
    input  wire        carry_pop,               // ... has taken carry_rdata: the next
    output reg  [7:0]  carry_rdata,             // the carried byte at hand (a register)
    output reg         carry_valid,             // ... is there (read from written bytes)
    output wire        frame_start,
    output reg         status_valid,
    output reg  [7:0]  status,
    output wire        idle                     // between frames
);
`include "rfl_layout.vh"
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (CARRY_BYTES < 1 || CW < 1 || CW > 16 || (1 << CW) < CARRY_BYTES)
            $fatal(1,
                   "rfl_gsubscriber: CARRY_BYTES must be at least 1 and at most 2**CW (CW 1..16)");
        if (MIN_BODY < 0 || MIN_BODY > MAX_FRAME)
            $fatal(1, "rfl_gsubscriber: MIN_BODY must be at most MAX_FRAME");
        if (EARLY != -1 && EARLY != STREAM_EARLY)
            $fatal(1, "rfl_gsubscriber: EARLY must be the walk's STREAM_EARLY (rfl_layout.vh)");
        if (RECORDS != 2)
            $fatal(1, "rfl_gsubscriber: holds 2 records (rfl_layout.vh's RECORDS)");
    end
`else
    if (CARRY_BYTES < 1 || CW < 1 || CW > 16 || (1 << CW) < CARRY_BYTES) begin : g_bad_carry
        $error("rfl_gsubscriber: CARRY_BYTES must be at least 1 and at most 2**CW (CW 1..16)");
    end
    if (MIN_BODY < 0 || MIN_BODY > MAX_FRAME) begin : g_bad_frame
        $error("rfl_gsubscriber: MIN_BODY must be at most MAX_FRAME");
    end
    if (EARLY != -1 && EARLY != STREAM_EARLY) begin : g_bad_early
        $error("rfl_gsubscriber: EARLY must be the walk's STREAM_EARLY (rfl_layout.vh)");
    end
    if (RECORDS != 2) begin : g_bad_records
        $error("rfl_gsubscriber: holds 2 records (rfl_layout.vh's RECORDS)");
    end
`endif

    localparam [3:0] S_FLEN = 4'd0, S_DECODE = 4'd1, S_COUNT = 4'd2, S_COUNTED = 4'd3,
                     S_BODY = 4'd4, S_FINISH = 4'd5, S_SKIP = 4'd6, S_PAD = 4'd7, S_TAIL = 4'd8,
                     S_LEAST = 4'd9, S_FCHK = 4'd10;

    reg [3:0]  state;
    reg [15:0] pc;
    reg [31:0] pos;                             // bytes of this frame taken so far
    reg [31:0] left_f;                          // bytes of the frame left: 4 + frame length - pos
    reg        last_f;                          // left_f == 1 (kept with it: S_SKIP, S_TAIL)
    reg [2:0]  padn;                            // alignment bytes to skip (S_PAD; fewer than 8)
    reg [3:0]  pad_ret;                         // the state after them
    reg        nul_bad;                         // a string's last byte was not 0
    reg [31:0] cnt;                             // bytes of the current part taken so far
    reg [31:0] n;                               // a count, shifted in little-endian
    reg [34:0] left_b;                          // bytes of the current body still to take
    reg        last_b;                          // left_b == 1 (kept with it: S_BODY's end)
    reg [31:0] room;                            // bytes left for the fields (CDR: before the end padding)
    reg [63:0] least_r;                         // OP_LOOP: count x elem_min, added up (S_LEAST)
    reg [63:0] nsh;                             // the count shifted by the elem_min bits done
    reg [31:0] mrem;                            // elem_min's bits still to add
    reg [63:0] value;                           // a SUB_RANGE field, little-endian
    reg        same;                            // a SUB_CHECK field equals its constant so far
    reg        streamed;                        // the stream went out (set as its body starts:
                                                // every byte of it is taken before a decision)
    reg        released;                        // handed over early (STREAM_EARLY)
    // SUB_CHECK's next byte in a body: its constant's address (kaddr + cnt) and the constant's
    // bytes left (klen - cnt, 0 once past), counted with cnt so that the check starts from
    // flip-flops, not from an adder and a 32-bit comparison (Fmax)
    reg [15:0] kp, kleft;
    reg [31:0] out_len;
    // elements left of each open loop, 32 bits each (a vector, not a memory: Verilator keeps
    // a memory's every write site, the reset's one per entry, as work on every clock)
    reg [32*LOOPS-1:0] left;
    reg [LOOPS-1:0] quiet_of;              // that loop is written empty
    reg [DB-1:0] depth;
    reg [7:0]  quiet;
    // the carry memory: two banks of 2**CW bytes, a frame's in the bank of its record
    reg [7:0]  carry_mem [0:(2 << CW)-1];

    // The decisions' registers (r_out_*, the bounds' masks and keys, the next instructions, p_*
    // and c_*) load on every clock but a field's bytes (S_BODY), where nothing reads them and a
    // simulation spends nearly all its clocks (each load is work for Verilator, not for an
    // FPGA). A decision reads what it would read if they loaded on every clock: what they are
    // computed from holds through S_BODY (the instruction, out_len, n), or changes there (the
    // field's value, the counts of bytes left, pos, same) and reaches the decision through at
    // most two of them, which S_FINISH's two settling clocks load.
    wire dec_load = (state != S_BODY);

    // The current instruction, prog_word(pc): a memory of one word, written at one place (as
    // rfl_gpublisher's w).
    reg [IW-1:0] w_q [0:0];
    wire [IW-1:0] w = w_q[0];
    // CDR's parts, constant for TCPROS (CDR = 0) so that synthesis removes their logic
    wire [3:0]  align = CDR ? w[221:218] : 4'd1;
    wire [3:0]  elem_align = CDR ? w[217:214] : 4'd1;
    wire        nul = CDR ? w[213] : 1'b0;
    wire [7:0]  st3 = w[212:205];
    wire [2:0]  op = w[204:202];
    wire [2:0]  sub = w[201:199];
    wire [2:0]  pub = w[198:196];
    wire        variable = w[195];
    wire [1:0]  kind = w[194:193];
    wire [7:0]  st = w[192:185];
    wire [7:0]  st2 = w[184:177];
    wire [31:0] size = w[176:145];
    wire [31:0] count = w[144:113];
    wire [15:0] kaddr = w[112:97];
    wire [15:0] klen = w[96:81];
    wire [15:0] jump = w[80:65];
    wire        fits = w[64];
    wire [31:0] fixed_after = w[63:32];
    wire [31:0] elem_min = w[31:0];
    wire [1:0]  lsize = w[223:222];

    // A new frame waits while both records are held (the publisher has not taken the older).
    // (In S_FLEN, as in S_COUNT, cnt counts the length's bytes, 0..3.)
    reg        nxt_valid;                       // the second record is held (behind meta_*)
    wire stall = (state == S_FLEN) && (cnt[1:0] == 2'd0) && nxt_valid;
    wire streaming = (state == S_BODY) && (sub == SUB_STREAM);
    wire reading = (state == S_FLEN && !stall) || state == S_COUNT || state == S_BODY
                   || state == S_SKIP || state == S_PAD || state == S_TAIL;
    assign s_tready = streaming ? m_tready : reading;
    assign m_tvalid = streaming && s_tvalid;
    assign m_tdata = s_tdata;
    wire take = s_tvalid && s_tready;
    assign frame_start = take && (state == S_FLEN) && (cnt[1:0] == 2'd0);
    assign idle = (state == S_FLEN) && (cnt[1:0] == 2'd0);

    // the count completed by this byte (a function: evaluated in S_FLEN and S_COUNT only)
    function [31:0] n_next(input [7:0] byte_in);
        n_next = {byte_in, n[31:8]};
    endfunction
    wire [31:0] pos_next = pos + 32'd1;
    wire        at_end = (left_f == 32'd0);         // nothing left of the frame to skip
    // CDR: the bytes left after the last field are the unannounced padding up to a multiple of
    // END_ALIGN
    wire        tail_pad = CDR && unannounced_pad(room, left_f, pos);
    wire [31:0] pad_f = pad_at(pos, align);         // before a field or a count
    wire [31:0] pad_e = pad_at(pos, elem_align);    // before an OP_VAR's elements
    wire [31:0] room_f = room - pad_f;              // bytes left after that padding
    wire [31:0] room_e = room - pad_e;              // (each used only when the padding fits)
    // OP_VAR: count x size, and its low 32 bits (functions, not wires, so that a simulation
    // evaluates them only where a decision reads them, not on every clock)
    function [34:0] body_of(input [31:0] count_n);
        body_of = {3'd0, count_n} << lsize;
    endfunction
    function [31:0] body32(input [31:0] count_n);
        body32 = count_n << lsize;
    endfunction
    // what the publisher writes for this OP_FIXED / OP_VAR: its bytes, and where they start
    function [31:0] written_of(input [31:0] bytes);  // bytes: the OP_VAR's body
        written_of = (op == OP_FIXED) ? size
                     : (pub == PUB_CARRY || pub == PUB_STREAM) ? bytes
                     : (pub == PUB_CONST) ? {16'd0, klen} + {31'd0, nul} : {31'd0, nul};
    endfunction
    wire [31:0] out_base = (op == OP_FIXED) ? out_len : out_len + 32'd4;
    // (registered on every clock but S_BODY's: out_len, n and the instruction hold from
    // S_COUNTED, or the field's last byte, to S_FINISH, whose first settling clock adds them up
    // into p_out_at)
    reg [31:0]  r_out_base, r_out_pad;
    always @(posedge clk) if (dec_load) begin
        r_out_base <= out_base;
        r_out_pad <= (written_of(body32(n)) == 32'd0) ? 32'd0
                     : pad_at(out_base + 32'd4, (op == OP_FIXED) ? align : elem_align);
    end
    // fewest bytes of the counted elements (OP_VAR: its elements' bytes)
    function [63:0] least_of(input [34:0] bytes);
        least_of = (op == OP_VAR) ? {29'd0, bytes} : least_r;
    endfunction
    wire        keep = (state == S_COUNT) ? (sub == SUB_CARRY)
                       : (sub == SUB_CARRY || sub == SUB_RANGE);

    // Bounds of a SUB_RANGE field: low, then high, little-endian, `size` bytes each.
    function [63:0] bound(input [15:0] at, input [31:0] nbytes);
        integer b;
        begin
            bound = 64'd0;
            for (b = 0; b < 8; b = b + 1)
                if (b < nbytes) bound[8*b +: 8] = konst(at + b[15:0]);
        end
    endfunction

    // The order key of a value (larger key, larger value); floats: -0.0 counts as +0.0. `sign`
    // is the value's sign bit (1 << (8 x bytes - 1)), `all` its bits (registered below).
    function [63:0] order_key(input [63:0] v, input [63:0] sign, input [63:0] all,
                              input [1:0] k);
        reg [63:0] x;
        begin
            x = v;
            if (k == 2'd2 && x == sign) x = 64'd0;
            if (k == 2'd1) order_key = x ^ sign;
            else if (k == 2'd2) order_key = ((x & sign) != 64'd0) ? (~x & all) : (x | sign);
            else order_key = x;
        end
    endfunction

    /* verilator lint_off UNUSEDSIGNAL */
    function is_nan(input [63:0] v, input [31:0] nbytes);
        begin
            if (nbytes == 32'd4) is_nan = (v[30:23] == 8'hff) && (v[22:0] != 23'd0);
            else is_nan = (v[62:52] == 11'h7ff) && (v[51:0] != 52'd0);
        end
    endfunction
    /* verilator lint_on UNUSEDSIGNAL */

    // The bounds' keys, registered: they depend on the instruction only, which holds from
    // S_DECODE (three clocks) through S_BODY to S_FINISH, where in_range is read (the masks
    // are registered one clock after the instruction, the keys one clock after the masks).
    // The sign and all-bits masks of the field's size (1, 2, 4 or 8 bytes) the same way.
    reg [63:0] lo_key, hi_key, sign_m, all_m;
    always @(posedge clk) if (dec_load) begin
        sign_m <= 64'd1 << (8 * size[3:0] - 1);
        all_m <= (64'd1 << (8 * size[3:0] - 1)) | ((64'd1 << (8 * size[3:0] - 1)) - 64'd1);
        lo_key <= order_key(bound(kaddr, size), sign_m, all_m, kind);
        hi_key <= order_key(bound(kaddr + size[15:0], size), sign_m, all_m, kind);
    end

    // The records and the carry memory's banks. The walk hands a frame over (hand_over, below)
    // into meta_* when they are free (or being released), else into nxt_*, the second record;
    // meta_release moves nxt_* into meta_*. A frame writes its carried bytes into bank fbank,
    // chosen as it starts (step == G_FIRST) as the bank no held record has; wcnt counts each
    // bank's bytes written (one bit more: 2**CW fit). The publisher reads the bank of meta_*.
    reg        nxt_drop, nxt_bank, meta_bank, fbank;
`ifdef FORMAL
    // (proofs only) records numbered as handed over: f_in the next number, f_out the next to
    // be released, f_head and f_nxt those held, f_own0/1 the number of the record whose
    // frame writes (wrote) each bank
    reg [2:0]  f_in, f_out, f_head, f_nxt, f_own0, f_own1;
`endif
    reg [31:0] nxt_out_len;
    reg [CW:0] wcnt0, wcnt1;
    wire [CW-1:0] waddr = fbank ? wcnt1[CW-1:0] : wcnt0[CW-1:0];  // where the next carried byte goes
    wire       carry_we = take && keep && (state == S_COUNT || state == S_BODY);

    // Hand the frame over: its record behind the held one, if one is held and not being
    // released now (a frame starts with nxt_* empty and hands over at most once).
    task hand_over(input drop, input [31:0] len);
        begin
            if (meta_valid && !meta_release) begin
                nxt_valid <= 1'b1;
                nxt_drop <= drop;
                nxt_out_len <= len;
`ifdef FORMAL
                f_nxt <= f_in;
`endif
            end else begin
                meta_valid <= 1'b1;
                meta_drop <= drop;
                meta_out_len <= len;
`ifdef FORMAL
                f_head <= f_in;
`endif
            end
`ifdef FORMAL
            f_in <= f_in + 3'd1;
`endif
        end
    endtask

    // The carry memory's read side: the publisher takes the carried bytes of meta_*'s bank in
    // order, from the first, once per frame (carry_restart, then carry_pop for each); no other
    // frame writes the bank before meta_release (a new frame takes the other bank), so its
    // count holds while they are read. They are read ahead into two registers, as rfl_fifo's
    // OUTREG does: the block RAM's read register (cq), then carry_rdata in the fabric, so that
    // the publisher's byte does not start from a block RAM's slow clock-to-output (100 MHz
    // timing on an ECP5). A byte is read only once written
    // (craddr < the bank's count): with STREAM_EARLY the publisher starts before the carried
    // fields after the stream are in; carry_valid says carry_rdata holds the next carried byte.
    // Two clocks after carry_restart the first byte is in carry_rdata (the publisher's first
    // carried byte comes after the frame length's 4 bytes and a decode); from then on each
    // carry_pop moves the next one in (when written).
    reg [CW:0] craddr;                          // the next byte to read
    reg [7:0]  cq;                              // the byte after carry_rdata
    reg        cq_valid;
    wire [CW:0] rcnt = meta_bank ? wcnt1 : wcnt0;                     // the bank's bytes written
    wire       c_move = cq_valid && (!carry_valid || carry_pop);      // cq -> carry_rdata
    wire       c_read = (!cq_valid || c_move) && (craddr != rcnt);    // memory -> cq
    always @(posedge clk) begin
        if (c_read) cq <= carry_mem[{meta_bank, craddr[CW-1:0]}];
        if (c_move) carry_rdata <= cq;
        if (!rst_n || carry_restart) begin
            craddr <= {(CW + 1){1'b0}};
            cq_valid <= 1'b0;
            carry_valid <= 1'b0;
        end else begin
            if (c_read) craddr <= craddr + 1'b1;
            cq_valid <= c_read || (cq_valid && !c_move);
            carry_valid <= c_move || (carry_valid && !carry_pop);
        end
    end

    // The decisions' arithmetic, registered: S_FCHK, S_DECODE, S_COUNTED and S_FINISH take
    // three clocks, the first two (settled 0, 1) with nothing changing but these registers (p_*: the
    // subtractions and the value's key; c_*: the comparisons, from p_*), so that the third
    // decides from flip-flops (100 MHz on an ECP5) as the same expressions would.
    reg [1:0] settled;
    reg [31:0] p_room_f, p_room_e;
    reg [63:0] p_vkey, p_least, p_least_fa;
    reg [31:0] p_out_at, p_written;                // S_FINISH: where the field's bytes start, and how many
    reg        p_vnan;
    wire in_range = !p_vnan && lo_key <= p_vkey && p_vkey <= hi_key;
    reg c_tail, c_left1, c_padf_bad, c_size_gt, c_roomf_lt4, c_count_bad, c_fit_bad, c_least_gt,
        c_body0, c_pade_bad, c_body_gt, c_encap_bad, c_encap_pad_gt, c_check_bad, c_range_bad,
        c_at_end, c_room0, c_room_lt4, c_size0, c_n0, c_n1, c_flen_long, c_flen_short, c_body1,
        c_size1;
    reg [31:0] c_out_len;                          // S_FINISH: out_len after the field
    // out_len and room after a decision's additions, settled the same way (each decision acts
    // on flip-flops only): an OP_VAR's count padding, a variable OP_LOOP's count, OP_ENCAP's
    // header and end padding
    reg [31:0] p_out_var, p_out4, p_out_klen, p_room_encap, p_out_early;
    // CDR's early release: where the stream's elements would end, and the bytes after them
    // to the fields' end (room) and to the sample's end (left_f)
    reg [31:0] p_end_pos, p_end_room, p_end_left;
    reg        c_early_bad;
    // The next instructions, registered (the ROM look-up and the adders are not on the
    // decision's path): pc holds from one go() through the two settling clocks of the decision
    // that does the next, so by then these are prog_next(pc), prog_jump(pc) and their pcs.
    reg [IW-1:0] w_nx, w_jp;
    reg [15:0] pc_nx, pc_jp;
    always @(posedge clk) if (dec_load) begin
        w_nx <= prog_next(pc);
        w_jp <= prog_jump(pc);
        pc_nx <= pc + 16'd1;
        pc_jp <= jump + 16'd1;
        p_out_var <= out_len + pad_at(out_len + 32'd4, align);
        p_out4 <= out_len + 32'd4;
        p_out_klen <= out_len + {16'd0, klen};
        p_room_encap <= room - {24'd0, value[31:24] & ENCAP_PAD_MASK};
        p_out_early <= out_len + EARLY_ADD;
        p_end_pos <= pos + body32(n);
        p_end_room <= room - body32(n);
        p_end_left <= left_f - body32(n);
    end
    always @(posedge clk) if (dec_load) begin
        c_tail <= tail_pad;
        c_at_end <= at_end;
        c_room0 <= (room == 32'd0);
        c_room_lt4 <= (room < 32'd4);
        c_size0 <= (size == 32'd0);
        c_n0 <= (n == 32'd0);
        c_n1 <= (n == 32'd1);
        c_flen_long <= (n > MAX_FRAME);
        c_flen_short <= (n < MIN_BODY);
        c_left1 <= (left[{depth - 1'b1, 5'd0} +: 32] != 32'd1);
        c_padf_bad <= (pad_f != 32'd0 && pad_f >= room);
        p_room_f <= room_f;
        p_room_e <= room_e;
        p_vkey <= order_key(value, sign_m, all_m, kind);
        p_vnan <= (kind == 2'd2 && is_nan(value, size));
        p_least <= least_of(body_of(n));
        p_out_at <= r_out_base + r_out_pad;
        p_written <= written_of(body32(n));
        p_least_fa <= least_of(body_of(n)) + {32'd0, fixed_after};
        c_size_gt <= (size > p_room_f);
        c_roomf_lt4 <= (p_room_f < 32'd4);
        c_count_bad <= (sub == SUB_STREAM ? n != count : n > count) || (nul && n == 32'd0);
        c_fit_bad <= fits && p_least_fa != {32'd0, room};
        c_least_gt <= (p_least > {32'd0, room});
        c_body0 <= (body_of(n) == 35'd0);
        c_body1 <= (body_of(n) == 35'd1);
        c_size1 <= (size == 32'd1);
        c_pade_bad <= (pad_e != 32'd0 && pad_e >= room);
        c_body_gt <= (body_of(n) > {3'd0, p_room_e});
        c_encap_bad <= (value[7:0] != konst(kaddr) || value[15:8] != konst(kaddr + 16'd1));
        c_encap_pad_gt <= ({24'd0, value[31:24] & ENCAP_PAD_MASK} > room);
        c_check_bad <= sub == SUB_CHECK && (!same || (op == OP_VAR ? body_of(n) - {34'd0, nul}
                                                      : {3'd0, size}) != {19'd0, klen});
        c_range_bad <= (sub == SUB_RANGE && !in_range);  // from p_vkey, p_vnan
        c_out_len <= p_out_at + p_written;
        // (the elements end the payload, or leave only its unannounced end padding)
        c_early_bad <= STREAM_EARLY != 0 && CDR != 0 && sub == SUB_STREAM && p_end_room != 32'd0
                       && !unannounced_pad(p_end_room, p_end_left, p_end_pos);
    end

    // Skip `p` alignment bytes (if any), then go to state `next`.
    task pad_then(input [31:0] p, input [3:0] next);
        begin
            cnt <= 32'd0;
            if (p != 32'd0) begin
                padn <= p[2:0];
                pad_ret <= next;
                state <= S_PAD;
            end else begin
                state <= next;
            end
        end
    endtask

    // Refuse the frame with status `code`; skip what is left of it (`to_end`: nothing is).
    task refuse(input [7:0] code, input to_end);
        begin
            status_valid <= 1'b1;
            status <= code;
            cnt <= 32'd0;
            if (streamed && !released) hand_over(1'b1, out_len);  // (never released:
            // STREAM_EARLY's rule; the publisher reads no length of a dropped frame)
            if (to_end) begin
                state <= S_FLEN;
                pos <= 32'd0;
            end else begin
                state <= S_SKIP;
            end
        end
    endtask

    // Accept the frame: hand its fields over; skip what is left of it (`to_end`: nothing is).
    task accept(input to_end);
        begin
            status_valid <= 1'b1;
            status <= SUB_OK;
            if (!released) hand_over(1'b0, out_len);  // (STREAM_EARLY: at the stream's count)
            released <= 1'b0;
            cnt <= 32'd0;
            if (to_end) begin
                state <= S_FLEN;
                pos <= 32'd0;
            end else begin
                state <= S_SKIP;  // CDR: the payload's end padding
            end
        end
    endtask

    // Where the program goes on this clock (the decisions that call go below): pc and w load as
    // it says, at one place (the end of the walk's block).
    localparam [1:0] G_STAY = 2'd0, G_FIRST = 2'd1, G_NEXT = 2'd2, G_JUMP = 2'd3;
    reg [1:0] step;
    always @* begin
        step = G_STAY;
        if (settled == 2'd2)
            case (state)
                S_FCHK: if (!c_flen_long && !c_flen_short) step = G_FIRST;
                S_DECODE:
                    if (op == OP_END) step = c_left1 ? G_JUMP : G_NEXT;
                    else if (op == OP_FIXED && c_size0) step = G_NEXT;
                S_COUNTED:
                    if (op == OP_LOOP && !c_count_bad && !c_fit_bad && !c_least_gt)
                        step = c_n0 ? G_JUMP : G_NEXT;
                S_FINISH:
                    if (CDR && op == OP_ENCAP) begin
                        if (!c_encap_bad && !c_encap_pad_gt) step = G_NEXT;
                    end else if (!c_check_bad && !c_range_bad && !nul_bad) step = G_NEXT;
                default: step = G_STAY;
            endcase
    end

    // The carry memory's write side (a frame's bank and its count: see hand_over).
    wire       fbank_nx = meta_valid ? !meta_bank : fbank;   // (nxt_* is empty as a frame starts)
    always @(posedge clk) begin
        if (carry_we) carry_mem[{fbank, waddr}] <= s_tdata;
        if (!rst_n) begin
            fbank <= 1'b0;
            wcnt0 <= {(CW + 1){1'b0}};
            wcnt1 <= {(CW + 1){1'b0}};
`ifdef FORMAL
            f_own0 <= 3'd0;
            f_own1 <= 3'd0;
`endif
        end else if (step == G_FIRST) begin  // a frame starts: its bank, empty
            fbank <= fbank_nx;
            if (fbank_nx) wcnt1 <= {(CW + 1){1'b0}};
            else wcnt0 <= {(CW + 1){1'b0}};
`ifdef FORMAL
            if (fbank_nx) f_own1 <= f_in;
            else f_own0 <= f_in;
`endif
        end else if (carry_we) begin
            if (fbank) wcnt1 <= wcnt1 + 1'b1;
            else wcnt0 <= wcnt0 + 1'b1;
        end
    end

    // Go on with the instruction `step` loads.
    task go;
        begin
            state <= S_DECODE;
            cnt <= 32'd0;
        end
    endtask

    always @(posedge clk) begin
        if (!rst_n) begin
            state <= S_FLEN;
            pos <= 32'd0;
            left_f <= 32'd0;
            last_f <= 1'b0;
            padn <= 3'd0;
            pad_ret <= S_FLEN;
            nul_bad <= 1'b0;
            cnt <= 32'd0;
            n <= 32'd0;
            left_b <= 35'd0;
            last_b <= 1'b0;
            settled <= 2'd0;
            room <= 32'd0;
            least_r <= 64'd0;
            nsh <= 64'd0;
            mrem <= 32'd0;
            value <= 64'd0;
            same <= 1'b0;
            streamed <= 1'b0;
            out_len <= 32'd0;
            released <= 1'b0;
            depth <= {DB{1'b0}};
            quiet <= 8'd0;
            quiet_of <= {LOOPS{1'b0}};
            left <= {(32 * LOOPS){1'b0}};
            meta_valid <= 1'b0;
            meta_out_len <= 32'd0;
            meta_drop <= 1'b0;
            meta_bank <= 1'b0;
            nxt_valid <= 1'b0;
            nxt_out_len <= 32'd0;
            nxt_drop <= 1'b0;
            nxt_bank <= 1'b0;
`ifdef FORMAL
            f_in <= 3'd0;
            f_out <= 3'd0;
            f_head <= 3'd0;
            f_nxt <= 3'd0;
`endif
            status_valid <= 1'b0;
            status <= SUB_OK;
            kp <= 16'd0;
            kleft <= 16'd0;
        end else begin
            status_valid <= 1'b0;
            // The records' banks: a record handed over gets fbank, so a free record's bank
            // follows fbank on every clock (timing: the hand-over's decision, S_COUNTED's chain
            // of checks, reaches neither; seed 1, laserscan_min_cdr's top at 125 MHz: 103.2 ->
            // 109.7 MHz). Nothing kept reads a free record's bank: the carry read ahead restarts
            // (carry_restart) as the publisher takes a record.
            if (!nxt_valid) nxt_bank <= fbank;
            if (meta_release) meta_bank <= nxt_valid ? nxt_bank : fbank;
            else if (!meta_valid) meta_bank <= fbank;
            if (meta_release) begin  // the second record moves up (hand_over may follow)
                meta_valid <= nxt_valid;
                meta_drop <= nxt_drop;
                meta_out_len <= nxt_out_len;
                nxt_valid <= 1'b0;
`ifdef FORMAL
                f_head <= f_nxt;
                f_out <= f_out + {2'd0, meta_valid};  // (a release of nothing: no record)
`endif
            end
            if (take) begin
                pos <= pos_next;
                room <= room - 32'd1;
                left_f <= left_f - 32'd1;
                last_f <= (left_f == 32'd2);
                cnt <= cnt + 32'd1;
            end
            // a SUB_RANGE or OP_ENCAP field's bytes: taken whenever offered (the same byte again
            // until it is taken; only a streamed one waits for m_tready), so that take's fan-out
            // does not reach these 64 enables (S_DECODE clears value after this)
            if (state == S_BODY && s_tvalid && cnt < 32'd8) value[8*cnt[2:0] +: 8] <= s_tdata;
            case (state)
                S_FLEN: if (take) begin
                    n <= n_next(s_tdata);
                    if (cnt[1:0] == 2'd3) begin  // (cnt counts 0..3 here)
                        cnt <= 32'd0;
                        state <= S_FCHK;
                    end
                end
                S_FCHK: if (settled != 2'd2) settled <= settled + 2'd1; else begin
                    // the frame length n, settled as S_DECODE's decisions are (c_flen_*)
                    settled <= 2'd0;
                    begin
                        if (c_flen_long) begin
                            // Not to be trusted for skipping: wait for the next frame length.
                            status_valid <= 1'b1;
                            status <= SUB_BAD_FRAME_LENGTH;
                            pos <= 32'd0;
                            state <= S_FLEN;
                        end else if (c_flen_short) begin
                            status_valid <= 1'b1;
                            status <= SUB_BAD_FRAME_LENGTH;
                            left_f <= n;                        // pos is 4
                            last_f <= c_n1;
                            if (c_n0) begin
                                pos <= 32'd0;
                                state <= S_FLEN;
                            end else state <= S_SKIP;
                        end else begin
                            left_f <= n;                        // pos is 4
                            last_f <= c_n1;
                            room <= n;
                            streamed <= 1'b0;
                            released <= 1'b0;
                            out_len <= 32'd0;
                            depth <= {DB{1'b0}};
                            quiet <= 8'd0;
                            go;
                        end
                    end
                end
                S_DECODE: if (settled != 2'd2) settled <= settled + 2'd1; else begin
                    settled <= 2'd0;
                    cnt <= 32'd0;
                    same <= 1'b1;
                    nul_bad <= 1'b0;
                    value <= 64'd0;
                    case (op)
                        OP_DONE: begin
                            if (c_tail) state <= S_TAIL;
                            else if (!c_room0) refuse(SUB_BAD_FRAME_LENGTH, 1'b0);
                            else accept(c_at_end);
                        end
                        OP_ENCAP: begin
                            if (c_room_lt4) refuse(st, c_at_end);
                            else begin
                                left_b <= 35'd4;
                                last_b <= 1'b0;
                                state <= S_BODY;
                            end
                        end
                        OP_END: begin
                            if (c_left1) begin
                                left[{depth - 1'b1, 5'd0} +: 32] <= left[{depth - 1'b1, 5'd0} +: 32] - 32'd1;
                                go;
                            end else begin
                                depth <= depth - 1'b1;
                                if (quiet_of[depth - 1'b1]) quiet <= quiet - 8'd1;
                                go;
                            end
                        end
                        OP_FIXED: begin
                            if (c_size0) go;
                            else if (c_padf_bad)
                                refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                            else if (c_size_gt)
                                refuse(st != 8'd0 ? st : SUB_BAD_FRAME_LENGTH, c_at_end);
                            else begin
                                left_b <= {3'd0, size};
                                last_b <= c_size1;
                                if (sub == SUB_STREAM) streamed <= 1'b1;
                                pad_then(pad_f, S_BODY);
                            end
                        end
                        default: begin  // OP_VAR, OP_LOOP
                            if (op == OP_LOOP && !variable) begin
                                n <= count;
                                nsh <= {32'd0, count};
                                least_r <= 64'd0;
                                mrem <= elem_min;
                                state <= S_LEAST;
                            end else if (c_padf_bad)
                                refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                            else if (c_roomf_lt4) refuse(st, c_at_end);  // cut short in its count
                            else begin
                                if (quiet == 8'd0) out_len <= p_out_var;
                                pad_then(pad_f, S_COUNT);
                            end
                        end
                    endcase
                end
                S_COUNT: begin
                    // S_LEAST's start, set on every clock here (the last is the count's last byte)
                    nsh <= {32'd0, n_next(s_tdata)};
                    least_r <= 64'd0;
                    mrem <= elem_min;
                    if (take) begin
                        n <= n_next(s_tdata);
                        if (cnt[1:0] == 2'd3) begin  // (cnt counts 0..3 here)
                            state <= (op == OP_LOOP) ? S_LEAST : S_COUNTED;
                            cnt <= 32'd0;
                        end
                    end
                end
                S_LEAST: begin  // OP_LOOP: least_r = n x elem_min, a bit of elem_min per clock
                    if (mrem == 32'd0) state <= S_COUNTED;
                    else begin
                        if (mrem[0]) least_r <= least_r + nsh;
                        nsh <= nsh << 1;
                        mrem <= mrem >> 1;
                    end
                end
                S_COUNTED: if (settled != 2'd2) settled <= settled + 2'd1; else begin
                    settled <= 2'd0;
                    if (c_count_bad)
                        refuse(st, c_at_end);
                    else if (c_fit_bad)
                        refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                    else if (c_least_gt)
                        refuse(st, c_at_end);
                    else if (op == OP_LOOP) begin
                        begin
                            if (variable && quiet == 8'd0) out_len <= p_out4;
                            if (c_n0) go;
                            else begin
                                left[{depth, 5'd0} +: 32] <= n;
                                quiet_of[depth] <= variable && pub == PUB_ZERO;
                                if (variable && pub == PUB_ZERO) quiet <= quiet + 8'd1;
                                depth <= depth + 1'b1;
                                go;
                            end
                        end
                    end else if (c_body0) begin
                        state <= S_FINISH;
                    end else if (c_pade_bad) begin
                        refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                    end else if (c_body_gt) begin
                        refuse(st != 8'd0 ? st : SUB_BAD_FRAME_LENGTH, c_at_end);
                    end else if (c_early_bad) begin  // as OP_DONE would, before the stream
                        refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                    end else begin
                        left_b <= body_of(n);
                        last_b <= c_body1;
                        if (sub == SUB_STREAM) streamed <= 1'b1;
                        pad_then(pad_e, S_BODY);
                        if (STREAM_EARLY && sub == SUB_STREAM && !released) begin  // nothing
                            // after can refuse (and a frame hands over once)
                            hand_over(1'b0, p_out_early);
                            released <= 1'b1;
                        end
                    end
                end
                S_PAD: if (take && cnt[2:0] + 3'd1 == padn) begin
                    state <= pad_ret;
                    cnt <= 32'd0;
                end
                S_BODY: if (take) begin
                    left_b <= left_b - 35'd1;
                    last_b <= (left_b == 35'd2);
                    if (nul && last_b) nul_bad <= (s_tdata != 8'd0);
                    else if (kleft == 16'd0) same <= 1'b0;
                    else if (s_tdata != konst(kp)) same <= 1'b0;  // (the ROM
                    // looked up only for a byte that has a constant: not on every clock)
                    if (last_b) state <= S_FINISH;
                end
                S_FINISH: if (settled != 2'd2) settled <= settled + 2'd1; else begin
                    settled <= 2'd0;
                    if (CDR && op == OP_ENCAP) begin  // CDR little-endian, then the end padding
                        if (c_encap_bad)
                            refuse(st, c_at_end);
                        else if (c_encap_pad_gt)
                            refuse(SUB_BAD_FRAME_LENGTH, c_at_end);
                        else begin
                            room <= p_room_encap;
                            out_len <= p_out_klen;
                            go;
                        end
                    end
                    else if (c_check_bad)
                        refuse(op == OP_VAR ? st2 : st, c_at_end);
                    else if (c_range_bad) refuse(st, c_at_end);
                    else if (nul_bad) refuse(st3, c_at_end);
                    else begin
                        if (quiet == 8'd0) out_len <= c_out_len;
                        go;
                    end
                end
                S_TAIL: if (take && last_f) accept(1'b1);  // CDR: the unannounced end padding
                S_SKIP: if (take && last_f) begin
                    state <= S_FLEN;
                    cnt <= 32'd0;
                    pos <= 32'd0;
                end
                default: state <= S_FLEN;
            endcase
            // (after the walk's reads of kp and kleft above: a simulation copies neither)
            if (state == S_BODY) begin
                if (take) begin
                    if (kleft != 16'd0) kleft <= kleft - 16'd1;
                    kp <= kp + 16'd1;
                end
            end else begin  // (a body starts with cnt 0)
                kp <= kaddr;
                kleft <= klen;
            end
        end
        // (w follows pc: w_nx and w_jp are the words of pc_nx and pc_jp)
        if (!rst_n || step != G_STAY) begin
            w_q[0] <= (!rst_n || step == G_FIRST) ? prog_word(16'd0)
                      : (step == G_JUMP) ? w_jp : w_nx;
            pc <= (!rst_n || step == G_FIRST) ? 16'd0 : (step == G_JUMP) ? pc_jp : pc_nx;
        end
    end
`ifdef FORMAL
    // the instruction register holds the word of pc (an invariant the proofs carry)
    always @(*) if (rst_n) assert(w == prog_word(pc));
    always @(*) if (rst_n) assert(last_b == (left_b == 35'd1));
    always @(*) if (rst_n && state == S_BODY)
        assert(kp == kaddr + cnt[15:0]
               && (kleft == 16'd0
                   || (cnt < {16'd0, klen} && kleft == klen - cnt[15:0])));
    always @(*) if (rst_n && !STREAM_EARLY) assert(!released);
    // a decision settles only in its own state, from 0 (each decision ends at 2 with 0)
    always @(*) if (rst_n)
        assert(settled == 2'd0 || (settled != 2'd3 && (state == S_FCHK || state == S_DECODE
                                                       || state == S_COUNTED || state == S_FINISH)));
    // ... and, once a clock has settled, the next instructions are those of pc
    always @(*) if (rst_n && settled != 2'd0)
        assert(w_nx == prog_next(pc) && w_jp == prog_jump(pc) && pc_nx == pc + 16'd1
               && pc_jp == jump + 16'd1);
    // The records: the publisher takes them in the order they were handed over, each once, none
    // lost (the held ones are the oldest not yet released: meta_* the oldest, then nxt_*) ...
    always @(*) if (rst_n) begin
        assert(!nxt_valid || meta_valid);
        assert(f_in == f_out + {2'd0, meta_valid} + {2'd0, nxt_valid});
        if (meta_valid) assert(f_head == f_out);
        if (nxt_valid) assert(f_nxt == f_out + 3'd1 && nxt_bank != meta_bank);
        // ... each held record's bank holds its own frame's bytes (no later frame took it) ...
        if (meta_valid) assert((meta_bank ? f_own1 : f_own0) == f_head);
        if (nxt_valid) assert((nxt_bank ? f_own1 : f_own0) == f_nxt);
        // ... and a frame being walked (it writes only then) writes its own bank (its record's
        // number: handed over early, or still to come)
        if (state != S_FLEN && state != S_FCHK && state != S_SKIP) begin
            assert((fbank ? f_own1 : f_own0) == f_in - {2'd0, released});
            // (it started with nxt_* empty; handed over early, its record is the newest)
            if (!released) assert(!nxt_valid);
            else assert(!meta_valid || (nxt_valid ? nxt_bank : meta_bank) == fbank);
        end
        if ((state == S_FLEN && cnt[1:0] != 2'd0) || state == S_FCHK) assert(!nxt_valid);
        if (carry_we) assert(state == S_COUNT || state == S_BODY);
    end
    // A frame hands over at most one record: one (drop) if refused after its stream went out,
    // none if refused before (a dropped frame's record never reaches the publisher). f_at: f_in as the frame's length was checked (S_FCHK: nothing handed over).
    reg [2:0] f_at;
    reg       f_atv = 1'b0;             // f_at is set (a frame length was checked)
    reg       f_streamed, f_released, f_first;
    always @(posedge clk) begin
        if (state == S_FCHK) f_at <= f_in;
        if (!rst_n) f_atv <= 1'b0;
        else if (state == S_FCHK) f_atv <= 1'b1;
        f_streamed <= streamed;
        f_released <= released;
        f_first <= (state == S_FCHK);
        if (rst_n && f_atv && state != S_FCHK)
            assert(f_in == f_at || f_in == f_at + 3'd1);
        // (while walking: handed over only early; early, its stream has begun)
        if (rst_n && state != S_FLEN && state != S_FCHK && state != S_SKIP)
            assert(f_atv && f_in == f_at + {2'd0, released} && (!released || streamed));
        if (rst_n && f_atv && status_valid && !f_first && status != SUB_OK) begin
            if (f_streamed && !f_released)
                assert(f_in == f_at + 3'd1 && (nxt_valid ? nxt_drop : meta_drop));
            else if (!f_streamed) assert(f_in == f_at);
        end
    end
`endif
endmodule

`default_nettype wire
