// rfl_rtps_ctrl -- the RTPS control-submessage watcher of the fabric participant (issue #31:
// its built-in writers are reliable): fed the received UDP payloads (RTPS messages; 8-bit
// AXI4-Stream, TLAST on a datagram's last byte; it is always ready, so a top feeds it the beats
// rfl_rtps_rx takes), it finds the ACKNACKs to this participant's answering writers and the
// HEARTBEATs to its built-in SEDP readers, and asks rfl_rtps_disc_answer for the answers:
// one request a beat on m_axis, {base[63:0], guidPrefix[95:0], message[7:0]}: send answer ROM
// message `message` to participant `guidPrefix` (its INFO_DST), an ACKNACK answer with `base`.
// The slots (which entities answer, and their messages) come from rosfpga_lab.rtl.discrom
// (answer_params; its docstring says what each answer is and why it is what the software
// participant sends). Slot i: entity id SLOT_IDS[32i +: 32], first answer message
// SLOT_MSGS[8i +: 8], last sequence number SLOT_LASTS[8i +: 8] (a writer: 1..8; 0: a built-in
// reader).
// The walk (a byte per clock, never a wait; where each byte is: rfl_rtps_walk):
//   header    "RTPS", major version 2, the sender's GUID prefix (the source); a bad header
//             (magic, version) or a datagram shorter than a header: ignored and counted
//             (cnt_bad_header, as rfl_rtps_rx's); a message from cfg_prefix (our own, looped
//             back): the rest of the datagram is ignored, uncounted (found two clocks after
//             the header: a datagram that ends before is walked whole). The destination resets
//             to "any" at each message.
//   submessage headers: id, flags (bit 0 E: byte order of the rest), octetsToNextHeader (0:
//             to the end of the message, but for PAD and INFO_TS).
//   bodies    INFO_DST (the destination: ours or all-zero keeps what follows), INFO_SRC (the
//             source), ACKNACK (readerId, writerId, readerSNState base, numBits, the first
//             bitmap word, count) and HEARTBEAT (readerId, writerId, firstSN, lastSN, count);
//             other submessages are skipped by length.
// At the end of an ACKNACK or HEARTBEAT for us, the fields go to a register stage (d_*); two
// clocks after (the numbers asked registered between: timing), each slot matches:
//   ACKNACK to writer slot i (writerId = its id): base 0 (preemptive) asks its HEARTBEAT
//     (message SLOT_MSGS[i]); else each sequence number s in 1..last with its bit set (s >=
//     base, s - base < numBits) asks message SLOT_MSGS[i] + s (its DATA and a HEARTBEAT);
//     numbers past last are ignored (never written: no GAP, as the software writer); a base
//     at or below last with no held number asked (Cyclone DDS's preemptive form, base 1, no
//     bits) asks the HEARTBEAT: the circuit's writers send no periodic HEARTBEAT (the software
//     writer's tick does), so a reader that lost the first one learns what they hold then.
//   HEARTBEAT without F to reader slot i (readerId = its id, or ENTITYID_UNKNOWN and the
//     writerId the matching built-in writer: its id with kind 0xC2 for 0xC7): its ACKNACK
//     (message SLOT_MSGS[i]) with base lastSN + 1.
// Bounded: each slot holds one pending request set (the asker's prefix, a bit per message); a
// request for a slot whose set is not yet sent is dropped and counted (cnt_busy): a flood of
// ACKNACKs asks at most one set per slot at a time, and rfl_rtps_disc_answer's credit bounds
// the bytes sent per byte received (rx_byte: a pulse per byte taken).
// Refused and counted (cnt_malformed; the rest of the datagram ignored, RTPS 2.3 8.3.4.1): a
// submessage longer than the datagram, a length not a multiple of 4 that is not the last, an
// ACKNACK with numBits > 256 or a body too short for its fields (ACKNACK, HEARTBEAT, INFO_DST,
// INFO_SRC).
// Timing: the slot decisions read registers only (the d_* stage, taken at every submessage's
// end), their outcome is registered (want_r) before it sets a slot, and the pick of the next
// request is registered.
`default_nettype none

module rfl_rtps_ctrl #(
    parameter SLOTS = 5,                        // answering entities: 1..8, checked
    parameter [32*SLOTS-1:0] SLOT_IDS = 0,      // entity ids, slot 0 in the low bits
    parameter [8*SLOTS-1:0] SLOT_MSGS = 0,      // first answer message of each slot
    parameter [8*SLOTS-1:0] SLOT_LASTS = 0,     // last sequence number (0..8; 0: a reader)
    parameter COUNT_BITS = 32                   // width of the counters: 1..32, checked
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [95:0]           cfg_prefix,    // this participant's GUID prefix
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready, // always 1: a watcher
    input  wire                  s_axis_tlast,
    output wire [167:0]          m_axis_tdata,  // {base, guidPrefix, message}
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  rx_byte,       // a byte taken (rfl_rtps_disc_answer's credit)
    output wire [COUNT_BITS-1:0] cnt_requests,  // request sets taken into a slot
    output wire [COUNT_BITS-1:0] cnt_busy,      // request sets dropped: the slot was pending
    output wire [COUNT_BITS-1:0] cnt_malformed,
    output wire [COUNT_BITS-1:0] cnt_bad_header // bad magic or version, or shorter than 20
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    integer ci;
    initial begin
        if (SLOTS < 1 || SLOTS > 8) $fatal(1, "rfl_rtps_ctrl: SLOTS must be 1..8");
        if (COUNT_BITS < 1 || COUNT_BITS > 32) $fatal(1, "rfl_rtps_ctrl: COUNT_BITS must be 1..32");
        for (ci = 0; ci < SLOTS && ci < 8; ci = ci + 1)
            if (SLOT_LASTS[8*ci +: 8] > 8) $fatal(1, "rfl_rtps_ctrl: a slot's last must be 0..8");
    end
`else
    if (SLOTS < 1 || SLOTS > 8) begin : g_bad_slots
        $error("rfl_rtps_ctrl: SLOTS must be 1..8");
    end
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_rtps_ctrl: COUNT_BITS must be 1..32");
    end
    genvar gi;
    for (gi = 0; gi < SLOTS && gi < 8; gi = gi + 1) begin : g_check_last
        if (SLOT_LASTS[8*gi +: 8] > 8) begin : g_bad_last
            $error("rfl_rtps_ctrl: a slot's last must be 0..8");
        end
    end
`endif

    localparam NS = (SLOTS >= 1 && SLOTS <= 8) ? SLOTS : 1;    // (sizes legal when refused)
    // the slot table padded to 8 slots (a slot past SLOTS never matches)
    localparam [32*NS+255:0] IDS_W = {256'd0, SLOT_IDS};
    localparam [8*NS+63:0] MSGS_W = {64'd0, SLOT_MSGS};
    localparam [8*NS+63:0] LASTS_W = {64'd0, SLOT_LASTS};
    localparam [255:0] IDS = IDS_W[255:0];
    localparam [63:0] MSGS = MSGS_W[63:0];
    localparam [63:0] LASTS = LASTS_W[63:0];
`include "rfl_rtps_wire.vh"             // ID_*

    assign s_axis_tready = 1'b1;
    wire take = s_axis_tvalid;
    wire [7:0] b = s_axis_tdata;
    wire tl = s_axis_tlast;
    assign rx_byte = take;

    // the walk: where the byte is (the header, a submessage header or body, dropped)
    wire w_hdr, w_sub, w_body, w_last, w_empty, w_mis, w_hdr_bad;
    wire [4:0] w_idx;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [7:0] w_flags;                         // (E, F read: 0..1)
    /* verilator lint_on UNUSEDSIGNAL */
    wire [15:0] pos;                            // body byte
    reg drop;
    /* verilator lint_off PINCONNECTEMPTY */
    rfl_rtps_walk #(.POS_BITS(16)) u_walk (
        .clk(clk), .rst_n(rst_n), .in_data(s_axis_tdata), .in_take(take), .in_last(s_axis_tlast),
        .drop(drop), .m_hdr(w_hdr), .m_subhdr(w_sub), .m_body(w_body), .m_dropped(), .m_idx(w_idx),
        .m_sub_id(), .m_sub_flags(w_flags), .m_sub_len(), .m_sub_pos(pos), .m_sub_mis(w_mis),
        .m_sub_last(w_last), .m_sub_empty(w_empty), .m_hdr_bad(w_hdr_bad));
    /* verilator lint_on PINCONNECTEMPTY */

    reg [95:0] src;
    reg [87:0] src_sh, dst_sh;           // the last 11 bytes of a prefix coming in
    reg dst_ok;                                 // the submessages are for us
    reg [95:0] dst;                             // the last INFO_DST's prefix
    reg dst_chk, own_chk;                       // compare dst / src with ours (two clocks late)
    reg dst_chk2, own_chk2, dst_eq, own_eq;
    wire le = w_flags[0], flag_f = w_flags[1];
    reg k_ack, k_hb, k_dst, k_src;
    reg [31:0] acc_e;
    reg [23:0] acc_b;
    reg [31:0] f_rid, f_wid, f_hi, f_lo, f_nbits, f_word0;
    reg [15:0] need_m1;                         // the byte before the ACKNACK's fields' last
    reg fields_done;
    reg [COUNT_BITS-1:0] n_req, n_busy, n_bad, n_hdr;

    wire [31:0] acc_e_n = le ? {b, acc_e[31:8]} : {acc_e[23:0], b};
    wire [31:0] acc_b_n = {acc_b, b};
    wire [3:0] nwords = acc_e_n[8:5] + {3'd0, |acc_e_n[4:0]};   // bitmap words (<= 256 bits)
    wire body_last = w_last;
    wire trunc = tl && !body_last;
    // the byte at pos is the last of the submessage's fields (registered a byte ahead: timing;
    // an ACKNACK's last is known from byte 19 on, and is at least 23)
    reg at_need;
    wire done_n = fields_done || at_need;
    wire parsed = k_ack || k_hb || k_dst || k_src;
    // numBits > 256, from its register the byte after (timing)
    wire nbits_bad = k_ack && (pos == 16'd20) && (|f_nbits[31:9] || (f_nbits[8] && |f_nbits[7:0]));
    // the end of a submessage: its fields short, cut, or misaligned and not the last
    wire sub_bad = trunc || (body_last && ((parsed && !done_n) || (w_mis && !tl)));
    wire [95:0] src_sh_n = {src_sh[87:0], b};
    // the rest of the datagram ignored: a malformed submessage, or our own message (the walk
    // ignores it once the datagram has ended)
    always @(*) drop = (take && w_body && (nbits_bad || sub_bad)) || (own_chk2 && own_eq);
    wire [95:0] dst_sh_n = {dst_sh[87:0], b};

    // the decision stage
    reg d_valid, d_ack, d_final;
    reg [31:0] d_rid, d_wid, d_hi, d_lo, d_word0;
    reg [8:0] d_nbits;
    reg [95:0] d_prefix;

    // the slots
    reg [71:0] pend;                            // 9 bits a slot; bit 0: the first message,
                                                // bit s: DATA s
    reg [767:0] p_prefix;                       // 96 bits a slot
    reg [511:0] p_base;                         // 64 bits a slot
    reg [167:0] o_data;
    reg o_valid;
    assign m_axis_tdata = o_data;
    assign m_axis_tvalid = o_valid;
    assign cnt_requests = n_req;
    assign cnt_busy = n_busy;
    assign cnt_malformed = n_bad;
    assign cnt_bad_header = n_hdr;

    // what each slot wants of the decision in d_*
    wire d_base0 = (d_hi == 32'd0) && (d_lo == 32'd0);
    wire d_small = (d_hi == 32'd0) && (d_lo[31:4] == 28'd0);
    wire [63:0] d_next = {d_hi, d_lo} + 64'd1;
    wire [71:0] want;                           // 9 bits a slot, as pend
    wire [8:1] asked_n;
    reg [8:1] asked;                            // the numbers 1..8 the ACKNACK asks
    reg d_valid2, base0_r, small_r;             // the decision, a clock later
    genvar gw, gs;
    generate
        // the sequence numbers 1..8 the bitmap asks (any writer's), a clock after the decision
        // (timing: d_* hold until the next one)
        for (gs = 1; gs <= 8; gs = gs + 1) begin : g_seq
            localparam [4:0] S5 = gs;
            wire [4:0] off = S5 - {1'b0, d_lo[3:0]};         // its bit in the bitmap
            assign asked_n[gs] = d_small && !d_base0 && (S5 >= {1'b0, d_lo[3:0]}) &&
                                 ({4'd0, off} < d_nbits) && d_word0[5'd31 - off];
        end
        for (gw = 0; gw < 8; gw = gw + 1) begin : g_want
            wire [31:0] id = IDS[32*gw +: 32];
            wire [7:0] lastsn = LASTS[8*gw +: 8];
            wire is_w = (gw < NS) && d_valid2 && d_ack && (lastsn != 8'd0) && (d_wid == id);
            wire is_r = (gw < NS) && d_valid2 && !d_ack && !d_final && (lastsn == 8'd0) &&
                        (d_rid == id || (d_rid == 32'd0 && {d_wid[31:8], 8'hC7} == id));
            wire [8:1] held;                            // asked and held
            for (gs = 1; gs <= 8; gs = gs + 1) begin : g_held
                localparam [7:0] S8 = gs;
                assign held[gs] = asked[gs] && (S8 <= lastsn);
            end
            // the HEARTBEAT: base 0 (preemptive), or a base at or below last with no held
            // number asked (the reader lacks samples it does not know of: the circuit's
            // writer sends no periodic HEARTBEAT, so it tells it now)
            wire behind = small_r && ({4'd0, d_lo[3:0]} <= lastsn) && !(|held);
            assign want[9*gw] = (is_w && (base0_r || behind)) || is_r;
            assign want[9*gw+1 +: 8] = is_w ? held : 8'd0;
        end
    endgenerate

    // the index of a one-hot 9-bit value, from its bits 8..1 (0: none of them)
    function [3:0] lowest(input [8:1] h);
        lowest = {h[8], h[4] | h[5] | h[6] | h[7], h[2] | h[3] | h[6] | h[7],
                  h[1] | h[3] | h[5] | h[7]};
    endfunction
    // the next request: the lowest slot pending, its lowest message (every slot's at once,
    // one-hot, registered; then an AND-OR of the one picked: timing)
    wire [7:0] nz;                              // slots pending
    wire [71:0] low;                            // each slot's lowest pending bit, one-hot
    wire [7:0] sel;                             // the lowest slot pending, one-hot
    genvar gp, gb;
    generate
        for (gp = 0; gp < 8; gp = gp + 1) begin : g_pick
            wire [8:0] p = pend[9*gp +: 9];
            assign nz[gp] = |p;
            assign low[9*gp] = p[0];
            for (gb = 1; gb < 9; gb = gb + 1) begin : g_low
                assign low[9*gp + gb] = p[gb] && !(|p[gb-1:0]);
            end
            if (gp == 0) begin : g_first
                assign sel[0] = nz[0];
            end else begin : g_next
                assign sel[gp] = nz[gp] && !(|nz[gp-1:0]);
            end
        end
    endgenerate
    // the pick, registered (timing): it stays right while no request goes out (a slot's bits
    // are only cleared by a request going out, only set while it has none), so a request
    // goes out at most every other clock
    reg pk_r, loaded;
    reg [7:0] sel_r;
    reg [71:0] low_r;
    reg [167:0] pick_data;
    integer pj;
    always @(*) begin
        pick_data = 168'd0;
        for (pj = 0; pj < 8; pj = pj + 1)
            if (sel_r[pj])
                pick_data = pick_data | {p_base[64*pj +: 64], p_prefix[96*pj +: 96],
                                         MSGS[8*pj +: 8] + {4'd0, lowest(low_r[9*pj+1 +: 8])}};
    end
    wire load = pk_r && !loaded && (!o_valid || m_axis_tready);

    // the slot's set, set or dropped; any hit counts once
    // what the slots want, registered (timing): d_* hold until the next decision, at least a
    // submessage (24 bytes) later, so the prefix and base are still the decision's
    reg [71:0] want_r;
    reg any_want, any_busy;
    integer ai;
    always @(*) begin
        any_want = 1'b0;
        any_busy = 1'b0;
        for (ai = 0; ai < 8; ai = ai + 1)
            if (want_r[9*ai +: 9] != 9'd0) begin
                any_want = 1'b1;
                if (pend[9*ai +: 9] != 9'd0) any_busy = 1'b1;
            end
    end
    integer i;

    always @(posedge clk) begin
        if (!rst_n) begin
            dst_ok <= 1'b1;
            dst_chk <= 1'b0;
            own_chk <= 1'b0;
            d_valid <= 1'b0;
            o_valid <= 1'b0;
            n_req <= {COUNT_BITS{1'b0}};
            n_busy <= {COUNT_BITS{1'b0}};
            n_bad <= {COUNT_BITS{1'b0}};
            n_hdr <= {COUNT_BITS{1'b0}};
            pend <= 72'd0;
            want_r <= 72'd0;
            d_valid2 <= 1'b0;
            pk_r <= 1'b0;
            loaded <= 1'b0;
        end else begin
            d_valid <= 1'b0;
            dst_chk <= 1'b0;                    // (pulses, set below)
            own_chk <= 1'b0;
            if (take && w_hdr) begin
                src_sh <= src_sh_n[87:0];
                dst_ok <= 1'b1;
                if (w_hdr_bad) n_hdr <= n_hdr + 1'b1;
                if (w_idx == 5'd19 && !tl) begin
                    src <= src_sh_n;
                    own_chk <= !w_hdr_bad;      // ours, looped back: dropped two clocks late
                end
            end else if (take && w_sub) begin
                if (w_idx == 5'd0) begin
                    k_ack <= (b == ID_ACKNACK);
                    k_hb <= (b == ID_HEARTBEAT);
                    k_dst <= (b == ID_INFO_DST);
                    k_src <= (b == ID_INFO_SRC);
                end
                fields_done <= 1'b0;
                at_need <= 1'b0;                // (body byte 0 is no field's last)
                // the datagram ends in or right after a submessage header (not empty)
                if (tl && !w_empty) n_bad <= n_bad + 1'b1;
            end else if (take && w_body) begin
                acc_e <= acc_e_n;
                acc_b <= acc_b_n[23:0];
                fields_done <= done_n;
                at_need <= k_ack ? (pos == need_m1) : k_hb ? (pos == 16'd26) :
                           k_dst ? (pos == 16'd10) : (pos == 16'd18);
                if (k_dst && pos < 16'd12) dst_sh <= dst_sh_n[87:0];
                if (k_src && pos >= 16'd8 && pos < 16'd20) src_sh <= src_sh_n[87:0];
                if (pos == 16'd3) f_rid <= acc_b_n;
                if (pos == 16'd7) f_wid <= acc_b_n;
                if (pos == 16'd11 && k_ack) f_hi <= acc_e_n;
                if (pos == 16'd15 && k_ack) f_lo <= acc_e_n;
                if (pos == 16'd19 && k_hb) f_hi <= acc_e_n;
                if (pos == 16'd23 && k_hb) f_lo <= acc_e_n;
                if (pos == 16'd19) begin
                    f_nbits <= acc_e_n;
                    need_m1 <= 16'd22 + {10'd0, nwords, 2'b00};
                end
                if (pos == 16'd23) f_word0 <= acc_e_n;
                if (k_dst && pos == 16'd11) begin
                    dst <= dst_sh_n;
                    dst_chk <= 1'b1;
                end
                if (k_src && pos == 16'd19) src <= src_sh_n;
                if (body_last) begin
                    // every submessage's fields, taken at its end (timing: no condition
                    // but the end; d_valid says whether they are a decision; the next
                    // end is at least 5 bytes later, after the slots have used them)
                    d_ack <= k_ack;
                    d_final <= flag_f;
                    d_rid <= f_rid;
                    d_wid <= f_wid;
                    d_hi <= f_hi;
                    d_lo <= f_lo;               // HEARTBEAT: lastSN's low half
                    d_nbits <= f_nbits[8:0];    // (0: no number asked, whatever word0)
                    d_word0 <= f_word0;
                    d_prefix <= src;
                end
                if (nbits_bad || sub_bad) n_bad <= n_bad + 1'b1;
                else if (body_last && (k_ack || k_hb) && dst_ok) d_valid <= 1'b1;
            end
            // the late comparisons (timing): INFO_DST's prefix ours or any; the message ours
            // (each compared into a register, then acted on: two clocks)
            dst_eq <= (dst == cfg_prefix) || (dst == 96'd0);
            own_eq <= (src == cfg_prefix);
            dst_chk2 <= dst_chk;
            own_chk2 <= own_chk;
            if (dst_chk2) dst_ok <= dst_eq;
            // the slots: a request set taken, or dropped (busy); the next request out
            if (any_want) begin
                if (any_busy) n_busy <= n_busy + 1'b1;
                else n_req <= n_req + 1'b1;
            end
            for (i = 0; i < 8; i = i + 1)
                if (want_r[9*i +: 9] != 9'd0 && pend[9*i +: 9] == 9'd0) begin
                    pend[9*i +: 9] <= want_r[9*i +: 9];
                    p_prefix[96*i +: 96] <= d_prefix;
                    p_base[64*i +: 64] <= d_next;
                end
            want_r <= want;
            d_valid2 <= d_valid;
            asked <= asked_n;
            base0_r <= d_base0;
            small_r <= d_small;
            pk_r <= |nz;
            sel_r <= sel;
            low_r <= low;
            loaded <= load;
            if (load) begin
                for (i = 0; i < 8; i = i + 1)
                    if (sel_r[i]) pend[9*i +: 9] <= pend[9*i +: 9] & ~low_r[9*i +: 9];
                o_data <= pick_data;
                o_valid <= 1'b1;
            end else if (m_axis_tready) begin
                o_valid <= 1'b0;
            end
        end
    end
`ifdef FORMAL
    // what the slots may hold (the induction's strengthening): a bit only for a message of
    // the slot (a writer: its HEARTBEAT and sequence numbers 1..last; a reader: its ACKNACK),
    // none past SLOTS; the request offered names a message of some slot
    integer fi, fs;
    reg f_named;
    always @(*) begin
        f_named = 1'b0;
        for (fi = 0; fi < 8; fi = fi + 1)
            if (fi < NS && o_data[7:0] >= MSGS[8*fi +: 8] &&
                o_data[7:0] <= MSGS[8*fi +: 8] + LASTS[8*fi +: 8])
                f_named = 1'b1;
    end
    always @(posedge clk) if (rst_n) begin
        for (fi = 0; fi < 8; fi = fi + 1)
            for (fs = 1; fs <= 8; fs = fs + 1)
                if (fi >= NS || fs > LASTS[8*fi +: 8]) assert(!pend[9*fi + fs]);
        for (fi = NS; fi < 8; fi = fi + 1) assert(!pend[9*fi]);
        if (o_valid) assert(f_named);
        // the registered pick: one slot, still pending, its lowest message
        if (pk_r && !loaded) begin
            assert(sel_r != 8'd0 && (sel_r & (sel_r - 8'd1)) == 8'd0);
            for (fi = 0; fi < 8; fi = fi + 1)
                if (sel_r[fi]) begin
                    assert(pend[9*fi +: 9] != 9'd0);
                    assert(low_r[9*fi +: 9] == low[9*fi +: 9]);
                end
        end
    end
`endif
endmodule

`default_nettype wire
