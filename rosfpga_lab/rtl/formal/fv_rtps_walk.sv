// fv_rtps_walk -- rfl_rtps_walk (rtl/fabric) on its ports: any input bytes under the stream
// rules, any ready (the stage's), any drop. Each byte taken is exactly one of header,
// submessage header, body, dropped, and its place follows from the byte taken before it (p_*):
// a datagram's first byte is its header's byte 0 (so nothing is walked past a TLAST); the
// header's and a submessage header's bytes count up by one; the header's byte 19 leads to a
// submessage header, or to dropped when m_hdr_bad; a submessage header's byte 3 to the body's
// byte 0, or, when m_sub_empty, to the next submessage header; a body byte to the next one
// (position + 1), or after m_sub_last to the next submessage header; a drop (with a byte past
// the header's byte 18, or without a byte past the header) leaves only dropped bytes up to the
// TLAST. m_sub_last only in a body, m_sub_empty only at a submessage header's byte 3,
// m_hdr_bad only in a header. Bounded (not FV_PROVE, against the wrapper's own reading of the
// bytes): m_sub_id, m_sub_flags and m_sub_len are the submessage header's bytes; a body with a
// length never passes it, m_sub_last on its last byte exactly (a length 0: on the TLAST),
// m_sub_empty exactly for a PAD or INFO_TS of length 0; m_hdr_bad exactly for bad magic or
// major version at byte 19, or a TLAST before it.
module fv_rtps_walk (
    input clk, input rst_n, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tready, input s_axis_tlast, input drop
);
    wire m_hdr, m_subhdr, m_body, m_dropped, m_sub_mis, m_sub_last, m_sub_empty, m_hdr_bad;
    wire [4:0] m_idx;
    wire [7:0] m_sub_id, m_sub_flags;
    wire [15:0] m_sub_len, m_sub_pos;
    rfl_rtps_walk #(.POS_BITS(16)) dut (
        .clk(clk), .rst_n(rst_n), .in_data(s_axis_tdata),
        .in_take(s_axis_tvalid && s_axis_tready), .in_last(s_axis_tlast), .drop(drop),
        .m_hdr(m_hdr), .m_subhdr(m_subhdr), .m_body(m_body), .m_dropped(m_dropped),
        .m_idx(m_idx), .m_sub_id(m_sub_id), .m_sub_flags(m_sub_flags), .m_sub_len(m_sub_len),
        .m_sub_pos(m_sub_pos), .m_sub_mis(m_sub_mis), .m_sub_last(m_sub_last),
        .m_sub_empty(m_sub_empty), .m_hdr_bad(m_hdr_bad));
`include "fv_env.vh"
`include "rfl_rtps_wire.vh"             // RTPS_MAGIC, RTPS_VERSION, ID_PAD, ID_INFO_TS
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast})
    wire take = s_axis_tvalid && s_axis_tready;
    wire tl = s_axis_tlast;
    wire [7:0] b = s_axis_tdata;

    // the byte taken before (p_*), a drop since it (without a byte, past the header), and the
    // wrapper's own reading of the header and the submessage header
    reg p_any, p_tl, p_hdr, p_sub, p_body, p_dropped, p_last, p_empty, p_bad, p_drop;
    reg [4:0] p_idx;
    reg [15:0] p_pos;
    reg dropped_since;
    reg f_bad;
    reg [7:0] f_id, f_flags, f_lo;
    reg [15:0] f_len;
    wire [15:0] len_n = f_flags[0] ? {b, f_lo} : {f_lo, b};
    wire past_hdr_18 = !(p_hdr && p_idx < 5'd19);     // a drop with the last byte counts
    always @(posedge clk) begin
        if (!rst_n) begin
            p_any <= 1'b0;
            dropped_since <= 1'b0;
        end else if (take) begin
            p_any <= 1'b1;
            p_tl <= tl;
            p_hdr <= m_hdr;
            p_sub <= m_subhdr;
            p_body <= m_body;
            p_dropped <= m_dropped;
            p_last <= m_sub_last;
            p_empty <= m_sub_empty;
            p_bad <= m_hdr_bad;
            p_drop <= drop;
            p_idx <= m_idx;
            p_pos <= m_sub_pos;
            dropped_since <= 1'b0;
            if (m_hdr) begin
                if (m_idx == 5'd0) f_bad <= 1'b0;
                if ((m_idx == 5'd0 && b != RTPS_MAGIC[31:24]) ||
                    (m_idx == 5'd1 && b != RTPS_MAGIC[23:16]) ||
                    (m_idx == 5'd2 && b != RTPS_MAGIC[15:8]) ||
                    (m_idx == 5'd3 && b != RTPS_MAGIC[7:0]) ||
                    (m_idx == 5'd4 && b != RTPS_VERSION[15:8]))
                    f_bad <= 1'b1;
            end
            if (m_subhdr) begin
                if (m_idx == 5'd0) f_id <= b;
                if (m_idx == 5'd1) f_flags <= b;
                if (m_idx == 5'd2) f_lo <= b;
                if (m_idx == 5'd3) f_len <= len_n;
            end
        end else if (drop && p_any && !p_tl && !(p_hdr && p_idx < 5'd19)) begin
            dropped_since <= 1'b1;
        end
    end

    always @(posedge clk) if (!fv_init && rst_n) begin
        // one place a byte; the index within its part
        assert(m_hdr + m_subhdr + m_body + m_dropped == 1);
        if (m_hdr) assert(m_idx <= 5'd19);
        if (m_subhdr) assert(m_idx <= 5'd3);
        if (m_sub_last) assert(m_body);
        if (m_sub_empty) assert(m_subhdr && m_idx == 5'd3);
        if (m_hdr_bad) assert(m_hdr);
        // the byte before (the induction's strengthening: as the byte now)
        if (p_any) begin
            assert(p_hdr + p_sub + p_body + p_dropped == 1);
            if (p_hdr) assert(p_idx <= 5'd19);
            if (p_sub) assert(p_idx <= 5'd3);
            if (p_last) assert(p_body);
            if (p_empty) assert(p_sub && p_idx == 5'd3);
            if (p_bad) assert(p_hdr);
        end
        if (dropped_since) assert(p_any && !p_tl && past_hdr_18);
        // where the byte offered now is (whether or not it is taken), from the one taken before
        if (!p_any || p_tl) assert(m_hdr && m_idx == 5'd0);       // nothing past a TLAST
        else if (dropped_since || (p_drop && past_hdr_18) || p_dropped) assert(m_dropped);
        else if (p_hdr) begin
            if (p_idx != 5'd19) assert(m_hdr && m_idx == p_idx + 5'd1);
            else if (p_bad) assert(m_dropped);
            else assert(m_subhdr && m_idx == 5'd0);
        end else if (p_sub) begin
            if (p_idx != 5'd3) assert(m_subhdr && m_idx == p_idx + 5'd1);
            else if (p_empty) assert(m_subhdr && m_idx == 5'd0);
            else assert(m_body && m_sub_pos == 16'd0);
        end else if (p_body) begin
            if (p_last) assert(m_subhdr && m_idx == 5'd0);
            else assert(m_body && m_sub_pos == p_pos + 16'd1);
        end
        if (take) begin
`ifndef FV_PROVE
            // against the bytes themselves
            if (m_hdr) assert(m_hdr_bad == ((m_idx == 5'd19) ? f_bad : tl));
            if (m_subhdr && m_idx >= 5'd1) assert(m_sub_id == f_id);
            if (m_subhdr && m_idx >= 5'd2) assert(m_sub_flags == f_flags);
            if (m_subhdr && m_idx == 5'd3) begin
                assert(m_sub_len == len_n);
                assert(m_sub_empty == (len_n == 16'd0 && (f_id == ID_PAD || f_id == ID_INFO_TS)));
            end
            if (m_body) begin
                assert(m_sub_id == f_id && m_sub_flags == f_flags);
                assert(m_sub_mis == (f_len[1:0] != 2'd0));
                if (f_len != 16'd0) begin
                    assert(m_sub_pos < f_len);
                    assert(m_sub_last == (m_sub_pos == f_len - 16'd1));
                end else assert(m_sub_last == tl);
            end
`endif
        end
    end
endmodule
