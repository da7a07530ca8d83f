// fv_elem_pack -- rfl_elem_pack on its ports (2 bytes per element, arrays of 3): the beat
// stream keeps the rules, TKEEP is the element's lanes, TUSER is set on the first element of
// every array only and TLAST on its last only, and a beat carries the EBYTES bytes taken since
// the last one, lane 0 first. With FV_LINES: arrays of 4 in lines of 2 (a video stream's
// framing), TLAST on the last element of every line only.
`ifdef FV_LINES
`define FV_LENGTH 4
`define FV_LINE 2
`else
`define FV_LENGTH 3
`define FV_LINE 3
`endif
module fv_elem_pack #(parameter EBYTES = 2, parameter LENGTH = `FV_LENGTH,
                      parameter LINE = `FV_LINE) (
    input clk, input rst_n, input [7:0] s_tdata, input s_tvalid, input m_axis_tready
);
    localparam EW = 8 * EBYTES;
    wire s_tready, m_tuser, m_tlast, m_tvalid;
    wire [EW-1:0] m_tdata;
    wire [EBYTES-1:0] m_tkeep;
    rfl_elem_pack #(.EBYTES(EBYTES), .LENGTH(LENGTH), .LINE(LINE)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_axis_tdata(m_tdata), .m_axis_tkeep(m_tkeep), .m_axis_tuser(m_tuser),
        .m_axis_tlast(m_tlast), .m_axis_tvalid(m_tvalid), .m_axis_tready(m_axis_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_axis_tready, {m_tuser, m_tlast, m_tkeep, m_tdata})

    // beats out: the element's index in its array; bytes in: the element being assembled
    reg [7:0] idx;
    reg [3:0] lane;
    reg [EW-1:0] elem;
    wire take = s_tvalid && s_tready, give = m_tvalid && m_axis_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            idx <= 0; lane <= 0; elem <= 0;
        end else begin
            if (take) begin
                lane <= (lane == EBYTES - 1) ? 4'd0 : lane + 4'd1;
                elem <= (lane == 0 ? {EW{1'b0}} : elem) | ({{(EW-8){1'b0}}, s_tdata} << (8 * lane));
            end
            if (give) idx <= (idx == LENGTH - 1) ? 8'd0 : idx + 8'd1;
        end
    end
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(idx < LENGTH && lane < EBYTES);
        assert(m_tkeep == {EBYTES{1'b1}});
`ifndef FV_PROVE   // bounded only: the index counted here is not visible on the ports
        if (m_tvalid) begin
            assert(m_tuser == (idx == 0));              // TUSER: an array's first element only
            assert(m_tlast == (idx % LINE == LINE - 1)); // TLAST: a line's last element only
        end
        // a beat appears only after the last byte of its element, with exactly those bytes
        if (m_tvalid && !$past(m_tvalid && !m_axis_tready)) begin
            assert(lane == 0);
            assert(m_tdata == elem);
        end
`endif
    end
endmodule
