// rfl_fabric_top -- the ROS 2 node in the fabric on the network (issue 31): the vendored LiteEth
// UDP/IP core (vendor/README.md) -> rfl_udp_port -> rfl_fabric_node, and back. The core: the
// GMII simulation variant (vendor/liteeth_udp_gmii.v, one clock), or with RFL_FABRIC_RGMII
// defined the ECP5 RGMII board variant (vendor/liteeth_udp_ecp5_rgmii.v: the PHY's receive
// clock drives its receive and send side, its 32-bit core runs on eth_clk, its 8-bit UDP port
// on clk, FIFOs crossing between the three), the glue the same; the board top
// rfl_board_5a75b.v defines it.
// Ports (RTPS 2.3 9.6.1.1, the mapping rtps.entities owns; rtl.discrom.top_parameters gives
// them and SPDP_GROUP; 0, the default, is refused): SPDP_PORT (the domain's SPDP multicast
// port), META_PORT and USER_PORT (this participant's metatraffic and user-data unicast ports).
// LiteEth passes up the datagrams to the ports that agree with all three on the bits where the
// three agree; this top keeps the three and drops the others (counted: cnt_rx_port). Kind (the
// node's s_axis_tuser): 1 for USER_PORT, 0 for SPDP_PORT and META_PORT.
// Sent, by the node's TDEST (rtl.discrom's DEST_SPDP, DEST_META, DEST_USER): 0 to
// SPDP_GROUP:SPDP_PORT (LiteEth maps the group to its multicast MAC), 1 to the peer's
// metatraffic locator, 2 (and 3) to its default (user-data) locator; from META_PORT, or
// USER_PORT for user data. One peer: with cfg_learn high the one rfl_spdp_peer learns from the
// SPDP announcements that come to SPDP_PORT or META_PORT (so of this domain: LiteEth's port
// filter and this top's keep only this domain's ports), whose taking or change sends the SEDP
// set (send_sedp; rfl_spdp_peer's header says which participant is the peer, and why); a
// datagram to the peer while none is known is dropped. With cfg_learn low the registers
// cfg_peer_* (a point-to-point link, or a peer the host's software chose) and the send_sedp
// input. So an answer to another asker (the node's m_dst_prefix, not read here) still goes to
// the one peer, and user data reaches one reader.
// The counter readout (rfl_counter_readout) takes what comes to COUNTERS_PORT (the fourth port
// LiteEth passes) and answers a well-formed request with every counter, the top's, the node's
// (its cnt_stages) and its own, in rosfpga_lab.rtl.fabriccounters' order (rfl_fabric_counters.vh),
// to the request's sender from COUNTERS_PORT; rfl_frame_arbiter puts its answers and the node's
// datagrams out whole, one after the other.
// The glue is proven with LiteEth and the node as stream models (rtl/formal/fv_fabric_top.sv).
`default_nettype none
`include "rfl_fabric_counters.vh"

module rfl_fabric_top #(
`include "rfl_fabric_top_params.vh"
) (
`ifdef RFL_FABRIC_RGMII
    input  wire         clk,                    // 125 MHz: the node's and LiteEth's UDP port's
    input  wire         eth_clk,                // LiteEth's 32-bit core's (52.08 MHz)
    input  wire         eth_rst_n,              // eth_clk's reset (rst_n is clk's)
`else
    input  wire         clk,                    // 125 MHz: GMII's receive and send clock
`endif
    input  wire         rst_n,
    input  wire [47:0]  cfg_mac,                // held while running, as the cfg_peer_*
    input  wire         cfg_learn,              // 1: the peer from SPDP; 0: cfg_peer_*
    input  wire [31:0]  cfg_ip,
    input  wire [31:0]  cfg_peer_ip,
    input  wire [15:0]  cfg_peer_meta_port,
    input  wire [15:0]  cfg_peer_user_port,
    input  wire [31:0]  cfg_reader,
    input  wire [31:0]  cfg_writer,
    input  wire [63:0]  cfg_time,
    input  wire         send_sedp,              // (with cfg_learn as well)
`ifdef RFL_FABRIC_RGMII
    input  wire         rgmii_rx_clk,           // 125 MHz from the PHY
    input  wire         rgmii_rx_ctl,
    input  wire [3:0]   rgmii_rxd,
    output wire         rgmii_tx_clk,
    output wire         rgmii_tx_ctl,
    output wire [3:0]   rgmii_txd,
`else
    input  wire [7:0]   gmii_rxd,
    input  wire         gmii_rx_dv,
    input  wire         gmii_rx_er,
    output wire [7:0]   gmii_txd,
    output wire         gmii_tx_en,
    output wire         gmii_tx_er,
`endif
    output wire         status_valid,
    output wire [7:0]   status,
    output wire [15:0]  credit,
    output wire [31:0]  cnt_samples,
    output wire [31:0]  cnt_answers,
    output wire [31:0]  cnt_no_credit,
    output wire [31:0]  cnt_rx_packets,         // rfl_udp_port's
    output wire [31:0]  cnt_rx_error,
    output wire [31:0]  cnt_rx_length,
    output wire [31:0]  cnt_rx_overflow,
    output wire [31:0]  cnt_tx_packets,
    output wire [31:0]  cnt_tx_overflow,
    output wire [31:0]  cnt_rx_port,            // datagrams to another port LiteEth passed
    output wire [31:0]  cnt_rx_header,          // rfl_udp_port's: frames LiteEth dropped
    output wire [31:0]  cnt_rx_other,
    output wire [31:0]  cnt_peer_learned,       // rfl_spdp_peer's: peers taken or changed,
    output wire [31:0]  cnt_peer_refused,       // announcements refused,
    output wire [31:0]  cnt_peer_other          // another participant's while the peer is live
);
    // 0: unset (the defaults), refused outside a proof: Yosys elaborates a file's defaults when
    // it reads it, the proof sets them
    localparam UNSET = SPDP_PORT == 0 || META_PORT == 0 || USER_PORT == 0 || SPDP_GROUP == 0 ||
                       COUNTERS_PORT == 0 || COUNTERS_GAP == 0;
    localparam SAME = SPDP_PORT == META_PORT || SPDP_PORT == USER_PORT || META_PORT == USER_PORT ||
                      COUNTERS_PORT == SPDP_PORT || COUNTERS_PORT == META_PORT ||
                      COUNTERS_PORT == USER_PORT;
`ifdef __ICARUS__
    initial begin
        if (UNSET)
            $fatal(1, "rfl_fabric_top: set the *_PORT parameters, SPDP_GROUP and COUNTERS_GAP");
        if (SPDP_PORT < 0 || SPDP_PORT > 65535 || META_PORT < 0 || META_PORT > 65535 ||
            USER_PORT < 0 || USER_PORT > 65535 || COUNTERS_PORT < 0 || COUNTERS_PORT > 65535)
            $fatal(1, "rfl_fabric_top: the ports must be 1..65535");
        if (!UNSET && SAME)
            $fatal(1, "rfl_fabric_top: the four *_PORT parameters must differ");
        if (!UNSET && SPDP_GROUP[31:28] != 4'he)
            $fatal(1, "rfl_fabric_top: SPDP_GROUP must be an IPv4 multicast group");
    end
`else
`ifndef FORMAL
    if (UNSET) begin : g_unset
        $error("rfl_fabric_top: set the *_PORT parameters, SPDP_GROUP and COUNTERS_GAP");
    end
`endif
    if (SPDP_PORT < 0 || SPDP_PORT > 65535 || META_PORT < 0 || META_PORT > 65535 ||
        USER_PORT < 0 || USER_PORT > 65535 || COUNTERS_PORT < 0 || COUNTERS_PORT > 65535
    ) begin : g_bad_ports
        $error("rfl_fabric_top: the ports must be 1..65535");
    end
    if (!UNSET && SAME) begin : g_same_ports
        $error("rfl_fabric_top: the four *_PORT parameters must differ");
    end
    if (!UNSET && SPDP_GROUP[31:28] != 4'he) begin : g_bad_group
        $error("rfl_fabric_top: SPDP_GROUP must be an IPv4 multicast group");
    end
`endif
    localparam [15:0] SPDP = SPDP_PORT[15:0], META = META_PORT[15:0], USER = USER_PORT[15:0];
    localparam [15:0] CNT = COUNTERS_PORT[15:0];
    // the bits on which the four ports agree: LiteEth's port filter
    localparam [15:0] PORT_MASK = ~((SPDP ^ META) | (SPDP ^ USER) | (SPDP ^ CNT));

    // ---- LiteEth <-> rfl_udp_port
    wire [7:0] le_rx_data, le_tx_data;
    wire le_rx_valid, le_rx_ready, le_rx_last, le_rx_error, le_rx_last_be;
    wire le_tx_valid, le_tx_ready, le_tx_last;
    wire le_drop_header, le_drop_other;
    wire [31:0] le_rx_ip, le_tx_ip;
    wire [15:0] le_rx_sport, le_rx_dport, le_rx_len, le_tx_sport, le_tx_dport, le_tx_len;
`ifdef RFL_FABRIC_RGMII
    liteeth_udp_ecp5_rgmii u_eth (
        .sys_clock(eth_clk), .sys_reset(!eth_rst_n), .port_clock(clk), .port_reset(!rst_n),
        .mac_address(cfg_mac), .ip_address(cfg_ip), .udp_rx_port(SPDP),
        .udp_rx_port_mask(PORT_MASK), .ip_multicast(SPDP_GROUP),
        .rgmii_clocks_rx(rgmii_rx_clk), .rgmii_clocks_tx(rgmii_tx_clk),
        .rgmii_pads_rx_ctl(rgmii_rx_ctl), .rgmii_pads_rx_data(rgmii_rxd),
        .rgmii_pads_tx_ctl(rgmii_tx_ctl), .rgmii_pads_tx_data(rgmii_txd),
`else
    liteeth_udp_gmii u_eth (
        .sys_clock(clk), .sys_reset(!rst_n),
        .mac_address(cfg_mac), .ip_address(cfg_ip), .udp_rx_port(SPDP),
        .udp_rx_port_mask(PORT_MASK), .ip_multicast(SPDP_GROUP),
        // LiteEth's GMII PHY ignores rx_er: a byte the PHY marks bad is inverted, so the
        // frame's FCS fails (CRC-32 finds any one bad byte; several, all but 1 in 2**32) and
        // it is dropped and counted in cnt_rx_error as one
        .gmii_pads_rx_data(gmii_rxd ^ {8{gmii_rx_dv && gmii_rx_er}}),
        .gmii_pads_rx_dv(gmii_rx_dv), .gmii_pads_rx_er(gmii_rx_er),
        .gmii_pads_tx_data(gmii_txd), .gmii_pads_tx_en(gmii_tx_en), .gmii_pads_tx_er(gmii_tx_er),
`endif
        .udp_source_data(le_rx_data), .udp_source_valid(le_rx_valid),
        .udp_source_ready(le_rx_ready), .udp_source_last(le_rx_last),
        .udp_source_last_be(le_rx_last_be), .udp_source_error(le_rx_error),
        .udp_source_ip_address(le_rx_ip), .udp_source_src_port(le_rx_sport),
        .udp_source_dst_port(le_rx_dport), .udp_source_length(le_rx_len),
        .udp_sink_data(le_tx_data), .udp_sink_valid(le_tx_valid), .udp_sink_ready(le_tx_ready),
        .udp_sink_last(le_tx_last), .udp_sink_last_be(le_tx_last),
        .udp_sink_ip_address(le_tx_ip), .udp_sink_src_port(le_tx_sport),
        .udp_sink_dst_port(le_tx_dport), .udp_sink_length(le_tx_len),
        .rx_drop_header(le_drop_header), .rx_drop_other(le_drop_other));

    // ---- rfl_udp_port: whole payloads each way
    wire [7:0] p_rx_tdata, p_tx_tdata;
    wire p_rx_tvalid, p_rx_tready, p_rx_tlast, p_tx_tvalid, p_tx_tready, p_tx_tlast;
    wire [31:0] p_rx_ip;
    wire [15:0] p_rx_sport, p_rx_dport, p_rx_len;
    reg [31:0] p_tx_ip;
    reg [15:0] p_tx_sport, p_tx_dport;
    /* verilator lint_off UNUSEDSIGNAL */
    wire unused_ok = &{1'b0, le_rx_last_be, p_rx_len};
    /* verilator lint_on UNUSEDSIGNAL */
    rfl_udp_port #(.RX_BITS(RX_BITS), .TX_BITS(TX_BITS), .QUEUE_BITS(QUEUE_BITS),
                   .COUNT_BITS(32)) u_port (
        .clk(clk), .rst_n(rst_n),
        .le_rx_data(le_rx_data), .le_rx_valid(le_rx_valid), .le_rx_ready(le_rx_ready),
        .le_rx_last(le_rx_last), .le_rx_error(le_rx_error), .le_rx_ip(le_rx_ip),
        .le_rx_src_port(le_rx_sport), .le_rx_dst_port(le_rx_dport), .le_rx_length(le_rx_len),
        .le_rx_drop_header(le_drop_header), .le_rx_drop_other(le_drop_other),
        .le_tx_data(le_tx_data), .le_tx_valid(le_tx_valid), .le_tx_ready(le_tx_ready),
        .le_tx_last(le_tx_last), .le_tx_ip(le_tx_ip), .le_tx_src_port(le_tx_sport),
        .le_tx_dst_port(le_tx_dport), .le_tx_length(le_tx_len),
        .m_axis_tdata(p_rx_tdata), .m_axis_tvalid(p_rx_tvalid), .m_axis_tready(p_rx_tready),
        .m_axis_tlast(p_rx_tlast), .m_udp_ip(p_rx_ip), .m_udp_src_port(p_rx_sport),
        .m_udp_dst_port(p_rx_dport), .m_udp_length(p_rx_len),
        .s_axis_tdata(p_tx_tdata), .s_axis_tvalid(p_tx_tvalid), .s_axis_tready(p_tx_tready),
        .s_axis_tlast(p_tx_tlast), .s_udp_ip(p_tx_ip), .s_udp_src_port(p_tx_sport),
        .s_udp_dst_port(p_tx_dport),
        .cnt_rx_packets(cnt_rx_packets), .cnt_rx_error(cnt_rx_error),
        .cnt_rx_length(cnt_rx_length), .cnt_rx_overflow(cnt_rx_overflow),
        .cnt_tx_packets(cnt_tx_packets), .cnt_tx_overflow(cnt_tx_overflow),
        .cnt_rx_header(cnt_rx_header), .cnt_rx_other(cnt_rx_other));

    // ---- received: the kind from the destination port (held by rfl_udp_port for the packet)
    wire to_user = p_rx_dport == USER;
    wire keep = to_user || p_rx_dport == META || p_rx_dport == SPDP;
    wire to_cnt = p_rx_dport == CNT;            // the readout: always ready
    wire n_rx_tready;
    assign p_rx_tready = keep ? n_rx_tready : 1'b1;
    reg [31:0] c_port;
    always @(posedge clk) begin
        if (!rst_n) c_port <= 32'd0;
        else if (p_rx_tvalid && p_rx_tready && p_rx_tlast && !keep && !to_cnt &&
                 c_port != 32'hffffffff)
            c_port <= c_port + 32'd1;
    end
    assign cnt_rx_port = c_port;

    // ---- the peer: learned from SPDP (cfg_learn) or the registers
    wire l_valid, l_sedp;
    wire [31:0] l_meta_ip, l_user_ip;
    wire [15:0] l_meta_port, l_user_port;
    /* verilator lint_off UNUSEDSIGNAL */
    wire l_ready;                               // (always 1)
    /* verilator lint_on UNUSEDSIGNAL */
    // PERIOD is rtps.limits.ANNOUNCE_SECONDS (1 s) of clocks (rtl.discrom): the lease's second
    rfl_spdp_peer #(.SPDP_WRITER_ID(SPDP_WRITER_ID), .SPDP_PIDS(SPDP_PIDS),
                    .SPDP_ENCAPS(SPDP_ENCAPS), .SPDP_LOCATOR_KIND(SPDP_LOCATOR_KIND),
                    .SPDP_LEASE_DEFAULT(SPDP_LEASE_DEFAULT), .SPDP_LEASE_MAX(SPDP_LEASE_MAX),
                    .TICK(PERIOD), .RESEND(PERIOD < 2 ? 2 : PERIOD)) u_peer (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(GUID_PREFIX), .s_axis_tdata(p_rx_tdata),
        .s_axis_tvalid(p_rx_tvalid && p_rx_tready && keep && !to_user),
        .s_axis_tready(l_ready), .s_axis_tlast(p_rx_tlast), .s_src_ip(p_rx_ip),
        .peer_known(l_valid),
        .peer_meta_ip(l_meta_ip), .peer_meta_port(l_meta_port), .peer_user_ip(l_user_ip),
        .peer_user_port(l_user_port), .send_sedp(l_sedp), .cnt_learned(cnt_peer_learned),
        .cnt_refused(cnt_peer_refused), .cnt_other(cnt_peer_other));
    wire [31:0] peer_meta_ip = cfg_learn ? l_meta_ip : cfg_peer_ip;
    wire [31:0] peer_user_ip = cfg_learn ? l_user_ip : cfg_peer_ip;
    wire [15:0] peer_meta_port = cfg_learn ? l_meta_port : cfg_peer_meta_port;
    wire [15:0] peer_user_port = cfg_learn ? l_user_port : cfg_peer_user_port;
    wire node_sedp = cfg_learn ? l_sedp : send_sedp;

    // ---- the counter readout: the top's counters and the node's, then its own
    wire [32*`RFL_NODE_COUNTER_COUNT-1:0] cnt_stages;
    wire [7:0] r_tdata;
    wire r_tvalid, r_tready, r_tlast;
    wire [31:0] r_ip;
    wire [15:0] r_port;
    /* verilator lint_off UNUSEDSIGNAL */
    wire r_in_ready;                            // (always 1)
    wire [31:0] cr_answered, cr_malformed, cr_limited;  // in its answers
    /* verilator lint_on UNUSEDSIGNAL */
    rfl_counter_readout #(.COUNT(`RFL_TOP_COUNTER_COUNT), .MAGIC(`RFL_COUNTERS_MAGIC),
                          .GAP(COUNTERS_GAP < 1 ? 1 : COUNTERS_GAP)) u_counters (  // 0: UNSET
        .clk(clk), .rst_n(rst_n), .counters(`RFL_TOP_COUNTER_BUS),
        .s_axis_tdata(p_rx_tdata), .s_axis_tvalid(p_rx_tvalid && to_cnt),
        .s_axis_tready(r_in_ready), .s_axis_tlast(p_rx_tlast), .s_ip(p_rx_ip),
        .s_port(p_rx_sport), .m_axis_tdata(r_tdata), .m_axis_tvalid(r_tvalid),
        .m_axis_tready(r_tready), .m_axis_tlast(r_tlast), .m_ip(r_ip), .m_port(r_port),
        .cnt_answered(cr_answered), .cnt_malformed(cr_malformed),
        .cnt_limited(cr_limited));

    // ---- sent: the node's datagrams and the readout's answers, whole, one after the other
    // (TUSER: 1 and the answer's address and port for the readout's, 0 for the node's)
    wire [1:0] n_tdest, a_tdest;
    wire [7:0] n_tdata;
    wire n_tvalid, n_tlast, n_tready, a_tvalid, a_tready, a_tlast;
    wire [48:0] a_tuser;
    wire a_cnt = a_tuser[48];
    /* verilator lint_off UNUSEDSIGNAL */
    wire [2:0] arb_ready;                       // (the third source is none)
    /* verilator lint_on UNUSEDSIGNAL */
    assign n_tready = arb_ready[0];
    assign r_tready = arb_ready[1];
    rfl_frame_arbiter #(.DATA_BITS(8), .DEST_BITS(2), .USER_BITS(49)) u_tx_arb (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata({8'd0, r_tdata, n_tdata}),
        .s_axis_tvalid({1'b0, r_tvalid, n_tvalid}), .s_axis_tready(arb_ready),
        .s_axis_tlast({1'b0, r_tlast, n_tlast}), .s_axis_tdest({2'd0, 2'd0, n_tdest}),
        .s_axis_tuser({49'd0, 1'b1, r_ip, r_port, 49'd0}),
        .m_axis_tdata(p_tx_tdata), .m_axis_tvalid(a_tvalid), .m_axis_tready(a_tready),
        .m_axis_tlast(a_tlast), .m_axis_tdest(a_tdest), .m_axis_tuser(a_tuser));

    // the destination from TDEST (held until taken); a datagram to the peer while none is
    // learned is dropped (decided at its first beat, for all of it)
    reg tx_in, tx_drop_r;
    wire tx_drop = tx_in ? tx_drop_r : (cfg_learn && !l_valid && a_tdest != 2'd0 && !a_cnt);
    assign p_tx_tvalid = a_tvalid && !tx_drop;
    assign p_tx_tlast = a_tlast;
    assign a_tready = tx_drop ? 1'b1 : p_tx_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            tx_in <= 1'b0;
            tx_drop_r <= 1'b0;
        end else if (a_tvalid && a_tready) begin
            tx_in <= !a_tlast;
            tx_drop_r <= tx_drop;
        end
    end
    /* verilator lint_off UNUSEDSIGNAL */
    wire [95:0] n_dst_prefix;                   // one peer: see the header
    /* verilator lint_on UNUSEDSIGNAL */
    always @* begin
        case (a_cnt ? 2'd0 : a_tdest)
            2'd0: begin
                p_tx_ip = a_cnt ? a_tuser[47:16] : SPDP_GROUP;
                p_tx_dport = a_cnt ? a_tuser[15:0] : SPDP;
                p_tx_sport = a_cnt ? CNT : META;
            end
            2'd1: begin
                p_tx_ip = peer_meta_ip;
                p_tx_dport = peer_meta_port;
                p_tx_sport = META;
            end
            default: begin
                p_tx_ip = peer_user_ip;
                p_tx_dport = peer_user_port;
                p_tx_sport = USER;
            end
        endcase
    end

    rfl_fabric_node #(
        .USER_DEST(2),
`include "rfl_fabric_node_pass.vh"
    ) u_node (
        .clk(clk), .rst_n(rst_n), .cfg_reader(cfg_reader),
        .cfg_writer(cfg_writer), .cfg_time(cfg_time), .send_sedp(node_sedp),
        .s_axis_tdata(p_rx_tdata), .s_axis_tvalid(p_rx_tvalid && keep),
        .s_axis_tready(n_rx_tready), .s_axis_tlast(p_rx_tlast), .s_axis_tuser(to_user),
        .m_axis_tdata(n_tdata), .m_axis_tvalid(n_tvalid), .m_axis_tready(n_tready),
        .m_axis_tlast(n_tlast), .m_axis_tdest(n_tdest), .m_dst_prefix(n_dst_prefix),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(cnt_samples), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit),
        .cnt_stages(cnt_stages));
endmodule

`default_nettype wire
