// fv_rtps_to_cdr -- rfl_rtps_to_cdr (rtl/fabric) with MAX_BYTES 5 (a ring of 16 bytes: two
// records of 4-byte packets) on its ports: any input packets (any bytes, TLAST, TUSER) under the
// stream rules. Always (prove): the output keeps the stream rules. Bounded (bmc, not FV_PROVE):
// a record goes out only for a packet that ended without TUSER and fitted, in order, its length
// (4 bytes, little-endian) that packet's byte count and its body that packet's bytes; and the
// input waits only in the 4 clocks after a kept packet or while the ring is full (records not
// yet out + 4 + the packet's bytes stored = 16) with the packet still within MAX_BYTES: never
// while a record goes out with room left (the one-buffer seam did), never on a byte past
// MAX_BYTES.
module fv_rtps_to_cdr (
    input clk, input rst_n, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tlast, input s_axis_tuser, input m_tready
);
    localparam MAX = 5;
    localparam RING = 16;
    wire s_axis_tready, m_tvalid;
    wire [7:0] m_tdata;
    wire [3:0] cnt_samples, cnt_dropped, cnt_too_long;
    rfl_rtps_to_cdr #(.MAX_BYTES(MAX), .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast),
        .s_axis_tuser(s_axis_tuser), .m_tdata(m_tdata), .m_tvalid(m_tvalid),
        .m_tready(m_tready), .cnt_samples(cnt_samples), .cnt_dropped(cnt_dropped),
        .cnt_too_long(cnt_too_long));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_axis_tuser})
    `FV_SINK(m_tvalid, m_tready, m_tdata)

`ifndef FV_PROVE
    // the good packets taken and not yet out, in order: slot k of 8 holds packet k mod 8 (its
    // first MAX bytes, its length); enough for 20 clocks (asserted: pending <= 7)
    reg [7:0] shadow [0:63];
    reg [7:0] plen [0:7];
    reg [3:0] in_ptr, out_ptr;                     // packets kept; records out
    reg [7:0] in_cnt;                              // bytes of the packet coming in, taken so far
    reg [7:0] out_idx;                             // bytes of the record going out, taken
    reg [31:0] out_len;                            // its length as sent
    reg [7:0] unsent;                              // bytes of kept records not yet out
    reg [2:0] since_keep;                          // 1..4: the clocks after a kept packet
    wire take_in = s_axis_tvalid && s_axis_tready;
    wire take_out = m_tvalid && m_tready;
    wire good = !s_axis_tuser && in_cnt < MAX;     // with TLAST: the packet is kept
    wire [7:0] stored = (in_cnt < MAX) ? in_cnt : MAX;
    wire [31:0] len_n = {m_tdata, out_len[31:8]};
    wire [3:0] pending = in_ptr - out_ptr;
    always @(posedge clk) begin
        if (!rst_n) begin
            in_ptr <= 4'd0;
            out_ptr <= 4'd0;
            in_cnt <= 8'd0;
            out_idx <= 8'd0;
            out_len <= 32'd0;
            unsent <= 8'd0;
            since_keep <= 3'd0;
        end else begin
            since_keep <= (since_keep == 3'd0 || since_keep == 3'd4) ? 3'd0 : since_keep + 3'd1;
            if (take_in) begin
                if (in_cnt < MAX) shadow[{in_ptr[2:0], in_cnt[2:0]}] <= s_axis_tdata;
                in_cnt <= (in_cnt == 8'd255) ? in_cnt : in_cnt + 8'd1;
                if (s_axis_tlast) begin
                    in_cnt <= 8'd0;
                    if (good) begin
                        plen[in_ptr[2:0]] <= in_cnt + 8'd1;
                        in_ptr <= in_ptr + 4'd1;
                        since_keep <= 3'd1;
                    end
                end
            end
            if (take_out) begin
                assert(pending != 4'd0);                   // a record of a kept packet only
                if (out_idx < 8'd4) out_len <= len_n;             // the length, LE
                else assert(m_tdata == shadow[{out_ptr[2:0], out_idx[2:0] - 3'd4}]);
                if (out_idx == 8'd3) assert(len_n == {24'd0, plen[out_ptr[2:0]]});
                if (out_idx >= 8'd4 && out_idx == 8'd3 + out_len[7:0]) begin
                    out_idx <= 8'd0;                       // the record's last byte
                    out_ptr <= out_ptr + 4'd1;
                end else out_idx <= out_idx + 8'd1;
            end
            unsent <= unsent - {7'd0, take_out} +
                      ((take_in && s_axis_tlast && good) ? in_cnt + 8'd5 : 8'd0);
        end
    end
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(pending <= 4'd7);
        if (!s_axis_tready)
            assert(since_keep != 3'd0 || (unsent + 8'd4 + stored >= RING && in_cnt < MAX));
    end
`endif
endmodule
