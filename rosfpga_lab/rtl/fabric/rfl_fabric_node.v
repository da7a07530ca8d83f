// rfl_fabric_node -- the ROS 2 node in the fabric behind one UDP payload interface (issue 31).
// Timing: register slices (rfl_slice) on the way in and between rfl_rtps_rx and the seam cut
// the combinational paths across modules (each a clock of latency, no byte changed).
// In: UDP payloads, one datagram per packet (TLAST on its last byte), s_axis_tuser its kind as
// rfl_udp_port's destination port tells it (1: the user-data port, 0: a metatraffic port; read
// on a packet's first beat and held for the packet). User-data datagrams go through
// rfl_rtps_rx -> rfl_rtps_to_cdr -> rfl_node (the generated wire: cdr top) -> rfl_rtps_tx;
// metatraffic goes to rfl_rtps_ctrl (ACKNACK / HEARTBEAT) -> rfl_rtps_disc_answer, whose bytes
// out stay within BURST + RATE x the metatraffic bytes in (rtl/limits.py's ANSWER_BURST,
// ANSWER_RATE); rfl_rtps_disc_rom sends the SPDP announcement every PERIOD clocks (and SEDP on
// a send_sedp pulse). Out: UDP payloads, TDEST their destination as rfl_rtps_disc_rom numbers
// them (0 SPDP, 1 metatraffic unicast, 2 user-data unicast: the transmit path's USER_DEST) and
// m_dst_prefix the asker an answer goes to (0 for the others).
// The arbiter (rfl_frame_arbiter) is frame-atomic: it grants one source a whole datagram (round
// robin among transmit path, answers, discovery ROM, one idle clock between grants) and passes
// its beats as they are, so a datagram is never interleaved with another and the stream rules
// of the sources (TDATA, TLAST, TDEST stable until taken) hold on the output.
// cnt_stages: the RTPS stages' counters packed (rosfpga_lab.rtl.fabriccounters' order), for
// rfl_fabric_top's counter readout.
`default_nettype none
`include "rfl_fabric_counters.vh"

module rfl_fabric_node #(
    parameter USER_DEST = 2,                    // TDEST of the transmit path's datagrams
`include "rfl_fabric_node_params.vh"
) (
    input  wire         clk,
    input  wire         rst_n,
    input  wire [31:0]  cfg_reader,             // our reader's entity id
    input  wire [31:0]  cfg_writer,             // the writer taken (0: any)
    input  wire [63:0]  cfg_time,               // INFO_TS of the transmit path
    input  wire         send_sedp,              // one clock: send the SEDP messages
    input  wire [7:0]   s_axis_tdata,
    input  wire         s_axis_tvalid,
    output wire         s_axis_tready,
    input  wire         s_axis_tlast,
    input  wire         s_axis_tuser,           // 1: user data, 0: metatraffic
    output wire [7:0]   m_axis_tdata,
    output wire         m_axis_tvalid,
    input  wire         m_axis_tready,
    output wire         m_axis_tlast,
    output wire [1:0]   m_axis_tdest,
    output wire [95:0]  m_dst_prefix,
    output wire         status_valid,           // the generated subscriber's status
    output wire [7:0]   status,
    output wire [15:0]  credit,                 // the answers' byte credit
    output wire [31:0]  cnt_samples,            // samples sent by the transmit path
    output wire [31:0]  cnt_answers,
    output wire [31:0]  cnt_no_credit,
    output wire [32*`RFL_NODE_COUNTER_COUNT-1:0] cnt_stages
);
`ifdef __ICARUS__
    initial begin
        if (PERIOD < 1) $fatal(1, "rfl_fabric_node: PERIOD must be at least 1");
        if (USER_DEST < 0 || USER_DEST > 3) $fatal(1, "rfl_fabric_node: USER_DEST must be 0..3");
    end
`else
    if (PERIOD < 1) begin : g_bad_period
        $error("rfl_fabric_node: PERIOD must be at least 1");
    end
    if (USER_DEST < 0 || USER_DEST > 3) begin : g_bad_user_dest
        $error("rfl_fabric_node: USER_DEST must be 0..3");
    end
`endif
    localparam [1:0] UDEST = USER_DEST[1:0];

    // ---- a register slice in (rfl_slice; timing): the stages' input decode starts at its
    // flip-flops, not at the top's port compare and rfl_udp_port's store, and s_axis_tready
    // is a flip-flop, not rfl_rtps_rx's ready through the routing below (a clock of latency)
    wire [7:0] i_tdata;
    wire i_tvalid, i_tready, i_tlast, i_tuser;
    rfl_slice #(.WIDTH(10)) u_in (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({s_axis_tuser, s_axis_tlast, s_axis_tdata}), .s_tvalid(s_axis_tvalid),
        .s_tready(s_axis_tready),
        .m_tdata({i_tuser, i_tlast, i_tdata}), .m_tvalid(i_tvalid), .m_tready(i_tready));

    // ---- routing in: the kind of a packet is its first beat's TUSER
    reg in_pkt, in_kind;
    wire kind = in_pkt ? in_kind : i_tuser;
    wire rx_in_ready, ctrl_in_ready;
    wire rx_in_valid = i_tvalid && kind;
    wire ctrl_in_valid = i_tvalid && !kind;
    assign i_tready = kind ? rx_in_ready : ctrl_in_ready;
    always @(posedge clk) begin
        if (!rst_n) begin
            in_pkt <= 1'b0;
            in_kind <= 1'b0;
        end else if (i_tvalid && i_tready) begin
            in_pkt <= !i_tlast;
            in_kind <= kind;
        end
    end

    // ---- user data: rx -> seam -> generated top -> tx
    wire [7:0] rx_tdata, rec_tdata, pub_tdata, tx_tdata;
    wire rx_tvalid, rx_tready, rx_tlast, rx_tuser, rec_tvalid, rec_tready;
    wire pub_tvalid, pub_tready, tx_tvalid, tx_tready, tx_tlast;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [127:0] guid;
    wire [63:0] seq, ts, tx_seq;
    wire ts_valid, frame_start, busy, rom_busy;
    wire [31:0] cnt_packets, cnt_bad_header, cnt_malformed, cnt_rx_samples, cnt_rx_dropped;
    wire [31:0] cnt_rx_repeated;
    wire [31:0] cnt_seam_samples, cnt_seam_dropped, cnt_too_long, cnt_datagrams, cnt_dropped;
    wire [31:0] cnt_requests, cnt_busy, cnt_ctrl_malformed, cnt_ctrl_bad_header;
    wire [7:0] framing;
    /* verilator lint_on UNUSEDSIGNAL */
    rfl_rtps_rx u_rx (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(GUID_PREFIX), .cfg_reader(cfg_reader),
        .cfg_writer(cfg_writer), .s_axis_tdata(i_tdata),
        .s_axis_tvalid(rx_in_valid), .s_axis_tready(rx_in_ready),
        .s_axis_tlast(i_tlast),
        .m_axis_tdata(rx_tdata), .m_axis_tvalid(rx_tvalid), .m_axis_tready(rx_tready),
        .m_axis_tlast(rx_tlast), .m_axis_tuser(rx_tuser), .m_sample_guid(guid),
        .m_sample_seq(seq), .m_sample_ts(ts), .m_sample_ts_valid(ts_valid),
        .cnt_packets(cnt_packets), .cnt_bad_header(cnt_bad_header),
        .cnt_malformed(cnt_malformed), .cnt_samples(cnt_rx_samples),
        .cnt_dropped(cnt_rx_dropped), .cnt_repeated(cnt_rx_repeated));
    // a register slice (timing): the seam's ready (its ring's fill compare) does not reach
    // rfl_rtps_rx's take, nor its output rfl_rtps_rx's input
    wire [7:0] rs_tdata;
    wire rs_tvalid, rs_tready, rs_tlast, rs_tuser;
    rfl_slice #(.WIDTH(10)) u_rx_out (
        .clk(clk), .rst_n(rst_n),
        .s_tdata({rx_tuser, rx_tlast, rx_tdata}), .s_tvalid(rx_tvalid), .s_tready(rx_tready),
        .m_tdata({rs_tuser, rs_tlast, rs_tdata}), .m_tvalid(rs_tvalid), .m_tready(rs_tready));
    rfl_rtps_to_cdr #(.MAX_BYTES(MAX_BYTES)) u_seam (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(rs_tdata), .s_axis_tvalid(rs_tvalid), .s_axis_tready(rs_tready),
        .s_axis_tlast(rs_tlast), .s_axis_tuser(rs_tuser),
        .m_tdata(rec_tdata), .m_tvalid(rec_tvalid), .m_tready(rec_tready),
        .cnt_samples(cnt_seam_samples), .cnt_dropped(cnt_seam_dropped),
        .cnt_too_long(cnt_too_long));
    rfl_node u_node (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(rec_tdata), .s_tvalid(rec_tvalid), .s_tready(rec_tready),
        .m_tdata(pub_tdata), .m_tvalid(pub_tvalid), .m_tready(pub_tready),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .busy(busy),
        .framing(framing));
    rfl_rtps_tx #(.GUID_PREFIX(GUID_PREFIX), .WRITER_ID(WRITER_ID), .READER_ID(READER_ID),
                  .FRAG_BYTES(FRAG_BYTES), .MAX_DATAGRAM(MAX_DATAGRAM), .INFO_TS(INFO_TS)) u_tx (
        .clk(clk), .rst_n(rst_n), .cfg_time(cfg_time),
        .s_tdata(pub_tdata), .s_tvalid(pub_tvalid), .s_tready(pub_tready),
        .m_axis_tdata(tx_tdata), .m_axis_tvalid(tx_tvalid),
        .m_axis_tready(tx_tready), .m_axis_tlast(tx_tlast), .m_seq(tx_seq),
        .cnt_samples(cnt_samples), .cnt_datagrams(cnt_datagrams), .cnt_dropped(cnt_dropped));

    assign cnt_stages = `RFL_NODE_COUNTER_BUS;

    // ---- metatraffic: ctrl -> answers
    wire [167:0] req_tdata;
    wire req_tvalid, req_tready, rx_byte;
    wire [7:0] an_tdata;
    wire an_tvalid, an_tready, an_tlast;
    wire [1:0] an_tdest;
    wire [95:0] an_prefix;
    rfl_rtps_ctrl #(.SLOTS(SLOTS), .SLOT_IDS(SLOT_IDS), .SLOT_MSGS(SLOT_MSGS),
                    .SLOT_LASTS(SLOT_LASTS)) u_ctrl (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(GUID_PREFIX), .s_axis_tdata(i_tdata),
        .s_axis_tvalid(ctrl_in_valid), .s_axis_tready(ctrl_in_ready),
        .s_axis_tlast(i_tlast), .m_axis_tdata(req_tdata), .m_axis_tvalid(req_tvalid),
        .m_axis_tready(req_tready), .rx_byte(rx_byte), .cnt_requests(cnt_requests),
        .cnt_busy(cnt_busy), .cnt_malformed(cnt_ctrl_malformed),
        .cnt_bad_header(cnt_ctrl_bad_header));
    rfl_rtps_disc_answer #(.ROM_FILE(ANSWER_FILE), .TABLE_FILE(ANSWER_TABLE_FILE),
                           .ROM_BYTES(ANSWER_BYTES), .MESSAGES(ANSWERS), .DST_AT(DST_AT),
                           .BASE_AT(BASE_AT), .COUNT_START(COUNT_START), .BURST(BURST),
                           .RATE(RATE)) u_answer (
        .clk(clk), .rst_n(rst_n), .rx_byte(rx_byte), .s_axis_tdata(req_tdata),
        .s_axis_tvalid(req_tvalid), .s_axis_tready(req_tready), .m_axis_tdata(an_tdata),
        .m_axis_tvalid(an_tvalid), .m_axis_tready(an_tready),
        .m_axis_tlast(an_tlast), .m_axis_tdest(an_tdest), .m_dst_prefix(an_prefix),
        .credit(credit), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit));

    // ---- discovery: SPDP every PERIOD clocks, SEDP on request
    wire [7:0] rom_tdata;
    wire rom_tvalid, rom_tready, rom_tlast;
    wire [1:0] rom_tdest;
    rfl_rtps_disc_rom #(.ROM_FILE(ROM_FILE), .TABLE_FILE(TABLE_FILE), .ROM_BYTES(ROM_BYTES),
                        .MESSAGES(MESSAGES), .PERIOD(PERIOD)) u_rom (
        .clk(clk), .rst_n(rst_n), .send_sedp(send_sedp), .busy(rom_busy),
        .m_axis_tdata(rom_tdata), .m_axis_tvalid(rom_tvalid), .m_axis_tready(rom_tready),
        .m_axis_tlast(rom_tlast), .m_axis_tdest(rom_tdest));

    // ---- frame-atomic round-robin arbiter: 0 transmit path, 1 answers, 2 discovery ROM
    rfl_frame_arbiter #(.DATA_BITS(8), .DEST_BITS(2), .USER_BITS(96)) u_arb (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata({rom_tdata, an_tdata, tx_tdata}),
        .s_axis_tvalid({rom_tvalid, an_tvalid, tx_tvalid}),
        .s_axis_tready({rom_tready, an_tready, tx_tready}),
        .s_axis_tlast({rom_tlast, an_tlast, tx_tlast}),
        .s_axis_tdest({rom_tdest, an_tdest, UDEST}),
        .s_axis_tuser({96'd0, an_prefix, 96'd0}),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast),
        .m_axis_tdest(m_axis_tdest), .m_axis_tuser(m_dst_prefix));

`ifdef FORMAL
    // The routing in, on the input slice's output (fv_fabric_node proves it): f_pkt, a packet's
    // beat taken and not yet its TLAST; f_kind, the TUSER of its first beat. Each beat is offered
    // to the side of its packet's kind alone, taken when that side is ready; metatraffic is
    // never held back there (rfl_rtps_ctrl is always ready). The latch agrees with f_pkt, f_kind (the invariant).
    // The answers' credit is earned by each metatraffic byte taken and by nothing else: with
    // rfl_rtps_disc_answer's bound (its FORMAL block, in place), the answers' bytes out are never
    // more than BURST + RATE x the metatraffic bytes in.
    reg f_pkt, f_kind;
    always @(posedge clk) begin
        if (!rst_n) begin
            f_pkt <= 1'b0;
            f_kind <= 1'b0;
        end else if (i_tvalid && i_tready) begin
            if (!f_pkt) f_kind <= i_tuser;
            f_pkt <= !i_tlast;
        end
    end
    wire f_k = f_pkt ? f_kind : i_tuser;
    always @(*) if (rst_n) begin
        assert(rx_in_valid == (i_tvalid && f_k));
        assert(ctrl_in_valid == (i_tvalid && !f_k));
        assert(i_tready == (f_k ? rx_in_ready : ctrl_in_ready));
        if (i_tvalid && !f_k) assert(i_tready);
        assert(in_pkt == f_pkt);
        if (f_pkt) assert(in_kind == f_kind);
        assert(rx_byte == (i_tvalid && i_tready && !f_k));
    end
`endif
endmodule

`default_nettype wire
