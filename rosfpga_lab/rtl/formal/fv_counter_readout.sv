// fv_counter_readout -- rfl_counter_readout (two counters given, so answers of 28 bytes; a gap
// of 40 clocks) on its ports, for ANY input bytes, datagram ends, senders and counter values,
// and any readiness downstream: its FORMAL block's properties (output stream rules with the
// destination held over an answer, no more bytes out than well-formed requests' bytes in, an
// answer at most every GAP clocks, always ready, counters never falling), and here: an answer
// is exactly 28 beats, starting with the magic word and the count (FV_OUTSIDE: counted from the
// outside as well, for a bounded check by hand).
module fv_counter_readout (
    input clk, input rst_n, input [63:0] counters, input [7:0] s_axis_tdata,
    input s_axis_tvalid, input s_axis_tlast, input [31:0] s_ip, input [15:0] s_port,
    input m_axis_tready
);
    localparam GAP = 40;                        // longer than an answer
    wire s_axis_tready, m_axis_tvalid, m_axis_tlast;
    wire [7:0] m_axis_tdata;
    wire [31:0] m_ip, cnt_answered, cnt_malformed, cnt_limited;
    wire [15:0] m_port;
    rfl_counter_readout #(.COUNT(2), .MAGIC(32'h52464301), .GAP(GAP)) dut (
        .clk(clk), .rst_n(rst_n), .counters(counters), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .s_axis_tlast(s_axis_tlast), .s_ip(s_ip), .s_port(s_port),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast), .m_ip(m_ip),
        .m_port(m_port), .cnt_answered(cnt_answered), .cnt_malformed(cnt_malformed),
        .cnt_limited(cnt_limited));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_ip, s_port})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_ip, m_port})
`ifdef FV_OUTSIDE
    // counted from the outside too (a bounded check: the induction has the design's own
    // invariants, rfl_counter_readout's FORMAL block)
    reg [5:0] f_beat;                           // beats of the answer going out so far
    always @(posedge clk) begin
        if (!rst_n) f_beat <= 6'd0;
        else if (m_axis_tvalid && m_axis_tready) f_beat <= m_axis_tlast ? 6'd0 : f_beat + 6'd1;
    end
    always @(*) if (!fv_init && rst_n && m_axis_tvalid) begin
        assert(m_axis_tlast == (f_beat == 6'd27));
        case (f_beat)
            6'd0: assert(m_axis_tdata == 8'h52);
            6'd1: assert(m_axis_tdata == 8'h46);
            6'd2: assert(m_axis_tdata == 8'h43);
            6'd3: assert(m_axis_tdata == 8'h01);
            6'd4, 6'd5, 6'd6: assert(m_axis_tdata == 8'h00);
            6'd7: assert(m_axis_tdata == 8'h05);
            default: ;
        endcase
    end
`endif
endmodule
