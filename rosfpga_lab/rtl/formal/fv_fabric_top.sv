// fv_fabric_top -- rfl_fabric_top's own glue (rtl/fabric): the kind of a received datagram from
// its UDP destination port, the datagrams to other ports dropped, the destination of a sent one
// from its TDEST. The vendored LiteEth core and rfl_fabric_node (each proven or held by its own
// test) are replaced here by the models below, of the same name and ports: any streams by the
// stream rules, each datagram tagged in its first byte (LiteEth's: the low byte of its
// destination port, the three ports' low bytes differ; the node's: its TDEST). rfl_udp_port is
// the real one (16-byte buffers, 2 payloads each way). Bounded (bmc): the node's input keeps the
// stream rules with its TUSER; every datagram reaching it was sent to one of the three ports,
// TUSER 1 exactly for the user-data port; LiteEth's send stream keeps the stream rules with its
// addresses, and every datagram goes where its TDEST says (0: the group and SPDP port, 1: the
// peer's metatraffic port, 2 and 3: its user-data port; from the metatraffic port, the
// user-data port for user data). The ports and the peer are fixed here (RTPS domain 0's).
`define FV_SPDP 7400
`define FV_META 7410
`define FV_USER 7411
`define FV_COUNTERS 7408
`define FV_GROUP 32'hefff0001
`define FV_PEER_IP 32'hc0a80a01
`define FV_PEER_META 16'd7412
`define FV_PEER_USER 16'd7413

module fv_fabric_top (
    input clk, input rst_n, input [7:0] gmii_rxd, input gmii_rx_dv, input gmii_rx_er,
    input [47:0] cfg_mac, input [31:0] cfg_ip, input send_sedp
);
    wire [7:0] gmii_txd, status;
    wire gmii_tx_en, gmii_tx_er, status_valid;
    wire [15:0] credit;
    wire [31:0] c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11, c12, c13, c14;
    rfl_fabric_top #(.SPDP_PORT(`FV_SPDP), .META_PORT(`FV_META), .USER_PORT(`FV_USER),
                     .SPDP_GROUP(`FV_GROUP), .COUNTERS_PORT(`FV_COUNTERS), .COUNTERS_GAP(64),
                     .RX_BITS(4), .TX_BITS(4), .QUEUE_BITS(1)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_mac(cfg_mac), .cfg_ip(cfg_ip), .cfg_learn(1'b0),
        .cfg_peer_ip(`FV_PEER_IP), .cfg_peer_meta_port(`FV_PEER_META),
        .cfg_peer_user_port(`FV_PEER_USER), .cfg_reader(32'd0),
        .cfg_writer(32'd0), .cfg_time(64'd0), .send_sedp(send_sedp),
        .gmii_rxd(gmii_rxd), .gmii_rx_dv(gmii_rx_dv), .gmii_rx_er(gmii_rx_er),
        .gmii_txd(gmii_txd), .gmii_tx_en(gmii_tx_en), .gmii_tx_er(gmii_tx_er),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(c0), .cnt_answers(c1), .cnt_no_credit(c2), .cnt_rx_packets(c3),
        .cnt_rx_error(c4), .cnt_rx_length(c5), .cnt_rx_overflow(c6), .cnt_tx_packets(c7),
        .cnt_tx_overflow(c8), .cnt_rx_port(c9), .cnt_rx_header(c10), .cnt_rx_other(c11),
        .cnt_peer_learned(c12), .cnt_peer_refused(c13), .cnt_peer_other(c14));
endmodule

// LiteEth's UDP port as seen by rfl_fabric_top: any received datagrams (the first byte: the low
// byte of the destination port), any readiness to send; what is sent is checked.
module liteeth_udp_gmii (
    input sys_clock, input sys_reset, input [47:0] mac_address, input [31:0] ip_address,
    input [15:0] udp_rx_port, input [15:0] udp_rx_port_mask, input [31:0] ip_multicast,
    input [7:0] gmii_pads_rx_data, input gmii_pads_rx_dv, input gmii_pads_rx_er,
    output [7:0] gmii_pads_tx_data, output gmii_pads_tx_en, output gmii_pads_tx_er,
    output [7:0] udp_source_data, output udp_source_valid, input udp_source_ready,
    output udp_source_last, output udp_source_last_be, output udp_source_error,
    output [31:0] udp_source_ip_address, output [15:0] udp_source_src_port,
    output [15:0] udp_source_dst_port, output [15:0] udp_source_length,
    input [7:0] udp_sink_data, input udp_sink_valid, output udp_sink_ready,
    input udp_sink_last, input udp_sink_last_be, input [31:0] udp_sink_ip_address,
    input [15:0] udp_sink_src_port, input [15:0] udp_sink_dst_port, input [15:0] udp_sink_length,
    output rx_drop_header, output rx_drop_other
);
    wire clk = sys_clock;
    wire rst_n = !sys_reset;
    (* anyseq *) reg [7:0] rx_data;
    (* anyseq *) reg rx_valid, rx_last, rx_error, tx_ready;
    (* anyseq *) reg [31:0] rx_ip;
    (* anyseq *) reg [15:0] rx_sport, rx_dport, rx_length;
    (* anyseq *) reg drop_header, drop_other;
    assign rx_drop_header = drop_header;
    assign rx_drop_other = drop_other;
    assign udp_source_data = rx_data;
    assign udp_source_valid = rx_valid;
    assign udp_source_last = rx_last;
    assign udp_source_last_be = rx_last;
    assign udp_source_error = rx_error;
    assign udp_source_ip_address = rx_ip;
    assign udp_source_src_port = rx_sport;
    assign udp_source_dst_port = rx_dport;
    assign udp_source_length = rx_length;
    assign udp_sink_ready = tx_ready;
    assign gmii_pads_tx_data = 8'd0;
    assign gmii_pads_tx_en = 1'b0;
    assign gmii_pads_tx_er = 1'b0;
`include "fv_env.vh"
    `FV_SOURCE(rx_valid, udp_source_ready, {rx_data, rx_last, rx_error, rx_ip, rx_sport, rx_dport,
                                            rx_length})
    `FV_SINK(udp_sink_valid, udp_sink_ready, {udp_sink_data, udp_sink_last, udp_sink_ip_address,
                                              udp_sink_src_port, udp_sink_dst_port,
                                              udp_sink_length})
    reg rx_in, tx_in;                           // within a datagram (after its first beat)
    always @(posedge clk) begin
        if (!rst_n) begin
            rx_in <= 1'b0;
            tx_in <= 1'b0;
        end else begin
            if (rx_valid && udp_source_ready) rx_in <= !rx_last;
            if (udp_sink_valid && udp_sink_ready) tx_in <= !udp_sink_last;
        end
    end
    reg [79:0] rx_held;                         // a datagram's sideband, held over it
    always @(posedge clk) if (rx_valid && udp_source_ready) rx_held <= {rx_ip, rx_sport, rx_dport,
                                                                        rx_length};
    always @(*) if (rx_valid && rx_in) assume({rx_ip, rx_sport, rx_dport, rx_length} == rx_held);
    always @(*) if (rx_valid && !rx_in) assume(rx_data == rx_dport[7:0]);
    wire [15:0] spdp = `FV_SPDP, meta = `FV_META, user = `FV_USER, counters = `FV_COUNTERS;
    always @(posedge clk) if (!fv_init && rst_n && udp_sink_valid && !tx_in) begin
        assert(udp_sink_last_be == udp_sink_last);
        if (udp_sink_data == 8'd0)
            assert(udp_sink_ip_address == `FV_GROUP && udp_sink_dst_port == spdp &&
                   udp_sink_src_port == meta);
        else if (udp_sink_data == 8'd1)
            assert(udp_sink_ip_address == `FV_PEER_IP && udp_sink_dst_port == `FV_PEER_META &&
                   udp_sink_src_port == meta);
        else
            assert(udp_sink_ip_address == `FV_PEER_IP && udp_sink_dst_port == `FV_PEER_USER &&
                   udp_sink_src_port == user);
    end
    always @(posedge clk) if (!fv_init && rst_n) begin
        // the port filter passes the four ports
        assert(udp_rx_port == spdp && (meta & udp_rx_port_mask) == (spdp & udp_rx_port_mask) &&
               (user & udp_rx_port_mask) == (spdp & udp_rx_port_mask) &&
               (counters & udp_rx_port_mask) == (spdp & udp_rx_port_mask) &&
               ip_multicast == `FV_GROUP);
    end
endmodule

// rfl_fabric_node as seen by rfl_fabric_top: what it takes is checked, it sends any datagrams
// (the first byte: their TDEST) with any TDEST held over a datagram.
module rfl_fabric_node #(
    parameter MAX_BYTES = 2048, parameter [95:0] GUID_PREFIX = 0,
    parameter [31:0] WRITER_ID = 0, parameter [31:0] READER_ID = 0, parameter FRAG_BYTES = 1344,
    parameter MAX_DATAGRAM = 1472, parameter INFO_TS = 1, parameter ROM_FILE = "",
    parameter TABLE_FILE = "", parameter ROM_BYTES = 1472, parameter MESSAGES = 3,
    parameter PERIOD = 1, parameter SLOTS = 5, parameter [32*SLOTS-1:0] SLOT_IDS = 0,
    parameter [8*SLOTS-1:0] SLOT_MSGS = 0, parameter [8*SLOTS-1:0] SLOT_LASTS = 0,
    parameter ANSWER_FILE = "", parameter ANSWER_TABLE_FILE = "", parameter ANSWER_BYTES = 2048,
    parameter ANSWERS = 9, parameter DST_AT = 24, parameter BASE_AT = 48,
    parameter COUNT_START = 3, parameter BURST = 4096, parameter RATE = 4,
    parameter USER_DEST = 2
) (
    input clk, input rst_n, input [31:0] cfg_reader,
    input [31:0] cfg_writer, input [63:0] cfg_time, input send_sedp,
    input [7:0] s_axis_tdata, input s_axis_tvalid, output s_axis_tready, input s_axis_tlast,
    input s_axis_tuser,
    output [7:0] m_axis_tdata, output m_axis_tvalid, input m_axis_tready, output m_axis_tlast,
    output [1:0] m_axis_tdest, output [95:0] m_dst_prefix,
    output status_valid, output [7:0] status, output [15:0] credit, output [31:0] cnt_samples,
    output [31:0] cnt_answers, output [31:0] cnt_no_credit, output [479:0] cnt_stages
);
    (* anyseq *) reg [7:0] tx_data;
    (* anyseq *) reg tx_valid, tx_last, rx_ready;
    (* anyseq *) reg [1:0] tx_dest;
    assign s_axis_tready = rx_ready;
    assign m_axis_tdata = tx_data;
    assign m_axis_tvalid = tx_valid;
    assign m_axis_tlast = tx_last;
    assign m_axis_tdest = tx_dest;
    assign m_dst_prefix = 96'd0;
    assign status_valid = 1'b0;
    assign status = 8'd0;
    assign credit = 16'd0;
    assign cnt_samples = 32'd0;
    assign cnt_answers = 32'd0;
    assign cnt_no_credit = 32'd0;
    assign cnt_stages = 480'd0;
`include "fv_env.vh"
    `FV_SOURCE(tx_valid, m_axis_tready, {tx_data, tx_last, tx_dest})
    `FV_SINK(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_axis_tuser})
    reg rx_in, tx_in, tx_dest_in;
    reg [1:0] tx_dest_held;
    always @(posedge clk) begin
        if (!rst_n) begin
            rx_in <= 1'b0;
            tx_in <= 1'b0;
        end else begin
            if (s_axis_tvalid && s_axis_tready) rx_in <= !s_axis_tlast;
            if (tx_valid && m_axis_tready) begin
                tx_in <= !tx_last;
                tx_dest_held <= tx_dest;
            end
        end
    end
    // a datagram's TDEST is held over it, its first byte says it
    always @(*) if (tx_valid && tx_in) assume(tx_dest == tx_dest_held);
    always @(*) if (tx_valid && !tx_in) assume(tx_data == {6'd0, tx_dest});
    wire [15:0] spdp = `FV_SPDP, meta = `FV_META, user = `FV_USER;
    always @(posedge clk) if (!fv_init && rst_n && s_axis_tvalid && !rx_in) begin
        assert(s_axis_tdata == spdp[7:0] || s_axis_tdata == meta[7:0] ||
               s_axis_tdata == user[7:0]);
        assert(s_axis_tuser == (s_axis_tdata == user[7:0]));
    end
endmodule
