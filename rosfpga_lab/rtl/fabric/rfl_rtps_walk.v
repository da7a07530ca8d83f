// rfl_rtps_walk -- the RTPS message walk the fabric's receiving stages share (issue #31):
// rfl_rtps_rx (the data reader), rfl_rtps_ctrl (HEARTBEAT / ACKNACK) and rfl_spdp_peer (SPDP)
// each instantiate it beside their own field logic, so where the header, the submessage
// headers and the bodies are is decided once. It watches the stage's input stream (8-bit
// AXI4-Stream, TLAST on a datagram's last byte): in_data and in_last are its TDATA and TLAST,
// in_take its TVALID and TREADY (a byte taken). It tells, for the byte offered now, where it
// is (combinational from its registers, the byte and TLAST; it advances on each byte taken):
//   m_hdr      the 20-byte RTPS header, byte m_idx (0..19): "RTPS", major version 2, vendor
//              id, the sender's GUID prefix (bytes 8..19).
//   m_subhdr   a submessage header, byte m_idx (0..3): id, flags (FLAG_E: the byte order of
//              the rest), octetsToNextHeader (m_sub_len, at byte 3, in the flags' order).
//   m_body     a submessage body, byte m_sub_pos (from 0; counts modulo 2^POS_BITS).
//   m_dropped  the rest of a datagram abandoned (a bad header, or the stage's drop).
// With them: m_sub_id (from the submessage header's byte 1 on), m_sub_flags (from byte 2 on),
// m_sub_mis (the length is not a multiple of 4; in the body), m_sub_last (the body's last
// byte: its byte length - 1; a length 0 means "to the end of the message", the datagram's last
// byte), m_sub_empty (at a submessage header's byte 3: a PAD or INFO_TS of length 0, empty,
// this its last byte; the next is a submessage header), m_hdr_bad (at the header's byte 19:
// bad magic or major version; or at a TLAST before it: a datagram shorter than a header). A
// submessage cut short by the datagram's end (TLAST without m_sub_last) is the stage's to
// refuse; the next byte after a TLAST is always a header's byte 0.
// drop: abandon the rest of the datagram (no sideband but m_dropped up to its TLAST), with a
// byte taken (the header's last or any later one: the byte is walked, the ones after it are
// not) or in a clock without one (past the header). Ignored in the header before its byte 19
// and with a TLAST taken (the datagram ends anyway).
// Timing: the outputs decode registers (the state, the id's kind, sub_left == 1 registered)
// and the byte only where a length is read (m_sub_len, m_sub_empty).
`default_nettype none

module rfl_rtps_walk #(
    parameter POS_BITS = 16                     // m_sub_pos's width: 1..16, checked
) (
    input  wire                clk,
    input  wire                rst_n,
    input  wire [7:0]          in_data,         // the stage's input stream: TDATA,
    input  wire                in_take,         // TVALID and TREADY (a byte taken),
    input  wire                in_last,         // TLAST
    input  wire                drop,
    output wire                m_hdr,
    output wire                m_subhdr,
    output wire                m_body,
    output wire                m_dropped,
    output wire [4:0]          m_idx,
    output wire [7:0]          m_sub_id,
    output wire [7:0]          m_sub_flags,
    output wire [15:0]         m_sub_len,
    output wire [POS_BITS-1:0] m_sub_pos,
    output wire                m_sub_mis,
    output wire                m_sub_last,
    output wire                m_sub_empty,
    output wire                m_hdr_bad
);
`ifdef __ICARUS__
    initial begin
        if (POS_BITS < 1 || POS_BITS > 16) $fatal(1, "rfl_rtps_walk: POS_BITS must be 1..16");
    end
`else
    if (POS_BITS < 1 || POS_BITS > 16) begin : g_bad_pos_bits
        $error("rfl_rtps_walk: POS_BITS must be 1..16");
    end
`endif
`include "rfl_rtps_wire.vh"             // ID_PAD, ID_INFO_TS, RTPS_MAGIC, RTPS_VERSION, FLAG_E
    localparam [1:0] W_HDR = 2'd0, W_SUB = 2'd1, W_BODY = 2'd2, W_DROP = 2'd3;

    wire take = in_take;
    wire [7:0] b = in_data;
    wire tl = in_last;

    reg [1:0] st;
    reg [4:0] idx;
    reg hdr_bad;                                // bytes 0..4 so far: magic, major version
    reg [7:0] sub_id, flags, len_lo;
    reg k_empty;                                // PAD or INFO_TS: length 0 is empty
    reg [15:0] sub_left;                        // body bytes left (not with to_end)
    reg sl1, to_end, mis;                       // sub_left == 1, registered (timing)
    reg [POS_BITS-1:0] pos;

    wire [15:0] len_n = (flags & FLAG_E) != 8'd0 ? {b, len_lo} : {len_lo, b};
    wire empty_n = k_empty && (len_n == 16'd0);
    wire body_last = to_end ? tl : sl1;
    wire [7:0] magic = (idx[1:0] == 2'd0) ? RTPS_MAGIC[31:24] :
                       (idx[1:0] == 2'd1) ? RTPS_MAGIC[23:16] :
                       (idx[1:0] == 2'd2) ? RTPS_MAGIC[15:8] : RTPS_MAGIC[7:0];
    wire hdr_bad_n = ((idx != 5'd0) && hdr_bad) || ((idx < 5'd4) && (b != magic)) ||
                     ((idx == 5'd4) && (b != RTPS_VERSION[15:8]));

    assign m_hdr = (st == W_HDR);
    assign m_subhdr = (st == W_SUB);
    assign m_body = (st == W_BODY);
    assign m_dropped = (st == W_DROP);
    assign m_idx = idx;
    assign m_sub_id = sub_id;
    assign m_sub_flags = flags;
    assign m_sub_len = len_n;
    assign m_sub_pos = pos;
    assign m_sub_mis = mis;
    assign m_sub_last = m_body && body_last;
    assign m_sub_empty = m_subhdr && (idx == 5'd3) && empty_n;
    assign m_hdr_bad = m_hdr && (((idx == 5'd19) && hdr_bad) || (tl && (idx != 5'd19)));

    always @(posedge clk) begin
        if (!rst_n) begin
            st <= W_HDR;
            idx <= 5'd0;
            hdr_bad <= 1'b0;
        end else if (take) begin
            case (st)
            W_HDR: begin
                hdr_bad <= hdr_bad_n;
                if (tl) idx <= 5'd0;
                else if (idx == 5'd19) begin
                    idx <= 5'd0;
                    st <= (hdr_bad || drop) ? W_DROP : W_SUB;
                end else idx <= idx + 5'd1;
            end
            W_SUB: begin
                idx <= idx + 5'd1;
                pos <= {POS_BITS{1'b0}};
                if (idx == 5'd0) begin
                    sub_id <= b;
                    k_empty <= (b == ID_PAD) || (b == ID_INFO_TS);
                end
                if (idx == 5'd1) flags <= b;
                if (idx == 5'd2) len_lo <= b;
                if (idx == 5'd3) begin
                    sub_left <= len_n;
                    sl1 <= (len_n == 16'd1);
                    to_end <= (len_n == 16'd0) && !k_empty;
                    mis <= (len_n[1:0] != 2'd0);
                end
                if (tl || drop || idx == 5'd3) idx <= 5'd0;
                if (tl) st <= W_HDR;
                else if (drop) st <= W_DROP;
                else if (idx == 5'd3 && !empty_n) st <= W_BODY;
            end
            W_BODY: begin
                pos <= pos + {{(POS_BITS-1){1'b0}}, 1'b1};
                sub_left <= sub_left - 16'd1;
                sl1 <= (sub_left == 16'd2);
                if (tl) st <= W_HDR;
                else if (drop) st <= W_DROP;
                else if (body_last) st <= W_SUB;
            end
            default: if (tl) st <= W_HDR;        // W_DROP: the rest of the datagram
            endcase
        end else if (drop && st != W_HDR) begin
            st <= W_DROP;
            idx <= 5'd0;
        end
    end
`ifdef FORMAL
    // the registers' invariants (fv_rtps_walk's induction): the index in range, none past
    // the header while dropped, sl1 is sub_left == 1
    always @(posedge clk) if (rst_n) begin
        if (st == W_HDR) assert(idx <= 5'd19);
        if (st == W_SUB) assert(idx <= 5'd3);
        if (st == W_BODY || st == W_DROP) assert(idx == 5'd0);
        if (st == W_BODY && !to_end) assert(sl1 == (sub_left == 16'd1) && sub_left != 16'd0);
    end
`endif
endmodule

`default_nettype wire
