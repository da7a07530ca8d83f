// fv_rtps_disc_answer -- rfl_rtps_disc_answer (16-byte ROM, 2 answers, INFO_DST at byte 2, a
// base at byte 4, a credit of 8 bytes earning 1 per byte received) on its ports, for ANY
// contents of the ROM and of its table (any lengths) and any requests under the stream rules.
// Always (prove): the output keeps the stream rules (TDATA, TLAST, TDEST and the asker's prefix
// unchanged until taken), TDEST and the prefix do not change inside a datagram, a datagram goes
// on to its TLAST without a gap, the credit never exceeds BURST, and (the module's FORMAL block,
// with its invariants) the bytes sent never exceed BURST + RATE x the bytes received.
// Bounded (bmc, not FV_PROVE): the same bound by counting the bytes (its own count, not the
// module's block).
module fv_rtps_disc_answer (
    input clk, input rst_n, input rx_byte, input [167:0] s_axis_tdata, input s_axis_tvalid,
    input m_axis_tready
);
    localparam BURST = 8, RATE = 1;
    wire s_axis_tready, m_axis_tvalid, m_axis_tlast;
    wire [7:0] m_axis_tdata;
    wire [1:0] m_axis_tdest;
    wire [95:0] m_dst_prefix;
    wire [15:0] credit;
    wire [3:0] cnt_answers, cnt_no_credit;
    rfl_rtps_disc_answer #(.ROM_BYTES(16), .MESSAGES(2), .DST_AT(2), .BASE_AT(4),
                           .BURST(BURST), .RATE(RATE), .DEST_BITS(2), .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .rx_byte(rx_byte), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast),
        .m_axis_tdest(m_axis_tdest), .m_dst_prefix(m_dst_prefix), .credit(credit),
        .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, s_axis_tdata)
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdest, m_dst_prefix, m_axis_tlast, m_axis_tdata})

    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(credit <= BURST);
        if (m_axis_tvalid) assert(!s_axis_tready);      // one answer at a time
        if ($past(rst_n) && $past(m_axis_tvalid && m_axis_tready && !m_axis_tlast)) begin
            assert(m_axis_tvalid);                      // a datagram goes on to its TLAST
            assert(m_axis_tdest == $past(m_axis_tdest));
            assert(m_dst_prefix == $past(m_dst_prefix));
        end
    end

`ifndef FV_PROVE
    reg [7:0] fv_in, fv_out;
    always @(posedge clk) begin
        if (!rst_n) begin
            fv_in <= 8'd0;
            fv_out <= 8'd0;
        end else begin
            if (rx_byte) fv_in <= fv_in + 8'd1;
            if (m_axis_tvalid && m_axis_tready) fv_out <= fv_out + 8'd1;
        end
    end
    always @(posedge clk) if (!fv_init && rst_n) assert({2'd0, fv_out} <= BURST + RATE * {2'd0, fv_in});
`endif
endmodule
