// fv_rtps_disc_rom -- rfl_rtps_disc_rom (16-byte ROM, 4 messages, an SPDP every 5 clocks) on
// its ports, for ANY contents of the ROM and of its message table (no file: the memories start
// arbitrary and stay so) and any send_sedp requests: the output keeps the stream rules (a beat
// offered stays offered, TDATA, TLAST and TDEST unchanged, until taken), TDEST does not change
// inside a datagram, and busy is set while a beat is offered.
module fv_rtps_disc_rom (
    input clk, input rst_n, input send_sedp, input m_axis_tready
);
    wire [7:0] m_axis_tdata;
    wire m_axis_tvalid, m_axis_tlast, busy;
    wire [1:0] m_axis_tdest;
    rfl_rtps_disc_rom #(.ROM_BYTES(16), .MESSAGES(4), .PERIOD(5), .DEST_BITS(2)) dut (
        .clk(clk), .rst_n(rst_n), .send_sedp(send_sedp), .busy(busy),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast),
        .m_axis_tdest(m_axis_tdest));
`include "fv_env.vh"
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdest, m_axis_tlast, m_axis_tdata})

    always @(posedge clk) if (!fv_init && rst_n) begin
        if (m_axis_tvalid) assert(busy);
        if ($past(rst_n) && $past(m_axis_tvalid && m_axis_tready && !m_axis_tlast)) begin
            assert(m_axis_tvalid);                      // a datagram goes on to its TLAST
            assert(m_axis_tdest == $past(m_axis_tdest));
        end
    end
endmodule
