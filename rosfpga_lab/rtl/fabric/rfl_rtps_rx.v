// rfl_rtps_rx -- the RTPS receive walker (issue #31, first stage of the ROS 2 node in the
// fabric): one UDP payload per input packet (8-bit AXI4-Stream, TLAST on its last byte), the
// serialized payloads (CDR encapsulation header + data, as carried) of the DATA / DATA_FRAG
// samples of one writer out, a packet per sample, a byte per clock.
//
// How the walk works (a byte per clock; st: where the byte is in the message, rfl_rtps_walk's
// S_HDR, S_SUBHDR, S_DROP, and in a submessage's body this stage's own ph):
//   S_HDR     the 20-byte header: "RTPS", major version 2, vendor id, the sender's 12-byte GUID
//             prefix (the source). Bad magic/version or a packet shorter than 20 bytes: the
//             packet is dropped and counted (cnt_bad_header); a message from cfg_prefix (our
//             own, looped back) is dropped silently. The destination resets to "any" and the
//             timestamp to invalid at each message (RTPS 2.3 8.3.4).
//   S_SUBHDR  id, flags (bit 0 E: byte order of the rest), octetsToNextHeader. Length 0 means
//             "to the end of the message" except for PAD and INFO_TS (empty).
//   S_FIELDS  the fixed fields of INFO_TS (timestamp, unless flag I), INFO_DST (destination
//             prefix: ours or all-zero keeps what follows, another one ignores DATA until the
//             next INFO_DST or the end of the message), INFO_SRC (source prefix), DATA
//             (readerId, writerId, writerSN) and DATA_FRAG (+ fragmentStartingNum, count,
//             size, sampleSize).
//   S_D1/S_D2 two clocks without input (dwait): the comparisons are registered (D1), then the
//             decision (D2): a DATA (flag D, not K) or DATA_FRAG is taken when it is for us
//             (destination), for cfg_reader or ENTITYID_UNKNOWN, from cfg_writer (0: any) and
//             writerSN >= 1. A DATA_FRAG continues the sample being streamed when it has the
//             same writer GUID, writerSN, fragment and sample sizes and fragmentStartingNum is
//             the next one; with number 1 it starts a new sample; anything else is dropped.
//             A repeat is skipped whole and counted (cnt_repeated), the sample going on: a
//             DATA_FRAG of that sample (same GUID, writerSN and sizes) whose fragmentStartingNum
//             is 1 or more and below the next one, or 2 or more of the fragmented sample sent
//             last whole (RTPS lets a reader see a fragment twice; Fast DDS sends each twice,
//             one per locator it has for the reader). Fragments past the next one in a repeat
//             are not taken: a sample that needed them is dropped at its next fragment. No
//             history of writerSNs is kept: a sample sent again from fragment 1 once it went
//             out (as a DATA sent again) comes out again.
//             A taken DATA, or a DATA_FRAG that neither continues nor repeats, drops the
//             sample in progress (its packet ends with TUSER set).
//   S_GAP     the bytes up to octetsToInlineQos; S_QOS the inline QoS parameter list (flag Q)
//             up to PID_SENTINEL; S_PAY the payload: streamed when taken (a DATA's to the end
//             of the submessage; a DATA_FRAG's fragments up to the sample's end), else skipped.
//   S_SKIP    the rest of a submessage (HEARTBEAT, ACKNACK, GAP, unknown ids: skipped by
//             length, RTPS 8.3.4.1); S_DROP the rest of a packet after an error (the walk's
//             drop).
// Output: m_axis_* a sample per packet; TLAST on its last byte; TUSER (on the TLAST beat) set:
// the sample is dropped, discard the packet (a fragment missing, out of order or malformed, a
// truncated or malformed submessage). A packet with TUSER may end with a byte 0 that is not
// the sample's. m_sample_* (writer GUID = source prefix + writerId, writerSN, the INFO_TS time
// {seconds, fraction}, meaningful with m_sample_ts_valid) hold for every beat of its packet.
// The payload is as on the wire: padding declared in the encapsulation options (and a
// DATA_FRAG sample's bytes past sampleSize) are left to the CDR stage / not sent.
// Refused and counted (cnt_malformed, the rest of the packet dropped, RTPS 2.3 8.3.4.1): a
// submessage header cut short, a submessage longer than the packet, a length not a multiple of
// 4 that is not the last, fields missing (INFO_TS/DST/SRC, DATA, DATA_FRAG, inline QoS), DATA
// with both D and K. Other submessages' own fields are not checked (skipped by length).
// Bounded: every output beat is either an input byte taken in the same clock or the one beat
// that ends a dropped sample in S_D2 (after at least 36 header bytes taken): never more output
// than input, never a wait on anything but the output's TREADY.
// Timing: the decisions read registers only (S_D1); 16/32-bit counters count down by one.
`default_nettype none

module rfl_rtps_rx #(
    parameter COUNT_BITS = 32                   // width of the counters: 1..32, checked
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [95:0]           cfg_prefix,    // this participant's GUID prefix
    input  wire [31:0]           cfg_reader,    // our reader's entity id
    input  wire [31:0]           cfg_writer,    // the writer's entity id taken (0: any)
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,
    input  wire                  s_axis_tlast,
    output wire [7:0]            m_axis_tdata,
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  m_axis_tlast,
    output wire                  m_axis_tuser,  // with TLAST: the sample is dropped
    output wire [127:0]          m_sample_guid,
    output wire [63:0]           m_sample_seq,
    output wire [63:0]           m_sample_ts,
    output wire                  m_sample_ts_valid,
    output wire [COUNT_BITS-1:0] cnt_packets,   // input packets
    output wire [COUNT_BITS-1:0] cnt_bad_header,
    output wire [COUNT_BITS-1:0] cnt_malformed,
    output wire [COUNT_BITS-1:0] cnt_samples,   // samples sent whole
    output wire [COUNT_BITS-1:0] cnt_dropped,   // samples dropped, fragments out of order
    output wire [COUNT_BITS-1:0] cnt_repeated   // DATA_FRAGs skipped: fragments taken before
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (COUNT_BITS < 1 || COUNT_BITS > 32) $fatal(1, "rfl_rtps_rx: COUNT_BITS must be 1..32");
    end
`else
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_rtps_rx: COUNT_BITS must be 1..32");
    end
`endif

    localparam [3:0] S_HDR = 4'd0, S_SUBHDR = 4'd1, S_FIELDS = 4'd2, S_D1 = 4'd3, S_D2 = 4'd4,
                     S_GAP = 4'd5, S_QOS = 4'd6, S_PAY = 4'd7, S_SKIP = 4'd8, S_DROP = 4'd9;
`include "rfl_rtps_wire.vh"             // ID_*

    reg [3:0] ph;                               // in a body: S_FIELDS .. S_SKIP
    reg dwait;                                  // in S_D1 or S_D2 (timing: no state decode)
    reg [2:0] idx;                              // byte of an inline QoS parameter's head

    // the output register
    reg [7:0] o_data;
    reg o_valid, o_last, o_user;
    wire o_free = !o_valid || m_axis_tready;
    assign s_axis_tready = !dwait && o_free;
    wire take = s_axis_tvalid && s_axis_tready;
    wire [7:0] b = s_axis_tdata;
    wire tl = s_axis_tlast;

    // the walk: where the byte is (the header, a submessage header or body, dropped)
    wire w_hdr, w_sub, w_body, w_last, w_empty, w_mis, w_hdr_bad;
    wire [4:0] w_idx;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [7:0] w_flags;                         // (E, Q (INFO_TS: I), D, K read: 0..3)
    /* verilator lint_on UNUSEDSIGNAL */
    wire [15:0] w_len;
    wire [5:0] pos;                             // the body's byte (the fields: 0..31)
    reg drop;
    /* verilator lint_off PINCONNECTEMPTY */
    rfl_rtps_walk #(.POS_BITS(6)) u_walk (
        .clk(clk), .rst_n(rst_n), .in_data(s_axis_tdata), .in_take(take), .in_last(s_axis_tlast),
        .drop(drop), .m_hdr(w_hdr), .m_subhdr(w_sub), .m_body(w_body), .m_dropped(), .m_idx(w_idx),
        .m_sub_id(), .m_sub_flags(w_flags), .m_sub_len(w_len), .m_sub_pos(pos), .m_sub_mis(w_mis),
        .m_sub_last(w_last), .m_sub_empty(w_empty), .m_hdr_bad(w_hdr_bad));
    /* verilator lint_on PINCONNECTEMPTY */
    // the state, as one number (rtl/tb/rfl_fabric_demo_tb.v dumps it): the walk's, or ph
    /* verilator lint_off UNUSEDSIGNAL */
    wire [3:0] st = dwait ? ph : w_hdr ? S_HDR : w_sub ? S_SUBHDR : w_body ? ph : S_DROP;
    /* verilator lint_on UNUSEDSIGNAL */

    // the message
    reg own_eq;
    reg [95:0] cmp_sh;                          // cfg_prefix, shifted a byte per byte compared
    reg [95:0] src_prefix;
    reg dst_ok, dst_cfg, dst_zero;
    reg [31:0] ts_sec;
    reg [63:0] ts;
    reg ts_valid;
    wire cmp_eq = (b == cmp_sh[95:88]);
    wire own_n = ((w_idx == 5'd8) || own_eq) && cmp_eq;

    // the submessage
    reg k_ts, k_dst, k_src, k_data, k_frag;     // the submessage id, decoded once
    wire [3:0] sm_flags = w_flags[3:0];         // E, Q (INFO_TS: I), D, K
    reg [31:0] acc_e;                           // the last four bytes, in E order
    reg [23:0] acc_b;                           // the last three bytes, as they came
    wire le = sm_flags[0];
    wire [31:0] acc_e_n = le ? {b, acc_e[31:8]} : {acc_e[23:0], b};
    wire [31:0] acc_b_n = {acc_b, b};
    wire [15:0] e16 = le ? acc_e_n[31:16] : acc_e_n[15:0];      // a 16-bit field ending here
    wire is_frag = k_frag;
    wire fields_kind = k_data || k_frag || k_dst || k_src || (k_ts && !sm_flags[1]);
    wire [5:0] fields_last = k_ts ? 6'd7 : k_dst ? 6'd11 : k_frag ? 6'd31 : 6'd19;
    wire body_last = w_last;                    // (in a body)
    wire body_end = body_last || tl;            // the submessage's last byte in this packet
    wire trunc = tl && !body_last;
    wire end_bad = trunc || (body_last && w_mis && !tl); // cut short; misaligned, not last

    // DATA / DATA_FRAG fields
    reg [16:0] gap;                             // signed: bytes from the fields to the QoS
    reg [31:0] reader, writer, frag_start, sample_size;
    reg [63:0] seq;
    reg [15:0] frag_count, frag_size;
    reg [15:0] q_left;
    reg q_sent, ql1, q_pid1, q_z2, g1;         // ql1: q_left == 1; g1: gap == 1
    wire gap_pos = !gap[16] && (gap != 17'd0);
    wire q_len0 = q_z2 && (b == 8'h00);        // the parameter's length is 0
    wire q_done = ((idx == 3'd3) && q_len0 && q_pid1) || ((idx == 3'd4) && ql1 && q_sent);

    // the sample being streamed
    reg act, act_frag, beats, pay_on, hold, sm_acc;
    reg al1, fl1, fc1, afs1;                    // a_left, f_left, f_cnt, a_fsize == 1
    reg [7:0] hold_data;
    wire [7:0] held = hold ? hold_data : 8'h00; // an ended sample's last beat, or 0
    reg [31:0] next_frag, a_ssize, a_left;
    reg [15:0] a_fsize, f_left, f_cnt;
    reg [95:0] meta_prefix;
    reg [31:0] meta_writer;
    reg [63:0] meta_seq, meta_ts;
    reg meta_ts_valid;
    reg a_done;                                 // meta_* is a fragmented sample sent whole
    wire fin = act_frag ? al1 : body_last;      // the sample's last byte
    wire fset_end = act_frag && fl1 && fc1;

    // the decision (S_D1 registers, S_D2 reads)
    reg d_body_end, d_pkt_end, d_bad;
    reg eq_pfx, eq_wr, eq_seq;                  // registered every clock (timing)
    // S_D1 registers the decision's terms, reduced to what S_D2 reads with act (the one term
    // that S_D2 changes: an abort, then decide again); the rest holds from S_D1 to the decision
    // (timing: S_D2 reads a few registers, not the comparisons)
    // (the fields a DATA_FRAG's decision compares are the last byte's or older: registered every
    // clock as eq_*; a DATA's writerSN and a sample size end at its last byte: compared in S_D1)
    reg r_start_eq, r_start1, r_start0, r_below, r_fsz_eq, r_frag_nz, r_seq_hi_nz, r_reader0;
    wire n_k_eq = eq_pfx && eq_wr && eq_seq;    // DATA_FRAG: writerSN is 12 bytes old
    wire n_valid = r_frag_nz && (sample_size != 32'd0);
    wire n_matched = dst_ok && (r_reader0 || reader == cfg_reader) &&
                     (cfg_writer == 32'd0 || writer == cfg_writer) && !seq[63] &&
                     (r_seq_hi_nz || seq[31:0] != 32'd0) && (is_frag || sm_flags[3:2] == 2'b01);
    wire n_same = n_matched && is_frag && n_k_eq && r_fsz_eq && (sample_size == a_ssize) &&
                  n_valid;
    wire n_cont = n_same && act_frag && r_start_eq;                    // with act
    wire n_rep_done = n_same && !r_start0 && a_done && !r_start1;
    wire n_rep_act = n_same && !r_start0 && act_frag && r_below;       // with act
    reg f_matched, f_cont, f_rep_done, f_rep_act, f_start_ok, f_abort, f_gap_pos, d_ok;
    wire cont_now = act && f_cont;
    wire rep_now = f_rep_done || (act && f_rep_act);
    wire need_abort = act && f_abort;
    wire start_now = f_start_ok && !rep_now;

    reg p_pkt, p_badhdr, p_mal, p_ok, p_drop, p_rep;    // counter pulses

    // the byte an emit sends: the input byte in a taken sample's payload, else an ended sample's
    // held last byte or 0 (timing: o_data's input is this mux, not the state machine's chain)
    wire from_b = !dwait && w_body && (ph == S_PAY) && pay_on;
    wire [7:0] o_next = from_b ? b : (dwait && !need_abort) ? 8'h00 : held;

    task emit(input l, input u);
        begin
            o_valid <= 1'b1;
            o_data <= o_next;
            o_last <= l;
            o_user <= u;
            if (l && u) p_drop <= 1'b1;
            if (l && !u) p_ok <= 1'b1;
        end
    endtask

    // the sample in progress is dropped: its packet, if a byte went out, ends with TUSER
    task abort_act;
        begin
            if (act) begin
                if (hold || beats) emit(1'b1, 1'b1);      // held
                else p_drop <= 1'b1;
            end
            act <= 1'b0;
            hold <= 1'b0;
            pay_on <= 1'b0;
        end
    endtask

    // a malformed submessage: it and the rest of the packet are dropped (the walk's drop,
    // set in the same clock by the always @(*) below)
    task malformed;
        begin
            p_mal <= 1'b1;
            if (sm_acc) abort_act;
        end
    endtask

    // the submessage ends where its payload would start (an empty payload)
    task end_no_payload;
        begin
            if (end_bad) malformed;
            else if (sm_acc && act) begin
                if (act_frag) abort_act;        // the fragment is missing
                else act <= 1'b0;               // a DATA with nothing in it: nothing sent
            end
        end
    endtask

    task load_meta;
        begin
            meta_prefix <= src_prefix;
            meta_writer <= writer;
            meta_seq <= seq;
            meta_ts <= ts;
            meta_ts_valid <= ts_valid;
        end
    endtask

    // the rest of the packet dropped (the walk's drop), in the clock the state machine below
    // finds the packet malformed or not ours (a TLAST taken ends it anyway)
    always @(*) begin
        drop = 1'b0;
        if (dwait) begin
            // S_D2: nothing after the fields, and they are bad
            drop = (ph == S_D2) && o_free && !need_abort && d_body_end && !d_pkt_end && !d_ok;
        end else if (take) begin
            if (w_hdr) drop = (w_idx == 5'd19) && own_n;     // our own message, looped back
            else if (w_sub) drop = (w_idx == 5'd3) &&        // D and K; INFO_TS without time
                                   ((k_data && sm_flags[3:2] == 2'b11) || (w_empty && fields_kind));
            else if (w_body) case (ph)
                S_FIELDS: drop = (pos == fields_last) ? (!k_data && !k_frag && end_bad) : body_end;
                S_GAP:    drop = body_end && (!g1 || sm_flags[1] || end_bad);
                S_QOS:    drop = body_end && (!q_done || end_bad);
                S_PAY:    drop = body_end && end_bad;
                S_SKIP:   drop = end_bad;
                default:  drop = 1'b0;
            endcase
        end
    end

    always @(posedge clk) begin
        eq_pfx <= (src_prefix == meta_prefix);
        eq_wr <= (writer == meta_writer);
        eq_seq <= (seq == meta_seq);
        r_start_eq <= (frag_start == next_frag);
        r_start1 <= (frag_start == 32'd1);
        r_start0 <= (frag_start == 32'd0);
        r_below <= (frag_start < next_frag);
        r_fsz_eq <= (frag_size == a_fsize);
        r_frag_nz <= (frag_size != 16'd0) && (frag_count != 16'd0);
        r_seq_hi_nz <= (seq[63:32] != 32'd0);
        r_reader0 <= (reader == 32'd0);
        p_pkt <= 1'b0;
        p_badhdr <= 1'b0;
        p_mal <= 1'b0;
        p_ok <= 1'b0;
        p_drop <= 1'b0;
        p_rep <= 1'b0;
        if (m_axis_tready) o_valid <= 1'b0;
        if (take) begin
            acc_e <= acc_e_n;
            acc_b <= acc_b_n[23:0];
        end
        if (!rst_n) begin
            ph <= S_FIELDS;
            dwait <= 1'b0;
            idx <= 3'd0;
            o_valid <= 1'b0;
            act <= 1'b0;
            hold <= 1'b0;
            pay_on <= 1'b0;
            sm_acc <= 1'b0;
            a_done <= 1'b0;
        end else if (dwait) begin
            case (ph)
            S_D1: begin
                f_matched <= n_matched;
                f_cont <= n_cont;
                f_rep_done <= n_rep_done;
                f_rep_act <= n_rep_act;
                f_start_ok <= n_matched && (!is_frag || (r_start1 && n_valid));
                f_abort <= n_matched && !n_rep_done && !n_rep_act && (!is_frag || !n_cont);
                f_gap_pos <= gap_pos;
                d_ok <= !d_bad && !gap_pos && !sm_flags[1];
                ph <= S_D2;
            end
            default: if (o_free) begin          // S_D2
                if (need_abort) abort_act;      // then decide again, without it
                else begin
                    dwait <= 1'b0;
                    if (start_now || cont_now) begin
                        sm_acc <= 1'b1;
                        pay_on <= 1'b1;
                        f_left <= frag_size;
                        fl1 <= (frag_size == 16'd1);
                        f_cnt <= frag_count;
                        fc1 <= (frag_count == 16'd1);
                    end
                    if (start_now) begin
                        load_meta;
                        act <= 1'b1;
                        act_frag <= is_frag;
                        a_done <= 1'b0;
                        beats <= 1'b0;
                        next_frag <= 32'd1;
                        a_fsize <= frag_size;
                        afs1 <= (frag_size == 16'd1);
                        a_ssize <= sample_size;
                        a_left <= sample_size;
                        al1 <= (sample_size == 32'd1);
                    end else if (rep_now) p_rep <= 1'b1;
                    else if (f_matched && !cont_now) p_drop <= 1'b1;        // out of order
                    if (d_body_end) begin       // nothing after the fields (the walk is past
                                                // them: at the next submessage or packet)
                        if (!d_ok) p_mal <= 1'b1;
                        if ((start_now || cont_now) && (is_frag || !d_ok)) begin
                            if (cont_now && beats) emit(1'b1, 1'b1);  // 0
                            else p_drop <= 1'b1;
                        end
                        if (start_now || cont_now) begin
                            act <= 1'b0;
                            pay_on <= 1'b0;
                        end
                    end else begin
                        idx <= 3'd0;
                        ph <= f_gap_pos ? S_GAP : sm_flags[1] ? S_QOS : S_PAY;
                    end
                end
            end
            endcase
        end else if (take && w_hdr) begin
            if (w_hdr_bad) p_badhdr <= 1'b1;    // bad magic or version, shorter than a header
            if (w_idx == 5'd0) begin
                p_pkt <= 1'b1;
                dst_ok <= 1'b1;
                ts_valid <= 1'b0;
            end
            if (w_idx == 5'd7) cmp_sh <= cfg_prefix;
            if (w_idx >= 5'd8) begin
                src_prefix <= {src_prefix[87:0], b};
                cmp_sh <= {cmp_sh[87:0], 8'h00};
                own_eq <= own_n;
            end
        end else if (take && w_sub) begin
            if (w_idx == 5'd0) begin
                k_ts <= (b == ID_INFO_TS);
                k_dst <= (b == ID_INFO_DST);
                k_src <= (b == ID_INFO_SRC);
                k_data <= (b == ID_DATA);
                k_frag <= (b == ID_DATA_FRAG);
                sm_acc <= 1'b0;
            end
            if (w_idx == 5'd3) begin
                if (k_ts && sm_flags[1]) ts_valid <= 1'b0;
                if (k_dst) begin
                    cmp_sh <= cfg_prefix;
                    dst_cfg <= 1'b1;
                    dst_zero <= 1'b1;
                end
                if (tl) begin                   // no body in this packet
                    if (w_len != 16'd0 || fields_kind) p_mal <= 1'b1;
                end else if (k_data && sm_flags[3:2] == 2'b11) begin
                    p_mal <= 1'b1;              // D and K: invalid (RTPS 2.3 8.3.7.2)
                end else if (w_empty) begin     // empty (PAD, INFO_TS of length 0)
                    if (fields_kind) p_mal <= 1'b1;     // INFO_TS without its time
                end else ph <= fields_kind ? S_FIELDS : S_SKIP;
            end else if (tl) p_mal <= 1'b1;     // a submessage header cut short
        end else if (take && w_body) begin
            case (ph)
            S_FIELDS: begin
                if (k_ts) begin
                    if (pos == 6'd3) ts_sec <= acc_e_n;
                    if (pos == 6'd7) begin
                        ts <= {ts_sec, acc_e_n};
                        ts_valid <= 1'b1;
                    end
                end else if (k_dst) begin
                    dst_cfg <= dst_cfg && cmp_eq;
                    dst_zero <= dst_zero && (b == 8'h00);
                    cmp_sh <= {cmp_sh[87:0], 8'h00};
                    if (pos == 6'd11) dst_ok <= (dst_cfg && cmp_eq) || (dst_zero && b == 8'h00);
                end else if (k_src) begin
                    if (pos >= 6'd8) src_prefix <= {src_prefix[87:0], b};
                end else begin                  // DATA, DATA_FRAG
                    if (pos == 6'd3) begin
                        gap <= {1'b0, e16} - (is_frag ? 17'd28 : 17'd16);
                        g1 <= (e16 == (is_frag ? 16'd29 : 16'd17));
                    end
                    // the fields themselves: the always block after this one
                end
                if (pos == fields_last) begin
                    if (k_data || k_frag) begin
                        d_body_end <= body_end;
                        d_pkt_end <= tl;
                        d_bad <= end_bad;
                        dwait <= 1'b1;
                        ph <= S_D1;
                    end else if (end_bad) malformed;
                    else if (!body_end) ph <= S_SKIP;
                end else if (body_end) malformed;   // fields missing
            end
            S_GAP: begin
                gap <= gap - 17'd1;
                g1 <= (gap == 17'd2);
                if (g1) begin
                    if (body_end) begin
                        if (sm_flags[1]) malformed;     // the inline QoS is missing
                        else end_no_payload;
                    end else ph <= sm_flags[1] ? S_QOS : S_PAY;
                end else if (body_end) malformed;
            end
            S_QOS: begin
                if (idx == 3'd4) begin          // in a parameter's value
                    q_left <= q_left - 16'd1;
                    ql1 <= (q_left == 16'd2);
                    if (ql1) idx <= 3'd0;
                end else if (idx == 3'd3) begin
                    q_left <= e16;
                    ql1 <= (e16 == 16'd1);
                    q_sent <= q_pid1;
                    idx <= q_len0 ? 3'd0 : 3'd4;
                end else idx <= idx + 3'd1;
                if (idx == 3'd1) q_pid1 <= (e16 == 16'h0001);   // the parameter id
                if (idx == 3'd2) q_z2 <= (b == 8'h00);
                if (body_end) begin
                    if (q_done) end_no_payload;
                    else malformed;
                end else if (q_done) begin
                    idx <= 3'd0;
                    ph <= S_PAY;
                end
            end
            S_PAY: begin
                if (pay_on) begin
                    if (act_frag) begin
                        a_left <= a_left - 32'd1;
                        al1 <= (a_left == 32'd2);
                        if (fl1) begin
                            f_left <= a_fsize;
                            fl1 <= afs1;
                            f_cnt <= f_cnt - 16'd1;
                            fc1 <= (f_cnt == 16'd2);
                            next_frag <= next_frag + 32'd1;
                        end else begin
                            f_left <= f_left - 16'd1;
                            fl1 <= (f_left == 16'd2);
                        end
                    end
                    if (fin) begin
                        pay_on <= 1'b0;
                        if (body_end) begin
                            emit(1'b1, end_bad);  // b
                            act <= 1'b0;
                            a_done <= act_frag && !end_bad;
                        end else begin          // its verdict comes with the submessage's end
                            hold <= 1'b1;
                            hold_data <= b;
                        end
                    end else if (body_end && (end_bad || !fset_end)) begin
                        emit(1'b1, 1'b1);       // b: cut short, or fragments missing
                        act <= 1'b0;
                        pay_on <= 1'b0;
                    end else begin
                        emit(1'b0, 1'b0);     // b
                        beats <= 1'b1;
                        if (fset_end) pay_on <= 1'b0;
                    end
                end else if (body_end && hold) begin
                    emit(1'b1, end_bad);  // held
                    hold <= 1'b0;
                    act <= 1'b0;
                    a_done <= act_frag && !end_bad;
                end else if (body_end && end_bad && sm_acc) abort_act;
                if (body_end && end_bad) p_mal <= 1'b1;
            end
            default: if (end_bad) malformed;    // S_SKIP
            endcase
        end
    end

    // DATA / DATA_FRAG's fields, in a block of their own (timing: their enables are the byte's
    // place only, not the state machine's if/else chain nor the take: a field is written while
    // its last byte is offered, last with the byte taken, and read only once the fields end)
    wire df_field = w_body && (ph == S_FIELDS) && !k_ts && !k_dst && !k_src;
    always @(posedge clk) if (df_field) begin
        if (pos == 6'd7) reader <= acc_b_n;
        if (pos == 6'd11) writer <= acc_b_n;
        if (pos == 6'd15) seq[63:32] <= acc_e_n;
        if (pos == 6'd19) seq[31:0] <= acc_e_n;
        if (pos == 6'd23) frag_start <= acc_e_n;
        if (pos == 6'd25) frag_count <= e16;
        if (pos == 6'd27) frag_size <= e16;
        if (pos == 6'd31) sample_size <= acc_e_n;
    end

    // counters (a clock after the event)
    reg [COUNT_BITS-1:0] c_pkt, c_badhdr, c_mal, c_ok, c_drop, c_rep;
    always @(posedge clk) begin
        if (!rst_n) begin
            c_pkt <= {COUNT_BITS{1'b0}};
            c_badhdr <= {COUNT_BITS{1'b0}};
            c_mal <= {COUNT_BITS{1'b0}};
            c_ok <= {COUNT_BITS{1'b0}};
            c_drop <= {COUNT_BITS{1'b0}};
            c_rep <= {COUNT_BITS{1'b0}};
        end else begin
            c_pkt <= c_pkt + {{(COUNT_BITS-1){1'b0}}, p_pkt};
            c_badhdr <= c_badhdr + {{(COUNT_BITS-1){1'b0}}, p_badhdr};
            c_mal <= c_mal + {{(COUNT_BITS-1){1'b0}}, p_mal};
            c_ok <= c_ok + {{(COUNT_BITS-1){1'b0}}, p_ok};
            c_drop <= c_drop + {{(COUNT_BITS-1){1'b0}}, p_drop};
            c_rep <= c_rep + {{(COUNT_BITS-1){1'b0}}, p_rep};
        end
    end

    assign m_axis_tdata = o_data;
    assign m_axis_tvalid = o_valid;
    assign m_axis_tlast = o_last;
    assign m_axis_tuser = o_user;
    assign m_sample_guid = {meta_prefix, meta_writer};
    assign m_sample_seq = meta_seq;
    assign m_sample_ts = meta_ts;
    assign m_sample_ts_valid = meta_ts_valid;
    assign cnt_packets = c_pkt;
    assign cnt_bad_header = c_badhdr;
    assign cnt_malformed = c_mal;
    assign cnt_samples = c_ok;
    assign cnt_dropped = c_drop;
    assign cnt_repeated = c_rep;
endmodule

`default_nettype wire
