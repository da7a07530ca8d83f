// rfl_rtps_tx -- the RTPS transmit path (issue #31): the generated wire: cdr top's publisher
// records in (8-bit byte stream, no TLAST: a sample's length, 4 bytes little-endian, then its
// serialized payload with the encapsulation header), RTPS datagrams of the node's data writer
// out (one UDP payload per AXI4-Stream packet, TLAST on its last byte), a byte per clock.
//
// A sample's datagrams, as the software participant builds them (rtps.build; participant_base
// _sample_subs): the 20-byte header (RTPS 2.3, vendor 0x0000, GUID_PREFIX), INFO_TS (with
// INFO_TS = 1: cfg_time, {seconds, fraction}, sampled when the record's first byte is taken:
// the same time in every datagram of the sample), then
//   DATA (flags E|D; readerId READER_ID, writerId WRITER_ID, writerSN) when the padded sample
//       fits FRAG_BYTES, else
//   DATA_FRAG, one per datagram (fragmentStartingNum 1, 2, ..; fragmentsInSubmessage 1;
//       fragmentSize FRAG_BYTES; sampleSize the padded length),
// and in the sample's last datagram a HEARTBEAT (no F flag: readers answer; reader READER_ID).
// The payload goes out as rtps.build.pad_payload makes it: a length L not a multiple of 4 gets
// 4 - L % 4 zeros at the end, announced in the encapsulation options' low 2 bits (byte 3 of
// the payload; untouched when L % 4 == 0 or L < 4), so every fragment but the last is
// FRAG_BYTES and no DATA_FRAG needs padding of its own (FRAG_BYTES is a multiple of 4).
// No INFO_DST: the datagrams are for any participant (the UDP side sends them to each matched
// reader's locator, or to a multicast group); READER_ID 0 (ENTITYID_UNKNOWN) reaches every
// reader of the topic there.
// Streaming: L is known from the record's first 4 bytes, so every length field is written
// before the payload and no sample is stored: the payload passes from the input to the output
// register. The writer's history holds nothing: the HEARTBEAT says firstSN = writerSN + 1,
// lastSN = writerSN (RTPS 2.3 8.3.7.5: no sample available), so a reliable reader that lost
// the sample learns at once that it will not come again (as from a GAP) instead of asking for
// it; its count is writerSN's low 32 bits (one HEARTBEAT per sample: it rises by one each).
// writerSN counts the samples sent from 1. A record of length 0 sends nothing; one longer than
// MAX_SAMPLE is taken and thrown away (both counted in cnt_dropped, no writerSN used).
// How (st): S_LEN takes the 4 length bytes; S_P1, S_P2 (no input) register the padded length
// w4 and the DATA / DATA_FRAG choice; per datagram S_P3 its payload bytes, S_P4 loads the
// header, INFO_TS and submessage fields into one shift register (every length already
// registered), S_HDR shifts them out, S_PAY sends the payload bytes (input bytes, then the
// padding zeros), S_HB the HEARTBEAT from the same shift register.
// Bounded: a sample of L bytes (4 + L in) sends L rounded up to 4, plus per datagram the header
// (20), INFO_TS (12 * INFO_TS) and DATA (24) or DATA_FRAG (36), plus one HEARTBEAT (32): at most
// 80 + 12 * INFO_TS bytes for 5 in (L = 1), 1 + (56 + 12 * INFO_TS) / FRAG_BYTES per byte for a
// large one; a dropped record sends nothing. The input waits only on the output's TREADY, while
// the header and HEARTBEAT go out, and the clocks without output (2 per datagram: S_P3, S_P4;
// 2 more per sample: S_P1, S_P2).
// Timing: the output register is the register slice (m_axis_* from flip-flops); the fields are
// registered a state before the shift register loads them; 32/16-bit counters count down with
// their "last" flags registered.
`default_nettype none

module rfl_rtps_tx #(
    // the defaults are rtl.discrom.tx_parameters of a shipped wire: cdr configuration (the
    // lab's fabric GUID prefix, the output topic's writer); a project passes its own
    parameter [95:0] GUID_PREFIX = 96'h010f_7266_6c46_4142_5249_4300,
    parameter [31:0] WRITER_ID = 32'h00000203,  // the data writer's entity id (a writer kind)
    parameter [31:0] READER_ID = 32'd0,         // 0 (ENTITYID_UNKNOWN) or a reader's entity id
    parameter FRAG_BYTES = 1344,                // DATA_FRAG fragment size: 4..65532, 4 | it
    parameter MAX_DATAGRAM = 1472,              // largest UDP payload sent: at most 65507
    parameter MAX_SAMPLE = 16777216,            // longest record sent: 1..2**31-1 bytes
    parameter INFO_TS = 1,                      // 1: INFO_TS(cfg_time) in every datagram
    parameter COUNT_BITS = 32                   // width of the counters: 1..32
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [63:0]           cfg_time,      // {seconds, fraction of 2**32}: INFO_TS
    input  wire [7:0]            s_tdata,       // records: length (LE32), payload
    input  wire                  s_tvalid,
    output wire                  s_tready,
    output wire [7:0]            m_axis_tdata,  // RTPS datagrams (UDP payloads)
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  m_axis_tlast,
    output wire [63:0]           m_seq,         // the writerSN of the next sample sent
    output wire [COUNT_BITS-1:0] cnt_samples,   // samples sent
    output wire [COUNT_BITS-1:0] cnt_datagrams, // datagrams sent
    output wire [COUNT_BITS-1:0] cnt_dropped    // records of length 0 or over MAX_SAMPLE
);
    localparam HEAD_BYTES = 20 + 12 * INFO_TS + 36;    // header, INFO_TS, DATA_FRAG's fields
    localparam MIN_DATAGRAM = HEAD_BYTES + FRAG_BYTES + 32;

    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (GUID_PREFIX == 96'd0)
            $fatal(1, "rfl_rtps_tx: GUID_PREFIX must be the participant's, not 0");
        if (WRITER_ID[5:0] != 6'h02 && WRITER_ID[5:0] != 6'h03)
            $fatal(1, "rfl_rtps_tx: WRITER_ID must be a writer's entity id (kind 0x02/0x03)");
        if (READER_ID != 32'd0 && READER_ID[5:0] != 6'h04 && READER_ID[5:0] != 6'h07)
            $fatal(1, "rfl_rtps_tx: READER_ID must be 0 or a reader's entity id (kind 0x04/0x07)");
        if (FRAG_BYTES < 4 || FRAG_BYTES > 65532 || FRAG_BYTES % 4 != 0)
            $fatal(1, "rfl_rtps_tx: FRAG_BYTES must be 4..65532 and a multiple of 4");
        if (MAX_DATAGRAM > 65507 || MAX_DATAGRAM < MIN_DATAGRAM)
            $fatal(1, {"rfl_rtps_tx: MAX_DATAGRAM must be at most 65507 and hold a ",
                       "DATA_FRAG's datagram"});
        if (MAX_SAMPLE < 1 || MAX_SAMPLE > 2147483647)
            $fatal(1, "rfl_rtps_tx: MAX_SAMPLE must be 1..2**31-1");
        if (INFO_TS != 0 && INFO_TS != 1) $fatal(1, "rfl_rtps_tx: INFO_TS must be 0 or 1");
        if (COUNT_BITS < 1 || COUNT_BITS > 32) $fatal(1, "rfl_rtps_tx: COUNT_BITS must be 1..32");
    end
`else
    if (GUID_PREFIX == 96'd0) begin : g_bad_prefix
        $error("rfl_rtps_tx: GUID_PREFIX must be the participant's, not 0");
    end
    if (WRITER_ID[5:0] != 6'h02 && WRITER_ID[5:0] != 6'h03) begin : g_bad_writer
        $error("rfl_rtps_tx: WRITER_ID must be a writer's entity id (kind 0x02/0x03)");
    end
    if (READER_ID != 32'd0 && READER_ID[5:0] != 6'h04 && READER_ID[5:0] != 6'h07)
    begin : g_bad_reader
        $error("rfl_rtps_tx: READER_ID must be 0 or a reader's entity id (kind 0x04/0x07)");
    end
    if (FRAG_BYTES < 4 || FRAG_BYTES > 65532 || FRAG_BYTES % 4 != 0) begin : g_bad_frag
        $error("rfl_rtps_tx: FRAG_BYTES must be 4..65532 and a multiple of 4");
    end
    if (MAX_DATAGRAM > 65507 || MAX_DATAGRAM < MIN_DATAGRAM) begin : g_bad_datagram
        $error("rfl_rtps_tx: MAX_DATAGRAM must be at most 65507 and hold a DATA_FRAG's datagram");
    end
    if (MAX_SAMPLE < 1 || MAX_SAMPLE > 2147483647) begin : g_bad_sample
        $error("rfl_rtps_tx: MAX_SAMPLE must be 1..2**31-1");
    end
    if (INFO_TS != 0 && INFO_TS != 1) begin : g_bad_ts
        $error("rfl_rtps_tx: INFO_TS must be 0 or 1");
    end
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_rtps_tx: COUNT_BITS must be 1..32");
    end
`endif

    localparam SHW = 8 * HEAD_BYTES;
`include "rfl_rtps_wire.vh"             // ID_*, RTPS_MAGIC, RTPS_VERSION, FLAG_E
    localparam [31:0] FRAG_32 = FRAG_BYTES;
    localparam [31:0] MAX_32 = MAX_SAMPLE;
    localparam [6:0] N_FRAG = HEAD_BYTES, N_DATA = HEAD_BYTES - 12, N_HB = 7'd32;
    localparam [3:0] S_LEN = 4'd0, S_P1 = 4'd1, S_P2 = 4'd2, S_P3 = 4'd3, S_P4 = 4'd4,
                     S_HDR = 4'd5, S_PAY = 4'd6, S_HB = 4'd7, S_SKIP = 4'd8;

    function [31:0] le32(input [31:0] x);
        le32 = {x[7:0], x[15:8], x[23:16], x[31:24]};
    endfunction
    function [15:0] le16(input [15:0] x);
        le16 = {x[7:0], x[15:8]};
    endfunction

    reg [3:0] st;
    reg [1:0] li;                               // S_LEN: the length byte taken
    reg [31:0] len;                             // the sample's length L
    /* verilator lint_off UNUSEDSIGNAL */
    reg [63:0] ts;                              // its INFO_TS time (unused with INFO_TS = 0)
    /* verilator lint_on UNUSEDSIGNAL */
    reg zero, big;                              // L == 0, L > MAX_SAMPLE
    reg [31:0] w4;                              // L rounded up to 4 (DATA's bytes, sampleSize)
    reg [1:0] padc;                             // w4 - L: the options' padding count
    reg frag;                                   // the sample goes as DATA_FRAGs
    reg [31:0] rem;                             // bytes of w4 not yet in a datagram
    reg [31:0] in_left;                         // record bytes still to take
    reg inz;                                    // in_left == 0
    reg [15:0] fb;                              // this datagram's payload bytes
    reg last_dg;                                // this datagram is the sample's last
    reg [31:0] fnum;                            // fragmentStartingNum
    reg [15:0] pay_left;
    reg pl1;                                    // pay_left == 1
    reg [2:0] nb;                               // payload bytes taken, up to 4
    reg [SHW-1:0] sh;                           // the fields going out, first byte on top
    reg [6:0] hcnt;
    reg h1;                                     // hcnt == 1
    reg [63:0] seq, seq1;                       // writerSN, writerSN + 1
    reg p_sample, p_dg, p_drop;                 // counter pulses

    // the output register (the register slice)
    reg [7:0] o_data;
    reg o_valid, o_last;
    wire o_free = !o_valid || m_axis_tready;
    assign s_tready = (st == S_LEN) || (st == S_SKIP) || (st == S_PAY && !inz && o_free);
    wire take = s_tvalid && s_tready;
    wire pay_go = o_free && (inz || s_tvalid);  // S_PAY: a payload byte goes out
    wire [7:0] pay_byte = inz ? 8'h00 :
                          (nb == 3'd3 && padc != 2'd0) ? {s_tdata[7:2], padc} : s_tdata;

    // what S_P4 loads: header, INFO_TS, DATA / DATA_FRAG fields (DATA uses the first N_DATA)
    wire [15:0] sublen = fb + (frag ? 16'd32 : 16'd20);
    wire [159:0] v_hdr = {RTPS_MAGIC, RTPS_VERSION, RTPS_VENDOR, GUID_PREFIX};
    wire [191:0] v_sub = {frag ? ID_DATA_FRAG : ID_DATA, frag ? FLAG_E : FLAG_E | 8'h04,  // D
                          le16(sublen), 16'h0000,
                          frag ? 16'h1C00 : 16'h1000, READER_ID, WRITER_ID, le32(seq[63:32]),
                          le32(seq[31:0])};
    wire [95:0] v_frag = {le32(fnum), 16'h0100, le16(FRAG_32[15:0]), le32(w4)};
    wire [SHW-1:0] v_head;
    generate
        if (INFO_TS != 0) begin : g_ts
            assign v_head = {v_hdr, ID_INFO_TS, FLAG_E, 16'h0800, le32(ts[63:32]),
                             le32(ts[31:0]), v_sub, v_frag};
        end else begin : g_no_ts
            assign v_head = {v_hdr, v_sub, v_frag};
        end
    endgenerate
    wire [255:0] v_hb = {ID_HEARTBEAT, FLAG_E, 16'h1C00, READER_ID, WRITER_ID,
                         le32(seq1[63:32]), le32(seq1[31:0]), le32(seq[63:32]), le32(seq[31:0]),
                         le32(seq[31:0])};

    task emit(input [7:0] d, input l);
        begin
            o_valid <= 1'b1;
            o_data <= d;
            o_last <= l;
        end
    endtask

    always @(posedge clk) begin
        p_sample <= 1'b0;
        p_dg <= 1'b0;
        p_drop <= 1'b0;
        if (m_axis_tready) o_valid <= 1'b0;
        if (!rst_n) begin
            st <= S_LEN;
            li <= 2'd0;
            o_valid <= 1'b0;
            seq <= 64'd1;
            seq1 <= 64'd2;
        end else begin
            case (st)
            S_LEN: if (take) begin
                len <= {s_tdata, len[31:8]};
                li <= li + 2'd1;
                if (li == 2'd0) ts <= cfg_time;
                if (li == 2'd3) st <= S_P1;
            end
            S_P1: begin
                zero <= (len == 32'd0);
                big <= (len > MAX_32);
                w4 <= {len[31:2] + {29'd0, |len[1:0]}, 2'b00};
                padc <= 2'd0 - len[1:0];
                in_left <= len;
                inz <= 1'b0;
                nb <= 3'd0;
                st <= S_P2;
            end
            S_P2: begin
                if (zero || big) p_drop <= 1'b1;
                frag <= (w4 > FRAG_32);
                rem <= w4;
                fnum <= 32'd1;
                st <= zero ? S_LEN : big ? S_SKIP : S_P3;
            end
            S_P3: begin
                last_dg <= !frag || (rem <= FRAG_32);
                fb <= (!frag || rem <= FRAG_32) ? rem[15:0] : FRAG_32[15:0];
                st <= S_P4;
            end
            S_P4: begin
                sh <= v_head;
                hcnt <= frag ? N_FRAG : N_DATA;
                h1 <= 1'b0;
                pay_left <= fb;
                pl1 <= (fb == 16'd1);
                st <= S_HDR;
            end
            S_HDR: if (o_free) begin
                emit(sh[SHW-1 -: 8], 1'b0);
                sh <= sh << 8;
                hcnt <= hcnt - 7'd1;
                h1 <= (hcnt == 7'd2);
                if (h1) st <= S_PAY;
            end
            S_PAY: if (pay_go) begin
                emit(pay_byte, pl1 && !last_dg);
                if (!inz) begin
                    in_left <= in_left - 32'd1;
                    inz <= (in_left == 32'd1);
                    if (!nb[2]) nb <= nb + 3'd1;
                end
                pay_left <= pay_left - 16'd1;
                pl1 <= (pay_left == 16'd2);
                if (pl1) begin
                    rem <= rem - {16'd0, fb};
                    if (last_dg) begin
                        sh <= {v_hb, {(SHW - 256){1'b0}}};
                        hcnt <= N_HB;
                        h1 <= 1'b0;
                        st <= S_HB;
                    end else begin
                        p_dg <= 1'b1;
                        fnum <= fnum + 32'd1;
                        st <= S_P3;
                    end
                end
            end
            S_HB: if (o_free) begin
                emit(sh[SHW-1 -: 8], h1);
                sh <= sh << 8;
                hcnt <= hcnt - 7'd1;
                h1 <= (hcnt == 7'd2);
                if (h1) begin
                    p_dg <= 1'b1;
                    p_sample <= 1'b1;
                    seq <= seq1;
                    seq1 <= seq1 + 64'd1;
                    st <= S_LEN;
                end
            end
            S_SKIP: if (take) begin
                in_left <= in_left - 32'd1;
                if (in_left == 32'd1) st <= S_LEN;
            end
            default: st <= S_LEN;
            endcase
        end
    end

    // counters (a clock after the event)
    reg [COUNT_BITS-1:0] c_samples, c_dg, c_drop;
    always @(posedge clk) begin
        if (!rst_n) begin
            c_samples <= {COUNT_BITS{1'b0}};
            c_dg <= {COUNT_BITS{1'b0}};
            c_drop <= {COUNT_BITS{1'b0}};
        end else begin
            c_samples <= c_samples + {{(COUNT_BITS-1){1'b0}}, p_sample};
            c_dg <= c_dg + {{(COUNT_BITS-1){1'b0}}, p_dg};
            c_drop <= c_drop + {{(COUNT_BITS-1){1'b0}}, p_drop};
        end
    end

`ifdef FORMAL
    // Framing on the ports, with the invariants that make it inductive (fv_rtps_tx proves
    // them): f_pos counts the bytes of the current datagram the sink has taken; every datagram
    // opens with the magic's "R" and is at most MAX_DATAGRAM bytes, TLAST on its last byte.
    // f_fresh: between datagrams (nothing of one out, or its TLAST beat still offered).
    reg [15:0] f_pos;
    always @(posedge clk) begin
        if (!rst_n) f_pos <= 16'd0;
        else if (m_axis_tvalid && m_axis_tready) f_pos <= m_axis_tlast ? 16'd0 : f_pos + 16'd1;
    end
    localparam [15:0] F_MAX = MAX_DATAGRAM;
    wire [15:0] f_h = {9'd0, frag ? N_FRAG : N_DATA};
    wire [15:0] f_e = f_pos + {15'd0, o_valid};
    wire f_fresh = (!o_valid && f_pos == 16'd0) ||
                   (o_valid && o_last && f_pos != 16'd0 && f_pos < F_MAX);
    wire f_fb = fb != 16'd0 && fb <= FRAG_32[15:0] &&
                (last_dg || (frag && fb == FRAG_32[15:0] && rem > FRAG_32));
    always @(*) if (rst_n) begin
        assert(f_e <= F_MAX);                                   // no datagram longer
        if (o_valid && f_pos == 16'd0) assert(o_data == RTPS_MAGIC[31:24]);  // "RTPS" first
        assert(st <= S_SKIP);
        case (st)
        S_P2: assert(f_fresh && (zero || big || w4 != 32'd0));
        S_P3: assert(f_fresh && rem != 32'd0 && (frag || rem <= FRAG_32));
        S_P4: assert(f_fresh && f_fb);
        S_HDR: begin
            assert(f_fb && hcnt != 7'd0 && {9'd0, hcnt} <= f_h && h1 == (hcnt == 7'd1));
            assert(pay_left == fb && pl1 == (fb == 16'd1));
            if ({9'd0, hcnt} == f_h) assert(f_fresh && sh[SHW-1 -: 8] == RTPS_MAGIC[31:24]);
            else assert(!(o_valid && o_last) && f_e == f_h - {9'd0, hcnt});
        end
        S_PAY: begin
            assert(f_fb && pay_left != 16'd0 && pay_left <= fb && pl1 == (pay_left == 16'd1));
            assert(!(o_valid && o_last) && f_e == f_h + fb - pay_left);
        end
        S_HB: begin
            assert(f_fb && hcnt != 7'd0 && hcnt <= N_HB && h1 == (hcnt == 7'd1));
            assert(!(o_valid && o_last) && f_e == f_h + fb + {9'd0, N_HB - hcnt});
        end
        default: assert(f_fresh);                               // S_LEN, S_P1, S_SKIP
        endcase
    end
`endif

    assign m_axis_tdata = o_data;
    assign m_axis_tvalid = o_valid;
    assign m_axis_tlast = o_last;
    assign m_seq = seq;
    assign cnt_samples = c_samples;
    assign cnt_datagrams = c_dg;
    assign cnt_dropped = c_drop;
endmodule

`default_nettype wire
