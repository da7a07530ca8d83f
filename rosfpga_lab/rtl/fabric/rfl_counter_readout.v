// rfl_counter_readout -- the fabric node's counters on the network, no bus needed (issue 31):
// a request datagram (s_axis: the payloads rfl_fabric_top routes from its counters port, s_ip
// and s_port the sender's, held for the packet) of exactly BYTES = 8 + 4 x (COUNT + 3) bytes,
// MAGIC big endian then zeros, is answered by one datagram of BYTES bytes (m_axis, m_ip and
// m_port its destination: the request's sender, held over it): MAGIC, COUNT + 3, then the
// counters' values (32 bits, big endian; `counters` holds COUNT of them, counter i in bits
// [32*i +: 32], then this module's own three: cnt_answered, cnt_malformed, cnt_limited).
// rosfpga_lab.rtl.fabriccounters owns the format and the order. Each value is read when its
// first byte is sent (a value is whole; the answer is not one instant's).
// Bounded: a request is answered only if it is well formed (else dropped: cnt_malformed), no
// answer is going out and GAP clocks have passed since the last one was started (else dropped:
// cnt_limited); so at most one answer a request, never more bytes out than in, and at most one
// answer every max(GAP, BYTES) clocks whatever comes in. Always ready.
`default_nettype none

module rfl_counter_readout #(
    parameter COUNT = 1,                        // counters given (the readout adds its three)
    parameter [31:0] MAGIC = 32'h52464301,
    parameter GAP = 256                         // clocks from an answer to the next, >= 1
) (
    input  wire                clk,
    input  wire                rst_n,
    input  wire [32*COUNT-1:0] counters,
    input  wire [7:0]          s_axis_tdata,
    input  wire                s_axis_tvalid,
    output wire                s_axis_tready,
    input  wire                s_axis_tlast,
    input  wire [31:0]         s_ip,
    input  wire [15:0]         s_port,
    output wire [7:0]          m_axis_tdata,
    output wire                m_axis_tvalid,
    input  wire                m_axis_tready,
    output wire                m_axis_tlast,
    output wire [31:0]         m_ip,
    output wire [15:0]         m_port,
    output wire [31:0]         cnt_answered,    // requests answered
    output wire [31:0]         cnt_malformed,   // datagrams not a request
    output wire [31:0]         cnt_limited      // requests while busy or within GAP
);
    localparam WORDS = COUNT + 5;               // magic, count, COUNT + 3 values
    localparam BYTES = 4 * WORDS;
    localparam NB = $clog2(BYTES + 2);          // a request's bytes, BYTES + 1: too long
    localparam NW = NB - 2;                     // a word of the answer
    localparam NG = $clog2(GAP + 1);
`ifdef __ICARUS__
    initial begin
        if (COUNT < 1) $fatal(1, "rfl_counter_readout: COUNT must be at least 1");
        if (GAP < 1) $fatal(1, "rfl_counter_readout: GAP must be at least 1");
    end
`else
    if (COUNT < 1) begin : g_bad_count
        $error("rfl_counter_readout: COUNT must be at least 1");
    end
    if (GAP < 1) begin : g_bad_gap
        $error("rfl_counter_readout: GAP must be at least 1");
    end
`endif
    localparam integer LAST_I = BYTES - 1, TWO_I = 2;
    localparam [NB-1:0] LAST_AT = LAST_I[NB-1:0];
    localparam [NB-1:0] TOO_LONG = BYTES[NB-1:0];
    localparam [NG-1:0] GAP_N = GAP[NG-1:0];
    localparam [NW-1:0] TWO = TWO_I[NW-1:0];
    localparam [31:0] TOTAL = COUNT + 3;

    // ---- requests
    reg [NB-1:0] rn;                            // bytes of this datagram so far (saturating)
    reg rbad;
    wire take = s_axis_tvalid;
    wire [7:0] want = rn >= 4 ? 8'd0 : MAGIC[31 - 8 * rn[1:0] -: 8];
    wire bad_now = rbad || rn == TOO_LONG || s_axis_tdata != want;
    wire fin = take && s_axis_tlast;
    wire good = fin && !bad_now && rn == LAST_AT;
    reg sending;
    reg [NG-1:0] gap;
    wire accept = good && !sending && gap == {NG{1'b0}};
    assign s_axis_tready = 1'b1;
    always @(posedge clk) begin
        if (!rst_n) begin
            rn <= {NB{1'b0}};
            rbad <= 1'b0;
        end else if (take) begin
            rn <= s_axis_tlast ? {NB{1'b0}} : (rn == TOO_LONG ? rn : rn + 1'b1);
            rbad <= !s_axis_tlast && bad_now;
        end
    end

    // ---- answers: word w of the answer, its byte b (big endian)
    reg [NB-1:0] an;                            // byte of the answer going out
    reg [31:0] word;
    reg [31:0] dst_ip;
    reg [15:0] dst_port;
    reg [31:0] c_ans, c_bad, c_lim;
    wire [32*(COUNT+3)-1:0] all = {c_lim, c_bad, c_ans, counters};
    wire [NW-1:0] w_next = an[NB-1:2] + 1'b1;
    wire [NW-1:0] v_at = w_next - TWO;
    wire [31:0] next_word = w_next == 1 ? TOTAL : all[32 * v_at +: 32];
    wire out = sending && m_axis_tready;
    wire out_last = an == LAST_AT;
    always @(posedge clk) begin
        if (!rst_n) begin
            sending <= 1'b0;
            an <= {NB{1'b0}};
            word <= 32'd0;
            gap <= {NG{1'b0}};
            dst_ip <= 32'd0;
            dst_port <= 16'd0;
        end else begin
            if (gap != {NG{1'b0}}) gap <= gap - 1'b1;
            if (accept) begin
                sending <= 1'b1;
                an <= {NB{1'b0}};
                word <= MAGIC;
                gap <= GAP_N;
                dst_ip <= s_ip;
                dst_port <= s_port;
            end else if (out) begin
                sending <= !out_last;
                an <= an + 1'b1;
                if (an[1:0] == 2'd3 && !out_last) word <= next_word;
            end
        end
    end
    assign m_axis_tdata = word[31 - 8 * an[1:0] -: 8];
    assign m_axis_tvalid = sending;
    assign m_axis_tlast = out_last;
    assign m_ip = dst_ip;
    assign m_port = dst_port;

    always @(posedge clk) begin
        if (!rst_n) begin
            c_ans <= 32'd0;
            c_bad <= 32'd0;
            c_lim <= 32'd0;
        end else if (fin) begin
            if (accept && c_ans != 32'hffffffff) c_ans <= c_ans + 32'd1;
            if (!good && c_bad != 32'hffffffff) c_bad <= c_bad + 32'd1;
            if (good && !accept && c_lim != 32'hffffffff) c_lim <= c_lim + 32'd1;
        end
    end
    assign cnt_answered = c_ans;
    assign cnt_malformed = c_bad;
    assign cnt_limited = c_lim;

`ifdef FORMAL
    // Proven (fv_counter_readout): the output keeps the stream rules with its destination, held
    // over an answer; an answer is BYTES beats (from 0, one a beat, TLAST on the last alone),
    // the magic word and the count first; the bytes out never
    // exceed the bytes of well-formed requests in (f_credit: that difference, saturating, so a
    // lower bound of it), the rest of an answer going out covered; an answer starts GAP clocks
    // or more after the last one started; always ready; the counters never fall.
    reg [15:0] f_credit;
    reg [NG-1:0] f_age;                         // clocks since the last answer started (sat.)
    localparam [15:0] F_BYTES = BYTES[15:0];
    wire [15:0] f_left = sending ? F_BYTES - {{(16-NB){1'b0}}, an} : 16'd0;
    always @(posedge clk) begin
        if (!rst_n) begin
            f_credit <= 16'd0;
            f_age <= GAP_N;
        end else begin
            f_credit <= (good && f_credit > 16'hffff - F_BYTES ? 16'hffff
                         : f_credit + (good ? F_BYTES : 16'd0)) - (out ? 16'd1 : 16'd0);
            f_age <= accept ? {NG{1'b0}} : (f_age == GAP_N ? f_age : f_age + 1'b1);
        end
    end
    always @(*) if (rst_n) begin
        assert(s_axis_tready);
        assert(f_credit >= f_left);
        assert(f_age <= GAP_N && gap == GAP_N - f_age);
        if (accept) assert(f_age == GAP_N);
        if (sending) assert(an <= LAST_AT);
        if (sending && an < 4) assert(word == MAGIC);
        if (sending && an >= 4 && an < 8) assert(word == TOTAL);
        assert(m_axis_tvalid == sending);
    end
    reg f_past;
    initial f_past = 1'b0;
    always @(posedge clk) f_past <= rst_n;
    always @(posedge clk) if (f_past && rst_n) begin
        if ($past(m_axis_tvalid && !m_axis_tready))
            assert(m_axis_tvalid && $stable({m_axis_tdata, m_axis_tlast, m_ip, m_port}));
        if ($past(m_axis_tvalid && m_axis_tready && !m_axis_tlast))
            assert(m_axis_tvalid && $stable({m_ip, m_port}) && an == $past(an) + 1'b1);
        if (m_axis_tvalid && !$past(m_axis_tvalid)) assert(an == {NB{1'b0}});
        assert(c_ans >= $past(c_ans) && c_bad >= $past(c_bad) && c_lim >= $past(c_lim));
    end
`endif
endmodule

`default_nettype wire
