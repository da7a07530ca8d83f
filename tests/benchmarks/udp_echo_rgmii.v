// udp_echo_rgmii -- a UDP echo on an ECP5 board's RGMII PHY (issue #31), the top that
// bench_udp_timing.py places and routes: the vendored LiteEth core's board variant
// (rtl/fabric/vendor/liteeth_udp_ecp5_rgmii.v: LiteEth's ECP5 RGMII PHY, DELAYG and DDR
// registers, 2 ns delays in the FPGA; receive and send on the PHY's receive clock, its 32-bit
// core on eth_clk, its 8-bit UDP port on clk, crossing in LiteEth's FIFOs) and rfl_udp_port,
// whose received payloads go straight back to their
// sender (ports swapped). Its only other pin is the LED (active low): on while nothing was
// dropped. Its pins are the board build's (bench_udp_timing.py derives them from
// rtl/fabric/rfl_board_5a75b.lpf), clk on the oscillator's: timed at 125 MHz as if from the
// PLL, which it leaves out. Reset: for 16 clocks after configuration (no reset pin).
// The simulated top the tests drive is tests/rtl/udp_gmii_top.v (GMII, one clock).
`default_nettype none

module udp_echo_rgmii #(
    parameter [47:0] MAC  = 48'h02_52_46_4C_00_02,
    parameter [31:0] IP   = 32'hC0_A8_0A_02,   // 192.168.10.2
    parameter [15:0] PORT = 16'd7411,          // with PORT_MASK: 7392..7423
    parameter [15:0] PORT_MASK = 16'hFFE0,
    parameter [31:0] MCAST = 32'hEF_FF_00_01   // 239.255.0.1
) (
    input  wire       clk,                      // the circuit's clock (125 MHz)
    input  wire       eth_clk,                  // LiteEth's 32-bit core's (52.08 MHz)
    input  wire       rgmii_rx_clk,             // 125 MHz from the PHY
    input  wire       rgmii_rx_ctl,
    input  wire [3:0] rgmii_rxd,
    output wire       rgmii_tx_clk,
    output wire       rgmii_tx_ctl,
    output wire [3:0] rgmii_txd,
    output wire       led_n
);
    reg [4:0] rst_count;                        // bit 4: out of reset
    initial rst_count = 5'd0;
    wire rst_n = rst_count[4];
    always @(posedge clk) if (!rst_n) rst_count <= rst_count + 5'd1;
    reg [4:0] eth_rst_count;
    initial eth_rst_count = 5'd0;
    wire eth_rst_n = eth_rst_count[4];
    always @(posedge eth_clk) if (!eth_rst_n) eth_rst_count <= eth_rst_count + 5'd1;

    wire [7:0] rx_data, tx_data, m_data;
    wire rx_valid, rx_ready, rx_last, rx_error, rx_last_be;
    wire tx_valid, tx_ready, tx_last;
    wire [31:0] rx_ip, tx_ip, m_ip;
    wire [15:0] rx_sport, rx_dport, rx_len, tx_sport, tx_dport, tx_len;
    wire drop_header, drop_other;
    wire [15:0] m_sport, m_dport, m_len;
    wire m_valid, m_ready, m_last;
    wire [7:0] c_rx, c_err, c_len, c_ovf, c_tx, c_tovf, c_hdr, c_oth;

    liteeth_udp_ecp5_rgmii u_eth (
        .sys_clock(eth_clk), .sys_reset(!eth_rst_n), .port_clock(clk), .port_reset(!rst_n),
        .mac_address(MAC), .ip_address(IP), .udp_rx_port(PORT), .udp_rx_port_mask(PORT_MASK),
        .ip_multicast(MCAST),
        .rgmii_clocks_rx(rgmii_rx_clk), .rgmii_clocks_tx(rgmii_tx_clk),
        .rgmii_pads_rx_ctl(rgmii_rx_ctl), .rgmii_pads_rx_data(rgmii_rxd),
        .rgmii_pads_tx_ctl(rgmii_tx_ctl), .rgmii_pads_tx_data(rgmii_txd),
        .udp_source_data(rx_data), .udp_source_valid(rx_valid), .udp_source_ready(rx_ready),
        .udp_source_last(rx_last), .udp_source_last_be(rx_last_be),
        .udp_source_error(rx_error), .udp_source_ip_address(rx_ip),
        .udp_source_src_port(rx_sport), .udp_source_dst_port(rx_dport),
        .udp_source_length(rx_len),
        .udp_sink_data(tx_data), .udp_sink_valid(tx_valid), .udp_sink_ready(tx_ready),
        .udp_sink_last(tx_last), .udp_sink_last_be(tx_last), .udp_sink_ip_address(tx_ip),
        .udp_sink_src_port(tx_sport), .udp_sink_dst_port(tx_dport), .udp_sink_length(tx_len),
        .rx_drop_header(drop_header), .rx_drop_other(drop_other));

    rfl_udp_port #(.COUNT_BITS(8)) u_port (
        .clk(clk), .rst_n(rst_n),
        .le_rx_data(rx_data), .le_rx_valid(rx_valid), .le_rx_ready(rx_ready),
        .le_rx_last(rx_last), .le_rx_error(rx_error), .le_rx_ip(rx_ip),
        .le_rx_src_port(rx_sport), .le_rx_dst_port(rx_dport), .le_rx_length(rx_len),
        .le_rx_drop_header(drop_header), .le_rx_drop_other(drop_other),
        .le_tx_data(tx_data), .le_tx_valid(tx_valid), .le_tx_ready(tx_ready),
        .le_tx_last(tx_last), .le_tx_ip(tx_ip), .le_tx_src_port(tx_sport),
        .le_tx_dst_port(tx_dport), .le_tx_length(tx_len),
        .m_axis_tdata(m_data), .m_axis_tvalid(m_valid), .m_axis_tready(m_ready),
        .m_axis_tlast(m_last), .m_udp_ip(m_ip), .m_udp_src_port(m_sport),
        .m_udp_dst_port(m_dport), .m_udp_length(m_len),
        .s_axis_tdata(m_data), .s_axis_tvalid(m_valid), .s_axis_tready(m_ready),
        .s_axis_tlast(m_last), .s_udp_ip(m_ip), .s_udp_src_port(m_dport),
        .s_udp_dst_port(m_sport),
        .cnt_rx_packets(c_rx), .cnt_rx_error(c_err), .cnt_rx_length(c_len),
        .cnt_rx_overflow(c_ovf), .cnt_tx_packets(c_tx), .cnt_tx_overflow(c_tovf),
        .cnt_rx_header(c_hdr), .cnt_rx_other(c_oth));

    assign led_n = |{c_err, c_len, c_ovf, c_tovf};
    wire unused_ok = &{1'b0, rx_last_be, m_len, c_rx, c_tx, c_hdr, c_oth};
endmodule

`default_nettype wire
