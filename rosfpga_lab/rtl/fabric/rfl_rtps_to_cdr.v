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
// Hence store and forward: one buffer of MAX_BYTES bytes (a RAM with a registered read).
//   S_FILL  input taken a byte per clock into the buffer. At TLAST: TUSER set -> the sample is
//           discarded (cnt_dropped); more than MAX_BYTES bytes -> discarded (cnt_too_long;
//           the bytes past the buffer are taken and thrown away, never a stall on them);
//           else -> S_LEN.
//   S_LEN   the length's four bytes out (the RAM's first byte read meanwhile); then S_BODY.
//   S_BODY  the buffer out, a byte per clock while TREADY; then S_FILL (cnt_samples). No
//           TLAST: the subscriber's byte stream has none (the length says where a record ends).
// The input waits (TREADY low) in S_LEN and S_BODY: one sample at a time, so a sample costs
// its length in clocks twice plus 5. Two buffers would overlap filling and sending; the
// subscriber's own rx FIFO (RX_DEPTH) takes the record at a byte per clock meanwhile.
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

    localparam AW = $clog2(MAX_BYTES);          // buffer address
    localparam NW = $clog2(MAX_BYTES + 1);      // a sample's length, 0..MAX_BYTES
    localparam [31:0] MAX_32 = MAX_BYTES;
    localparam [NW-1:0] FULL = MAX_32[NW-1:0];
    localparam [1:0] S_FILL = 2'd0, S_LEN = 2'd1, S_BODY = 2'd2;

    reg [1:0] st;
    reg [7:0] mem [0:(1 << AW)-1];             // MAX_BYTES used
    reg [NW-1:0] n;                             // S_FILL: bytes stored; S_LEN, S_BODY: the length
    reg over;                                   // S_FILL: the sample did not fit
    reg [AW-1:0] ra;                            // the next byte read from the buffer
    reg [NW-1:0] rleft;                         // bytes still to read from the buffer
    reg [NW-1:0] oleft;                         // S_BODY: bytes still to send
    reg [7:0] q;                                // the RAM's read register
    reg qvalid;
    reg [1:0] li;                               // S_LEN: the length byte out
    reg [COUNT_BITS-1:0] c_samples, c_dropped, c_too_long;

    wire full = (n == FULL);
    assign s_axis_tready = (st == S_FILL);
    wire take = s_axis_tvalid && s_axis_tready;
    wire wr = take && !full;
    wire [31:0] len32 = {{(32 - NW){1'b0}}, n};
    wire [7:0] len_byte = (li == 2'd0) ? len32[7:0] : (li == 2'd1) ? len32[15:8] :
                          (li == 2'd2) ? len32[23:16] : len32[31:24];
    assign m_tvalid = (st == S_LEN) || (st == S_BODY && qvalid);
    assign m_tdata = (st == S_LEN) ? len_byte : q;
    wire pop = m_tvalid && m_tready;
    wire pop_body = pop && (st == S_BODY);
    wire load = (st != S_FILL) && (rleft != {NW{1'b0}}) && (!qvalid || pop_body);
    assign cnt_samples = c_samples;
    assign cnt_dropped = c_dropped;
    assign cnt_too_long = c_too_long;

    always @(posedge clk) begin
        if (wr) mem[n[AW-1:0]] <= s_axis_tdata;
        if (load) q <= mem[ra];
    end

    always @(posedge clk) begin
        if (!rst_n) begin
            st <= S_FILL;
            n <= {NW{1'b0}};
            over <= 1'b0;
            ra <= {AW{1'b0}};
            rleft <= {NW{1'b0}};
            oleft <= {NW{1'b0}};
            qvalid <= 1'b0;
            li <= 2'd0;
            c_samples <= {COUNT_BITS{1'b0}};
            c_dropped <= {COUNT_BITS{1'b0}};
            c_too_long <= {COUNT_BITS{1'b0}};
        end else begin
            if (load) begin
                ra <= ra + 1'b1;
                rleft <= rleft - 1'b1;
            end
            if (load) qvalid <= 1'b1;
            else if (pop_body) qvalid <= 1'b0;
            case (st)
                S_FILL: if (take) begin
                    if (wr) n <= n + 1'b1;
                    if (full) over <= 1'b1;
                    if (s_axis_tlast) begin
                        over <= 1'b0;
                        ra <= {AW{1'b0}};
                        li <= 2'd0;
                        if (s_axis_tuser) begin
                            n <= {NW{1'b0}};
                            c_dropped <= c_dropped + 1'b1;
                        end else if (over || full) begin
                            n <= {NW{1'b0}};
                            c_too_long <= c_too_long + 1'b1;
                        end else begin
                            rleft <= n + 1'b1;
                            oleft <= n + 1'b1;
                            st <= S_LEN;
                        end
                    end
                end
                S_LEN: if (pop) begin
                    li <= li + 2'd1;
                    if (li == 2'd3) st <= S_BODY;
                end
                S_BODY: if (pop) begin
                    oleft <= oleft - 1'b1;
                    if (oleft == {{(NW-1){1'b0}}, 1'b1}) begin
                        n <= {NW{1'b0}};
                        c_samples <= c_samples + 1'b1;
                        st <= S_FILL;
                    end
                end
                default: st <= S_FILL;
            endcase
        end
    end
endmodule
`default_nettype wire
