// fv_rtps_to_cdr -- rfl_rtps_to_cdr (rtl/fabric) with a 4-byte buffer on its ports: any input
// packets (any bytes, TLAST, TUSER) under the stream rules. Always (prove): the output keeps the
// stream rules, and input is taken only while no record is going out (one sample at a time).
// Bounded (bmc, not FV_PROVE): a record goes out only for a packet that ended without TUSER and
// fitted the buffer, its length (4 bytes, little-endian) is that packet's byte count, and its
// body is that packet's bytes, in order.
module fv_rtps_to_cdr (
    input clk, input rst_n, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tlast, input s_axis_tuser, input m_tready
);
    localparam MAX = 4;
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
    always @(posedge clk) if (!fv_init && rst_n) begin
        if (s_axis_tready) assert(!m_tvalid);             // a record out: nothing taken
    end

`ifndef FV_PROVE
    // the last packet taken: its bytes (the first MAX), its length, whether it may go out
    reg [7:0] shadow [0:MAX-1];
    reg [7:0] in_cnt, pend_len;
    reg pending;
    // the record going out: bytes of it taken, its length as sent
    reg [7:0] out_idx;
    reg [31:0] out_len;
    wire take_in = s_axis_tvalid && s_axis_tready;
    wire take_out = m_tvalid && m_tready;
    wire [31:0] len_n = {m_tdata, out_len[31:8]};
    always @(posedge clk) begin
        if (!rst_n) begin
            in_cnt <= 8'd0;
            pending <= 1'b0;
            pend_len <= 8'd0;
            out_idx <= 8'd0;
            out_len <= 32'd0;
        end else begin
            if (take_in) begin
                if (in_cnt < MAX) shadow[in_cnt[1:0]] <= s_axis_tdata;
                in_cnt <= (in_cnt == 8'd255) ? in_cnt : in_cnt + 8'd1;
                if (s_axis_tlast) begin
                    in_cnt <= 8'd0;
                    pending <= !s_axis_tuser && in_cnt < MAX;
                    pend_len <= in_cnt + 8'd1;
                end
            end
            if (take_out) begin
                assert(pending);                           // a record of a good packet only
                if (out_idx < 8'd4) out_len <= len_n;             // the length, LE
                else assert(m_tdata == shadow[out_idx[1:0]]);     // body byte out_idx - 4
                if (out_idx == 8'd3) assert(len_n == {24'd0, pend_len});
                if (out_idx >= 8'd4 && out_idx == 8'd3 + out_len[7:0]) begin
                    out_idx <= 8'd0;                       // the record's last byte
                    pending <= 1'b0;
                end else out_idx <= out_idx + 8'd1;
            end
        end
    end
`endif
endmodule
