// rfl_rtps_to_cdr -- the seam between rfl_rtps_rx and a generated wire: cdr circuit (issue #31):
// a sample packet of rfl_rtps_rx in (8-bit AXI4-Stream, TLAST on its last byte, TUSER on the
// TLAST beat: dropped), the record the generated subscriber (rfl_gsubscriber, CDR) reads out:
// the sample's length (4 bytes, little-endian), then the serialized payload as carried
// (the 4-byte encapsulation header, the CDR data, the end padding).
//
// What the subscriber takes: one record after another on a byte stream, with no frame flag
// and no abort; it knows a record's end by the length in front. So nothing of a sample may go
// out before its last byte has come in good: the length is known only then, and a sample that
// ends with TUSER (a fragment missing, a malformed submessage) must not reach the subscriber.
// Hence store and forward, through a ring of RING = 2 x 2**clog2(MAX_BYTES) bytes (one block
// RAM, one write port, one registered read port) that holds the records themselves, so that
// samples fill it while earlier records go out:
//   Fill    a sample's bytes go in a byte per clock behind 4 bytes kept free for its length.
//           At TLAST: TUSER set -> discarded (cnt_dropped); more than MAX_BYTES bytes ->
//           discarded (cnt_too_long; the bytes past MAX_BYTES are taken and thrown away, never
//           a stall on them); else kept: its length goes in the 4 bytes kept for it, one a
//           clock (the input waits these 4 clocks), and the record is handed to the send side.
//           A discarded sample's space is taken back at once.
//   Send    the records handed over, a byte per clock while TREADY, through the RAM's read
//           register (cnt_samples at a record's last byte). No TLAST: the subscriber's byte
//           stream has none (the length says where a record ends).
// The input waits only for those 4 clocks after a kept sample, or while the ring is full (a
// byte of a sample still within MAX_BYTES, no room). A record is its sample + 4 bytes, the
// input's 4 clocks of waiting: with samples back to back and TREADY high, samples and records
// go through a byte a clock (the input waits exactly 4 clocks a kept sample; the ring never
// fills: it holds the record going out and the sample coming in, at most MAX_BYTES + 8 bytes,
// less than RING once MAX_BYTES > 8), and a record's first byte goes out 6 clocks after its
// sample's last byte came in.
// With the output stopped, the ring takes two records when their samples total at most
// RING - 8 bytes (two of MAX_BYTES when it is at most 2**clog2(MAX_BYTES) - 4).
// Block RAM on an ECP5 (DP16KD, 2048 x 9): RING / 2048 blocks, at least one (or LUT RAM, as
// Yosys picks): MAX_BYTES 2048 (rfl_fabric_node's default, the board's) 2, 4096 4, 16384 16.
// The padding the encapsulation options declare (their low 2 bits) is not stripped here: the
// subscriber reads it from the header and skips it after the last field (OP_ENCAP, S_SKIP), as
// Cyclone DDS's unannounced zeros to a multiple of 4 (S_TAIL); the lab's CDR models take the
// same record (a length, then the payload as on the wire).
// An empty good packet cannot come (rfl_rtps_rx ends each packet with a byte); a record of 1..3
// bytes goes out and the subscriber refuses it by its length.
`default_nettype none

module rfl_rtps_to_cdr #(
    parameter MAX_BYTES = 4096,                 // the longest sample taken: 4..2**24, checked
    parameter COUNT_BITS = 32                   // width of the counters: 1..32, checked
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,
    input  wire                  s_axis_tlast,
    input  wire                  s_axis_tuser,  // with TLAST: the sample is dropped
    output wire [7:0]            m_tdata,       // records: length (LE32), payload
    output wire                  m_tvalid,
    input  wire                  m_tready,
    output wire [COUNT_BITS-1:0] cnt_samples,   // records sent
    output wire [COUNT_BITS-1:0] cnt_dropped,   // samples that ended with TUSER
    output wire [COUNT_BITS-1:0] cnt_too_long   // samples longer than MAX_BYTES
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (MAX_BYTES < 4 || MAX_BYTES > 16777216)
            $fatal(1, "rfl_rtps_to_cdr: MAX_BYTES must be 4..2**24");
        if (COUNT_BITS < 1 || COUNT_BITS > 32)
            $fatal(1, "rfl_rtps_to_cdr: COUNT_BITS must be 1..32");
    end
`else
    if (MAX_BYTES < 4 || MAX_BYTES > 16777216) begin : g_bad_max_bytes
        $error("rfl_rtps_to_cdr: MAX_BYTES must be 4..2**24");
    end
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_rtps_to_cdr: COUNT_BITS must be 1..32");
    end
`endif

    localparam AW = $clog2(MAX_BYTES);
    localparam RW = AW + 1;                     // ring address: RING = 2**RW bytes
    localparam PW = AW + 2;                     // ring pointers, a bit more (a full ring)
    localparam NW = $clog2(MAX_BYTES + 1);      // a sample's length, 0..MAX_BYTES
    localparam [31:0] MAX_32 = MAX_BYTES;
    localparam [NW-1:0] FULL = MAX_32[NW-1:0];
    localparam [PW-1:0] RING = {1'b1, {RW{1'b0}}};
    localparam [PW-1:0] LEN_BYTES = 4;

    reg [7:0] mem [0:(1 << RW)-1];
    // fill side
    reg [PW-1:0] cp;                            // the record being filled starts here
    reg [PW-1:0] wp;                            // the next sample byte goes here (cp + 4 + n)
    reg [NW-1:0] n;                             // bytes of the sample stored
    reg hdr;                                    // writing the kept sample's length at cp
    reg [1:0] hi;                               // ... its byte hi
    reg [NW-1:0] klen;                          // ... the length
    // send side
    reg [PW-1:0] ce;                            // the records handed over end here
    reg [PW-1:0] rp;                            // the next byte read from the ring
    reg [7:0] q;                                // the RAM's read register
    reg qvalid;
    reg body;                                   // a record's body is going out (else its length)
    reg [1:0] oi;                               // length bytes out
    reg [31:0] ol;                              // the length as it went out; then bytes left
    reg [COUNT_BITS-1:0] c_samples, c_dropped, c_too_long;

    wire [PW-1:0] used = wp - rp;               // at most RING + 3: a ring's worth + the 4 kept
    wire room = (used < RING);
    wire full = (n == FULL);
    assign s_axis_tready = !hdr && (room || full);
    wire take = s_axis_tvalid && s_axis_tready;
    wire wr = take && !full;
    wire fin = take && s_axis_tlast;
    wire keep = fin && !s_axis_tuser && !full;
    wire [31:0] klen32 = {{(32 - NW){1'b0}}, klen};
    wire [7:0] hbyte = (hi == 2'd0) ? klen32[7:0] : (hi == 2'd1) ? klen32[15:8] :
                       (hi == 2'd2) ? klen32[23:16] : klen32[31:24];
    wire [RW-1:0] haddr = cp[RW-1:0] + {{(RW - 2){1'b0}}, hi};
    wire load = (rp != ce) && (!qvalid || m_tready);
    wire pop = qvalid && m_tready;
    assign m_tvalid = qvalid;
    assign m_tdata = q;
    assign cnt_samples = c_samples;
    assign cnt_dropped = c_dropped;
    assign cnt_too_long = c_too_long;

    always @(posedge clk) begin
        if (hdr) mem[haddr] <= hbyte;
        else if (wr) mem[wp[RW-1:0]] <= s_axis_tdata;
        if (load) q <= mem[rp[RW-1:0]];
    end

    always @(posedge clk) begin
        if (!rst_n) begin
            cp <= {PW{1'b0}};
            wp <= LEN_BYTES;
            n <= {NW{1'b0}};
            hdr <= 1'b0;
            hi <= 2'd0;
            klen <= {NW{1'b0}};
            ce <= {PW{1'b0}};
            rp <= {PW{1'b0}};
            qvalid <= 1'b0;
            body <= 1'b0;
            oi <= 2'd0;
            ol <= 32'd0;
            c_samples <= {COUNT_BITS{1'b0}};
            c_dropped <= {COUNT_BITS{1'b0}};
            c_too_long <= {COUNT_BITS{1'b0}};
        end else begin
            // ---- fill
            if (wr) begin
                wp <= wp + 1'b1;
                n <= n + 1'b1;
            end
            if (fin) begin
                n <= {NW{1'b0}};
                if (s_axis_tuser) c_dropped <= c_dropped + 1'b1;
                else if (full) c_too_long <= c_too_long + 1'b1;
                if (keep) begin
                    klen <= n + 1'b1;
                    hdr <= 1'b1;
                    hi <= 2'd0;
                end else begin
                    wp <= cp + LEN_BYTES;       // the space taken back
                end
            end
            if (hdr) begin
                hi <= hi + 2'd1;
                if (hi == 2'd3) begin           // the record is whole: hand it over
                    hdr <= 1'b0;
                    ce <= wp;
                    cp <= wp;
                    wp <= wp + LEN_BYTES;
                end
            end
            // ---- send
            if (load) rp <= rp + 1'b1;
            if (load) qvalid <= 1'b1;
            else if (pop) qvalid <= 1'b0;
            if (pop) begin
                if (!body) begin
                    ol <= {q, ol[31:8]};
                    oi <= oi + 2'd1;
                    if (oi == 2'd3) body <= 1'b1;
                end else begin
                    ol <= ol - 32'd1;
                    if (ol == 32'd1) begin
                        body <= 1'b0;
                        c_samples <= c_samples + 1'b1;
                    end
                end
            end
        end
    end
endmodule
`default_nettype wire
