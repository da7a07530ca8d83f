// fv_fabric_node -- rfl_fabric_node (rtl/fabric) on its ports, every stage inside, with small
// parameters: a 4-byte seam, 4-byte fragments and 104-byte datagrams, two answer slots, 16-byte
// ROMs of ANY contents (no file: their memories are free), an SPDP every 8 clocks; as the
// generated top, rfl_node below passes the seam's records to the transmit path unchanged (a
// generated top's own stream rules: `rosfpga-lab rtl prove CONFIG`). Any UDP payloads in (any
// kinds, bytes, lengths) under the stream rules, any backpressure, configuration and send_sedp.
// Always (prove, FV_PROVE): the output keeps the stream rules (TDATA, TLAST, TDEST and the
// prefix held, valid not dropped, until taken), with the FORMAL blocks of the node (each beat
// in offered to the side of its packet's kind, read on its first beat, alone; metatraffic never
// held back; the answers' credit earned by each metatraffic byte taken, nothing else) and of its
// stages in place: the arbiter's (a datagram's source alone on the output until its TLAST, a
// source waits behind at most two datagrams), the answers' (bytes sent at most BURST + RATE x
// bytes received: so the answers' bytes out at most BURST + RATE x the metatraffic bytes in)
// and the other stages' invariants.
// Bounded (bmc, not FV_PROVE): TDEST and the prefix do not change inside a datagram.
module fv_fabric_node (
    input clk, input rst_n, input [31:0] cfg_reader, input [31:0] cfg_writer,
    input [63:0] cfg_time, input send_sedp, input [7:0] s_axis_tdata, input s_axis_tvalid,
    input s_axis_tlast, input s_axis_tuser, input m_axis_tready
);
    wire s_axis_tready, m_axis_tvalid, m_axis_tlast, status_valid;
    wire [7:0] m_axis_tdata, status;
    wire [1:0] m_axis_tdest;
    wire [95:0] m_dst_prefix;
    wire [15:0] credit;
    wire [31:0] cnt_samples, cnt_answers, cnt_no_credit;
    rfl_fabric_node #(.MAX_BYTES(4), .GUID_PREFIX(96'h010f_0102_0304_0506_0708_090a),
                      .WRITER_ID(32'h00000102), .FRAG_BYTES(4), .MAX_DATAGRAM(104),
                      .ROM_BYTES(16), .MESSAGES(4), .PERIOD(8), .SLOTS(2),
                      .SLOT_IDS(64'h000003C7_000003C2), .SLOT_MSGS(16'h0300),
                      .SLOT_LASTS(16'h0002), .ANSWER_BYTES(16), .ANSWERS(4), .DST_AT(2),
                      .BASE_AT(4), .BURST(8), .RATE(1), .USER_DEST(2)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_reader(cfg_reader), .cfg_writer(cfg_writer),
        .cfg_time(cfg_time), .send_sedp(send_sedp), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .s_axis_tlast(s_axis_tlast), .s_axis_tuser(s_axis_tuser), .m_axis_tdata(m_axis_tdata),
        .m_axis_tvalid(m_axis_tvalid), .m_axis_tready(m_axis_tready),
        .m_axis_tlast(m_axis_tlast), .m_axis_tdest(m_axis_tdest), .m_dst_prefix(m_dst_prefix),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(cnt_samples), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit));
`include "fv_env.vh"
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_axis_tuser})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_axis_tdest,
             m_dst_prefix})

`ifndef FV_PROVE
    // the datagram going out: mid, a beat taken and not its TLAST; its TDEST and prefix
    reg mid;
    reg [1:0] dest;
    reg [95:0] prefix;
    always @(posedge clk) begin
        if (!rst_n) mid <= 1'b0;
        else if (m_axis_tvalid && m_axis_tready) begin
            mid <= !m_axis_tlast;
            dest <= m_axis_tdest;
            prefix <= m_dst_prefix;
        end
    end
    always @(posedge clk) if (!fv_init && rst_n && mid && m_axis_tvalid) begin
        assert(m_axis_tdest == dest);
        assert(m_dst_prefix == prefix);
    end
`endif
endmodule

// The generated top (wire: cdr) in the node: here the records of the seam go to the transmit
// path unchanged (the passthrough the FORMAL blocks of rfl_rtps_tx assume of its input).
module rfl_node (
    input clk, input rst_n,
    input [7:0] s_tdata, input s_tvalid, output s_tready,
    output [7:0] m_tdata, output m_tvalid, input m_tready,
    output frame_start, output status_valid, output [7:0] status, output busy,
    output [7:0] framing
);
    assign m_tdata = s_tdata;
    assign m_tvalid = s_tvalid;
    assign s_tready = m_tready;
    assign frame_start = 1'b0;
    assign status_valid = 1'b0;
    assign status = 8'd0;
    assign busy = s_tvalid;
    assign framing = 8'd0;
endmodule
