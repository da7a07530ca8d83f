// udp_gmii_top -- the UDP stage on a GMII PHY (issue #31): the vendored LiteEth core's
// simulation variant (vendor/liteeth_udp_gmii.v: GMII in LiteEth's model mode, receive and send
// on clk) joined to the lab's streams by rfl_udp_port (which says what is dropped and counted).
// The node's MAC and IP addresses and its UDP port are inputs (held while running): LiteEth
// answers ARP requests for cfg_ip and ICMP echo, and passes up the UDP datagrams to cfg_ip or
// the group cfg_mcast and to the ports cfg_port / cfg_port_mask select.
`default_nettype none

module udp_gmii_top #(
    parameter RX_BITS    = 11,                  // checked by rfl_udp_store / rfl_udp_port
    parameter TX_BITS    = 11,
    parameter QUEUE_BITS = 2,
    parameter COUNT_BITS = 32
) (
    input  wire                  clk,           // 125 MHz: GMII's receive and send clock
    input  wire                  rst_n,
    input  wire [47:0]           cfg_mac,
    input  wire [31:0]           cfg_ip,
    input  wire [15:0]           cfg_port,      // the UDP ports received: those equal to
    input  wire [15:0]           cfg_port_mask, // cfg_port on the mask's bits
    input  wire [31:0]           cfg_mcast,     // the IPv4 multicast group received
    input  wire [7:0]            gmii_rxd,
    input  wire                  gmii_rx_dv,
    input  wire                  gmii_rx_er,
    output wire [7:0]            gmii_txd,
    output wire                  gmii_tx_en,
    output wire                  gmii_tx_er,
    output wire [7:0]            m_axis_tdata,
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  m_axis_tlast,
    output wire [31:0]           m_udp_ip,
    output wire [15:0]           m_udp_src_port,
    output wire [15:0]           m_udp_dst_port,
    output wire [15:0]           m_udp_length,
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,
    input  wire                  s_axis_tlast,
    input  wire [31:0]           s_udp_ip,
    input  wire [15:0]           s_udp_src_port,
    input  wire [15:0]           s_udp_dst_port,
    output wire [COUNT_BITS-1:0] cnt_rx_packets,
    output wire [COUNT_BITS-1:0] cnt_rx_error,
    output wire [COUNT_BITS-1:0] cnt_rx_length,
    output wire [COUNT_BITS-1:0] cnt_rx_overflow,
    output wire [COUNT_BITS-1:0] cnt_tx_packets,
    output wire [COUNT_BITS-1:0] cnt_tx_overflow,
    output wire [COUNT_BITS-1:0] cnt_rx_header,
    output wire [COUNT_BITS-1:0] cnt_rx_other
);
    wire [7:0] rx_data, tx_data;
    wire rx_valid, rx_ready, rx_last, rx_error, rx_last_be;
    wire tx_valid, tx_ready, tx_last;
    wire [31:0] rx_ip, tx_ip;
    wire [15:0] rx_sport, rx_dport, rx_len, tx_sport, tx_dport, tx_len;
    wire drop_header, drop_other;

    liteeth_udp_gmii u_eth (
        .sys_clock(clk), .sys_reset(!rst_n),
        .mac_address(cfg_mac), .ip_address(cfg_ip), .udp_rx_port(cfg_port),
        .udp_rx_port_mask(cfg_port_mask), .ip_multicast(cfg_mcast),
        .gmii_pads_rx_data(gmii_rxd), .gmii_pads_rx_dv(gmii_rx_dv), .gmii_pads_rx_er(gmii_rx_er),
        .gmii_pads_tx_data(gmii_txd), .gmii_pads_tx_en(gmii_tx_en), .gmii_pads_tx_er(gmii_tx_er),
        .udp_source_data(rx_data), .udp_source_valid(rx_valid), .udp_source_ready(rx_ready),
        .udp_source_last(rx_last), .udp_source_last_be(rx_last_be),
        .udp_source_error(rx_error), .udp_source_ip_address(rx_ip),
        .udp_source_src_port(rx_sport), .udp_source_dst_port(rx_dport),
        .udp_source_length(rx_len),
        .udp_sink_data(tx_data), .udp_sink_valid(tx_valid), .udp_sink_ready(tx_ready),
        .udp_sink_last(tx_last), .udp_sink_last_be(tx_last), .udp_sink_ip_address(tx_ip),
        .udp_sink_src_port(tx_sport), .udp_sink_dst_port(tx_dport), .udp_sink_length(tx_len),
        .rx_drop_header(drop_header), .rx_drop_other(drop_other));

    wire unused_ok = &{1'b0, rx_last_be};      // 8 bits a beat: the last beat is one byte

    rfl_udp_port #(.RX_BITS(RX_BITS), .TX_BITS(TX_BITS), .QUEUE_BITS(QUEUE_BITS),
                   .COUNT_BITS(COUNT_BITS)) u_port (
        .clk(clk), .rst_n(rst_n),
        .le_rx_data(rx_data), .le_rx_valid(rx_valid), .le_rx_ready(rx_ready),
        .le_rx_last(rx_last), .le_rx_error(rx_error), .le_rx_ip(rx_ip),
        .le_rx_src_port(rx_sport), .le_rx_dst_port(rx_dport), .le_rx_length(rx_len),
        .le_rx_drop_header(drop_header), .le_rx_drop_other(drop_other),
        .le_tx_data(tx_data), .le_tx_valid(tx_valid), .le_tx_ready(tx_ready),
        .le_tx_last(tx_last), .le_tx_ip(tx_ip), .le_tx_src_port(tx_sport),
        .le_tx_dst_port(tx_dport), .le_tx_length(tx_len),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast), .m_udp_ip(m_udp_ip),
        .m_udp_src_port(m_udp_src_port), .m_udp_dst_port(m_udp_dst_port),
        .m_udp_length(m_udp_length),
        .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast), .s_udp_ip(s_udp_ip),
        .s_udp_src_port(s_udp_src_port), .s_udp_dst_port(s_udp_dst_port),
        .cnt_rx_packets(cnt_rx_packets), .cnt_rx_error(cnt_rx_error),
        .cnt_rx_length(cnt_rx_length), .cnt_rx_overflow(cnt_rx_overflow),
        .cnt_tx_packets(cnt_tx_packets), .cnt_tx_overflow(cnt_tx_overflow),
        .cnt_rx_header(cnt_rx_header), .cnt_rx_other(cnt_rx_other));
endmodule

`default_nettype wire
