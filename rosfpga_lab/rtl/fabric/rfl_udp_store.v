// rfl_udp_store -- store and forward of whole packets (issue #31, the UDP stage): a packet goes
// out only once its last byte came in good, with its length known before its first byte.
// rfl_udp_port uses it both ways: received UDP payloads (LiteEth flags a bad frame only on its
// last byte: such a packet never reaches the RTPS walker) and payloads to send (LiteEth's UDP
// transmitter writes the UDP length in the header, before the payload).
//
// In:  s_axis_* a packet (8-bit AXI4-Stream, TLAST on its last byte); TUSER with TLAST: discard
//      it; s_meta read with the TLAST beat (the sideband carried along, e.g. IP and ports).
// Out: m_axis_* the packets kept, in order, a byte per clock; m_meta and m_len (the packet's
//      length in bytes, 1..2**ADDR_BITS) hold for every beat of a packet.
// A packet is discarded whole (done_drop, with done_user when TUSER asked for it, else there was
// no room: its bytes did not fit in the 2**ADDR_BITS-byte buffer or 2**QUEUE_BITS packets were
// already waiting) or kept (done_keep); the done_* pulses come with its TLAST beat.
// WAIT = 0: TREADY is always high (a receiver cannot make the wire wait): a packet without room
// is discarded. WAIT = 1: TREADY waits for room, and only a packet longer than the whole buffer
// is discarded (its bytes are taken and dropped).
// How: the bytes go to a ring (one block RAM) at wr_ptr; commit_ptr is where the packet being
// written started, to which wr_ptr returns when it is discarded; a kept packet's length and meta
// go to a small queue, from which the read side takes one packet at a time through the RAM's
// registered read and an output register (no combinational path from m_axis_tready to the RAM).
`default_nettype none

module rfl_udp_store #(
    parameter ADDR_BITS  = 11,                  // the ring: 2**ADDR_BITS bytes, 4..15
    parameter QUEUE_BITS = 2,                   // packets waiting: up to 2**QUEUE_BITS, 1..6
    parameter META_W     = 64,                  // sideband bits, 1..128
    parameter WAIT       = 0                    // 0: discard without room; 1: wait for room
) (
    input  wire              clk,
    input  wire              rst_n,
    input  wire [7:0]        s_axis_tdata,
    input  wire              s_axis_tvalid,
    output wire              s_axis_tready,
    input  wire              s_axis_tlast,
    input  wire              s_axis_tuser,      // with TLAST: discard the packet
    input  wire [META_W-1:0] s_meta,            // read with the TLAST beat
    output wire [7:0]        m_axis_tdata,
    output wire              m_axis_tvalid,
    input  wire              m_axis_tready,
    output wire              m_axis_tlast,
    output wire [META_W-1:0] m_meta,
    output wire [15:0]       m_len,
    output wire              done_keep,         // a packet kept (with its TLAST beat)
    output wire              done_drop,         // a packet discarded
    output wire              done_user          // ... because TUSER asked for it
);
`ifdef __ICARUS__
    initial begin
        if (ADDR_BITS < 4 || ADDR_BITS > 15) $fatal(1, "rfl_udp_store: ADDR_BITS must be 4..15");
        if (QUEUE_BITS < 1 || QUEUE_BITS > 6) $fatal(1, "rfl_udp_store: QUEUE_BITS must be 1..6");
        if (META_W < 1 || META_W > 128) $fatal(1, "rfl_udp_store: META_W must be 1..128");
        if (WAIT != 0 && WAIT != 1) $fatal(1, "rfl_udp_store: WAIT must be 0 or 1");
    end
`else
    if (ADDR_BITS < 4 || ADDR_BITS > 15) begin : g_bad_addr_bits
        $error("rfl_udp_store: ADDR_BITS must be 4..15");
    end
    if (QUEUE_BITS < 1 || QUEUE_BITS > 6) begin : g_bad_queue_bits
        $error("rfl_udp_store: QUEUE_BITS must be 1..6");
    end
    if (META_W < 1 || META_W > 128) begin : g_bad_meta_w
        $error("rfl_udp_store: META_W must be 1..128");
    end
    if (WAIT != 0 && WAIT != 1) begin : g_bad_wait
        $error("rfl_udp_store: WAIT must be 0 or 1");
    end
`endif

    localparam A = ADDR_BITS;
    localparam Q = QUEUE_BITS;

    reg [7:0] mem [0:(1 << A) - 1];
    reg [META_W + 15:0] queue [0:(1 << Q) - 1];

    // ---- write side -------------------------------------------------------------------------
    reg [A:0] wr_ptr, commit_ptr, rd_ptr;
    reg [Q:0] q_wp, q_rp;
    reg ovf;                                    // the packet being written is discarded
    reg [15:0] n_in;                            // bytes of this packet stored so far
    wire [A:0] used = wr_ptr - rd_ptr;
    wire [A:0] cur = wr_ptr - commit_ptr;       // bytes of this packet stored so far
    wire full = used[A];
    wire [Q:0] q_used = q_wp - q_rp;
    wire q_full = q_used[Q];
    wire q_empty = (q_used == {(Q + 1){1'b0}});
    wire never = cur[A];                        // this packet alone fills the ring
    assign s_axis_tready = (WAIT == 0) ? 1'b1 : (!q_full && (!full || ovf || never));
    wire take = s_axis_tvalid && s_axis_tready;
    wire lost = ovf || full;                    // this byte does not fit
    wire fin = take && s_axis_tlast;
    wire drop = lost || s_axis_tuser || q_full;
    assign done_keep = fin && !drop;
    assign done_drop = fin && drop;
    assign done_user = fin && s_axis_tuser;
    wire [A:0] wr_next = wr_ptr + 1'b1;
    wire [15:0] len_in = n_in + 16'd1;

    always @(posedge clk) begin
        if (take && !lost) mem[wr_ptr[A-1:0]] <= s_axis_tdata;
        if (done_keep) queue[q_wp[Q-1:0]] <= {s_meta, len_in};
    end

    always @(posedge clk) begin
        if (!rst_n) begin
            wr_ptr <= {(A + 1){1'b0}};
            commit_ptr <= {(A + 1){1'b0}};
            q_wp <= {(Q + 1){1'b0}};
            ovf <= 1'b0;
            n_in <= 16'd0;
        end else if (fin) begin
            ovf <= 1'b0;
            n_in <= 16'd0;
            if (drop) begin
                wr_ptr <= commit_ptr;
            end else begin
                wr_ptr <= wr_next;
                commit_ptr <= wr_next;
                q_wp <= q_wp + 1'b1;
            end
        end else if (take) begin
            if (lost) begin
                ovf <= 1'b1;
            end else begin
                wr_ptr <= wr_next;
                n_in <= len_in;
            end
        end
    end

    // ---- read side: one packet at a time, RAM read register -> output register -------------
    reg busy;                                   // a packet is being read
    reg [15:0] left;                            // its bytes not yet read from the RAM
    reg [META_W + 15:0] head;                   // its meta and length
    reg [7:0] r_data;                           // the RAM's read register
    reg r_valid, r_last;
    reg [7:0] o_data;
    reg o_valid, o_last;
    wire o_free = !o_valid || m_axis_tready;
    wire r_move = r_valid && o_free;
    wire issue = busy && (left != 16'd0) && (!r_valid || r_move);
    wire start = !busy && !q_empty;
    wire o_end = o_valid && o_last && m_axis_tready;

    always @(posedge clk) begin
        if (issue) r_data <= mem[rd_ptr[A-1:0]];
        if (start) head <= queue[q_rp[Q-1:0]];
        if (r_move) o_data <= r_data;
    end

    always @(posedge clk) begin
        if (!rst_n) begin
            rd_ptr <= {(A + 1){1'b0}};
            q_rp <= {(Q + 1){1'b0}};
            busy <= 1'b0;
            left <= 16'd0;
            r_valid <= 1'b0;
            r_last <= 1'b0;
            o_valid <= 1'b0;
            o_last <= 1'b0;
        end else begin
            if (start) begin
                busy <= 1'b1;
                left <= queue[q_rp[Q-1:0]][15:0];
                q_rp <= q_rp + 1'b1;
            end else if (o_end) begin
                busy <= 1'b0;
            end
            if (issue) begin
                rd_ptr <= rd_ptr + 1'b1;
                left <= left - 16'd1;
                r_last <= (left == 16'd1);
                r_valid <= 1'b1;
            end else if (r_move) begin
                r_valid <= 1'b0;
            end
            if (r_move) begin
                o_valid <= 1'b1;
                o_last <= r_last;
            end else if (m_axis_tready) begin
                o_valid <= 1'b0;
            end
        end
    end

    assign m_axis_tdata = o_data;
    assign m_axis_tvalid = o_valid;
    assign m_axis_tlast = o_last;
    assign m_meta = head[META_W + 15:16];
    assign m_len = head[15:0];
endmodule

`default_nettype wire
