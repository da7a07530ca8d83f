// rfl_fabric_top -- the ROS 2 node in the fabric on the network (issue 31): the vendored LiteEth
// UDP/IP core (vendor/README.md) -> rfl_udp_port -> rfl_fabric_node, and back. The core: the
// GMII simulation variant (vendor/liteeth_udp_gmii.v, one clock), or with RFL_FABRIC_RGMII
// defined the ECP5 RGMII board variant (vendor/liteeth_udp_ecp5_rgmii.v: the PHY's receive
// clock drives its receive and send side, its FIFOs cross to clk), the glue the same; the
// board top rfl_board_5a75b.v defines it.
// Ports (RTPS 2.3 9.6.1.1, the mapping rtps.entities owns; rtl.discrom.top_parameters gives
// them and SPDP_GROUP; 0, the default, is refused): SPDP_PORT (the domain's SPDP multicast
// port), META_PORT and USER_PORT (this participant's metatraffic and user-data unicast ports).
// LiteEth passes up the datagrams to the ports that agree with all three on the bits where the
// three agree; this top keeps the three and drops the others (counted: cnt_rx_port). Kind (the
// node's s_axis_tuser): 1 for USER_PORT, 0 for SPDP_PORT and META_PORT.
// Sent, by the node's TDEST (rtl.discrom's DEST_SPDP, DEST_META, DEST_USER): 0 to
// SPDP_GROUP:SPDP_PORT (LiteEth maps the group to its multicast MAC), 1 to
// cfg_peer_ip:cfg_peer_meta_port, 2 (and 3) to cfg_peer_ip:cfg_peer_user_port; from META_PORT,
// or USER_PORT for user data. The peer's locators are registers the host sets (one peer: a
// point-to-point link, or the peer the software side discovered; its ports from the mapping for
// its participant index): the circuit does not read the locators of the peers' SPDP
// announcements. So an answer to another asker (the node's m_dst_prefix, not read here) still
// goes to cfg_peer_*, and user data reaches one reader.
// The glue is proven with LiteEth and the node as stream models (rtl/formal/fv_fabric_top.sv).
`default_nettype none

module rfl_fabric_top #(
`include "rfl_fabric_top_params.vh"
) (
`ifdef RFL_FABRIC_RGMII
    input  wire         clk,                    // 125 MHz: LiteEth's sys clock and the node's
`else
    input  wire         clk,                    // 125 MHz: GMII's receive and send clock
`endif
    input  wire         rst_n,
    input  wire [47:0]  cfg_mac,                // held while running, as the cfg_peer_*
    input  wire [31:0]  cfg_ip,
    input  wire [31:0]  cfg_peer_ip,
    input  wire [15:0]  cfg_peer_meta_port,
    input  wire [15:0]  cfg_peer_user_port,
    input  wire [31:0]  cfg_reader,
    input  wire [31:0]  cfg_writer,
    input  wire [63:0]  cfg_time,
    input  wire         send_sedp,
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
    output wire [31:0]  cnt_rx_other
);
    // 0: unset (the defaults), refused outside a proof: Yosys elaborates a file's defaults when
    // it reads it, the proof sets them
    localparam UNSET = SPDP_PORT == 0 || META_PORT == 0 || USER_PORT == 0 || SPDP_GROUP == 0;
    localparam SAME = SPDP_PORT == META_PORT || SPDP_PORT == USER_PORT || META_PORT == USER_PORT;
`ifdef __ICARUS__
    initial begin
        if (UNSET)
            $fatal(1, "rfl_fabric_top: set SPDP_PORT, META_PORT, USER_PORT and SPDP_GROUP");
        if (SPDP_PORT < 0 || SPDP_PORT > 65535 || META_PORT < 0 || META_PORT > 65535 ||
            USER_PORT < 0 || USER_PORT > 65535)
            $fatal(1, "rfl_fabric_top: the ports must be 1..65535");
        if (!UNSET && SAME)
            $fatal(1, "rfl_fabric_top: SPDP_PORT, META_PORT and USER_PORT must differ");
        if (!UNSET && SPDP_GROUP[31:28] != 4'he)
            $fatal(1, "rfl_fabric_top: SPDP_GROUP must be an IPv4 multicast group");
    end
`else
`ifndef FORMAL
    if (UNSET) begin : g_unset
        $error("rfl_fabric_top: set SPDP_PORT, META_PORT, USER_PORT and SPDP_GROUP");
    end
`endif
    if (SPDP_PORT < 0 || SPDP_PORT > 65535 || META_PORT < 0 || META_PORT > 65535 ||
        USER_PORT < 0 || USER_PORT > 65535) begin : g_bad_ports
        $error("rfl_fabric_top: the ports must be 1..65535");
    end
    if (!UNSET && SAME) begin : g_same_ports
        $error("rfl_fabric_top: SPDP_PORT, META_PORT and USER_PORT must differ");
    end
    if (!UNSET && SPDP_GROUP[31:28] != 4'he) begin : g_bad_group
        $error("rfl_fabric_top: SPDP_GROUP must be an IPv4 multicast group");
    end
`endif
    localparam [15:0] SPDP = SPDP_PORT[15:0], META = META_PORT[15:0], USER = USER_PORT[15:0];
    // the bits on which the three ports agree: LiteEth's port filter
    localparam [15:0] PORT_MASK = ~((SPDP ^ META) | (SPDP ^ USER));

    // ---- LiteEth <-> rfl_udp_port
    wire [7:0] le_rx_data, le_tx_data;
    wire le_rx_valid, le_rx_ready, le_rx_last, le_rx_error, le_rx_last_be;
    wire le_tx_valid, le_tx_ready, le_tx_last;
    wire le_drop_header, le_drop_other;
    wire [31:0] le_rx_ip, le_tx_ip;
    wire [15:0] le_rx_sport, le_rx_dport, le_rx_len, le_tx_sport, le_tx_dport, le_tx_len;
`ifdef RFL_FABRIC_RGMII
    liteeth_udp_ecp5_rgmii u_eth (
        .sys_clock(clk), .sys_reset(!rst_n),
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
    wire unused_ok = &{1'b0, le_rx_last_be, p_rx_ip, p_rx_sport, p_rx_len};
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
    wire n_tready;
    assign p_rx_tready = keep ? n_tready : 1'b1;
    reg [31:0] c_port;
    always @(posedge clk) begin
        if (!rst_n) c_port <= 32'd0;
        else if (p_rx_tvalid && p_rx_tready && p_rx_tlast && !keep && c_port != 32'hffffffff)
            c_port <= c_port + 32'd1;
    end
    assign cnt_rx_port = c_port;

    // ---- sent: the destination from TDEST (held by the node until taken)
    wire [1:0] n_tdest;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [95:0] n_dst_prefix;                   // one peer: see the header
    /* verilator lint_on UNUSEDSIGNAL */
    always @* begin
        case (n_tdest)
            2'd0: begin
                p_tx_ip = SPDP_GROUP;
                p_tx_dport = SPDP;
                p_tx_sport = META;
            end
            2'd1: begin
                p_tx_ip = cfg_peer_ip;
                p_tx_dport = cfg_peer_meta_port;
                p_tx_sport = META;
            end
            default: begin
                p_tx_ip = cfg_peer_ip;
                p_tx_dport = cfg_peer_user_port;
                p_tx_sport = USER;
            end
        endcase
    end

    rfl_fabric_node #(
        .USER_DEST(2),
`include "rfl_fabric_node_pass.vh"
    ) u_node (
        .clk(clk), .rst_n(rst_n), .cfg_reader(cfg_reader),
        .cfg_writer(cfg_writer), .cfg_time(cfg_time), .send_sedp(send_sedp),
        .s_axis_tdata(p_rx_tdata), .s_axis_tvalid(p_rx_tvalid && keep),
        .s_axis_tready(n_tready), .s_axis_tlast(p_rx_tlast), .s_axis_tuser(to_user),
        .m_axis_tdata(p_tx_tdata), .m_axis_tvalid(p_tx_tvalid), .m_axis_tready(p_tx_tready),
        .m_axis_tlast(p_tx_tlast), .m_axis_tdest(n_tdest), .m_dst_prefix(n_dst_prefix),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(cnt_samples), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit));
endmodule

`default_nettype wire
