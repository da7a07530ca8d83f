// rfl_spdp_peer -- the fabric participant learns its one peer from SPDP (issue #31): fed the
// metatraffic datagrams that came to the domain's SPDP port or to this participant's
// metatraffic port (RTPS messages; 8-bit AXI4-Stream, TLAST on a datagram's last byte; always
// ready, a watcher of the beats the top takes), it reads each SPDP participant announcement (a
// DATA of the built-in participant writer SPDP_WRITER_ID, flag D, not K) and takes from its
// parameter list a UDPv4 locator (kind SPDP_LOCATOR_KIND) of PID_METATRAFFIC_UNICAST_LOCATOR
// and of PID_DEFAULT_UNICAST_LOCATOR (the first, unless a later one is at the address the
// datagram came from, s_src_ip: a multi-homed host lists addresses the node may not reach, and
// reaches it from that one), and its lease (PID_PARTICIPANT_LEASE_DURATION, whole seconds;
// SPDP_LEASE_DEFAULT when absent, at most SPDP_LEASE_MAX, at least 1). The constants are
// parameters rosfpga_lab.rtl.discrom (spdp_parameters) takes from the software participant's
// builders (one owner).
// The peer (one; several peers are a later step): the first participant announced keeps the
// place while it announces itself within its lease; once it has been silent for its lease
// (counted in seconds of TICK clocks), the next participant announced takes it. So a flood of
// participants (or a second live one) cannot take the peer away from a live one, nor make the
// circuit flap between two (each change sends the SEDP set); a peer that left is replaced
// after its lease, or at once after its goodbye (an SPDP DATA whose inline QoS has
// PID_STATUS_INFO with the disposed or unregistered flag, as rosfpga_lab.rtps.spdp's goodbye).
// A newer announcement of the peer with other locators updates them. On each
// peer taken or changed: a send_sedp pulse, and a second one RESEND clocks later (the ROM's
// SPDP goes out between: a peer drops SEDP from a participant it has not discovered yet).
// Bounded, whatever comes in: at most one peer change a second (TICK clocks; a change the
// second after another waits for the peer's next announcement), two send_sedp pulses each, so
// at most two SEDP sets a second (rfl_rtps_disc_rom also merges requests that wait).
// Refused and counted (cnt_refused): an announcement whose submessage or parameter list ends
// before PID_SENTINEL (a length past the submessage's end included), an unknown encapsulation,
// octetsToInlineQos below 16, or no UDPv4 metatraffic or default locator (a locator of another
// kind, or a port 0 or above 65535, is skipped). Counted in cnt_other: a well-formed
// announcement of another participant while the peer is live, or a change in the second of
// the last. Our own (GUID prefix
// cfg_prefix, looped back) is ignored, as is a goodbye (of the peer: it ends the peer's place).
// Not read: INFO_SRC (the header's prefix names the participant), INFO_DST (an announcement is
// the participant's whoever it is addressed to).
// The walk: a byte a clock, the header, submessage headers and bodies by rfl_rtps_walk (a bad
// header: the datagram ignored), then in an SPDP DATA the inline QoS (flag Q, walked by its
// parameters' lengths for PID_STATUS_INFO), the encapsulation (PL_CDR_BE or PL_CDR_LE: the
// parameters' byte order) and the parameters.
`default_nettype none

module rfl_spdp_peer #(
    parameter [31:0] SPDP_WRITER_ID = 32'd0,    // all SPDP_*: rtl.discrom.spdp_parameters
    parameter [79:0] SPDP_PIDS = 80'd0,         // {status info, sentinel, lease, default,
                                                //  metatraffic}
    parameter [31:0] SPDP_ENCAPS = 32'd0,       // {PL_CDR_BE, PL_CDR_LE}
    parameter [31:0] SPDP_LOCATOR_KIND = 32'd0, // LOCATOR_KIND_UDPv4
    parameter SPDP_LEASE_DEFAULT = 100,         // seconds
    parameter SPDP_LEASE_MAX = 300,             // seconds, 1..65534
    parameter TICK = 125000000,                 // clocks a second, >= 1
    parameter RESEND = 125000000,               // clocks to the second send_sedp, >= 2
    parameter COUNT_BITS = 32                   // 1..32
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [95:0]           cfg_prefix,    // this participant's GUID prefix
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready, // always 1: a watcher
    input  wire                  s_axis_tlast,
    input  wire [31:0]           s_src_ip,      // the datagram's IPv4 source, held over it
    output wire                  peer_known,    // a peer was taken (its registers below)
    output wire [31:0]           peer_meta_ip,
    output wire [15:0]           peer_meta_port,
    output wire [31:0]           peer_user_ip,
    output wire [15:0]           peer_user_port,
    output wire                  send_sedp,     // one clock: send the SEDP set to the peer
    output wire [COUNT_BITS-1:0] cnt_learned,   // peers taken or changed
    output wire [COUNT_BITS-1:0] cnt_refused,
    output wire [COUNT_BITS-1:0] cnt_other
);
`ifdef __ICARUS__
    initial begin
        if (TICK < 1 || RESEND < 2) $fatal(1, "rfl_spdp_peer: TICK >= 1, RESEND >= 2");
        if (SPDP_LEASE_MAX < 1 || SPDP_LEASE_MAX > 65534)
            $fatal(1, "rfl_spdp_peer: SPDP_LEASE_MAX must be 1..65534");
        if (COUNT_BITS < 1 || COUNT_BITS > 32) $fatal(1, "rfl_spdp_peer: COUNT_BITS must be 1..32");
    end
`else
    if (TICK < 1 || RESEND < 2) begin : g_bad_tick
        $error("rfl_spdp_peer: TICK >= 1, RESEND >= 2");
    end
    if (SPDP_LEASE_MAX < 1 || SPDP_LEASE_MAX > 65534) begin : g_bad_lease
        $error("rfl_spdp_peer: SPDP_LEASE_MAX must be 1..65534");
    end
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_spdp_peer: COUNT_BITS must be 1..32");
    end
`endif
    localparam [15:0] PID_STATUS = SPDP_PIDS[79:64], PID_SENTINEL = SPDP_PIDS[63:48],
                      PID_LEASE = SPDP_PIDS[47:32], PID_USER = SPDP_PIDS[31:16],
                      PID_META = SPDP_PIDS[15:0];
    localparam [15:0] ENC_BE = SPDP_ENCAPS[31:16], ENC_LE = SPDP_ENCAPS[15:0];
    localparam [31:0] LEASE_MAX_32 = SPDP_LEASE_MAX, LEASE_DEF_32 = SPDP_LEASE_DEFAULT;
    localparam [15:0] LEASE_MAX = LEASE_MAX_32[15:0];
    localparam [15:0] LEASE_DEF = (SPDP_LEASE_DEFAULT < 1) ? 16'd1 :
                                  (SPDP_LEASE_DEFAULT > SPDP_LEASE_MAX) ? LEASE_MAX :
                                  LEASE_DEF_32[15:0];
    localparam TW = (TICK > 1) ? $clog2(TICK + 1) : 1;
    localparam RW = $clog2(RESEND + 1);
    localparam [31:0] TICK_LAST_32 = TICK - 1;
    localparam [TW-1:0] TICK_LAST = TICK_LAST_32[TW-1:0];
    localparam [31:0] RESEND_32 = RESEND;
    localparam [RW-1:0] RESEND_N = RESEND_32[RW-1:0];
`include "rfl_rtps_wire.vh"             // ID_*
    // within a DATA: the fixed fields, the inline QoS's parameter heads and values, the
    // encapsulation, the payload's heads and values, done (the sentinel), ignored
    localparam [2:0] P_FIX = 3'd0, P_QHEAD = 3'd1, P_QVAL = 3'd2, P_ENC = 3'd3,
                     P_HEAD = 3'd4, P_VAL = 3'd5, P_END = 3'd6, P_IGN = 3'd7;

    assign s_axis_tready = 1'b1;
    wire take = s_axis_tvalid;
    wire [7:0] b = s_axis_tdata;
    wire tl = s_axis_tlast;

    // the walk: where the byte is (the header, a submessage header or body, dropped)
    wire w_hdr, w_sub, w_body, w_last;
    wire [4:0] w_idx;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [7:0] w_flags;                         // (E, Q, D, K read: 0..3)
    /* verilator lint_on UNUSEDSIGNAL */
    wire [15:0] pos;                            // the body's byte
    /* verilator lint_off PINCONNECTEMPTY */
    rfl_rtps_walk #(.POS_BITS(16)) u_walk (
        .clk(clk), .rst_n(rst_n), .in_data(s_axis_tdata), .in_take(take), .in_last(s_axis_tlast),
        .drop(1'b0), .m_hdr(w_hdr), .m_subhdr(w_sub), .m_body(w_body), .m_dropped(), .m_idx(w_idx),
        .m_sub_id(), .m_sub_flags(w_flags), .m_sub_len(), .m_sub_pos(pos), .m_sub_mis(),
        .m_sub_last(w_last), .m_sub_empty(), .m_hdr_bad());
    /* verilator lint_on PINCONNECTEMPTY */

    reg [95:0] src;                             // the header's prefix, shifted in (the last
                                                // candidate's is used 2 clocks after its end)
    reg [7:0] len_lo;                           // octetsToInlineQos' first byte
    wire le = w_flags[0];                       // the submessage's byte order (FLAG_E)
    wire f_q = w_flags[1], f_d = w_flags[2], f_k = w_flags[3];
    reg k_data;                                 // the submessage is a DATA (decoded once)
    reg [2:0] ph;
    reg ple;                                    // the parameter list's byte order
    reg [1:0] hcnt;                             // byte of a parameter head / encapsulation
    reg [31:0] acc_e;                           // the last 4 bytes, in ple's order
    reg [23:0] acc_b;                           // the last 3 bytes, in arrival order
    reg [15:0] dstart_m1;                       // body byte before the inline QoS / payload
    reg [23:0] wid;                             // writerId's first 3 bytes
    reg wid_ok;                                 // writerId is SPDP_WRITER_ID
    reg f_bad;                                  // refused (counted if it is an announcement)
    reg [15:0] vleft;
    reg vl1;
    reg [4:0] vpos;                             // value byte, held at 31
    reg k_meta, k_user, k_lease, k_status;
    reg f_gone;                                 // a goodbye (PID_STATUS_INFO disposed or
                                                // unregistered)
    reg [31:0] v_kind, v_port;
    reg have_meta, have_user, have_lease, pl_ok;
    reg meta_src, user_src;                     // the one taken is at s_src_ip
    reg m_hi;                                   // a value's bytes 20..22 are s_src_ip's first
    reg [31:0] meta_ip, user_ip, lease_sec;
    reg [15:0] meta_port, user_port;

    wire ple_n = (ph == P_FIX) ? le : ple;     // (the inline QoS is in the submessage's order)
    wire [31:0] acc_e_n = ple_n ? {b, acc_e[31:8]} : {acc_e[23:0], b};
    wire [31:0] acc_b_n = {acc_b, b};
    wire [15:0] len_n = le ? {b, len_lo} : {len_lo, b};
    wire [15:0] hpid = ple ? acc_e_n[15:0] : acc_e_n[31:16];
    wire [15:0] hlen = ple ? acc_e_n[31:16] : acc_e_n[15:0];
    wire [15:0] pid_n = hpid[15] ? hpid : {2'b00, hpid[13:0]};    // must-understand bit off
    wire sub_end = w_last || tl;                // (tl first: cut short)
    wire spdp_data = k_data && wid_ok;
    wire announce = spdp_data && f_d && !f_k && !f_gone;
    // a UDPv4 locator with a port of 1..65535, its value's bytes 0..7 taken
    wire loc_ok = v_kind == SPDP_LOCATOR_KIND && v_port != 32'd0 && v_port[31:16] == 16'd0;
    wire src_match = m_hi && b == s_src_ip[7:0];   // (at a locator's byte 23)

    // the candidate (c_*: src and the locators taken hold it, the next header's prefix and the
    // next locator at least 20 bytes later), compared (e_*), then acted on; the peer (p_*)
    reg c_valid, c_bye, e_valid, e_own, e_same, e_loc_eq;
    reg [95:0] p_prefix;
    reg [31:0] p_mip, p_uip;
    reg [15:0] p_mport, p_uport;
    reg [15:0] c_lease, lease_left;
    reg have;
    reg [TW-1:0] tick;
    reg [RW-1:0] resend;
    reg sedp;
    reg [COUNT_BITS-1:0] n_learned, n_refused, n_other;
    assign peer_known = have;
    assign peer_meta_ip = p_mip;
    assign peer_meta_port = p_mport;
    assign peer_user_ip = p_uip;
    assign peer_user_port = p_uport;
    assign send_sedp = sedp;
    assign cnt_learned = n_learned;
    assign cnt_refused = n_refused;
    assign cnt_other = n_other;

    // the decision on the candidate compared (e_*): another's announcement (not ours looped
    // back) heard; a new peer (the place free: none yet, or silent for its lease) or the peer's
    // new locators taken, at most one change a second (recent: one in this second)
    reg recent;
    wire heard = e_valid && !e_own;
    wire change = heard && !c_bye && !recent &&
                  (e_same ? !e_loc_eq : (!have || lease_left == 16'd0));
    // the announced lease in seconds, 1..LEASE_MAX, and one more (a tick may come right after)
    wire [15:0] lease_n = !have_lease ? LEASE_DEF :
                          (lease_sec[31] || lease_sec > LEASE_MAX_32) ? LEASE_MAX :
                          (lease_sec == 32'd0) ? 16'd1 : lease_sec[15:0];

    always @(posedge clk) begin
        if (!rst_n) begin
            c_valid <= 1'b0;
            e_valid <= 1'b0;
            have <= 1'b0;
            p_prefix <= 96'd0;
            p_mip <= 32'd0;
            p_uip <= 32'd0;
            p_mport <= 16'd0;
            p_uport <= 16'd0;
            lease_left <= 16'd0;
            tick <= {TW{1'b0}};
            resend <= {RW{1'b0}};
            sedp <= 1'b0;
            recent <= 1'b0;
            n_learned <= {COUNT_BITS{1'b0}};
            n_refused <= {COUNT_BITS{1'b0}};
            n_other <= {COUNT_BITS{1'b0}};
        end else begin
            c_valid <= 1'b0;
            sedp <= 1'b0;
            if (take && w_hdr && w_idx >= 5'd8) src <= {src[87:0], b};
            if (take && w_sub) begin
                if (w_idx == 5'd0) k_data <= (b == ID_DATA);
                ph <= P_FIX;
                wid_ok <= 1'b0;
                f_bad <= 1'b0;
                f_gone <= 1'b0;
                have_meta <= 1'b0;
                have_user <= 1'b0;
                meta_src <= 1'b0;
                user_src <= 1'b0;
                have_lease <= 1'b0;
                pl_ok <= 1'b0;
            end else if (take && w_body) begin
                acc_e <= acc_e_n;
                acc_b <= acc_b_n[23:0];
                if (pos == 16'd3) dstart_m1 <= 16'd3 + len_n;   // (bytes 2, 3 in le's order)
                if (pos == 16'd10) wid <= acc_b_n[23:0];
                if (pos == 16'd11) wid_ok <= ({wid, b} == SPDP_WRITER_ID);
                if (pos == 16'd2) len_lo <= b;
                case (ph)
                P_FIX: if (pos == 16'd4 && dstart_m1 < 16'd19) begin
                    // octetsToInlineQos below 16 (or past 65532: 3 + it wraps), checked
                    // from its register (timing)
                    f_bad <= 1'b1;
                    ph <= P_IGN;
                end else if (pos >= 16'd19 && pos == dstart_m1) begin
                    ph <= f_q ? P_QHEAD : P_ENC;
                    ple <= le;
                    hcnt <= 2'd0;
                end
                P_QHEAD, P_HEAD: begin
                    hcnt <= hcnt + 1'b1;
                    if (hcnt == 2'd3) begin
                        k_meta <= (ph == P_HEAD) && pid_n == PID_META;
                        k_user <= (ph == P_HEAD) && pid_n == PID_USER;
                        k_lease <= (ph == P_HEAD) && pid_n == PID_LEASE;
                        k_status <= (ph == P_QHEAD) && pid_n == PID_STATUS;
                        vleft <= hlen;
                        vl1 <= (hlen == 16'd1);
                        vpos <= 5'd0;
                        if (pid_n == PID_SENTINEL) begin
                            ph <= (ph == P_QHEAD) ? P_ENC : P_END;
                            if (ph == P_HEAD) pl_ok <= 1'b1;
                        end else if (hlen != 16'd0) begin
                            ph <= (ph == P_QHEAD) ? P_QVAL : P_VAL;
                        end
                    end
                end
                P_QVAL, P_VAL: begin
                    vleft <= vleft - 1'b1;
                    vl1 <= (vleft == 16'd2);
                    if (vpos != 5'd31) vpos <= vpos + 1'b1;
                    if (vpos == 5'd3) v_kind <= acc_e_n;      // a locator's kind, or seconds
                    if (vpos == 5'd7) v_port <= acc_e_n;
                    // StatusInfo_t: octet[4], the flags in the last
                    if (k_status && vpos == 5'd3 && b[1:0] != 2'b00) f_gone <= 1'b1;
                    if (k_lease && vpos == 5'd3) begin
                        lease_sec <= acc_e_n;
                        have_lease <= 1'b1;
                    end
                    if (vpos == 5'd22) m_hi <= acc_b_n[23:0] == s_src_ip[31:8];
                    if (k_meta && vpos == 5'd23 && loc_ok &&
                        (!have_meta || (src_match && !meta_src))) begin
                        have_meta <= 1'b1;
                        meta_src <= src_match;
                        meta_ip <= acc_b_n;
                        meta_port <= v_port[15:0];
                    end
                    if (k_user && vpos == 5'd23 && loc_ok &&
                        (!have_user || (src_match && !user_src))) begin
                        have_user <= 1'b1;
                        user_src <= src_match;
                        user_ip <= acc_b_n;
                        user_port <= v_port[15:0];
                    end
                    if (vl1) begin
                        ph <= (ph == P_QVAL) ? P_QHEAD : P_HEAD;
                        hcnt <= 2'd0;
                    end
                end
                P_ENC: begin
                    hcnt <= hcnt + 1'b1;
                    if (hcnt == 2'd1) begin
                        if (acc_b_n[15:0] == ENC_BE) ple <= 1'b0;
                        else if (acc_b_n[15:0] == ENC_LE) ple <= 1'b1;
                        else begin
                            f_bad <= 1'b1;
                            ph <= P_IGN;
                        end
                    end
                    if (hcnt == 2'd3) ph <= P_HEAD;
                end
                default: ;                  // P_END, P_IGN: to the submessage's end
                endcase
                if (sub_end) begin
                    // (this byte's own field is not needed: an announcement ends after
                    // its sentinel, the last byte of which is taken above at hcnt 3)
                    if (spdp_data && f_gone) begin
                        c_valid <= 1'b1;
                        c_bye <= 1'b1;
                    end
                    if (announce) begin
                        c_bye <= 1'b0;
                        if (!f_bad && (pl_ok || (ph == P_HEAD && hcnt == 2'd3 &&
                                                  pid_n == PID_SENTINEL))
                            && have_meta && have_user) begin
                            c_valid <= 1'b1;
                            c_lease <= lease_n + 16'd1;
                        end else if (n_refused != {COUNT_BITS{1'b1}}) begin
                            n_refused <= n_refused + 1'b1;
                        end
                    end
                end
            end
            // the candidate compared (registered: timing), then acted on
            e_valid <= c_valid;
            e_own <= src == cfg_prefix;
            e_same <= have && src == p_prefix;
            e_loc_eq <= {meta_ip, meta_port, user_ip, user_port} ==
                        {p_mip, p_mport, p_uip, p_uport};
            // the lease, in seconds
            if (tick == TICK_LAST) begin
                tick <= {TW{1'b0}};
                if (lease_left != 16'd0) lease_left <= lease_left - 16'd1;
            end else begin
                tick <= tick + 1'b1;
            end
            if (resend != {RW{1'b0}}) begin
                resend <= resend - 1'b1;
                if (resend == {{(RW-1){1'b0}}, 1'b1}) sedp <= 1'b1;
            end
            if (tick == TICK_LAST) recent <= 1'b0;
            if (heard && e_same) lease_left <= c_lease;
            if (heard && c_bye && e_same) lease_left <= 16'd0;     // its goodbye: the place free
            if (change) begin
                have <= 1'b1;
                recent <= 1'b1;
                lease_left <= c_lease;
                p_prefix <= src;
                p_mip <= meta_ip;
                p_mport <= meta_port;
                p_uip <= user_ip;
                p_uport <= user_port;
                sedp <= 1'b1;
                resend <= RESEND_N;
                if (n_learned != {COUNT_BITS{1'b1}}) n_learned <= n_learned + 1'b1;
            end
            if (heard && !c_bye && !change && !(e_same && e_loc_eq) &&
                n_other != {COUNT_BITS{1'b1}})
                n_other <= n_other + 1'b1;
        end
    end
`ifdef FORMAL
    // The pulses (formal/fv_spdp_peer.sv proves them): f_change, a peer taken or changed now
    // (its registers and send_sedp a clock later); f_sent, the pulses decided since the last
    // change (that one included): one at the change, one when the resend count runs out, none
    // else, so never more than two per change.
    wire f_change = change;
    wire f_resend = resend == {{(RW-1){1'b0}}, 1'b1};
    reg [1:0] f_sent;
    reg f_any, f_tick;                          // a change yet; a second's end since the last
    always @(posedge clk) begin
        if (!rst_n) begin
            f_sent <= 2'd0;
            f_any <= 1'b0;
            f_tick <= 1'b0;
        end else begin
            if (f_change) f_sent <= 2'd1;
            else if (f_resend) f_sent <= f_sent + 2'd1;
            if (f_change) f_any <= 1'b1;
            f_tick <= !f_change && (f_tick || tick == TICK_LAST);
        end
    end
    always @(posedge clk) if (rst_n) begin
        assert(f_sent <= 2'd2);
        if (resend != {RW{1'b0}}) assert(f_sent == 2'd1);
        if (!have) assert(resend == {RW{1'b0}} && f_sent == 2'd0 && !sedp);
        if (!have) assert({p_mip, p_mport, p_uip, p_uport} == 96'd0);
        if ($past(rst_n)) assert(sedp == $past(f_change || f_resend));
        // at most one change a second: a second ends between two
        if (f_change) assert(!f_any || f_tick);
        assert(recent == (f_any && !f_tick));
    end
`endif
endmodule

`default_nettype wire
