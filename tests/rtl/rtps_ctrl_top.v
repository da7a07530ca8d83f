// The fabric participant's answer path for tests/rtl/test_fabric_answer.py: rfl_rtps_ctrl (the
// watcher) into rfl_rtps_disc_answer (the answers), as a top wires them; parameters as
// rosfpga_lab.rtl.discrom.answer_params gives them.
`default_nettype none

module rtps_ctrl_top #(
    parameter SLOTS = 5,
    parameter [32*SLOTS-1:0] SLOT_IDS = 0,
    parameter [8*SLOTS-1:0] SLOT_MSGS = 0,
    parameter [8*SLOTS-1:0] SLOT_LASTS = 0,
    parameter ROM_FILE = "rfl_rtps_disc_answer.hex",
    parameter TABLE_FILE = "rfl_rtps_disc_answer_table.hex",
    parameter ANSWER_BYTES = 1,
    parameter ANSWERS = 1,
    parameter DST_AT = 24,
    parameter BASE_AT = 48,
    parameter COUNT_START = 3,
    parameter BURST = 4096,
    parameter RATE = 4
) (
    input  wire         clk,
    input  wire         rst_n,
    input  wire [95:0]  cfg_prefix,
    input  wire [7:0]   s_axis_tdata,
    input  wire         s_axis_tvalid,
    output wire         s_axis_tready,
    input  wire         s_axis_tlast,
    output wire [7:0]   m_axis_tdata,
    output wire         m_axis_tvalid,
    input  wire         m_axis_tready,
    output wire         m_axis_tlast,
    output wire [1:0]   m_axis_tdest,
    output wire [95:0]  m_dst_prefix,
    output wire [15:0]  credit,
    output wire [31:0]  cnt_requests,
    output wire [31:0]  cnt_busy,
    output wire [31:0]  cnt_malformed,
    output wire [31:0]  cnt_answers,
    output wire [31:0]  cnt_no_credit
);
    wire [167:0] req_tdata;
    wire req_tvalid, req_tready, rx_byte;
    rfl_rtps_ctrl #(.SLOTS(SLOTS), .SLOT_IDS(SLOT_IDS), .SLOT_MSGS(SLOT_MSGS),
                    .SLOT_LASTS(SLOT_LASTS)) ctrl (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(cfg_prefix), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .s_axis_tlast(s_axis_tlast), .m_axis_tdata(req_tdata), .m_axis_tvalid(req_tvalid),
        .m_axis_tready(req_tready), .rx_byte(rx_byte), .cnt_requests(cnt_requests),
        .cnt_busy(cnt_busy), .cnt_malformed(cnt_malformed));
    rfl_rtps_disc_answer #(.ROM_FILE(ROM_FILE), .TABLE_FILE(TABLE_FILE),
                           .ROM_BYTES(ANSWER_BYTES), .MESSAGES(ANSWERS), .DST_AT(DST_AT),
                           .BASE_AT(BASE_AT), .COUNT_START(COUNT_START), .BURST(BURST),
                           .RATE(RATE)) answer (
        .clk(clk), .rst_n(rst_n), .rx_byte(rx_byte), .s_axis_tdata(req_tdata),
        .s_axis_tvalid(req_tvalid), .s_axis_tready(req_tready), .m_axis_tdata(m_axis_tdata),
        .m_axis_tvalid(m_axis_tvalid), .m_axis_tready(m_axis_tready),
        .m_axis_tlast(m_axis_tlast), .m_axis_tdest(m_axis_tdest), .m_dst_prefix(m_dst_prefix),
        .credit(credit), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit));
endmodule

`default_nettype wire
